//! prism's one ray/triangle test ([`TriangleRay`], which the BVH's leaves
//! also run) on the rays where a careless implementation returns an
//! infinite `t`: `t_max = ∞`, nearly parallel rays, and triangles so small
//! that the determinant underflows.

use prism_geometry::glam::Vec3;
use prism_geometry::{Ray, TriangleRay};
use proptest::prelude::*;

/// What every answer must satisfy: a finite `t` in the ray's interval and
/// barycentrics of a point inside the triangle.
fn check(ray: &Ray, tri: &[Vec3; 3]) -> Result<(), TestCaseError> {
    if let Some((t, b1, b2)) = TriangleRay::new(ray).intersect(tri) {
        prop_assert!(t.is_finite() && t >= ray.t_min && t <= ray.t_max, "t = {t} for {ray:?} {tri:?}");
        prop_assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-5, "({b1}, {b2}) for {ray:?} {tri:?}");
    }
    Ok(())
}

#[test]
fn a_tiny_triangle_never_gives_an_infinite_t() {
    // Edge functions of ~1e-41 (subnormal): 1/det overflows to +inf, and
    // so would t, without the finiteness check.
    for scale in [1e-19f32, 1e-20, 1e-21, 1e-22] {
        let tri = [Vec3::ZERO, Vec3::new(scale, 0.0, 0.0), Vec3::new(0.0, scale, 0.0)];
        let o = Vec3::new(0.25 * scale, 0.25 * scale, 1.0);
        for t_max in [f32::INFINITY, f32::MAX, 10.0] {
            let ray = Ray::with_interval(o, Vec3::NEG_Z, 0.0, t_max);
            if let Some((t, ..)) = TriangleRay::new(&ray).intersect(&tri) {
                assert!(t.is_finite(), "scale {scale}, t_max {t_max}: t = {t}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    /// Nearly parallel rays (the direction's component along the normal
    /// 1e-30 to 1e-3 of the rest) toward triangles of any scale, with
    /// `t_max = ∞`.
    #[test]
    fn nearly_parallel_rays_with_unbounded_interval(
        corners in prop::array::uniform3((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0)),
        scale_exp in -25i32..25,
        origin in (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0),
        along in (-1.0f32..1.0, -1.0f32..1.0),
        tilt_exp in -30i32..-3,
        flip in any::<bool>(),
    ) {
        let unit = corners.map(|(x, y, z)| Vec3::new(x, y, z));
        let n = (unit[1] - unit[0]).cross(unit[2] - unit[0]).normalize_or_zero();
        prop_assume!(n != Vec3::ZERO);
        let e1 = (unit[1] - unit[0]).normalize_or_zero();
        let e2 = n.cross(e1);
        let scale = 10f32.powi(scale_exp);
        let tri = unit.map(|v| v * scale);
        let tilt = 10f32.powi(tilt_exp) * if flip { -1.0 } else { 1.0 };
        let dir = e1 * along.0 + e2 * along.1 + n * tilt;
        prop_assume!(dir != Vec3::ZERO && dir.is_finite());
        let o = Vec3::new(origin.0, origin.1, origin.2) * scale;
        check(&Ray::new(o, dir), &tri)?;
        check(&Ray::new(o - n * (tilt * scale), dir), &tri)?;
    }

    /// Rays aimed at a random point of the triangle (which they must hit,
    /// unless the triangle is too thin to tell) with `t_max = ∞`.
    #[test]
    fn aimed_rays_hit_with_a_finite_t(
        corners in prop::array::uniform3((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0)),
        bary in (0.05f32..0.9, 0.05f32..0.9),
        origin in (-4.0f32..4.0, -4.0f32..4.0, -4.0f32..4.0),
    ) {
        let tri = corners.map(|(x, y, z)| Vec3::new(x, y, z));
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        prop_assume!(n.length() > 1e-2);
        let (b1, b2) = (bary.0, bary.1 * (1.0 - bary.0));
        let target = (1.0 - b1 - b2) * tri[0] + b1 * tri[1] + b2 * tri[2];
        let o = Vec3::new(origin.0, origin.1, origin.2);
        let ray = Ray::new(o, target - o);
        prop_assume!((target - o).normalize_or_zero().dot(n.normalize()).abs() > 1e-2);
        check(&ray, &tri)?;
        let hit = TriangleRay::new(&ray).intersect(&tri);
        prop_assert!(hit.is_some_and(|(t, ..)| (t - 1.0).abs() < 1e-3), "{hit:?} for {ray:?} {tri:?}");
    }
}

proptest! {
    // About one draw in seven is a sliver and rejected.
    #![proptest_config(ProptestConfig { cases: 20_000, max_global_rejects: 20_000, ..ProptestConfig::default() })]

    /// Grazing rays aimed at a point well inside the triangle (barycentrics
    /// at least 0.05 from every edge), at 1e-4 to 1e-2 of a radian to its
    /// plane, must hit it there: the checks above accept a miss, and a test
    /// that dropped grazing hits would pass them. Seen along such a ray the
    /// triangle is a sliver `tilt` times as thin as it is long, and the
    /// rounding of its corners relative to the origin (up to four of its
    /// sizes away) is about 3e-7 / `tilt` of that width: 0.3 % of it at
    /// 1e-4, well inside the 5 % margin, but 3 % at 1e-5, where a float
    /// test can no longer tell and found a miss.
    #[test]
    fn grazing_rays_aimed_inside_hit(
        corners in prop::array::uniform3((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0)),
        scale_exp in -6i32..6,
        bary in (0.05f32..0.9, 0.0f32..1.0),
        heading in 0.0f32..std::f32::consts::TAU,
        tilt_exp in -4.0f32..-2.0,
        flip in any::<bool>(),
        back in 0.1f32..4.0,
    ) {
        let unit = corners.map(|(x, y, z)| Vec3::new(x, y, z));
        let cross = (unit[1] - unit[0]).cross(unit[2] - unit[0]);
        // Not a sliver: every height at least a tenth of the longest edge.
        let longest = (0..3).map(|i| (unit[(i + 1) % 3] - unit[i]).length()).fold(0.0, f32::max);
        prop_assume!(cross.length() > 0.2 * longest * longest);
        let n = cross.normalize();
        let e1 = (unit[1] - unit[0]).normalize();
        let e2 = n.cross(e1);
        let scale = 10f32.powi(scale_exp);
        let tri = unit.map(|v| v * scale);
        let b1 = bary.0;
        let b2 = 0.05 + bary.1 * (0.9 - b1 - 0.05).max(0.0);
        prop_assume!(b1 + b2 <= 0.95);
        let target = (1.0 - b1 - b2) * tri[0] + b1 * tri[1] + b2 * tri[2];
        let tilt = 10f32.powf(tilt_exp) * if flip { -1.0 } else { 1.0 };
        let dir = (e1 * heading.cos() + e2 * heading.sin()) * (1.0 - tilt * tilt).sqrt() + n * tilt;
        let o = target - dir * (back * scale);
        let ray = Ray::new(o, dir);
        check(&ray, &tri)?;
        let hit = TriangleRay::new(&ray).intersect(&tri);
        // Rounding the corners, the target and the origin moves the plane
        // crossing by a few ulps of the coordinates across the plane, which
        // the grazing angle stretches along the ray by 1 / |tilt|.
        let expected = back * scale;
        let coords = tri.iter().chain([&o]).map(|v| v.abs().max_element()).fold(0.0, f32::max);
        let tolerance = 1e-5 * expected + 16.0 * f32::EPSILON * coords / tilt.abs();
        prop_assert!(
            hit.is_some_and(|(t, ..)| (t - expected).abs() <= tolerance),
            "{hit:?}, expected t = {expected}, for {ray:?} {tri:?}"
        );
    }
}
