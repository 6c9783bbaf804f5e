//! Triangles, with a watertight intersection test.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3, Vec3A};

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
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        TriangleRay::new(ray).intersect(&self.v).map(|(t, _, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t, b1, b2) = TriangleRay::new(ray).intersect(&self.v)?;
        let b0 = 1.0 - b1 - b2;
        let p = b0 * self.v[0] + b1 * self.v[1] + b2 * self.v[2];
        Some(Hit::new(t, p, self.normal(), Vec2::new(b1, b2), ray.dir))
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.v)
    }
}

/// A ray prepared for the watertight ray/triangle test of Woop, Benthin and
/// Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013): prism's one
/// implementation of that test, used by [`Triangle`], [`crate::TriangleMesh`]
/// and the BVH's leaves alike.
///
/// The ray is sheared so that it runs along +Z; each triangle is then
/// tested in 2D with edge functions that are exact in sign on shared edges
/// (falling back to `f64` when an edge function is exactly zero), so a ray
/// aimed at a shared edge or vertex of a closed mesh never slips through.
/// Prepare once per ray ([`TriangleRay::new`]), then test many triangles
/// ([`TriangleRay::intersect`]).
///
/// # Layout
///
/// The paper indexes the vertex by the permuted axes `kx`, `ky`, `kz` of the
/// ray's dominant direction and computes the sheared vertex as
/// `(a[kx] − sx·a[kz], a[ky] − sy·a[kz], sz·a[kz])`. Here the shear is
/// stored as three row vectors (`Vec3A`, SIMD-friendly) so that the same
/// three values are dot products instead of dynamically indexed loads: the
/// extra terms are products with exact zeros, so every value, and so every
/// edge-function sign (the watertightness), is the paper's (up to the sign
/// of an exactly zero coordinate, which no test below distinguishes).
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    origin: Vec3A,
    /// Row giving the sheared `x`: `1` at `kx`, `−sx` at `kz`.
    mx: Vec3A,
    /// Row giving the sheared `y`: `1` at `ky`, `−sy` at `kz`.
    my: Vec3A,
    /// Row giving the scaled `z`: `sz` at `kz`.
    mz: Vec3A,
    /// The ray's `t_min`, raised to `f32::MIN` (so `−∞` never passes).
    t_min: f32,
    /// The ray's `t_max`, lowered to `f32::MAX` (so `+∞` never passes).
    t_max: f32,
}

/// `[t_min, t_max]` narrowed to finite bounds: the interval test then also
/// rejects an infinite or `NaN` `t`, at no cost per triangle.
#[inline(always)]
fn finite_interval(t_min: f32, t_max: f32) -> (f32, f32) {
    (t_min.max(f32::MIN), t_max.min(f32::MAX))
}

