//! Spheres.

use super::{check_finite, check_positive};
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A sphere.
///
/// uv: with `d` the unit outward normal, `u = 0.5 + atan2(d.x, d.z) / 2π`,
/// `v = 0.5 − asin(d.y) / π` ([`sphere_uv`]): `v = 0` at the north pole
/// (+Y), `v = 1` at the south pole; `u = 0.5` faces +Z (the default
/// camera), and `u` grows eastward, toward +X seen from +Z, so that an
/// image seen from outside reads as in an image viewer (an Earth map
/// makes a globe, not its mirror image). The seam `u = 0 | 1` faces −Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    center: Vec3,
    radius: f32,
}

/// The azimuth of `d` about the Y axis as `u` in `[0, 1]`:
/// `0.5 + atan2(d.x, d.z) / 2π`. It is 0.5 at +Z, 0.75 at +X, 0.25 at −X,
/// and 0 or 1 at the seam, −Z; seen from outside (from +Y's side, looking
/// at the axis) it grows to the right.
#[inline]
#[must_use]
pub fn azimuth_u(d: Vec3) -> f32 {
    0.5 + d.x.atan2(d.z) / (2.0 * PI)
}

/// The spherical mapping of a unit direction `d` to `(u, v)`: `u` is
/// [`azimuth_u`], `v = 0.5 − asin(d.y) / π` (the report's equation 8).
#[inline]
#[must_use]
pub fn sphere_uv(d: Vec3) -> Vec2 {
    let u = azimuth_u(d);
    let v = 0.5 - d.y.clamp(-1.0, 1.0).asin() / PI;
    Vec2::new(u, v)
}

impl Sphere {
    /// A sphere of `radius` about `center`.
    ///
    /// # Errors
    /// If `radius` is not positive or a value is not finite.
    pub fn new(center: Vec3, radius: f32) -> Result<Self, GeometryError> {
        Ok(Self {
            center: check_finite("sphere centre", center)?,
            radius: check_positive("sphere radius", radius)?,
        })
    }

    /// Centre.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Radius.
    #[must_use]
    pub fn radius(&self) -> f32 {
        self.radius
    }
}

impl Sphere {
    /// The `t` of the nearest crossing in the ray's interval (shared by
    /// [`Intersect::intersect`] and [`Intersect::intersect_t`], so both
    /// give the same `t` bit for bit).
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<f32> {
        let f = ray.origin - self.center;
        // The squares the roots need anyway (the same expressions: computed
        // once), so the check costs four comparisons.
        let (ff, rr, a) = (f.length_squared(), self.radius * self.radius, ray.dir.length_squared());
        let (low, high) = (UNSCALED.0 * UNSCALED.0, UNSCALED.1 * UNSCALED.1);
        if !(ff.max(rr) >= low && ff.max(rr) <= high && a >= low && a <= high) {
            let size = f.abs().max_element().max(self.radius);
            return self.solve_scaled(ray, f, size, ray.dir.abs().max_element());
        }
        super::first_in(ray, roots(f, ray.dir, self.radius)?)
    }

    /// [`Sphere::solve`] for a sphere and ray whose squares would leave
    /// the normal range of `f32` (a sphere of radius 1e-22 seen from
    /// fifteen radii was unlit, one of 2e-26 covered the whole view): the
    /// origin's offset and the radius are scaled by the power of two that
    /// brings the larger to about 1, the direction by its own, and the
    /// roots scaled back. Powers of two change no digit, so the equation
    /// is the same one.
    #[cold]
    fn solve_scaled(&self, ray: &Ray, f: Vec3, size: f32, reach: f32) -> Option<f32> {
        if !(size.is_finite() && reach > 0.0 && reach.is_finite()) {
            return None;
        }
        // 2^−e for the exponent e of x, within f32's normal powers.
        let inverse = |x: f32| 2f64.powi(-(f64::from(x).log2().floor() as i32).clamp(-126, 126));
        let (sf, sd) = (inverse(size), inverse(reach));
        let (t0, t1) = roots(f * sf as f32, ray.dir * sd as f32, self.radius * sf as f32)?;
        // t = t'·sd / sf: the scaled ray meets the scaled sphere at t'.
        let back = |t: f32| (f64::from(t) * sd / sf) as f32;
        super::first_in(ray, (back(t0), back(t1)))
    }

    /// The unit outward normal where the ray is at `t`.
    #[inline]
    fn normal_at(&self, ray: &Ray, t: f32) -> Vec3 {
        ((ray.at(t) - self.center) / self.radius).normalize_or(Vec3::Y)
    }
}

/// The range of sizes (the larger of the origin's offset from the centre
/// and the radius, and the direction's length) that [`Sphere::solve`]
/// takes as they are: within it, the discriminant (of the order of both
/// squared, times each other) stays within 2^±124. Outside it, it scales
/// them.
const UNSCALED: (f32, f32) = (1.0 / (1u64 << 31) as f32, (1u64 << 31) as f32);

