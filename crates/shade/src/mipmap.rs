//! Mip-maps of image textures and the filtered checker: what a texture
//! looks like averaged over a pixel's footprint rather than at a point.
//!
//! An image's pyramid is built once, when the texture is made (so once per
//! file at load): each level halves the one above (rounding up, at least
//! one texel) by averaging 2 × 2 texels, read through the image's wrap
//! mode. Lookups are trilinear: bilinear in the two levels around the
//! footprint's size in texels, blended linearly in `log2` of that size
//! (the larger footprint axis decides, as pbrt's trilinear filter; EWA was
//! not needed by any measured scene).

use crate::texture::Wrap;
use prism_geometry::glam::{Vec2, Vec3};

/// One level of a pyramid: `width × height` linear texels, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

impl Level {
    /// The texel at integer coordinates, wrapped or clamped.
    #[inline]
    pub(crate) fn texel(&self, x: i64, y: i64, wrap: Wrap) -> Vec3 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x, y) = match wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        self.texels.get((y * w + x) as usize).copied().unwrap_or(Vec3::ZERO)
    }

    /// Bilinear lookup at `uv` (texel `(i, j)` centred on
    /// `((i + ½) / width, (j + ½) / height)`); non-finite uv reads as 0.
    #[inline]
    pub(crate) fn bilinear(&self, uv: Vec2, wrap: Wrap) -> Vec3 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let (mut x, mut y) = (uv.x * self.width as f32 - 0.5, uv.y * self.height as f32 - 0.5);
        if !(x.is_finite() && y.is_finite()) {
            // A uv so large that its texel position overflows (|uv| above
            // about 1e34): read it as 0, as a non-finite uv, not as NaN.
            (x, y) = (-0.5, -0.5);
        }
        let (x0, y0) = (floor_f32(x), floor_f32(y));
        let (fx, fy) = (x - x0, y - y0);
        let (ix, iy) = (x0 as i64, y0 as i64);
        let (ix1, iy1) = (ix.saturating_add(1), iy.saturating_add(1));
        let top = self.texel(ix, iy, wrap).lerp(self.texel(ix1, iy, wrap), fx);
        let bottom = self.texel(ix, iy1, wrap).lerp(self.texel(ix1, iy1, wrap), fx);
        top.lerp(bottom, fy)
    }

    /// The next smaller level: half the size (rounded up), each texel the
    /// mean of the 2 × 2 texels under it. `None` once 1 × 1.
    pub(crate) fn halve(&self, wrap: Wrap) -> Option<Level> {
        if self.width == 1 && self.height == 1 {
            return None;
        }
        let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let (sx, sy) = (i64::from((self.width > 1) as u8), i64::from((self.height > 1) as u8));
        let mut texels = Vec::with_capacity(w as usize * h as usize);
        for j in 0..i64::from(h) {
            for i in 0..i64::from(w) {
                let (x, y) = (i * (1 + sx), j * (1 + sy));
                let sum = self.texel(x, y, wrap)
                    + self.texel(x + sx, y, wrap)
                    + self.texel(x, y + sy, wrap)
                    + self.texel(x + sx, y + sy, wrap);
                texels.push(sum * 0.25);
            }
        }
        Some(Level { width: w, height: h, texels })
    }
}

/// The smaller levels of `base` (level 1 onwards), down to 1 × 1.
pub(crate) fn build_pyramid(base: &Level, wrap: Wrap) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::new();
    while let Some(next) = levels.last().unwrap_or(base).halve(wrap) {
        levels.push(next);
    }
    levels
}

/// The level of detail for footprint axes `duv` (in uv units) on an image
/// of `width × height` texels: `log2` of the longer axis in texels (0 or
/// less: the full-resolution image; an infinite footprint, a surface seen
/// edge-on at the horizon, is `+∞`: the coarsest level, the image's mean;
/// a `NaN` footprint is 0).
pub(crate) fn lod(width: u32, height: u32, duv: [Vec2; 2]) -> f32 {
    let size = Vec2::new(width as f32, height as f32);
    let texels = (duv[0] * size).length().max((duv[1] * size).length());
    if texels > 0.0 { texels.log2() } else { 0.0 }
}

/// Trilinear lookup: `base` is level 0, `smaller` the levels below it.
pub(crate) fn trilinear(base: &Level, smaller: &[Level], wrap: Wrap, uv: Vec2, lod: f32) -> Vec3 {
    let last = smaller.len() as f32;
    if !(lod > 0.0) {
        return base.bilinear(uv, wrap);
    }
    let lod = lod.min(last);
    let k = floor_f32(lod);
    let level = |i: usize| if i == 0 { base } else { &smaller[(i - 1).min(smaller.len() - 1)] };
    let lo = level(k as usize).bilinear(uv, wrap);
    let frac = lod - k;
    if frac <= 0.0 {
        return lo;
    }
    lo.lerp(level(k as usize + 1).bilinear(uv, wrap), frac)
}

