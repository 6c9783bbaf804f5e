//! What the solids standing on the Y axis (capped [`super::Cylinder`] and
//! [`super::Cone`]) share: the quadric's roots, the side's height check
//! sealed to the caps, the cap disks, their uv, and their bounds.

use super::{SEAL, check_finite, check_positive};
use crate::{Aabb, GeometryError, Ray};
use glam::{Vec2, Vec3};

/// Candidate hit kept while testing the side and the caps.
#[derive(Clone, Copy)]
pub(crate) enum Part {
    Side,
    Bottom,
    Top,
}

/// Keeps the nearest candidate.
#[inline]
pub(crate) fn keep(best: &mut Option<(f32, Part)>, t: f32, part: Part) {
    if best.is_none_or(|(b, _)| t < b) {
        *best = Some((t, part));
    }
}

/// Tests a cap disk at object height `y` (relative to the base) of radius
/// `r` about the axis.
#[inline]
pub(crate) fn cap_t(ray: &Ray, o: Vec3, y: f32, r: f32) -> Option<f32> {
    if ray.dir.y == 0.0 {
        return None;
    }
    let t = (y - o.y) / ray.dir.y;
    if !ray.contains(t) {
        return None;
    }
    let (x, z) = (o.x + t * ray.dir.x, o.z + t * ray.dir.z);
    (x * x + z * z <= r * r).then_some(t)
}

/// uv on a cap of radius `r`, from the point relative to the axis: seen
/// from outside, the top cap's image has its top toward −Z, the bottom
/// cap's toward +Z (each continues the side's `u = 0.5` column, as a box's
/// top and bottom continue its front face).
#[inline]
pub(crate) fn cap_uv(rel: Vec3, r: f32, top: bool) -> Vec2 {
    let z = if top { rel.z } else { -rel.z };
    Vec2::new((rel.x / r + 1.0) * 0.5, (z / r + 1.0) * 0.5)
}

/// Roots of `a t² + 2 hb t + c = 0` given its discriminant `hb² − a c`, in
/// ascending order; `a` may be zero (one root).
#[inline]
pub(crate) fn roots_from_disc(a: f32, hb: f32, c: f32, disc: f32) -> Option<(f32, f32)> {
    if a == 0.0 {
        return (hb != 0.0).then(|| {
            let t = -c / (2.0 * hb);
            (t, t)
        });
    }
    if !(disc >= 0.0) {
        return None;
    }
    let q = -(hb + hb.signum() * disc.sqrt());
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q / a, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// The nearer of the side's two `roots` (ascending, measured from `o`, the
/// ray's point `shift` along it, relative to the base) whose `t = shift +
/// root` lies in the ray's interval at a height `o.y + root·dir.y` within
/// `[0, h]`, the range widened by [`SEAL`]`·h` at both ends so that a ray
/// through a rim cannot slip between the side and the cap tests.
#[inline]
pub(crate) fn side_t(ray: &Ray, o: Vec3, shift: f32, roots: (f32, f32), h: f32) -> Option<f32> {
    let eps = SEAL * h;
    [roots.0, roots.1].into_iter().find_map(|root| {
        let (t, y) = (shift + root, o.y + root * ray.dir.y);
        (ray.contains(t) && y >= -eps && y <= h + eps).then_some(t)
    })
}

/// Whether a ray from `o` (relative to the base) along `d` stays below
/// the base plane or above the top (`y = h`) over its whole length: such a
/// ray cannot meet the solid, which lies in `0 <= y <= h`. It is rejected
/// before the side is tested, since the side's [`SEAL`] band reaches
/// beyond the caps and would catch a ray spawned from a cap that leaves
/// it grazing its plane (the spawned origin lies inside the band).
#[inline]
pub(crate) fn beyond_caps(o: Vec3, d: Vec3, h: f32) -> bool {
    (o.y < 0.0 && d.y <= 0.0) || (o.y > h && d.y >= 0.0)
}

/// Where a solid stands and how large it is: the centre of its base cap,
/// its (base) radius, and its height along +Y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Upright {
    pub base: Vec3,
    pub radius: f32,
    pub height: f32,
}

impl Upright {
    /// Checks the values, named in errors by `what` (`"cone"`, …) as
    /// `[base, radius, height]` labels.
    pub fn new(what: [&'static str; 3], base: Vec3, radius: f32, height: f32) -> Result<Self, GeometryError> {
        Ok(Self {
            base: check_finite(what[0], base)?,
            radius: check_positive(what[1], radius)?,
            height: check_positive(what[2], height)?,
        })
    }

    /// Bounds: `radius` about the Y axis through `base`, from `base.y` up
    /// to `base.y + height`, widened by the side's [`SEAL`]` · height` at
    /// both ends: the side accepts crossings that far beyond a cap, so a
    /// ray that grazes the rim just outside the exact box can still hit.
    pub fn bounds(&self) -> Aabb {
        let (b, r, eps) = (self.base, self.radius, SEAL * self.height);
        Aabb::new(b - Vec3::new(r, eps, r), b + Vec3::new(r, self.height + eps, r))
    }
}
