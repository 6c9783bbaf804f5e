//! Triangles, with a watertight intersection test.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A single triangle `(v0, v1, v2)`; its outward normal follows the
/// counter-clockwise winding, `(v1 − v0) × (v2 − v0)` (right-handed).
///
/// uv: the barycentric coordinates `(b1, b2)` of the hit, so that
/// `p = (1 − b1 − b2)·v0 + b1·v1 + b2·v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The three corners.
    pub v: [Vec3; 3],
}

impl Triangle {
    /// A triangle with corners `v`.
    ///
    /// # Errors
    /// If a corner is not finite or the triangle has zero area.
    pub fn new(v: [Vec3; 3]) -> Result<Self, GeometryError> {
        for p in v {
            check_finite("triangle corner", p)?;
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if n.length_squared() == 0.0 || !n.is_finite() {
            return Err(GeometryError::Degenerate("triangle has zero area"));
        }
        Ok(Self { v })
    }

    /// Unit outward normal (counter-clockwise winding).
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0]).normalize_or_zero()
    }
}

impl Intersect for Triangle {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t, b1, b2) = TriangleRay::new(ray).intersect(self.v[0], self.v[1], self.v[2])?;
        let b0 = 1.0 - b1 - b2;
        let p = b0 * self.v[0] + b1 * self.v[1] + b2 * self.v[2];
        Some(Hit::new(t, p, self.normal(), Vec2::new(b1, b2), ray.dir))
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.v)
    }
}

/// A ray prepared for the watertight ray/triangle test of Woop, Benthin and
/// Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013).
///
/// The ray is sheared so that it runs along +Z; each triangle is then
/// tested in 2D with edge functions that are exact in sign on shared edges
/// (falling back to `f64` when an edge function is exactly zero), so a ray
/// aimed at a shared edge or vertex of a closed mesh never slips through.
/// Prepare once per ray, test many triangles.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
    t_min: f32,
    t_max: f32,
}

impl TriangleRay {
    /// Prepares `ray` (its direction must be non-zero).
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = ray.dir[kz];
        Self {
            origin: ray.origin,
            kx,
            ky,
            kz,
            sx: ray.dir[kx] / dz,
            sy: ray.dir[ky] / dz,
            sz: 1.0 / dz,
            t_min: ray.t_min,
            t_max: ray.t_max,
        }
    }

    /// Narrows the accepted interval's upper end (after a closer hit).
    #[inline]
    pub fn set_t_max(&mut self, t_max: f32) {
        self.t_max = t_max;
    }

    /// `(t, b1, b2)` if the ray meets the triangle within its interval,
    /// from either side. Zero-area triangles are never hit.
    #[inline]
    #[must_use]
    pub fn intersect(&self, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<(f32, f32, f32)> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = v0 - self.origin;
        let b = v1 - self.origin;
        let c = v2 - self.origin;
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let rcp = 1.0 / det;
        let t = t_scaled * rcp;
        if !(t >= self.t_min && t <= self.t_max) {
            return None;
        }
        Some((t, v * rcp, w * rcp))
    }
}
