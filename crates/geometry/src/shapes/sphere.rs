//! Spheres.

use super::{check_finite, check_positive};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A sphere.
///
/// uv: with `d` the unit outward normal, `u = 0.5 + atan2(d.x, d.z) / 2π`,
/// `v = 0.5 − asin(d.y) / π` ([`sphere_uv`]): `v = 0` at the north pole
/// (+Y), `v = 1` at the south pole; `u = 0.5` faces +Z (the default
/// camera), and `u` grows eastward, toward +X seen from +Z, so that an
/// image seen from outside reads as in an image viewer (an Earth map
/// makes a globe, not its mirror image). The seam `u = 0 | 1` faces −Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
}

/// The azimuth of `d` about the Y axis as `u` in `[0, 1]`:
/// `0.5 + atan2(d.x, d.z) / 2π`. It is 0.5 at +Z, 0.75 at +X, 0.25 at −X,
/// and 0 or 1 at the seam, −Z; seen from outside (from +Y's side, looking
/// at the axis) it grows to the right.
#[inline]
#[must_use]
pub fn azimuth_u(d: Vec3) -> f32 {
    0.5 + d.x.atan2(d.z) / (2.0 * PI)
}

/// The spherical mapping of a unit direction `d` to `(u, v)`: `u` is
/// [`azimuth_u`], `v = 0.5 − asin(d.y) / π` (the report's equation 8).
#[inline]
#[must_use]
pub fn sphere_uv(d: Vec3) -> Vec2 {
    let u = azimuth_u(d);
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

impl Sphere {
    /// The `t` of the nearest crossing in the ray's interval (shared by
    /// [`Intersect::intersect`] and [`Intersect::intersect_t`], so both
    /// give the same `t` bit for bit).
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<f32> {
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
        super::first_in(ray, ts)
    }

    /// The unit outward normal where the ray is at `t`.
    #[inline]
    fn normal_at(&self, ray: &Ray, t: f32) -> Vec3 {
        ((ray.at(t) - self.center) / self.radius).normalize_or(Vec3::Y)
    }
}

impl Intersect for Sphere {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.solve(ray)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let t = self.solve(ray)?;
        let n = self.normal_at(ray, t);
        // Re-project onto the surface to remove the error in t.
        let point = self.center + self.radius * n;
        Some(Hit::new(t, point, n, sphere_uv(n), ray.dir))
    }

    /// No uv (`atan2`, `asin`) and no point: the normal decides the side.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let t = self.solve(ray)?;
        Some((t, Hit::faces(ray.dir, self.normal_at(ray, t))))
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.center - Vec3::splat(self.radius), self.center + Vec3::splat(self.radius))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close};

    fn sphere() -> Sphere {
        Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0).unwrap()
    }

    #[test]
    fn hit_from_outside_head_on() {
        let h = sphere().intersect(&Ray::new(Vec3::ZERO, Vec3::NEG_Z)).unwrap();
        // d = +Z faces the default camera: u = 0.5 + atan2(0, 1)/2π = 0.5, v = 0.5.
        check_hit(&h, 4.0, Vec3::new(0.0, 0.0, -4.0), Vec3::Z, Vec2::new(0.5, 0.5), true);
    }

    #[test]
    fn t_is_in_units_of_an_unnormalised_direction() {
        let h = sphere().intersect(&Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -2.0))).unwrap();
        close(h.t, 2.0, 1e-6);
    }

    #[test]
    fn hit_from_inside_is_the_far_side_with_outward_normal() {
        let h = sphere().intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::X)).unwrap();
        check_hit(&h, 1.0, Vec3::new(1.0, 0.0, -5.0), Vec3::X, Vec2::new(0.75, 0.5), false);
    }

    #[test]
    fn poles_seam_and_east_are_where_documented() {
        let s = sphere();
        let top = s.intersect(&Ray::new(Vec3::new(0.0, 5.0, -5.0), Vec3::NEG_Y)).unwrap();
        check_hit(&top, 4.0, Vec3::new(0.0, 1.0, -5.0), Vec3::Y, Vec2::new(0.5, 0.0), true);
        let bottom = s.intersect(&Ray::new(Vec3::new(0.0, -5.0, -5.0), Vec3::Y)).unwrap();
        check_hit(&bottom, 4.0, Vec3::new(0.0, -1.0, -5.0), Vec3::NEG_Y, Vec2::new(0.5, 1.0), true);
        // +X is u = 0.75, −X is 0.25, the seam −Z is 0 or 1 (atan2(0, −1) = π).
        let back = s.intersect(&Ray::new(Vec3::new(0.0, 0.0, -10.0), Vec3::Z)).unwrap();
        check_hit(&back, 4.0, Vec3::new(0.0, 0.0, -6.0), Vec3::NEG_Z, Vec2::new(1.0, 0.5), true);
        assert_eq!(sphere_uv(Vec3::new(-1.0, 0.0, 0.0)).x, 0.25);
        assert_eq!(sphere_uv(Vec3::X).x, 0.75);
        // Seen from +Z, a step to the right (+X) is a step east (u grows):
        // not mirrored.
        let (a, b) = (
            sphere_uv(Vec3::new(-0.1, 0.0, 1.0).normalize()),
            sphere_uv(Vec3::new(0.1, 0.0, 1.0).normalize()),
        );
        assert!(b.x > a.x, "{a} {b}");
    }

    #[test]
    fn grazing_ray_touches_at_one_point() {
        // Tangent to the sphere at its top, along +X (zero y and z components).
        let h = sphere().intersect(&Ray::new(Vec3::new(-5.0, 1.0, -5.0), Vec3::X)).unwrap();
        check_hit(&h, 5.0, Vec3::new(0.0, 1.0, -5.0), Vec3::Y, Vec2::new(0.5, 0.0), false);
    }

    #[test]
    fn misses_just_outside_the_silhouette() {
        let s = sphere();
        assert!(s.intersect(&Ray::new(Vec3::new(-5.0, 1.000_001, -5.0), Vec3::X)).is_none());
        assert!(s.intersect(&Ray::new(Vec3::new(1.000_001, 0.0, 0.0), Vec3::NEG_Z)).is_none());
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).is_none(), "behind the ray");
    }

    #[test]
    fn interval_selects_the_root() {
        let s = sphere();
        assert!(s.intersect(&Ray::with_interval(Vec3::ZERO, Vec3::NEG_Z, 0.0, 3.9)).is_none());
        let far = s.intersect(&Ray::with_interval(Vec3::ZERO, Vec3::NEG_Z, 4.5, 100.0)).unwrap();
        check_hit(&far, 6.0, Vec3::new(0.0, 0.0, -6.0), Vec3::NEG_Z, Vec2::new(1.0, 0.5), false);
    }

    #[test]
    fn distant_sphere_is_exact() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -1.0e4), 1.0).unwrap();
        let h = s.intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Z)).unwrap();
        let expected_z = -1.0e4 + 0.75f32.sqrt();
        close(h.point.z, expected_z, 2e-3);
        // Within a few ULPs of the largest coordinate (ulp(1e4) ≈ 1e-3).
        close(h.point.y, 0.5, 1e-3);
        close((h.point - s.center()).length(), 1.0, 2e-3);
    }

    #[test]
    fn zero_direction_never_hits() {
        assert!(sphere().intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO)).is_none());
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Sphere::new(Vec3::ZERO, 0.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, -1.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, f32::NAN).is_err());
        assert!(Sphere::new(Vec3::splat(f32::INFINITY), 1.0).is_err());
    }

    #[test]
    fn bounds_are_tight() {
        let b = sphere().bounds();
        assert_eq!(b, Aabb::new(Vec3::new(-1.0, -1.0, -6.0), Vec3::new(1.0, 1.0, -4.0)));
    }
}
