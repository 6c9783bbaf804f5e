//! Finite cones with a base cap.

use super::azimuth_u;
use super::upright::{Part, Upright, beyond_caps, cap_t, cap_uv, keep, roots_from_disc, side_t};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A solid cone along +Y: base centre `base`, base `radius`, apex at
/// `base + height·Y`, with a closed base cap and no second nappe above the
/// apex: the quadric `x² + z² = (k·(height − y))²` (`x, y, z` relative to
/// `base`, `k = radius / height`)
/// is also satisfied by the mirror cone above the apex (`y > base.y +
/// height`), whose hits are discarded (the original report's figure 3 shows
/// that second nappe by mistake).
///
/// On the side, the outward normal at a point at distance `s = height − y`
/// below the apex is `(radial + k·Y) / √(1 + k²)` with `k = radius / height`
/// (at the apex itself, `+Y`).
///
/// uv: on the side, `u` = [`crate::azimuth_u`], `v = 1 − (y − base.y) / height`
/// (the image's top row at the apex); on the base cap as
/// [`crate::Cylinder`]'s bottom cap, `((x / r + 1) / 2, (1 − z / r) / 2)`.
/// The side is accepted up to `1e-6 · height` below the base so that a ray
/// through the rim cannot slip between the side and cap tests; a ray that
/// stays below the base plane (one leaving the base cap, grazing it) or
/// above the apex meets nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone(Upright);

impl Cone {
    /// A cone standing on `base` (centre of its base cap).
    ///
    /// # Errors
    /// If the radius or height is not positive or a value is not finite.
    pub fn new(base: Vec3, radius: f32, height: f32) -> Result<Self, GeometryError> {
        Upright::new(["cone base", "cone radius", "cone height"], base, radius, height).map(Self)
    }

    /// Centre of the base cap.
    #[must_use]
    pub fn base(&self) -> Vec3 {
        self.0.base
    }

    /// Base radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.0.radius
    }

    /// Height of the apex above the base.
    #[must_use]
    pub fn height(&self) -> f32 {
        self.0.height
    }
}

impl Cone {
    /// The nearest crossing in the interval: its `t` and the part hit.
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<(f32, Part)> {
        let o = ray.origin - self.0.base;
        let d = ray.dir;
        let (r, h) = (self.0.radius, self.0.height);
        let k = r / h;
        let k2 = k * k;
        // A direction that is not finite meets nothing (its caps' `t`
        // would be `±0` wherever the solid lies).
        if beyond_caps(o, d, h) || !d.is_finite() {
            return None;
        }
        let mut best: Option<(f32, Part)> = None;
        // x² + z² = k² s², s = h − y in [0, h]: the lower nappe only. In
        // coordinates relative to the apex, p = (x, y − h, z), the side is
        // the quadric pᵀ M p = 0 with M = diag(1, −k², 1).
        //
        // From an origin far away (distance D), oᵀMo and oᵀMd cancel, and
        // for a ray close to the slope of a generator (a ≈ 0, a root from
        // c / hb) they left errors of hundreds of ε·D in t, false hits and
        // misses beside the rim. Such a ray is solved from `near`, the
        // line's point nearest the axis' middle, `shift` along it: there
        // the coefficients are of the cone's size, and only the sum `shift
        // + t` rounds at the scale of D, as the sphere's t does. A ray from
        // within twice the cone's size of it (a ray spawned from its
        // surface) is solved from its own origin, exactly as before: the
        // sum's rounding, about ε·(the cone's size), would exceed the
        // spawned origin's offset near a tall cone's apex or a flat one's
        // rim, and the ray would meet the surface it leaves.
        let oa0 = Vec3::new(o.x, o.y - h, o.z);
        let along = (Vec3::new(0.0, 0.5 * h, 0.0) - o).dot(d);
        let shift = along / d.length_squared();
        let far = along.abs() > 2.0 * (r + h) * d.length();
        let shift = if far && shift.is_finite() { shift } else { 0.0 };
        let near = o + shift * d;
        let oa = Vec3::new(near.x, near.y - h, near.z);
        let a = d.x * d.x + d.z * d.z - k2 * d.y * d.y;
        let hb = oa.x * d.x + oa.z * d.z - k2 * oa.y * d.y;
        let c = oa.x * oa.x + oa.z * oa.z - k2 * oa.y * oa.y;
        // The discriminant hb² − a c by the Gram identity
        // (oᵀMo)(dᵀMd) − (oᵀMd)² = det M · wᵀ M⁻¹ w with w = o × d: it is
        // computed from w directly, so it does not cancel. Every line
        // through the apex is a double root (w = 0) and stays one, instead
        // of losing √ε of its accuracy or the hit altogether.
        let w = oa.cross(d);
        let mut disc = k2 * (w.x * w.x + w.z * w.z) - w.y * w.y;
        // When w is no larger than its own rounding error the line passes
        // through the apex as far as f32 can tell: a double root there.
        // The error includes `near`'s rounding, of the scale of the
        // origin's own distance from the apex.
        let noise = 4.0 * f32::EPSILON * oa0.length().max(oa.length()) * d.length();
        if disc < 0.0 && w.length_squared() <= noise * noise {
            disc = 0.0;
        }
        if let Some(t) = roots_from_disc(a, hb, c, disc).and_then(|roots| side_t(ray, near, shift, roots, h))
        {
            keep(&mut best, t, Part::Side);
        }
        if let Some(t) = cap_t(ray, o, 0.0, r) {
            keep(&mut best, t, Part::Bottom);
        }
        best
    }

