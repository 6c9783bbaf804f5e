//! The environment image: an equirectangular (latitude–longitude) picture
//! of everything far away, seen by camera, mirror and glass rays that hit
//! nothing. It does not light surfaces (that would be image-based
//! lighting, which prism does not do): shadow rays and the Lambert term
//! never look at it.

use crate::ImageTexture;
use prism_geometry::glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};
use std::sync::Arc;

/// An equirectangular environment image turned about +Y.
///
/// Direction `d` (unit) reads the image at
/// `u = ½ + atan2(d.x, −d.z) / 2π + rotation / 360°` (wrapped), `v =
/// acos(d.y) / π`: the image's centre column is the −Z direction (where the
/// default camera looks), its top row straight up, and a positive rotation
/// turns the picture counter-clockwise seen from above, as a transform's
/// `rotate_y` turns an object (what was at +X comes to −Z at 90°). The
/// image is filtered across its left and right edges, which meet, but not
/// across its top or bottom: within half a row of a pole it reads the
/// first (or last) row.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// The image, linear RGB.
    pub image: Arc<ImageTexture>,
    /// Rotation about +Y in degrees.
    pub rotation_deg: f32,
}

impl Environment {
    /// The radiance arriving from direction `dir` (any length; zero reads
    /// straight up).
    #[inline]
    #[must_use]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let d = dir.normalize_or(Vec3::Y);
        let u = 0.5 + d.x.atan2(-d.z) / TAU + self.rotation_deg / 360.0;
        // Around the poles, between the first (or last) row's centres and
        // the pole: that row's colour. The image wraps left to right only;
        // filtering across the top edge would mix in the bottom row, the
        // other pole.
        let half = 0.5 / self.image.height() as f32;
        let v = (d.y.clamp(-1.0, 1.0).acos() / PI).clamp(half, 1.0 - half);
        self.image.sample(Vec2::new(u - u.floor(), v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Wrap;

    /// A 4×2 image whose columns are distinct colours.
    fn env(rotation_deg: f32) -> Environment {
        let cols = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        let texels = (0..8).map(|i| cols[i % 4]).collect();
        let image = Arc::new(ImageTexture::from_linear(4, 2, texels, Wrap::Repeat).unwrap());
        Environment { image, rotation_deg }
    }

    #[test]
    fn directions_map_to_their_columns() {
        // Column centres at u = 1/8, 3/8, 5/8, 7/8; −Z is u = ½, between
        // columns 1 and 2; turn by 45° to land on a column centre.
        let e = env(0.0);
        let at = |deg: f32| {
            let a = deg.to_radians();
            Vec3::new(a.sin(), 0.0, -a.cos())
        };
        assert!((e.radiance(at(45.0)) - Vec3::Z).length() < 1e-5);
        assert!((e.radiance(at(-45.0)) - Vec3::Y).length() < 1e-5);
        assert!((e.radiance(at(135.0)) - Vec3::ONE).length() < 1e-5);
        // Rotating the picture by +90° moves what was at +45° (toward +X)
        // to −45° (toward −X): counter-clockwise seen from above.
        let r = env(90.0);
        assert!((r.radiance(at(-45.0)) - e.radiance(at(45.0))).length() < 1e-5);
        assert!(e.radiance(Vec3::ZERO).is_finite());
    }

    #[test]
    fn the_poles_show_their_own_rows_not_the_other_pole() {
        // Rows of 0, 1, 2 … 7 (top to bottom): straight up, and just off it,
        // reads the top row; straight down the bottom one.
        let texels = (0..32).map(|i| Vec3::splat((i / 4) as f32)).collect();
        let image = Arc::new(ImageTexture::from_linear(4, 8, texels, Wrap::Repeat).unwrap());
        let e = Environment { image, rotation_deg: 0.0 };
        for d in [Vec3::Y, Vec3::new(0.0, 1.0, -1e-3), Vec3::new(2e-3, 1.0, 1e-3)] {
            assert_eq!(e.radiance(d), Vec3::ZERO, "{d}");
            assert_eq!(e.radiance(-d), Vec3::splat(7.0), "{}", -d);
        }
        // Between rows, the filter as before: 45° up is v = ¼, between
        // rows 1 and 2.
        assert!((e.radiance(Vec3::new(0.0, 1.0, -1.0)) - Vec3::splat(1.5)).length() < 1e-5);
    }

    #[test]
    fn rotation_turns_the_picture_as_rotate_y_turns_an_object() {
        // What the turned picture shows along `d` is what the picture
        // showed along the direction `rotate_y` carries to `d`.
        let e = env(0.0);
        for deg in [30.0f32, 90.0, -135.0] {
            let turn = prism_geometry::Transform::rotate_y(deg.to_radians());
            let r = env(deg);
            for k in 0..16 {
                let a = (k as f32 * 22.5 + 3.0).to_radians();
                let before = Vec3::new(a.sin(), 0.3, -a.cos());
                let after = turn.vector(before);
                assert!((r.radiance(after) - e.radiance(before)).length() < 1e-4, "{deg}° at {before}");
            }
        }
    }
}
