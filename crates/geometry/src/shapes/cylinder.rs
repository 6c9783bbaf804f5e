//! Finite cylinders with both caps.

use super::azimuth_u;
use super::upright::{Part, Upright, beyond_caps, cap_t, cap_uv, keep, roots_from_disc, side_t};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A solid cylinder along +Y: base centre `base`, `radius`, `height`; both
/// caps closed (the report's cylinder "with a visible top"): the side is
/// `(x − base.x)² + (z − base.z)² = radius²` for `base.y ≤ y ≤ base.y +
/// height`, the caps the disks of that radius at both ends.
///
/// uv: on the side, `u` = [`crate::azimuth_u`] about the axis (0.5 at +Z,
/// growing toward +X, seam at −Z, as on [`crate::Sphere`]) and
/// `v = 1 − (y − base.y) / height` (the image's top row at the top); on the
/// top cap `((x / r + 1) / 2, (z / r + 1) / 2)` (image top toward −Z), on
/// the bottom cap `((x / r + 1) / 2, (1 − z / r) / 2)` (image top toward
/// +Z), with `x, z` relative to the axis. All of `u`, `v` lie in `[0, 1]`,
/// and an image seen from outside reads as in an image viewer.
///
/// The side is accepted up to `1e-6 · height` beyond either cap so that a
/// ray through the rim cannot slip between the side and cap tests; a ray
/// that stays beyond a cap's plane (one leaving the cap, grazing it) meets
/// nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder(Upright);

impl Cylinder {
    /// A cylinder standing on `base` (centre of the bottom cap).
    ///
    /// # Errors
    /// If the radius or height is not positive or a value is not finite.
    pub fn new(base: Vec3, radius: f32, height: f32) -> Result<Self, GeometryError> {
        Upright::new(["cylinder base", "cylinder radius", "cylinder height"], base, radius, height).map(Self)
    }

    /// Centre of the bottom cap.
    #[must_use]
    pub fn base(&self) -> Vec3 {
        self.0.base
    }

    /// Radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.0.radius
    }

    /// Height.
    #[must_use]
    pub fn height(&self) -> f32 {
        self.0.height
    }
}

impl Cylinder {
    /// The nearest crossing in the interval: its `t` and the part hit.
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<(f32, Part)> {
        let o = ray.origin - self.0.base;
        let d = ray.dir;
        let (r, h) = (self.0.radius, self.0.height);
        // A direction that is not finite meets nothing (its caps' `t`
        // would be `±0` wherever the solid lies).
        if beyond_caps(o, d, h) || !d.is_finite() {
            return None;
        }
        let mut best: Option<(f32, Part)> = None;
        // Side: x² + z² = r², with 0 <= y <= h.
        let a = d.x * d.x + d.z * d.z;
        if a > 0.0 {
            let hb = o.x * d.x + o.z * d.z;
            // Discriminant in the cancellation-free form (see Sphere).
            let (lx, lz) = (o.x - hb / a * d.x, o.z - hb / a * d.z);
            let disc = a * (r * r - (lx * lx + lz * lz));
            if let Some(t) = roots_from_disc(a, hb, o.x * o.x + o.z * o.z - r * r, disc)
                .and_then(|roots| side_t(ray, o, 0.0, roots, h))
            {
                keep(&mut best, t, Part::Side);
            }
        }
        if let Some(t) = cap_t(ray, o, 0.0, r) {
            keep(&mut best, t, Part::Bottom);
        }
        if let Some(t) = cap_t(ray, o, h, r) {
            keep(&mut best, t, Part::Top);
        }
        best
    }
}

/// The unit outward normal of `part` at `rel` (relative to the base).
#[inline]
fn part_normal(rel: Vec3, part: Part) -> Vec3 {
    match part {
        Part::Side => Vec3::new(rel.x, 0.0, rel.z).normalize_or(Vec3::X),
        Part::Bottom => Vec3::NEG_Y,
        Part::Top => Vec3::Y,
    }
}

