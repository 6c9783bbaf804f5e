//! Camera motion for the viewer's keys and mouse: orbit about the point
//! looked at, move eye and target together, dolly toward the target. Each
//! returns `None` where the result would be degenerate (the state then
//! keeps its camera).

use prism_geometry::glam::{Quat, Vec3};
use prism_shade::Camera;

/// Closest the view direction may come to the up vector when orbiting
/// (radians, 2°), so the camera never becomes degenerate.
const MIN_POLAR: f32 = 2.0 * std::f32::consts::PI / 180.0;

/// `c` (projection and lens included) looking from `position` at `look_at`.
fn camera_with(c: &Camera, position: Vec3, look_at: Vec3) -> Option<Camera> {
    c.moved(position, look_at, c.up()).ok()
}

/// The camera orbited about its target; `None` if that would be degenerate.
pub(crate) fn orbit(c: &Camera, yaw: f32, pitch: f32) -> Option<Camera> {
    if !(yaw.is_finite() && pitch.is_finite()) {
        return None;
    }
    let up = c.up().try_normalize()?;
    let target = c.look_at();
    let offset = c.position() - target;
    let radius = offset.length();
    let dir = offset.try_normalize()?;
    // Polar angle of the eye from the up axis, kept inside (MIN_POLAR, π − MIN_POLAR).
    let polar = dir.dot(up).clamp(-1.0, 1.0).acos();
    let new_polar = (polar - pitch).clamp(MIN_POLAR, std::f32::consts::PI - MIN_POLAR);
    if yaw == 0.0 && (new_polar - polar).abs() < 1e-6 {
        // At the limit already.
        return None;
    }
    let yawed = Quat::from_axis_angle(up, yaw) * dir;
    let axis = up.cross(yawed).try_normalize()?;
    let pitched = Quat::from_axis_angle(axis, new_polar - polar) * yawed;
    camera_with(c, target + pitched * radius, target)
}

pub(crate) fn translate(c: &Camera, forward: f32, right: f32, up: f32) -> Option<Camera> {
    let dist = (c.look_at() - c.position()).length();
    let f = c.forward();
    let r = f.cross(c.up()).try_normalize()?;
    let u = r.cross(f);
    let delta = (forward * f + right * r + up * u) * dist;
    if !delta.is_finite() {
        return None;
    }
    camera_with(c, c.position() + delta, c.look_at() + delta)
}

pub(crate) fn dolly(c: &Camera, fraction: f32) -> Option<Camera> {
    if !fraction.is_finite() {
        return None;
    }
    // Never reach or pass the target.
    let fraction = fraction.clamp(-1.0, 0.9);
    let offset = c.look_at() - c.position();
    camera_with(c, c.position() + offset * fraction, c.look_at())
}
