//! Exact ray/shape intersection for the prism ray tracer, usable on its own.
//!
//! This crate depends on [`glam`] only. It answers "where does this ray
//! meet this shape?" for spheres, infinite planes, boxes, capped cylinders,
//! finite cones, disks, triangles (watertight) and triangle meshes, each in
//! its own object space and placeable anywhere by an affine [`Transform`]
//! (translate, rotate, scale, shear, or a full matrix).
//!
//! Conventions: right-handed coordinates, +Y up; angles in radians; normals
//! in a [`Hit`] are unit length and point *outward*, never flipped toward the
//! ray ([`Hit::front_face`] says which side the ray came from). Secondary
//! rays start with [`Ray::spawn`], which offsets the origin off the surface
//! ([`offset_ray_origin`]); that is the crate's only self-intersection
//! epsilon. No NaN leaves the crate for finite inputs.
//!
//! Some items mention "the report": the ray-tracing report whose scene
//! prism first reproduced. Each such mention also states the formula it
//! refers to, so these docs stand alone.
//!
//! # Example
//!
//! A box rotated 45° about Y (as in the report prism started from), hit
//! head-on along −Z:
//!
//! ```
//! use prism_geometry::{Cuboid, Instance, Intersect, Ray, Transform};
//! use glam::Vec3;
//!
//! let unit_box = Cuboid::new(Vec3::splat(-1.0), Vec3::splat(1.0))?;
//! let placed = Transform::rotate_y(45f32.to_radians())
//!     .then(&Transform::translate(Vec3::new(0.0, 0.0, -10.0))?);
//! let rotated = Instance::new(unit_box, placed);
//!
//! let ray = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
//! let hit = rotated.intersect(&ray).expect("the box is straight ahead");
//! // The nearest point is the box's vertical edge at distance √2 from its centre.
//! assert!((hit.t - (10.0 - 2f32.sqrt())).abs() < 1e-4);
//! assert!(hit.front_face);
//! # Ok::<(), prism_geometry::GeometryError>(())
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod aabb;
mod error;
mod hit;
mod mesh;
mod normals;
mod polygon;
mod ray;
mod shape;
pub mod shapes;
#[cfg(test)]
mod testutil;
// The README's example, run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
mod transform;

pub use aabb::Aabb;
pub use error::GeometryError;
pub use glam;
pub use hit::Hit;
pub use mesh::{TriangleMesh, weld_by_position};
pub use normals::{DEFAULT_CREASE_DEG, with_computed_normals};
pub use polygon::triangulate;
pub use ray::{Ray, offset_ray_origin, offset_ray_origin_scaled, offset_scale};
pub use shape::{Instance, Intersect, Shape};
pub use shapes::{
    Cone, Cuboid, Cylinder, Disk, Nearest8, PacketRays, Plane, Sphere, Triangle, TriangleRay, TriangleRays8,
    Triangles4, azimuth_u, sphere_uv,
};
pub use transform::{Shear, Transform};

/// `v` scaled to length 1, or `None` where it is zero or not finite.
/// Unlike `Vec3::try_normalize`, any finite vector works: it is divided by
/// its largest component first, so that its squared length neither
/// overflows (from about 1.8e19) nor vanishes (below about 1e-19).
#[must_use]
pub fn unit(v: glam::Vec3) -> Option<glam::Vec3> {
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    (v / largest).try_normalize()
}

/// The length of `v`, as `Vec3::length` gives it (the same bits) where
/// its squared length is a normal finite float, else computed from `v`
/// divided by its largest component, so that a vector longer than about
/// 1.8e19 (whose square overflows) or shorter than about 1e-19 (whose
/// square vanishes) still has its length: `0` only for the zero vector,
/// infinite only past `f32::MAX`.
#[must_use]
pub fn length(v: glam::Vec3) -> f32 {
    let l2 = v.length_squared();
    if (f32::MIN_POSITIVE..=f32::MAX).contains(&l2) {
        return l2.sqrt();
    }
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return if largest == 0.0 { 0.0 } else { largest.abs() };
    }
    (v / largest).length() * largest
}