/// The roots, ascending, of `|f + t·d|² = r²`, if real.
#[inline(always)]
fn roots(f: Vec3, d: Vec3, r: f32) -> Option<(f32, f32)> {
    let a = d.length_squared();
    let b = -f.dot(d);
    let c = f.length_squared() - r * r;
    // Hearn & Baker's form of the discriminant (Ray Tracing Gems ch. 7):
    // b² − ac = a (r² − |f − (f·d / a) d|²), exact for distant spheres.
    let l = f + (b / a) * d;
    let disc = a * (r * r - l.length_squared());
    if !(disc >= 0.0) {
        return None;
    }
    let q = b + b.signum() * disc.sqrt();
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

impl Intersect for Sphere {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.solve(ray)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let t = self.solve(ray)?;
        let n = self.normal_at(ray, t);
        // Re-project onto the surface to remove the error in t.
        let point = self.center + self.radius * n;
        Some(Hit::new(t, point, n, sphere_uv(n), ray.dir))
    }

    /// No uv (`atan2`, `asin`) and no point: the normal decides the side.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let t = self.solve(ray)?;
        Some((t, Hit::faces(ray.dir, self.normal_at(ray, t))))
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.center - Vec3::splat(self.radius), self.center + Vec3::splat(self.radius))
    }

    fn bounds_in(&self, to_world: &crate::Transform) -> Aabb {
        to_world.tightest(to_world.ball_aabb(self.center, self.radius), &self.bounds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close};

    fn sphere() -> Sphere {
        Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0).unwrap()
    }

    /// A sphere and the rays around it, scaled by 2ᵉ for e from −100 to
    /// 60 (directions by 1, 2ᵉ or 2⁻ᵉ), meet and leave as at unit size:
    /// the same hits at `t` scaled as the direction is (to a few ulps),
    /// and rays spawned outward from the hits (the offset of a scene that
    /// size) meet nothing. Below a radius of about 1e-19 the squares
    /// underflowed: a sphere of 1e-22 seen from fifteen radii went unlit,
    /// one of 2e-26 covered the whole view.
    #[test]
    fn spheres_of_any_size_are_met_and_left_as_at_unit_size() {
        let unit = Sphere::new(Vec3::new(0.2, -0.1, 0.3), 1.0).unwrap();
        let eye = Vec3::new(0.5, 0.4, 15.0);
        for e in (-100..=60).step_by(4) {
            let s = 2f32.powi(e);
            let sphere = Sphere::new(unit.center * s, s).unwrap();
            let offset = crate::offset_scale(15.0 * s);
            // (With a direction of 2⁻ᵉ, `t` is 15·2²ᵉ: past f32 below 2⁻⁶⁰.)
            let dirs: &[f32] = if e >= -60 { &[1.0, s, 1.0 / s] } else { &[1.0, s] };
            for &dir_scale in dirs {
                let mut met = 0;
                for i in 0..21 {
                    for j in 0..21 {
                        let aim = Vec3::new(i as f32 / 10.0 - 1.0, j as f32 / 10.0 - 1.0, 0.0);
                        let one = unit.intersect(&Ray::new(eye, aim - eye));
                        let ray = Ray::new(eye * s, (aim - eye) * dir_scale);
                        let hit = sphere.intersect(&ray);
                        assert_eq!(hit.is_some(), one.is_some(), "2^{e}, {dir_scale}: aimed at {aim}");
                        let (Some(h), Some(one)) = (hit, one) else { continue };
                        met += 1;
                        let want = one.t * s / dir_scale;
                        assert!(
                            (h.t - want).abs() <= 8.0 * f32::EPSILON * want,
                            "2^{e}: t {} against {want}",
                            h.t
                        );
                        assert!((h.normal - one.normal).abs().max_element() < 1e-5, "2^{e}: {h:?}");
                        for d in [h.normal, h.normal + Vec3::new(0.3, -0.2, 0.1), Vec3::new(1.0, 0.5, -0.2)] {
                            let d = if d.dot(h.geo_normal) < 0.0 { -d } else { d };
                            let again =
                                sphere.intersect(&Ray::spawn_scaled(h.point, h.geo_normal, d, offset));
                            assert!(again.is_none(), "2^{e}: left {h:?} along {d} and met {again:?}");
                        }
                    }
                }
                assert!(met > 100, "2^{e}: {met} met");
            }
        }
    }

    #[test]
    fn hit_from_outside_head_on() {
        let h = sphere().intersect(&Ray::new(Vec3::ZERO, Vec3::NEG_Z)).unwrap();
        // d = +Z faces the default camera: u = 0.5 + atan2(0, 1)/2π = 0.5, v = 0.5.
        check_hit(&h, 4.0, Vec3::new(0.0, 0.0, -4.0), Vec3::Z, Vec2::new(0.5, 0.5), true);
    }

    #[test]
    fn t_is_in_units_of_an_unnormalised_direction() {
        let h = sphere().intersect(&Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -2.0))).unwrap();
        close(h.t, 2.0, 1e-6);
    }

    #[test]
    fn hit_from_inside_is_the_far_side_with_outward_normal() {
        let h = sphere().intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::X)).unwrap();
        check_hit(&h, 1.0, Vec3::new(1.0, 0.0, -5.0), Vec3::X, Vec2::new(0.75, 0.5), false);
    }

    #[test]
    fn poles_seam_and_east_are_where_documented() {
        let s = sphere();
        let top = s.intersect(&Ray::new(Vec3::new(0.0, 5.0, -5.0), Vec3::NEG_Y)).unwrap();
        check_hit(&top, 4.0, Vec3::new(0.0, 1.0, -5.0), Vec3::Y, Vec2::new(0.5, 0.0), true);
        let bottom = s.intersect(&Ray::new(Vec3::new(0.0, -5.0, -5.0), Vec3::Y)).unwrap();
        check_hit(&bottom, 4.0, Vec3::new(0.0, -1.0, -5.0), Vec3::NEG_Y, Vec2::new(0.5, 1.0), true);
        // +X is u = 0.75, −X is 0.25, the seam −Z is 0 or 1 (atan2(0, −1) = π).
        let back = s.intersect(&Ray::new(Vec3::new(0.0, 0.0, -10.0), Vec3::Z)).unwrap();
        check_hit(&back, 4.0, Vec3::new(0.0, 0.0, -6.0), Vec3::NEG_Z, Vec2::new(1.0, 0.5), true);
        assert_eq!(sphere_uv(Vec3::new(-1.0, 0.0, 0.0)).x, 0.25);
        assert_eq!(sphere_uv(Vec3::X).x, 0.75);
        // Seen from +Z, a step to the right (+X) is a step east (u grows):
        // not mirrored.
        let (a, b) = (
            sphere_uv(Vec3::new(-0.1, 0.0, 1.0).normalize()),
            sphere_uv(Vec3::new(0.1, 0.0, 1.0).normalize()),
        );
        assert!(b.x > a.x, "{a} {b}");
    }

    #[test]
    fn grazing_ray_touches_at_one_point() {
        // Tangent to the sphere at its top, along +X (zero y and z components).
        let h = sphere().intersect(&Ray::new(Vec3::new(-5.0, 1.0, -5.0), Vec3::X)).unwrap();
        check_hit(&h, 5.0, Vec3::new(0.0, 1.0, -5.0), Vec3::Y, Vec2::new(0.5, 0.0), false);
    }

    #[test]
    fn misses_just_outside_the_silhouette() {
        let s = sphere();
        assert!(s.intersect(&Ray::new(Vec3::new(-5.0, 1.000_001, -5.0), Vec3::X)).is_none());
        assert!(s.intersect(&Ray::new(Vec3::new(1.000_001, 0.0, 0.0), Vec3::NEG_Z)).is_none());
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z)).is_none(), "behind the ray");
    }

    #[test]
    fn interval_selects_the_root() {
        let s = sphere();
        assert!(s.intersect(&Ray::with_interval(Vec3::ZERO, Vec3::NEG_Z, 0.0, 3.9)).is_none());
        let far = s.intersect(&Ray::with_interval(Vec3::ZERO, Vec3::NEG_Z, 4.5, 100.0)).unwrap();
        check_hit(&far, 6.0, Vec3::new(0.0, 0.0, -6.0), Vec3::NEG_Z, Vec2::new(1.0, 0.5), false);
    }

    #[test]
    fn distant_sphere_is_exact() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -1.0e4), 1.0).unwrap();
        let h = s.intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Z)).unwrap();
        let expected_z = -1.0e4 + 0.75f32.sqrt();
        close(h.point.z, expected_z, 2e-3);
        // Within a few ULPs of the largest coordinate (ulp(1e4) ≈ 1e-3).
        close(h.point.y, 0.5, 1e-3);
        close((h.point - s.center()).length(), 1.0, 2e-3);
    }

    #[test]
    fn zero_direction_never_hits() {
        assert!(sphere().intersect(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO)).is_none());
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Sphere::new(Vec3::ZERO, 0.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, -1.0).is_err());
        assert!(Sphere::new(Vec3::ZERO, f32::NAN).is_err());
        assert!(Sphere::new(Vec3::splat(f32::INFINITY), 1.0).is_err());
    }

    #[test]
    fn bounds_are_tight() {
        let b = sphere().bounds();
        assert_eq!(b, Aabb::new(Vec3::new(-1.0, -1.0, -6.0), Vec3::new(1.0, 1.0, -4.0)));
    }
}