/// `∫₀ˣ` of the indicator of the odd unit squares of a 1-D checker (1 on
/// `[2k + 1, 2k + 2)`, 0 elsewhere): pbrt's `BumpInt`.
#[inline]
fn odd_integral(x: f64) -> f64 {
    let half = x / 2.0;
    let k = floor_f64(half);
    k + 2.0 * (half - k - 0.5).max(0.0)
}

/// `x.floor()`, bit for bit (NaN, infinities and the sign of zero
/// included), without the libm call that the baseline x86-64 target makes
/// for it (no `roundsd` before SSE4.1): below `2^52` in magnitude the
/// truncation through `i64` is exact, and above it every `f64` is an integer.
#[inline]
pub(crate) fn floor_f64(x: f64) -> f64 {
    if !(x.abs() < 4_503_599_627_370_496.0) {
        return x;
    }
    let t = x as i64 as f64;
    let f = if t > x { t - 1.0 } else { t };
    // Truncation loses the sign of -0.0; the floor has the sign of `x`.
    f.copysign(x)
}

/// `x.floor()` for `f32`, bit for bit, as [`floor_f64`].
#[inline]
pub(crate) fn floor_f32(x: f32) -> f32 {
    if !(x.abs() < 8_388_608.0) {
        return x;
    }
    let t = x as i32 as f32;
    let f = if t > x { t - 1.0 } else { t };
    f.copysign(x)
}

/// The fraction of `[x − w/2, x + w/2]` covered by odd squares (unit
/// squares), exactly; a point sample where `w` is below a millionth.
#[inline]
fn odd_fraction(x: f64, w: f64) -> f64 {
    if !(w > 1e-6) {
        return if floor_f64(x).rem_euclid(2.0) == 1.0 { 1.0 } else { 0.0 };
    }
    if !w.is_finite() || w > 1e12 {
        return 0.5;
    }
    ((odd_integral(x + w / 2.0) - odd_integral(x - w / 2.0)) / w).clamp(0.0, 1.0)
}