impl Intersect for Cylinder {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.solve(ray).map(|(t, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let o = ray.origin - self.0.base;
        let d = ray.dir;
        let (r, h) = (self.0.radius, self.0.height);
        let (t, part) = self.solve(ray)?;
        let rel = o + t * d;
        let n = part_normal(rel, part);
        let (rel, uv) = match part {
            Part::Side => {
                let p = Vec3::new(n.x * r, rel.y.clamp(0.0, h), n.z * r);
                (p, Vec2::new(azimuth_u(n), 1.0 - p.y / h))
            }
            Part::Bottom => (Vec3::new(rel.x, 0.0, rel.z), cap_uv(rel, r, false)),
            Part::Top => (Vec3::new(rel.x, h, rel.z), cap_uv(rel, r, true)),
        };
        Some(Hit::new(t, self.0.base + rel, n, uv, d))
    }

    /// No uv (`atan2` on the side) and no point: the normal decides the side.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let (t, part) = self.solve(ray)?;
        let rel = (ray.origin - self.0.base) + t * ray.dir;
        Some((t, Hit::faces(ray.dir, part_normal(rel, part))))
    }

    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }

    /// The two caps' disks, each moved out by the side's `SEAL`
    /// band (as [`Intersect::bounds`]): the solid is their convex hull.
    fn bounds_in(&self, to_world: &crate::Transform) -> Aabb {
        let Upright { base, radius, height } = self.0;
        let eps = super::SEAL * height;
        let cap = |y: f32| to_world.disk_aabb(base + y * Vec3::Y, Vec3::Y, radius);
        let (low, high) = (cap(-eps), cap(height + eps));
        let exact = if low.is_empty() || high.is_empty() { Aabb::EMPTY } else { low.union(high) };
        to_world.tightest(exact, &self.bounds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close, close3};

    /// Radius 1, height 2, standing on (0, 0, 0) — shifted to test `base`.
    fn cyl() -> Cylinder {
        Cylinder::new(Vec3::new(0.0, -1.0, 0.0), 1.0, 2.0).unwrap()
    }

    /// The side accepts crossings up to `SEAL · height` beyond a cap by a
    /// ray heading toward the cap's plane; the bounds hold them, so that a
    /// hierarchy's box test cannot cull a hit the shape reports (a BVH leaf
    /// of one object found this). A ray that stays beyond the plane misses.
    #[test]
    fn bounds_hold_the_sealed_rim() {
        let c = cyl();
        for (y, toward) in [(1.0 + 1e-6, -1.0), (-1.0 - 1e-6, 1.0)] {
            let ray = Ray::new(Vec3::new(-5.0, y, 0.0), Vec3::new(1.0, toward * 1e-9, 0.0));
            assert!(c.intersect_t(&ray).is_some(), "side accepts y = {y}");
            assert!(c.bounds().intersect_ray(&ray).is_some(), "bounds hold y = {y}");
            for dy in [0.0, -toward * 1e-9] {
                let away = Ray::new(Vec3::new(-5.0, y, 0.0), Vec3::new(1.0, dy, 0.0));
                assert!(c.intersect_t(&away).is_none(), "y = {y}, dy = {dy}");
            }
        }
    }

    #[test]
    fn side_from_outside() {
        let h = cyl().intersect(&Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::NEG_X)).unwrap();
        check_hit(&h, 4.0, Vec3::new(1.0, 0.0, 0.0), Vec3::X, Vec2::new(0.75, 0.5), true);
        let h = cyl().intersect(&Ray::new(Vec3::new(0.0, 0.5, 3.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.0, 0.5, 1.0), Vec3::Z, Vec2::new(0.5, 0.25), true);
    }

    #[test]
    fn caps_from_outside() {
        let h = cyl().intersect(&Ray::new(Vec3::new(0.5, 5.0, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 4.0, Vec3::new(0.5, 1.0, 0.0), Vec3::Y, Vec2::new(0.75, 0.5), true);
        let h = cyl().intersect(&Ray::new(Vec3::new(0.0, -3.0, -0.5), Vec3::Y)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.0, -1.0, -0.5), Vec3::NEG_Y, Vec2::new(0.5, 0.75), true);
    }

    #[test]
    fn from_inside() {
        let h = cyl().intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap();
        check_hit(&h, 1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::Z, Vec2::new(0.5, 0.5), false);
        let h = cyl().intersect(&Ray::new(Vec3::ZERO, Vec3::Y)).unwrap();
        check_hit(&h, 1.0, Vec3::new(0.0, 1.0, 0.0), Vec3::Y, Vec2::new(0.5, 0.5), false);
        // Diagonal from inside out through the side, below the top.
        let h = cyl().intersect(&Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.0))).unwrap();
        check_hit(&h, 1.0, Vec3::new(1.0, 0.5, 0.0), Vec3::X, Vec2::new(0.75, 0.25), false);
    }

    #[test]
    fn enters_through_the_top_leaves_through_the_side() {
        // From (0, 2, 0) along (1, −1, 0): the infinite cylinder's first root
        // lies above the top, so the cap at t = 1 is the answer.
        let h = cyl().intersect(&Ray::new(Vec3::new(-1.5, 2.5, 0.0), Vec3::new(1.0, -1.0, 0.0))).unwrap();
        check_hit(&h, 1.5, Vec3::new(0.0, 1.0, 0.0), Vec3::Y, Vec2::new(0.5, 0.5), true);
        let inside = Ray::with_interval(Vec3::new(-1.5, 2.5, 0.0), Vec3::new(1.0, -1.0, 0.0), 1.6, f32::MAX);
        let h = cyl().intersect(&inside).unwrap();
        check_hit(&h, 2.5, Vec3::new(1.0, 0.0, 0.0), Vec3::X, Vec2::new(0.75, 0.5), false);
    }

    #[test]
    fn parallel_to_the_axis() {
        let c = cyl();
        assert!(c.intersect(&Ray::new(Vec3::new(2.0, 5.0, 0.0), Vec3::NEG_Y)).is_none());
        assert!(c.intersect(&Ray::new(Vec3::new(1.000_001, 5.0, 0.0), Vec3::NEG_Y)).is_none());
        // Exactly on the rim: touches the top cap's edge.
        let h = c.intersect(&Ray::new(Vec3::new(0.0, 5.0, 1.0), Vec3::NEG_Y)).unwrap();
        close(h.t, 4.0, 1e-6);
        close3(h.point, Vec3::new(0.0, 1.0, 1.0), 1e-6);
    }

    #[test]
    fn grazing_the_side() {
        let h = cyl().intersect(&Ray::new(Vec3::new(1.0, 0.0, -5.0), Vec3::Z)).unwrap();
        check_hit(&h, 5.0, Vec3::new(1.0, 0.0, 0.0), Vec3::X, Vec2::new(0.75, 0.5), false);
        assert!(cyl().intersect(&Ray::new(Vec3::new(1.000_001, 0.0, -5.0), Vec3::Z)).is_none());
    }

    #[test]
    fn cap_edges() {
        let c = cyl();
        // Horizontal ray in the plane of the top cap: hits the rim.
        let h = c.intersect(&Ray::new(Vec3::new(5.0, 1.0, 0.0), Vec3::NEG_X)).unwrap();
        close(h.t, 4.0, 1e-6);
        close3(h.point, Vec3::new(1.0, 1.0, 0.0), 1e-6);
        close3(h.geo_normal, Vec3::X, 1e-6);
        // Just above the top, or just below the bottom: miss.
        // (The side is sealed to the caps over 1e-6 of the height: 2e-6 here.)
        assert!(c.intersect(&Ray::new(Vec3::new(5.0, 1.000_004, 0.0), Vec3::NEG_X)).is_none());
        assert!(c.intersect(&Ray::new(Vec3::new(5.0, -1.000_004, 0.0), Vec3::NEG_X)).is_none());
        // Diagonally onto the top rim: cap and side meet at the same t.
        let h = c.intersect(&Ray::new(Vec3::new(2.0, 2.0, 0.0), Vec3::new(-1.0, -1.0, 0.0))).unwrap();
        close(h.t, 1.0, 1e-6);
        close3(h.point, Vec3::new(1.0, 1.0, 0.0), 1e-6);
        assert!(h.geo_normal == Vec3::X || h.geo_normal == Vec3::Y, "{h:?}");
        // Diagonally onto the bottom rim from below.
        let h = c.intersect(&Ray::new(Vec3::new(0.0, -2.0, -2.0), Vec3::new(0.0, 1.0, 1.0))).unwrap();
        close(h.t, 1.0, 1e-6);
        close3(h.point, Vec3::new(0.0, -1.0, -1.0), 1e-6);
        // Skimming past the rim by a hair, on the outside of the corner, misses.
        let miss = Ray::new(Vec3::new(2.0, 0.000_01, 0.0), Vec3::new(-1.0, 1.0, 0.0));
        assert!(c.intersect(&miss).is_none());
        let hit = Ray::new(Vec3::new(2.0, -0.000_01, 0.0), Vec3::new(-1.0, 1.0, 0.0));
        close3(c.intersect(&hit).unwrap().geo_normal, Vec3::X, 1e-6);
        let miss = Ray::new(Vec3::new(2.0, -0.000_01, 0.0), Vec3::new(-1.0, -1.0, 0.0));
        assert!(c.intersect(&miss).is_none());
    }

    #[test]
    fn construction_and_bounds() {
        assert!(Cylinder::new(Vec3::ZERO, 0.0, 1.0).is_err());
        assert!(Cylinder::new(Vec3::ZERO, 1.0, -1.0).is_err());
        assert!(Cylinder::new(Vec3::NAN, 1.0, 1.0).is_err());
        // y widened by SEAL · height = 2e-6 at both ends.
        let e = 2e-6;
        assert_eq!(
            cyl().bounds(),
            Aabb::new(Vec3::new(-1.0, -1.0 - e, -1.0), Vec3::new(1.0, -1.0 + (2.0 + e), 1.0))
        );
    }
}