/// `v` scaled to length 1 as `Vec3::normalize` does it (the same bits)
/// where its squared length is a normal finite float, else [`unit()`]'s
/// answer: for the hot paths that must not change their results for
/// ordinary vectors, but must not lose extreme ones (whose squared length
/// overflows or is subnormal) to a fallback.
#[inline]
#[must_use]
pub fn unit_or_extreme(v: glam::Vec3) -> Option<glam::Vec3> {
    let l2 = v.length_squared();
    if (f32::MIN_POSITIVE..=f32::MAX).contains(&l2) { Some(v.normalize()) } else { unit(v) }
}

/// The unit vector from `from` towards `to`, or `None` where they are the
/// same point or not finite. Any two finite points work: past f32's range
/// apart (about 3.4e38), where `to - from` overflows, their halves'
/// difference points the same way.
#[must_use]
pub fn unit_between(from: glam::Vec3, to: glam::Vec3) -> Option<glam::Vec3> {
    if !(from.is_finite() && to.is_finite()) {
        return None;
    }
    let d = to - from;
    unit(if d.is_finite() { d } else { to * 0.5 - from * 0.5 })
}

#[cfg(test)]
mod unit_tests {
    use super::unit;
    use glam::Vec3;

    #[test]
    fn unit_vectors_of_any_finite_size() {
        for s in [1e30f32, 1e20, 1.0, 1e-20, 1e-40] {
            let u = unit(Vec3::new(3.0, -4.0, 0.0) * s).unwrap_or_else(|| panic!("{s}"));
            assert!((u - Vec3::new(0.6, -0.8, 0.0)).length() < 1e-6, "{s}: {u}");
        }
        assert_eq!(unit(Vec3::new(0.0, -1e38, -1e38)), Some(Vec3::new(0.0, -1.0, -1.0).normalize()));
        for v in [Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::new(f32::NAN, 1.0, 0.0)] {
            assert_eq!(unit(v), None, "{v}");
        }
    }

    #[test]
    fn units_between_points_any_distance_apart() {
        use super::unit_between;
        let (a, b) = (Vec3::new(3e38, 1.0, 0.0), Vec3::new(-3e38, 1.0, 0.0));
        assert_eq!(unit_between(a, b), Some(Vec3::NEG_X));
        assert_eq!(unit_between(b, a), Some(Vec3::X));
        assert_eq!(unit_between(Vec3::ONE, Vec3::new(1.0, 1.0, 3.0)), Some(Vec3::Z));
        assert_eq!(unit_between(a, a), None);
        assert_eq!(unit_between(Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::ZERO), None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn length_holds_for_vectors_whose_square_is_out_of_range() {
        // Ordinary vectors: glam's bits.
        for v in [Vec3::new(3.0, 4.0, 0.0), Vec3::new(0.1, -0.2, 0.3), Vec3::splat(1e18)] {
            assert_eq!(length(v).to_bits(), v.length().to_bits(), "{v}");
        }
        // Squares past the range: the length still, to a few ulps.
        for (v, want) in [
            (Vec3::new(3e20, 4e20, 0.0), 5e20f32),
            (Vec3::new(0.0, 3e-25, -4e-25), 5e-25),
            (Vec3::new(1e38, 1e38, 1e38), 1e38 * 3f32.sqrt()),
            (Vec3::new(1e-40, 0.0, 0.0), 1e-40),
        ] {
            let got = length(v);
            assert!((got - want).abs() <= 4.0 * f32::EPSILON * want, "{v}: {got} vs {want}");
        }
        assert_eq!(length(Vec3::ZERO), 0.0);
        assert_eq!(length(Vec3::new(3e38, 3e38, 0.0)), f32::INFINITY);
        assert_eq!(length(Vec3::new(f32::INFINITY, 0.0, 0.0)), f32::INFINITY);
    }
}