/// The weight of a checker's second colour (the squares whose indices sum
/// to an odd number) averaged over the box `[x ± wx/2] × [y ± wy/2]`, in
/// units of one square: exact, since the box filter of a product of
/// square waves is the product of their filtered values (pbrt's filtered
/// checkerboard). With zero widths it is the point sample (0 or 1); with
/// large widths it tends to ½.
#[must_use]
pub(crate) fn checker_odd_weight(x: f32, y: f32, wx: f32, wy: f32) -> f32 {
    if !(x.is_finite() && y.is_finite()) {
        return 0.0;
    }
    let fx = odd_fraction(f64::from(x), f64::from(wx));
    let fy = odd_fraction(f64::from(y), f64::from(wy));
    (fx + fy - 2.0 * fx * fy) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Level {
        let texels =
            (0..height).flat_map(|j| (0..width).map(move |i| (i, j))).map(|(i, j)| Vec3::splat(f(i, j)));
        Level { width, height, texels: texels.collect() }
    }

    #[test]
    fn fast_floors_equal_floor_bit_for_bit() {
        let mut xs64 = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            2.0_f64.powi(52) - 0.5,
            -(2.0_f64.powi(52) - 0.5),
            2.0_f64.powi(52),
            -(2.0_f64.powi(53)),
            1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut z = 0x1234_5678_9abc_def0u64;
        for _ in 0..100_000 {
            z = crate::render::splitmix64(z);
            let scale = 2.0_f64.powi((z % 120) as i32 - 60);
            let x = ((z >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * scale;
            xs64.push(x);
            xs64.push(f64::from_bits(z));
        }
        for &x in &xs64 {
            assert_eq!(floor_f64(x).to_bits(), x.floor().to_bits(), "{x:e}");
            let y = x as f32;
            assert_eq!(floor_f32(y).to_bits(), y.floor().to_bits(), "{y:e}");
            let y = f32::from_bits(x.to_bits() as u32);
            if !y.is_nan() {
                assert_eq!(floor_f32(y).to_bits(), y.floor().to_bits(), "{y:e}");
            }
        }
        assert!(floor_f64(f64::NAN).is_nan() && floor_f32(f32::NAN).is_nan());
    }

    #[test]
    fn pyramid_halves_to_one_texel_and_keeps_the_mean() {
        let base = level(8, 4, |i, j| (i + 3 * j) as f32);
        let levels = build_pyramid(&base, Wrap::Clamp);
        let sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(4, 2), (2, 1), (1, 1)]);
        let mean = base.texels.iter().map(|t| t.x).sum::<f32>() / 32.0;
        assert!((levels[2].texels[0].x - mean).abs() < 1e-5);
        assert_eq!(levels[0].texels[0].x, (0.0 + 1.0 + 3.0 + 4.0) / 4.0);
        // Odd sizes round up and never panic.
        assert_eq!(build_pyramid(&level(5, 1, |_, _| 1.0), Wrap::Repeat).len(), 3);
    }

    #[test]
    fn level_selection_follows_the_footprint_in_texels() {
        // A 256-texel image: one texel per pixel is level 0, 4 texels level 2.
        assert_eq!(lod(256, 256, [Vec2::new(1.0 / 256.0, 0.0), Vec2::ZERO]), 0.0);
        assert!(
            (lod(256, 256, [Vec2::new(0.0, 4.0 / 256.0), Vec2::new(1.0 / 256.0, 0.0)]) - 2.0).abs() < 1e-5
        );
        // The longer axis decides; no footprint is level 0.
        assert!(
            (lod(256, 128, [Vec2::new(0.0, 8.0 / 128.0), Vec2::new(2.0 / 256.0, 0.0)]) - 3.0).abs() < 1e-5
        );
        assert_eq!(lod(256, 256, [Vec2::ZERO; 2]), 0.0);
        assert_eq!(lod(256, 256, [Vec2::NAN; 2]), 0.0);
        // An infinite footprint is the coarsest level, not the finest.
        assert_eq!(lod(256, 256, [Vec2::new(f32::INFINITY, 0.0), Vec2::ZERO]), f32::INFINITY);
        let base = level(16, 16, |i, _| (i % 2) as f32);
        let levels = build_pyramid(&base, Wrap::Repeat);
        let far = lod(16, 16, [Vec2::new(f32::INFINITY, 0.0), Vec2::ZERO]);
        assert!(
            (trilinear(&base, &levels, Wrap::Repeat, Vec2::new(0.5 / 16.0, 0.3), far).x - 0.5).abs() < 1e-6
        );
    }

    #[test]
    fn a_uv_too_large_for_a_texel_position_reads_as_zero_not_nan() {
        let base = level(16, 8, |i, j| (i + 16 * j) as f32);
        for wrap in [Wrap::Repeat, Wrap::Clamp] {
            for uv in [Vec2::new(1e38, 0.25), Vec2::new(0.25, -1e38), Vec2::splat(f32::MAX)] {
                let got = base.bilinear(uv, wrap);
                assert!(got.is_finite(), "{uv} ({wrap:?}): {got}");
                assert_eq!(got, base.bilinear(Vec2::ZERO, wrap), "{uv} ({wrap:?})");
            }
        }
    }

    #[test]
    fn trilinear_blends_levels_and_ends_at_the_mean() {
        // A one-texel-period stripe: its mean is 0.5 at every level from 1 on.
        let base = level(16, 16, |i, _| (i % 2) as f32);
        let levels = build_pyramid(&base, Wrap::Repeat);
        let uv = Vec2::new(0.5 / 16.0, 0.3);
        assert_eq!(trilinear(&base, &levels, Wrap::Repeat, uv, 0.0).x, 0.0);
        assert!((trilinear(&base, &levels, Wrap::Repeat, uv, 1.0).x - 0.5).abs() < 1e-6);
        assert!((trilinear(&base, &levels, Wrap::Repeat, uv, 0.5).x - 0.25).abs() < 1e-6);
        assert!((trilinear(&base, &levels, Wrap::Repeat, uv, 100.0).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn filtered_checker_is_the_point_sample_for_a_tiny_footprint() {
        for i in 0..400 {
            let (x, y) = (i as f32 * 0.173 - 30.0, i as f32 * 0.311 - 50.0);
            let point = ((x.floor() as i64 + y.floor() as i64) & 1) as f32;
            assert_eq!(checker_odd_weight(x, y, 0.0, 0.0), point, "({x}, {y})");
            // Well inside a square, a small footprint changes nothing.
            let (fx, fy) = (x - x.floor(), y - y.floor());
            if (0.01..0.99).contains(&fx) && (0.01..0.99).contains(&fy) {
                assert!((checker_odd_weight(x, y, 1e-3, 1e-3) - point).abs() < 1e-6, "({x}, {y})");
            }
        }
    }

    #[test]
    fn filtered_checker_tends_to_the_mean_over_a_large_footprint() {
        for (x, y) in [(0.3f32, 0.2f32), (10.5, -3.25), (1234.5, 77.7)] {
            for w in [10.0f32, 100.0, 1e4, 1e9] {
                let v = checker_odd_weight(x, y, w, w);
                assert!((v - 0.5).abs() <= 1.0 / w, "({x}, {y}) width {w}: {v}");
            }
            // Large along one axis only: still the mean (each row alternates).
            assert!((checker_odd_weight(x, y, 1e6, 0.0) - 0.5).abs() < 1e-5);
        }
        // Exact values: a box of width 1 centred on a square's edge sees half of each.
        assert!((checker_odd_weight(1.0, 0.5, 1.0, 0.0) - 0.5).abs() < 1e-6);
        // Width 2 anywhere covers one odd and one even square: ½.
        assert!((checker_odd_weight(0.37, 0.5, 2.0, 0.0) - 0.5).abs() < 1e-6);
        assert!(checker_odd_weight(f32::NAN, 0.0, 1.0, 1.0).is_finite());
    }
}
