//! The analytic shapes and triangles, each in its own object space.

mod cone;
mod cuboid;
mod cylinder;
mod disk;
mod plane;
mod sphere;
mod triangle;
mod upright;

pub use cone::Cone;
pub use cuboid::Cuboid;
pub use cylinder::Cylinder;
pub use disk::Disk;
pub use plane::Plane;
pub use sphere::{Sphere, azimuth_u, sphere_uv};
pub use triangle::{Nearest8, PacketRays, Triangle, TriangleRay, TriangleRays8, Triangles4};

use crate::{GeometryError, Ray};

/// How far (relative to the height) the side of a cylinder or cone is
/// accepted past its caps, so that a ray through the rim, where side and cap
/// meet, cannot slip between the two tests by rounding. Rays passing more
/// than `SEAL · height` beyond a cap miss, and so does a ray that stays
/// beyond a cap's plane over its whole length (`upright::beyond_caps`): the
/// band would catch a ray spawned from a cap that leaves it grazing.
pub(crate) const SEAL: f32 = 1e-6;

/// Smallest accepted radius, height or edge length.
pub(crate) fn check_positive(what: &'static str, v: f32) -> Result<f32, GeometryError> {
    if !v.is_finite() {
        Err(GeometryError::NonFinite(what))
    } else if v <= 0.0 {
        Err(GeometryError::NonPositive { what, value: v })
    } else {
        Ok(v)
    }
}

pub(crate) fn check_finite(what: &'static str, v: glam::Vec3) -> Result<glam::Vec3, GeometryError> {
    if v.is_finite() { Ok(v) } else { Err(GeometryError::NonFinite(what)) }
}

/// The first of the candidate `t` values that lies in the ray's interval.
#[inline]
pub(crate) fn first_in(ray: &Ray, ts: (f32, f32)) -> Option<f32> {
    if ray.contains(ts.0) {
        Some(ts.0)
    } else if ray.contains(ts.1) {
        Some(ts.1)
    } else {
        None
    }
}
