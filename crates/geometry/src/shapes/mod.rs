//! The analytic shapes and triangles, each in its own object space.

mod cone;
mod cuboid;
mod cylinder;
mod disk;
mod plane;
mod sphere;
mod triangle;

pub use cone::Cone;
pub use cuboid::Cuboid;
pub use cylinder::Cylinder;
pub use disk::Disk;
pub use plane::Plane;
pub use sphere::{Sphere, sphere_uv};
pub use triangle::{Triangle, TriangleRay};

use crate::{GeometryError, Ray};

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

/// Roots of `a t² + 2 h t + c = 0` in ascending order, computed without
/// catastrophic cancellation; `None` when there is no real root. `a` may be
/// zero (linear case).
#[inline]
pub(crate) fn solve_quadratic_half(a: f32, h: f32, c: f32) -> Option<(f32, f32)> {
    if a == 0.0 {
        if h == 0.0 {
            return None;
        }
        let t = -c / (2.0 * h);
        return Some((t, t));
    }
    let disc = h * h - a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -(h + h.signum() * disc.sqrt());
    if q == 0.0 {
        // h == 0 and disc == 0: the double root is 0 (c == 0).
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q / a, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
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
