//! Spheres.

use super::{check_finite, check_positive};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A sphere.
///
/// uv: with `d` the unit outward normal, `u = 0.5 + atan2(d.z, d.x) / 2π`,
/// `v = 0.5 − asin(d.y) / π` (the report's equations 7 and 8): `v = 0` at
/// the north pole (+Y), `v = 1` at the south pole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
}

/// The report's spherical mapping of a unit direction `d` to `(u, v)`.
#[inline]
#[must_use]
pub fn sphere_uv(d: Vec3) -> Vec2 {
    let u = 0.5 + d.z.atan2(d.x) / (2.0 * PI);
    let v = 0.5 - d.y.clamp(-1.0, 1.0).asin() / PI;
    Vec2::new(u, v)
}

impl Sphere {
    /// A sphere of `radius` about `center`.
    ///
    /// # Errors
    /// If `radius` is not positive or a value is not finite.
    pub fn new(center: Vec3, radius: f32) -> Result<Self, GeometryError> {
        Ok(Self {
            center: check_finite("sphere centre", center)?,
            radius: check_positive("sphere radius", radius)?,
        })
    }

    /// Centre.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }
}

impl Intersect for Sphere {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let f = ray.origin - self.center;
        let a = ray.dir.length_squared();
        let b = -f.dot(ray.dir);
        let c = f.length_squared() - self.radius * self.radius;
        // Hearn & Baker's form of the discriminant (Ray Tracing Gems ch. 7):
        // b² − ac = a (r² − |f − (f·d / a) d|²), exact for distant spheres.
        let l = f + (b / a) * ray.dir;
        let disc = a * (self.radius * self.radius - l.length_squared());
        if !(disc >= 0.0) {
            return None;
        }
        let q = b + b.signum() * disc.sqrt();
        let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
        let ts = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        let t = super::first_in(ray, ts)?;
        let n = (ray.at(t) - self.center) / self.radius;
        let n = n.normalize_or(Vec3::Y);
        // Re-project onto the surface to remove the error in t.
        let point = self.center + self.radius * n;
        Some(Hit::new(t, point, n, sphere_uv(n), ray.dir))
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.center - Vec3::splat(self.radius), self.center + Vec3::splat(self.radius))
    }
}
