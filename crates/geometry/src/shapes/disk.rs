//! Flat disks (also the caps of cylinders and cones).

use super::{check_finite, check_positive};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A flat disk of `radius` about `center`, facing `normal` (one-sided only
/// in the sense of where its normal points; rays hit it from both sides).
///
/// uv: polar, `u = angle / 2π` about the normal measured from the plane's
/// tangent (as [`crate::Plane`]), `v = distance from centre / radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    center: Vec3,
    normal: Vec3,
    radius: f32,
    tangent: Vec3,
}

impl Disk {
    /// A disk of `radius` about `center` with normal `normal`.
    ///
    /// # Errors
    /// If the radius is not positive, the normal is zero, or a value is not
    /// finite.
    pub fn new(center: Vec3, normal: Vec3, radius: f32) -> Result<Self, GeometryError> {
        let plane =
            crate::Plane::named(center, normal, ["disk centre", "disk normal", "disk normal is zero"])?;
        Ok(Self {
            center: check_finite("disk centre", center)?,
            normal: plane.normal(),
            radius: check_positive("disk radius", radius)?,
            tangent: plane.tangent(),
        })
    }

    /// Centre.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Unit normal.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// Radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }
}

impl Disk {
    /// `(t, rel, r2)`: the crossing's `t`, its offset from the centre in
    /// the disk's plane and that offset's squared length.
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<(f32, Vec3, f32)> {
        let denom = ray.dir.dot(self.normal);
        // Parallel, or a direction that is not finite (`±∞` or `NaN`).
        if denom == 0.0 || !denom.is_finite() {
            return None;
        }
        let t = (self.center - ray.origin).dot(self.normal) / denom;
        if !ray.contains(t) {
            return None;
        }
        let rel = ray.at(t) - self.center;
        let rel = rel - self.normal * rel.dot(self.normal);
        let r2 = rel.length_squared();
        // Written so that a `NaN` offset misses.
        if !(r2 <= self.radius * self.radius) {
            return None;
        }
        Some((t, rel, r2))
    }
}

impl Intersect for Disk {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.solve(ray).map(|(t, _, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t, rel, r2) = self.solve(ray)?;
        let bitangent = self.normal.cross(self.tangent);
        let angle = rel.dot(bitangent).atan2(rel.dot(self.tangent));
        let u = angle.rem_euclid(std::f32::consts::TAU) / std::f32::consts::TAU;
        let uv = Vec2::new(u, r2.sqrt() / self.radius);
        Some(Hit::new(t, self.center + rel, self.normal, uv, ray.dir))
    }

    /// No uv (`atan2`, `sqrt`) and no point.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let (t, _, _) = self.solve(ray)?;
        Some((t, Hit::faces(ray.dir, self.normal)))
    }

    fn bounds(&self) -> Aabb {
        let n = self.normal;
        // Along axis i, √(1 − n_i²) = √(n_j² + n_k²), the second without
        // the first's cancellation for a normal nearly along the axis.
        let e = self.radius * Vec3::new(n.y.hypot(n.z), n.x.hypot(n.z), n.x.hypot(n.y));
        Aabb::new(self.center - e, self.center + e)
    }

    fn bounds_in(&self, to_world: &crate::Transform) -> Aabb {
        to_world.tightest(to_world.disk_aabb(self.center, self.normal, self.radius), &self.bounds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::check_hit;

    fn disk() -> Disk {
        Disk::new(Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 2.0).unwrap()
    }

    #[test]
    fn hits_from_both_sides_with_polar_uv() {
        let d = disk();
        // Tangent +X (u = 0), bitangent Y × X = −Z (u = 1/4).
        let h = d.intersect(&Ray::new(Vec3::new(1.0, 5.0, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 4.0, Vec3::new(1.0, 1.0, 0.0), Vec3::Y, Vec2::new(0.0, 0.5), true);
        let h = d.intersect(&Ray::new(Vec3::new(0.0, -1.0, -1.0), Vec3::Y)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.0, 1.0, -1.0), Vec3::Y, Vec2::new(0.25, 0.5), false);
        let h = d.intersect(&Ray::new(Vec3::new(-2.0, 2.0, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 1.0, Vec3::new(-2.0, 1.0, 0.0), Vec3::Y, Vec2::new(0.5, 1.0), true);
    }

    #[test]
    fn rim_and_just_outside() {
        let d = disk();
        assert!(d.intersect(&Ray::new(Vec3::new(0.0, 5.0, 2.0), Vec3::NEG_Y)).is_some());
        assert!(d.intersect(&Ray::new(Vec3::new(0.0, 5.0, 2.000_001), Vec3::NEG_Y)).is_none());
        assert!(d.intersect(&Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X)).is_none(), "in its plane");
        assert!(d.intersect(&Ray::new(Vec3::new(0.0, 2.0, 0.0), Vec3::X)).is_none(), "parallel");
    }

    #[test]
    fn nearly_parallel_ray_never_returns_nan() {
        let r = Ray::new(Vec3::new(0.0, 1.0e10, 0.0), Vec3::new(0.0, -1.0e-30, 0.0));
        assert!(disk().intersect(&r).is_none());
    }

    #[test]
    fn bounds_of_a_tilted_disk() {
        let d = Disk::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0).unwrap();
        let b = d.bounds();
        let s = 0.5f32.sqrt();
        assert!((b.max - Vec3::new(s, s, 1.0)).abs().max_element() < 1e-6, "{b:?}");
        assert!(Disk::new(Vec3::ZERO, Vec3::Y, 0.0).is_err());
        // Errors name the disk, not the plane it lies in.
        let zero = Disk::new(Vec3::ZERO, Vec3::ZERO, 1.0).unwrap_err().to_string();
        assert!(zero.contains("disk normal is zero"), "{zero}");
        let nan = Disk::new(Vec3::NAN, Vec3::Y, 1.0).unwrap_err().to_string();
        assert!(nan.contains("disk centre"), "{nan}");
        // A normal of any finite size is a direction.
        assert_eq!(Disk::new(Vec3::ZERO, Vec3::Y * 1e-30, 1.0).unwrap().normal(), Vec3::Y);
    }
}