    /// The unit outward normal of `part` at `rel` (relative to the base).
    #[inline]
    fn part_normal(&self, rel: Vec3, part: Part) -> Vec3 {
        match part {
            Part::Side => {
                let k = self.0.radius / self.0.height;
                match Vec3::new(rel.x, 0.0, rel.z).try_normalize() {
                    Some(radial) => (radial + k * Vec3::Y) / (1.0 + k * k).sqrt(),
                    None => Vec3::Y,
                }
            }
            Part::Bottom | Part::Top => Vec3::NEG_Y,
        }
    }
}

/// `rel` (relative to the base) moved onto the side along the side's
/// normal, within `[0, h]` in height. `o + t·d` from an origin far away
/// (distance D) is off the surface by up to a few ε·D: from a telephoto
/// camera a hundred times the cone's size away, more than a spawned ray's
/// offset, and shadow rays met the side they left (black speckles). The
/// sphere and the cylinder project their points back the same way.
#[inline]
fn onto_side(rel: Vec3, r: f32, h: f32) -> Vec3 {
    let radial = Vec3::new(rel.x, 0.0, rel.z);
    let rho = radial.length();
    // In the half-plane of the point's azimuth, the side is the segment
    // from (ρ, s) = (0, 0) at the apex to (r, h) at the rim, s = h − y: the
    // point's projection onto that line is `λ·(r, h)`.
    let lambda = ((rho * r + (h - rel.y) * h) / (r * r + h * h)).clamp(0.0, 1.0);
    let to_rim = if rho > 0.0 { radial * (lambda * r / rho) } else { Vec3::ZERO };
    Vec3::new(to_rim.x, h - lambda * h, to_rim.z)
}

