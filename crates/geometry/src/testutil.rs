//! Assertion helpers shared by the unit tests.

use crate::Hit;
use glam::{Vec2, Vec3};

/// Asserts `|a − b| <= tol`.
#[track_caller]
pub(crate) fn close(a: f32, b: f32, tol: f32) {
    assert!((a - b).abs() <= tol, "{a} != {b} (tolerance {tol})");
}

/// Asserts every component of `a` is within `tol` of `b`.
#[track_caller]
pub(crate) fn close3(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} != {b} (tolerance {tol})");
}

/// Asserts every component of `a` is within `tol` of `b`.
#[track_caller]
pub(crate) fn close2(a: Vec2, b: Vec2, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} != {b} (tolerance {tol})");
}

/// Checks a hit against analytic values (tolerance 1e-5 relative to 1).
#[track_caller]
pub(crate) fn check_hit(h: &Hit, t: f32, point: Vec3, normal: Vec3, uv: Vec2, front: bool) {
    close(h.t, t, 1e-5 * t.abs().max(1.0));
    close3(h.point, point, 1e-5 * point.abs().max_element().max(1.0));
    close3(h.geo_normal, normal, 1e-5);
    close3(h.normal, normal, 1e-5);
    close2(h.uv, uv, 1e-5);
    assert_eq!(h.front_face, front, "front_face of {h:?}");
}

/// A reproducible stream of `f32` in `[-1, 1)` from `seed` (an LCG), for
/// tests over many random cases.
pub(crate) fn uniform(mut seed: u64) -> impl FnMut() -> f32 {
    move || {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}
