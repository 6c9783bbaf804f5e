//! Infinite planes.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// An infinite plane through `point` with unit normal `normal`.
///
/// uv: world-unit coordinates along two tangent axes: `u` along
/// [`Plane::tangent`], `v` along `tangent × normal`, measured from `point`,
/// so that an image seen from the normal's side is not mirrored.
/// On a wall or slope (a normal more than about 26° from ±Y) the tangent is
/// `Y × normal`, level and to the right of a viewer on the normal's side,
/// so `v` runs down the slope and an image stands upright, whichever way
/// the wall faces: facing +Z, `u` runs along +X and `v` along −Y; facing
/// −Z, `u` along −X; facing +X, `u` along −Z. On a floor or ceiling the
/// tangent is +X projected onto the plane: with `normal = +Y`, `u` runs
/// along +X and `v` along +Z (the image's top toward −Z).
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
        // Tangent: level and to the right, seen from the normal's side, on a
        // wall or slope; +X projected onto the plane on a floor or ceiling.
        // Either has length ≥ √(1 − 0.9²) before normalising.
        let tangent = if normal.y.abs() < 0.9 {
            Vec3::Y.cross(normal).normalize()
        } else {
            (Vec3::X - normal * normal.x).normalize()
        };
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
        // A direction that is not finite (`±∞`; `NaN` gives a `NaN` `t`)
        // divides to `t = ±0` wherever the plane lies: refused, the test
        // made on such a `t` alone (every query tests the floor).
        (ray.contains(t) && (t != 0.0 || denom.is_finite())).then_some(t)
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
        // A wall facing −X: the tangent is level, to the right seen from −X.
        let side = Plane::new(Vec3::ZERO, Vec3::NEG_X).unwrap();
        close3(side.tangent(), Vec3::Z, 1e-6);
        let h = side.intersect(&Ray::new(Vec3::new(-1.0, 2.0, 3.0), Vec3::X)).unwrap();
        // The ray comes from −X, the side the normal points to.
        check_hit(&h, 1.0, Vec3::new(0.0, 2.0, 3.0), Vec3::NEG_X, Vec2::new(3.0, -2.0), true);
    }

    #[test]
    fn every_wall_reads_upright_from_its_front() {
        // For any wall or slope: u level and to the right of a viewer on the
        // normal's side (looking along −normal with +Y up), v down the
        // slope, and the frame orthonormal and right-handed with the normal.
        for k in 0..72 {
            for tilt in [-0.8f32, -0.3, 0.0, 0.4, 0.85] {
                let a = (k as f32 * 5.0).to_radians();
                let n = Vec3::new(a.sin(), tilt, a.cos()).normalize();
                let p = Plane::new(Vec3::ZERO, n).unwrap();
                let (u, v) = (p.tangent(), p.tangent().cross(p.normal()));
                let right = (-n).cross(Vec3::Y).normalize();
                close3(u, right, 1e-5);
                assert!(u.y.abs() < 1e-6 && v.y < 0.0, "n {n}: u {u}, v {v}");
                assert!((u.cross(v).dot(n) + 1.0).abs() < 1e-5 && u.dot(n).abs() < 1e-6);
            }
        }
        // A floor keeps +X; a ceiling too.
        close3(floor().tangent(), Vec3::X, 1e-6);
        close3(Plane::new(Vec3::ZERO, Vec3::NEG_Y).unwrap().tangent(), Vec3::X, 1e-6);
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