impl TriangleRay {
    /// Prepares `ray` (its direction must be non-zero; a zero or non-finite
    /// direction hits nothing).
    #[inline(always)]
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
        let (sx, sy, sz) = (ray.dir[kx] / dz, ray.dir[ky] / dz, 1.0 / dz);
        let (mut mx, mut my, mut mz) = (Vec3A::ZERO, Vec3A::ZERO, Vec3A::ZERO);
        mx[kx] = 1.0;
        mx[kz] = -sx;
        my[ky] = 1.0;
        my[kz] = -sy;
        mz[kz] = sz;
        let (t_min, t_max) = finite_interval(ray.t_min, ray.t_max);
        Self { origin: ray.origin.into(), mx, my, mz, t_min, t_max }
    }

    /// Narrows the accepted interval's upper end (after a closer hit).
    #[inline(always)]
    pub fn set_t_max(&mut self, t_max: f32) {
        self.t_max = finite_interval(self.t_min, t_max).1;
    }

    /// `(t, b1, b2)` if the ray meets the triangle with corners `v` within
    /// its interval, from either side; `(b1, b2)` are the barycentric
    /// coordinates of `v[1]` and `v[2]` (see [`Triangle`]). Zero-area
    /// triangles are never hit, and neither is an infinite or `NaN` `t`
    /// (a nearly parallel ray whose plane crossing overflows), whatever
    /// the interval.
    #[inline(always)]
    #[must_use]
    pub fn intersect(&self, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let a = Vec3A::from(v[0]) - self.origin;
        let b = Vec3A::from(v[1]) - self.origin;
        let c = Vec3A::from(v[2]) - self.origin;
        let (ax, ay) = (self.mx.dot(a), self.my.dot(a));
        let (bx, by) = (self.mx.dot(b), self.my.dot(b));
        let (cx, cy) = (self.mx.dot(c), self.my.dot(c));
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
        let t_scaled = u * self.mz.dot(a) + v * self.mz.dot(b) + w * self.mz.dot(c);
        let rcp = 1.0 / det;
        let t = t_scaled * rcp;
        // The bounds are finite, so this also rejects an infinite or NaN t.
        if !(t >= self.t_min && t <= self.t_max) {
            return None;
        }
        Some((t, v * rcp, w * rcp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close};

    fn tri() -> Triangle {
        Triangle::new([Vec3::ZERO, Vec3::X, Vec3::Y]).unwrap()
    }

    #[test]
    fn hits_from_both_sides_with_barycentric_uv() {
        let h = tri().intersect(&Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.25, 0.5, 0.0), Vec3::Z, Vec2::new(0.25, 0.5), true);
        let h = tri().intersect(&Ray::new(Vec3::new(0.5, 0.25, -1.0), Vec3::new(0.0, 0.0, 0.5))).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.5, 0.25, 0.0), Vec3::Z, Vec2::new(0.5, 0.25), false);
        // Oblique.
        let h = tri().intersect(&Ray::new(Vec3::new(1.25, 0.25, 1.0), Vec3::new(-1.0, 0.0, -1.0))).unwrap();
        check_hit(&h, 1.0, Vec3::new(0.25, 0.25, 0.0), Vec3::Z, Vec2::new(0.25, 0.25), true);
    }

    #[test]
    fn edges_and_vertices_are_hit_and_just_outside_is_not() {
        let t = tri();
        for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.5, 0.5, 0.0)] {
            let h = t.intersect(&Ray::new(p + Vec3::Z, Vec3::NEG_Z)).unwrap_or_else(|| panic!("{p}"));
            close(h.t, 1.0, 1e-6);
        }
        for p in [Vec3::new(0.5, -1e-6, 1.0), Vec3::new(-1e-6, 0.5, 1.0), Vec3::new(0.5, 0.500_001, 1.0)] {
            assert!(t.intersect(&Ray::new(p, Vec3::NEG_Z)).is_none(), "{p}");
        }
    }

    #[test]
    fn parallel_rays_and_intervals() {
        let t = tri();
        assert!(t.intersect(&Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X)).is_none(), "in its plane");
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::X)).is_none());
        assert!(t.intersect(&Ray::with_interval(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z, 0.0, 0.5)).is_none());
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::Z)).is_none(), "behind");
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO)).is_none());
    }

    #[test]
    fn nearly_parallel_ray_never_returns_infinity() {
        // The plane is reached at t = 1e48, beyond f32: no hit, not t = ∞.
        let far = Triangle::new([
            Vec3::new(-1e15, -1e15, 0.0),
            Vec3::new(1e15, -1e15, 0.0),
            Vec3::new(0.0, 1e15, 0.0),
        ]);
        let r = Ray::new(Vec3::new(0.0, 0.0, 1e10), Vec3::new(1e-38, 0.0, -1e-38));
        if let Some(h) = far.unwrap().intersect(&r) {
            assert!(h.t.is_finite() && h.point.is_finite(), "{h:?}");
        }
    }

    #[test]
    fn degenerate_triangles_are_rejected() {
        assert!(Triangle::new([Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)]).is_err());
        assert!(Triangle::new([Vec3::ZERO, Vec3::X, Vec3::NAN]).is_err());
        assert_eq!(tri().bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(tri().normal(), Vec3::Z);
    }
}
