//! Finite cones with a base cap.

use super::cylinder::{Part, azimuth_u, cap_t, cap_uv, keep};
use super::{check_finite, check_positive, solve_quadratic_half};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A solid cone along +Y: base centre `base`, base `radius`, apex at
/// `base + height·Y`, with a closed base cap and no second nappe above the
/// apex (the report's figure 3 bug).
///
/// On the side, the outward normal at a point at distance `s = height − y`
/// below the apex is `(radial + k·Y) / √(1 + k²)` with `k = radius / height`
/// (at the apex itself, `+Y`).
///
/// uv: on the side, `u = 0.5 + atan2(z, x) / 2π`, `v = (y − base.y) / height`;
/// on the cap as [`crate::Cylinder`]'s caps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    base: Vec3,
    radius: f32,
    height: f32,
}

impl Cone {
    /// A cone standing on `base` (centre of its base cap).
    ///
    /// # Errors
    /// If the radius or height is not positive or a value is not finite.
    pub fn new(base: Vec3, radius: f32, height: f32) -> Result<Self, GeometryError> {
        Ok(Self {
            base: check_finite("cone base", base)?,
            radius: check_positive("cone radius", radius)?,
            height: check_positive("cone height", height)?,
        })
    }

    /// Centre of the base cap.
    #[must_use]
    pub fn base(&self) -> Vec3 {
        self.base
    }

    /// Base radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Height of the apex above the base.
    #[must_use]
    pub fn height(&self) -> f32 {
        self.height
    }
}

impl Intersect for Cone {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let o = ray.origin - self.base;
        let d = ray.dir;
        let (r, h) = (self.radius, self.height);
        let k = r / h;
        let k2 = k * k;
        let s0 = h - o.y;
        let mut best: Option<(f32, Part)> = None;
        // x² + z² = k² s², s = h − y in [0, h]: the lower nappe only.
        let a = d.x * d.x + d.z * d.z - k2 * d.y * d.y;
        let hb = o.x * d.x + o.z * d.z + k2 * s0 * d.y;
        let c = o.x * o.x + o.z * o.z - k2 * s0 * s0;
        if let Some(roots) = solve_quadratic_half(a, hb, c) {
            let eps = 1e-6 * h;
            for t in [roots.0, roots.1] {
                let y = o.y + t * d.y;
                if ray.contains(t) && y >= -eps && y <= h + eps {
                    keep(&mut best, t, Part::Side);
                    break;
                }
            }
        }
        if let Some(t) = cap_t(ray, o, 0.0, r) {
            keep(&mut best, t, Part::Bottom);
        }
        let (t, part) = best?;
        let rel = o + t * d;
        let (rel, n, uv) = match part {
            Part::Side => {
                let y = rel.y.clamp(0.0, h);
                let radial = Vec3::new(rel.x, 0.0, rel.z);
                let n = match radial.try_normalize() {
                    Some(radial) => (radial + k * Vec3::Y) / (1.0 + k2).sqrt(),
                    None => Vec3::Y,
                };
                (Vec3::new(rel.x, y, rel.z), n, Vec2::new(azimuth_u(radial), y / h))
            }
            Part::Bottom | Part::Top => (Vec3::new(rel.x, 0.0, rel.z), Vec3::NEG_Y, cap_uv(rel, r)),
        };
        Some(Hit::new(t, self.base + rel, n, uv, d))
    }

    fn bounds(&self) -> Aabb {
        let r = self.radius;
        Aabb::new(self.base - Vec3::new(r, 0.0, r), self.base + Vec3::new(r, self.height, r))
    }
}
