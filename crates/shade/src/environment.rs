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
        self.radiance_over(dir, 0.0)
    }

    /// The radiance arriving from around `dir` within a cone `angle`
    /// radians across (a pixel's ray cone at infinity): the image read
    /// trilinearly in its mip-map, as image textures are, at the level of
    /// the cone's extent in texels, so that a detailed sky does not alias
    /// where a pixel sees many of its texels. Across `u` the cone spans
    /// `angle / (2π sin θ)` of the width, more near the poles; the level
    /// takes at most eight times its extent along `v` (within 7° of a
    /// pole), so that the sky around the zenith is not blurred along `v`
    /// for the sake of columns that all meet there. `0`: the point.
    #[inline]
    #[must_use]
    pub fn radiance_over(&self, dir: Vec3, angle: f32) -> Vec3 {
        let d = dir.normalize_or(Vec3::Y);
        let u = 0.5 + d.x.atan2(-d.z) / TAU + self.rotation_deg / 360.0;
        // Around the poles, between the first (or last) row's centres and
        // the pole: that row's colour. The image wraps left to right only;
        // filtering across the top edge would mix in the bottom row, the
        // other pole.
        let half = 0.5 / self.image.height() as f32;
        let y = d.y.clamp(-1.0, 1.0);
        let v = (y.acos() / PI).clamp(half, 1.0 - half);
        let uv = Vec2::new(u - u.floor(), v);
        if !(angle > 0.0 && angle.is_finite()) {
            return self.image.sample(uv);
        }
        let sin_theta = (1.0 - y * y).max(0.0).sqrt().max(0.125);
        let du = (angle / (TAU * sin_theta)).min(1.0);
        self.image.sample_over(uv, [Vec2::new(du, 0.0), Vec2::new(0.0, angle / PI)])
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
    fn a_wide_cone_averages_the_texels_it_covers() {
        // 256 × 128 texels of one-texel stripes, 0 and 1: a point reads a
        // stripe, a cone a pixel wide covering ~20 columns their mean.
        let (w, h) = (256u32, 128u32);
        let texels = (0..w * h).map(|i| Vec3::splat((i % 2) as f32)).collect();
        let image = Arc::new(ImageTexture::from_linear(w, h, texels, Wrap::Repeat).unwrap());
        let e = Environment { image, rotation_deg: 0.0 };
        let mut far_from_half = 0;
        for k in 0..64 {
            let a = k as f32 * 0.097;
            let d = Vec3::new(a.sin(), 0.3 * (k as f32 * 0.31).sin(), -a.cos());
            let point = e.radiance(d).x;
            far_from_half += usize::from((point - 0.5).abs() > 0.2);
            let wide = e.radiance_over(d, 20.0 * TAU / w as f32).x;
            assert!((wide - 0.5).abs() < 0.02, "{d}: {wide}");
            // A cone narrower than a texel is the point.
            assert!((e.radiance_over(d, 1e-6).x - point).abs() < 1e-4, "{d}");
        }
        assert!(far_from_half > 32, "the point lookups see the stripes: {far_from_half}");
        // A flat image stays itself however wide the cone, at the poles too.
        let flat =
            Arc::new(ImageTexture::from_linear(8, 4, vec![Vec3::splat(0.25); 32], Wrap::Repeat).unwrap());
        let e = Environment { image: flat, rotation_deg: 0.0 };
        for d in [Vec3::Y, Vec3::NEG_Y, Vec3::new(0.3, 0.2, -1.0)] {
            assert!((e.radiance_over(d, 0.5) - Vec3::splat(0.25)).abs().max_element() < 1e-6);
        }
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