impl Intersect for Cone {
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
        let n = self.part_normal(rel, part);
        let (rel, uv) = match part {
            Part::Side => {
                let rel = onto_side(rel, r, h);
                let radial = Vec3::new(rel.x, 0.0, rel.z);
                (rel, Vec2::new(azimuth_u(radial), 1.0 - rel.y / h))
            }
            Part::Bottom | Part::Top => (Vec3::new(rel.x, 0.0, rel.z), cap_uv(rel, r, false)),
        };
        Some(Hit::new(t, self.0.base + rel, n, uv, d))
    }

    /// No uv (`atan2` on the side) and no point: the normal decides the side.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let (t, part) = self.solve(ray)?;
        let rel = (ray.origin - self.0.base) + t * ray.dir;
        Some((t, Hit::faces(ray.dir, self.part_normal(rel, part))))
    }

    fn bounds(&self) -> Aabb {
        self.0.bounds()
    }

    /// The base cap's disk and the apex, each moved out by the side's
    /// `SEAL` band (as [`Intersect::bounds`]; the side's radius
    /// there is `radius · (1 + SEAL)`): the solid is their convex hull.
    fn bounds_in(&self, to_world: &crate::Transform) -> Aabb {
        let Upright { base, radius, height } = self.0;
        let eps = super::SEAL * height;
        let low = to_world.disk_aabb(base - eps * Vec3::Y, Vec3::Y, radius * (1.0 + super::SEAL));
        let apex = to_world.ball_aabb(base + (height + eps) * Vec3::Y, 0.0);
        let exact = if low.is_empty() || apex.is_empty() { Aabb::EMPTY } else { low.union(apex) };
        to_world.tightest(exact, &self.bounds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close, close3};

    /// Base radius 1 at y = 0, apex at (0, 2, 0): k = 1/2.
    fn cone() -> Cone {
        Cone::new(Vec3::ZERO, 1.0, 2.0).unwrap()
    }

    fn side_normal(x: f32, z: f32) -> Vec3 {
        (Vec3::new(x, 0.0, z).normalize() + 0.5 * Vec3::Y) / 1.25f32.sqrt()
    }

    /// As the cylinder's: a crossing the side accepts just below the base
    /// lies inside the bounds; a ray that stays below the base misses.
    #[test]
    fn bounds_hold_the_sealed_rim() {
        let ray = Ray::new(Vec3::new(-5.0, -1e-6, 0.0), Vec3::new(1.0, 1e-9, 0.0));
        assert!(cone().intersect_t(&ray).is_some());
        assert!(cone().bounds().intersect_ray(&ray).is_some());
        for d in [Vec3::X, Vec3::new(1.0, -1e-9, 0.0)] {
            assert!(cone().intersect_t(&Ray::new(Vec3::new(-5.0, -1e-6, 0.0), d)).is_none(), "{d}");
        }
    }

    #[test]
    fn side_from_outside() {
        // At y = 1 the radius is 1/2.
        let h = cone().intersect(&Ray::new(Vec3::new(5.0, 1.0, 0.0), Vec3::NEG_X)).unwrap();
        check_hit(&h, 4.5, Vec3::new(0.5, 1.0, 0.0), side_normal(1.0, 0.0), Vec2::new(0.75, 0.5), true);
        let h = cone().intersect(&Ray::new(Vec3::new(0.0, 0.5, -4.0), Vec3::Z)).unwrap();
        check_hit(&h, 3.25, Vec3::new(0.0, 0.5, -0.75), side_normal(0.0, -1.0), Vec2::new(1.0, 0.75), true);
    }

    #[test]
    fn base_cap_from_below() {
        let h = cone().intersect(&Ray::new(Vec3::new(0.3, -5.0, 0.0), Vec3::Y)).unwrap();
        check_hit(&h, 5.0, Vec3::new(0.3, 0.0, 0.0), Vec3::NEG_Y, Vec2::new(0.65, 0.5), true);
    }

    #[test]
    fn from_inside() {
        let h = cone().intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::X)).unwrap();
        check_hit(&h, 0.75, Vec3::new(0.75, 0.5, 0.0), side_normal(1.0, 0.0), Vec2::new(0.75, 0.75), false);
        let h = cone().intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 0.5, Vec3::ZERO, Vec3::NEG_Y, Vec2::new(0.5, 0.5), false);
        let h = cone().intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::Y)).unwrap();
        check_hit(&h, 1.5, Vec3::new(0.0, 2.0, 0.0), Vec3::Y, Vec2::new(0.5, 0.0), false);
    }

    #[test]
    fn along_the_axis_hits_the_apex() {
        let h = cone().intersect(&Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 3.0, Vec3::new(0.0, 2.0, 0.0), Vec3::Y, Vec2::new(0.5, 0.0), true);
        // Another base position and height, where rounding differs.
        let c = Cone::new(Vec3::new(0.3, -0.7, 1.1), 0.7, 1.3).unwrap();
        let h = c.intersect(&Ray::new(Vec3::new(0.3, 3.0, 1.1), Vec3::NEG_Y)).unwrap();
        close(h.t, 3.0 - 0.6, 1e-5);
        assert!(h.front_face);
    }

    #[test]
    fn rays_through_the_apex_from_any_direction() {
        // Every line through the apex is a double root of the quadric; none
        // may be lost to rounding.
        let c = cone();
        let apex = Vec3::new(0.0, 2.0, 0.0);
        for i in 0..64 {
            let a = i as f32 * 0.1;
            // Directions inside the cone's half-angle from above.
            let d = Vec3::new(0.3 * a.cos(), -1.0, 0.3 * a.sin());
            let o = apex - 3.0 * d;
            let h = c.intersect(&Ray::new(o, d)).expect("aimed at the apex");
            close(h.t, 3.0, 1e-4);
            close3(h.point, apex, 1e-4);
            assert!(h.front_face, "{h:?}");
        }
    }

    #[test]
    fn no_second_nappe() {
        let c = cone();
        // Horizontal above the apex: the double cone would be hit at radius 1/2.
        assert!(c.intersect(&Ray::new(Vec3::new(5.0, 3.0, 0.0), Vec3::NEG_X)).is_none());
        // Down, off-axis: skips the upper nappe at y = 2.2, hits the lower at 1.8.
        let h = c.intersect(&Ray::new(Vec3::new(0.1, 5.0, 0.0), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 3.2, Vec3::new(0.1, 1.8, 0.0), side_normal(1.0, 0.0), Vec2::new(0.75, 0.1), true);
    }

    #[test]
    fn parallel_to_a_generator() {
        // Direction (1/2, −1, 0) makes the quadratic linear (a = 0).
        let h = cone().intersect(&Ray::new(Vec3::new(-1.0, 2.0, 0.0), Vec3::new(0.5, -1.0, 0.0))).unwrap();
        check_hit(&h, 1.0, Vec3::new(-0.5, 1.0, 0.0), side_normal(-1.0, 0.0), Vec2::new(0.25, 0.5), true);
    }

    #[test]
    fn grazing_the_side() {
        let h = cone().intersect(&Ray::new(Vec3::new(0.5, 1.0, -5.0), Vec3::Z)).unwrap();
        close(h.t, 5.0, 1e-5);
        close3(h.point, Vec3::new(0.5, 1.0, 0.0), 1e-5);
        assert!(cone().intersect(&Ray::new(Vec3::new(0.500_01, 1.0, -5.0), Vec3::Z)).is_none());
    }

    #[test]
    fn distant_rays_along_a_generator_hit_where_aimed() {
        // Radius = height: a ray parallel to the far side's generator (the
        // quadratic's a = 0) meets the near side head on. From afar the
        // coefficients taken at the origin cancelled: hundreds of ε·D off
        // (0.026 at D = 1000), and at D ≥ 1000 the ray went through the
        // side to the base cap, seen from inside.
        let c = Cone::new(Vec3::ZERO, 1.0, 1.0).unwrap();
        for dist in [10.0f32, 100.0, 1000.0, 10_000.0] {
            for i in 0..96 {
                let (s, co) = (i as f32 * 0.37).sin_cos();
                let radial = Vec3::new(s, 0.0, co);
                let y = 0.1 + 0.08 * (i % 11) as f32;
                let p = radial * (1.0 - y) + Vec3::Y * y;
                let n = (radial + Vec3::Y) / 2f32.sqrt();
                // Along the opposite generator, tilted by up to ±0.05.
                let jitter =
                    0.05 * Vec3::new(((i * 5) % 7) as f32 / 3.0 - 1.0, ((i * 3) % 5) as f32 / 2.0 - 1.0, 0.0);
                let d = (-radial - Vec3::Y + jitter).normalize();
                let ray = Ray::new(p - dist * d, d);
                let h = c.intersect(&ray).unwrap_or_else(|| panic!("D {dist}: missed {p} along {d}"));
                let off = (h.point - p).length() / (f32::EPSILON * dist);
                assert!(off <= 4.0, "D {dist}: hit {} for {p}, {off} ε·D off", h.point);
                // The normal turns with the point's azimuth: its error is the
                // point's over the radius there.
                let turn = 16.0 * f32::EPSILON * dist / (1.0 - y) + 1e-5;
                assert!(h.front_face && (h.geo_normal - n).length() < turn, "{h:?}");
                close(h.t, dist, 4.0 * f32::EPSILON * dist);
            }
        }
        // Beside the rim by 0.4 % of the cone's size (reaching the base's
        // plane at radius 1.004): a miss, not a hit on the side.
        let d = Vec3::new(0.0, -1.0, -1.0);
        assert_eq!(c.intersect(&Ray::new(Vec3::new(-0.72, 1000.7, 1000.0), d)), None);
        // Head on, from 1000 away, direction not unit: the side at
        // (0, 0.95, 0.05), not the base cap from inside.
        let h = c.intersect(&Ray::new(Vec3::new(0.0, 1000.9, 1000.0), 1000.0 * d)).unwrap();
        close3(h.point, Vec3::new(0.0, 0.95, 0.05), 1e-3);
        assert!(h.front_face);
    }

    #[test]
    fn hits_from_afar_lie_on_the_side() {
        // A telephoto camera 10³–10⁵ sizes away: `o + t·d` lies up to a few
        // ε·D from the true hit (along the ray), and was off the surface by
        // more than the offset a shadow ray leaves with (3.6e-6 at D = 1000
        // here, against a bound of 9.5e-7), which then met the side again
        // (black speckles). The point is moved back onto the surface, to a
        // few ε of the cone's size.
        let c = Cone::new(Vec3::new(0.3, -0.2, 0.1), 0.6, 1.4).unwrap();
        let (r, h) = (0.6f32, 1.4f32);
        let off_surface = |p: Vec3| {
            let rel = p - Vec3::new(0.3, -0.2, 0.1);
            ((rel.x.hypot(rel.z) * h - (h - rel.y) * r) / r.hypot(h)).abs()
        };
        let mut hits = 0;
        for dist in [1e3f32, 1e4, 1e5] {
            for i in 0..200 {
                let (s, co) = (i as f32 * 0.71).sin_cos();
                let y = 0.05 + 0.9 * ((i * 7) % 13) as f32 / 12.0;
                let aim = Vec3::new(0.3, -0.2, 0.1) + Vec3::new(s * r * (1.0 - y), y * h, co * r * (1.0 - y));
                let from = Vec3::new(s + 0.3 * co, 0.6 + 0.4 * ((i % 5) as f32 - 2.0) / 2.0, co - 0.3 * s);
                let ray = Ray::new(aim + dist * from.normalize(), -from.normalize());
                let Some(hit) = c.intersect(&ray) else { continue };
                hits += 1;
                assert!(
                    off_surface(hit.point) <= 4.0 * f32::EPSILON * (r + h),
                    "D {dist}: {} is {} off the side",
                    hit.point,
                    off_surface(hit.point)
                );
                assert!(hit.point.y >= -0.2 && hit.point.y <= -0.2 + h, "{}", hit.point);
            }
        }
        assert!(hits > 400, "{hits} hits");
    }

    #[test]
    fn cap_edge() {
        let c = cone();
        // Horizontal in the base plane: meets the rim.
        let h = c.intersect(&Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::NEG_X)).unwrap();
        close(h.t, 4.0, 1e-6);
        close3(h.point, Vec3::X, 1e-6);
        // Diagonally onto the rim from below and outside.
        let h = c.intersect(&Ray::new(Vec3::new(2.0, -1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0))).unwrap();
        close(h.t, 1.0, 1e-6);
        close3(h.point, Vec3::X, 1e-6);
        assert!(h.geo_normal == Vec3::NEG_Y || (h.geo_normal - side_normal(1.0, 0.0)).length() < 1e-6);
        // Just below the base, or just outside the rim: miss.
        // (The side is sealed to the cap over 1e-6 of the height: 2e-6 here.)
        assert!(c.intersect(&Ray::new(Vec3::new(5.0, -4.0e-6, 0.0), Vec3::NEG_X)).is_none());
        assert!(c.intersect(&Ray::new(Vec3::new(1.000_01, -5.0, 0.0), Vec3::Y)).is_none());
    }

    #[test]
    fn construction_and_bounds() {
        assert!(Cone::new(Vec3::ZERO, 0.0, 1.0).is_err());
        assert!(Cone::new(Vec3::ZERO, 1.0, 0.0).is_err());
        assert!(Cone::new(Vec3::INFINITY, 1.0, 1.0).is_err());
        let e = 2e-6; // SEAL · height
        assert_eq!(cone().bounds(), Aabb::new(Vec3::new(-1.0, -e, -1.0), Vec3::new(1.0, 2.0 + e, 1.0)));
    }
}
