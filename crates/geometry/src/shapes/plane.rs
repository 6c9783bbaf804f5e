//! Infinite planes.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// An infinite plane through `point` with unit normal `normal`.
///
/// uv: world-unit coordinates along two tangent axes: `u` along
/// [`Plane::tangent`], `v` along `tangent × normal`, measured from `point`,
/// so that an image seen from the normal's side is not mirrored.
/// The tangent is +X projected onto the plane (+Z when the normal is near
/// ±X), so for a floor with `normal = +Y`, `u` runs along +X and `v` along
/// +Z (the image's top toward −Z), and for a wall facing +Z, `u` runs along
/// +X and `v` along −Y (the image's top up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    point: Vec3,
    normal: Vec3,
    tangent: Vec3,
    bitangent: Vec3,
}

impl Plane {
    /// The plane through `point` with normal `normal` (any non-zero length).
    ///
    /// # Errors
    /// If `normal` is zero or a value is not finite.
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self, GeometryError> {
        Self::named(point, normal, ["plane point", "plane normal", "plane normal is zero"])
    }

    /// [`Plane::new`], its errors naming the point, the normal and a zero
    /// normal as `names` say (a disk's plane is the disk's).
    pub(crate) fn named(point: Vec3, normal: Vec3, names: [&'static str; 3]) -> Result<Self, GeometryError> {
        let [point_name, normal_name, zero] = names;
        let point = check_finite(point_name, point)?;
        let normal = check_finite(normal_name, normal)?;
        // Any finite size: `unit` where the squared length under- or overflows.
        let normal =
            normal.try_normalize().or_else(|| crate::unit(normal)).ok_or(GeometryError::Degenerate(zero))?;
        // Tangent: +X projected onto the plane, or +Z when the normal is ~X.
        let seed = if normal.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
        let tangent = (seed - normal * normal.dot(seed)).normalize();
        let bitangent = tangent.cross(normal);
        Ok(Self { point, normal, tangent, bitangent })
    }

    /// A point on the plane.
    #[must_use]
    pub fn point(&self) -> Vec3 {
        self.point
    }

    /// Unit normal.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// Unit tangent, the direction of increasing `u`.
    #[must_use]
    pub fn tangent(&self) -> Vec3 {
        self.tangent
    }
}

impl Intersect for Plane {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        let denom = ray.dir.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        ray.contains(t).then_some(t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let t = self.intersect_t(ray)?;
        let rel = ray.at(t) - self.point;
        // Project exactly onto the plane.
        let rel = rel - self.normal * rel.dot(self.normal);
        let uv = Vec2::new(rel.dot(self.tangent), rel.dot(self.bitangent));
        Some(Hit::new(t, self.point + rel, self.normal, uv, ray.dir))
    }

    /// No point and no uv.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let t = self.intersect_t(ray)?;
        Some((t, Hit::faces(ray.dir, self.normal)))
    }

    fn bounds(&self) -> Aabb {
        Aabb::INFINITE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close3};

    fn floor() -> Plane {
        Plane::new(Vec3::ZERO, Vec3::new(0.0, 3.0, 0.0)).unwrap()
    }

    #[test]
    fn hit_from_above_with_world_unit_uv() {
        let h = floor().intersect(&Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::NEG_Y)).unwrap();
        // u along +X, v along −Z.
        check_hit(&h, 2.0, Vec3::new(1.0, 0.0, 3.0), Vec3::Y, Vec2::new(1.0, 3.0), true);
    }

    #[test]
    fn hit_from_below_keeps_the_declared_normal() {
        let h = floor().intersect(&Ray::new(Vec3::new(0.0, -2.0, 0.0), Vec3::new(0.0, 1.0, -1.0))).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.0, 0.0, -2.0), Vec3::Y, Vec2::new(0.0, -2.0), false);
    }

    #[test]
    fn parallel_and_in_plane_rays_miss() {
        let p = floor();
        assert!(p.intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::X)).is_none());
        assert!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).is_none());
        assert!(p.intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::Y)).is_none(), "pointing away");
    }

    #[test]
    fn tilted_plane_and_tangent_frame() {
        let p = Plane::new(Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
        let h = p.intersect(&Ray::new(Vec3::new(0.5, 0.25, 0.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.5, 0.25, -2.0), Vec3::Z, Vec2::new(0.5, -0.25), true);
        // Normal near ±X: the tangent falls back to +Z; the frame is orthonormal.
        let side = Plane::new(Vec3::ZERO, Vec3::NEG_X).unwrap();
        close3(side.tangent(), Vec3::Z, 1e-6);
        let h = side.intersect(&Ray::new(Vec3::new(-1.0, 2.0, 3.0), Vec3::X)).unwrap();
        // The ray comes from −X, the side the normal points to.
        check_hit(&h, 1.0, Vec3::new(0.0, 2.0, 3.0), Vec3::NEG_X, Vec2::new(3.0, -2.0), true);
    }

    #[test]
    fn nearly_parallel_ray_never_returns_nan() {
        // The division overflows to t = ∞: that is no hit, not a NaN point.
        let r = Ray::new(Vec3::new(0.0, 1.0e10, 0.0), Vec3::new(1.0, -1.0e-30, 0.0));
        match floor().intersect(&r) {
            None => {}
            Some(h) => assert!(h.t.is_finite() && h.point.is_finite(), "{h:?}"),
        }
    }

    #[test]
    fn rejects_zero_normal() {
        assert!(Plane::new(Vec3::ZERO, Vec3::ZERO).is_err());
        assert!(Plane::new(Vec3::NAN, Vec3::Y).is_err());
        assert_eq!(Plane::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 3e-25)).unwrap().normal(), Vec3::Z);
        assert_eq!(floor().bounds(), Aabb::INFINITE);
    }
}
