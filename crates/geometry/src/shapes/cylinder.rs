//! Finite cylinders with both caps.

use super::{check_finite, check_positive};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A solid cylinder along +Y: base centre `base`, `radius`, `height`; both
/// caps closed (the report's cylinder "with a visible top").
///
/// uv: on the side, `u = 0.5 + atan2(z, x) / 2π` about the axis and
/// `v = (y − base.y) / height`; on a cap, `((x / r + 1) / 2, (z / r + 1) / 2)`
/// with `x, z` relative to the axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    base: Vec3,
    radius: f32,
    height: f32,
}

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

/// uv on a cap of radius `r`, from the point relative to the axis.
#[inline]
pub(crate) fn cap_uv(rel: Vec3, r: f32) -> Vec2 {
    Vec2::new((rel.x / r + 1.0) * 0.5, (rel.z / r + 1.0) * 0.5)
}

/// `u` about the Y axis, matching the sphere's convention.
#[inline]
pub(crate) fn azimuth_u(rel: Vec3) -> f32 {
    0.5 + rel.z.atan2(rel.x) / (2.0 * PI)
}

impl Cylinder {
    /// A cylinder standing on `base` (centre of the bottom cap).
    ///
    /// # Errors
    /// If the radius or height is not positive or a value is not finite.
    pub fn new(base: Vec3, radius: f32, height: f32) -> Result<Self, GeometryError> {
        Ok(Self {
            base: check_finite("cylinder base", base)?,
            radius: check_positive("cylinder radius", radius)?,
            height: check_positive("cylinder height", height)?,
        })
    }

    /// Centre of the bottom cap.
    #[must_use]
    pub fn base(&self) -> Vec3 {
        self.base
    }

    /// Radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Height.
    #[must_use]
    pub fn height(&self) -> f32 {
        self.height
    }
}

impl Intersect for Cylinder {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let o = ray.origin - self.base;
        let d = ray.dir;
        let (r, h) = (self.radius, self.height);
        let mut best: Option<(f32, Part)> = None;
        // Side: x² + z² = r², with 0 <= y <= h.
        let a = d.x * d.x + d.z * d.z;
        if a > 0.0 {
            let hb = o.x * d.x + o.z * d.z;
            // Discriminant in the cancellation-free form (see Sphere).
            let (lx, lz) = (o.x - hb / a * d.x, o.z - hb / a * d.z);
            let disc = a * (r * r - (lx * lx + lz * lz));
            if disc >= 0.0 {
                let c = o.x * o.x + o.z * o.z - r * r;
                let q = -(hb + hb.signum() * disc.sqrt());
                let roots = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
                let eps = 1e-6 * h;
                for t in [roots.0.min(roots.1), roots.0.max(roots.1)] {
                    let y = o.y + t * d.y;
                    if ray.contains(t) && y >= -eps && y <= h + eps {
                        keep(&mut best, t, Part::Side);
                        break;
                    }
                }
            }
        }
        if let Some(t) = cap_t(ray, o, 0.0, r) {
            keep(&mut best, t, Part::Bottom);
        }
        if let Some(t) = cap_t(ray, o, h, r) {
            keep(&mut best, t, Part::Top);
        }
        let (t, part) = best?;
        let rel = o + t * d;
        let (rel, n, uv) = match part {
            Part::Side => {
                let radial = Vec3::new(rel.x, 0.0, rel.z).normalize_or(Vec3::X);
                let p = Vec3::new(radial.x * r, rel.y.clamp(0.0, h), radial.z * r);
                (p, radial, Vec2::new(azimuth_u(radial), p.y / h))
            }
            Part::Bottom => (Vec3::new(rel.x, 0.0, rel.z), Vec3::NEG_Y, cap_uv(rel, r)),
            Part::Top => (Vec3::new(rel.x, h, rel.z), Vec3::Y, cap_uv(rel, r)),
        };
        Some(Hit::new(t, self.base + rel, n, uv, d))
    }

    fn bounds(&self) -> Aabb {
        let r = self.radius;
        Aabb::new(self.base - Vec3::new(r, 0.0, r), self.base + Vec3::new(r, self.height, r))
    }
}
