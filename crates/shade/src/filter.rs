//! Pixel reconstruction filters, applied by importance sampling: each
//! sample's image position is drawn from the filter's distribution about
//! the pixel centre and every sample has weight 1 (pbrt-v4's filter
//! sampling). A pixel's value is then the plain mean of its own samples:
//! nothing is splatted into neighbours, so a pixel depends on its own
//! samples only (tiles of a render equal the full render bit for bit).

use std::fmt;
use std::str::FromStr;

/// The pixel reconstruction filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PixelFilter {
    /// The box over the pixel's own square (the historical default):
    /// stratified positions in `[i, i + 1) × [j, j + 1)`.
    #[default]
    Box,
    /// A Gaussian of standard deviation 0.5 pixel, truncated at radius
    /// 1.5 pixels and shifted to reach 0 there (pbrt-v4's default).
    Gaussian,
    /// The 4-term Blackman–Harris window over radius 2 pixels (standard
    /// deviation 0.55 pixel, against the truncated Gaussian's 0.48): a
    /// little softer than the Gaussian, with a smoother tail.
    BlackmanHarris,
}

impl PixelFilter {
    /// Every filter, in the order of [`PixelFilter::name`]s in the docs.
    pub const ALL: [PixelFilter; 3] = [PixelFilter::Box, PixelFilter::Gaussian, PixelFilter::BlackmanHarris];

    /// The name used in scene files and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            PixelFilter::Box => "box",
            PixelFilter::Gaussian => "gaussian",
            PixelFilter::BlackmanHarris => "blackman-harris",
        }
    }

    /// Support radius in pixels (the filter is zero beyond it on each axis).
    #[must_use]
    pub fn radius(self) -> f32 {
        match self {
            PixelFilter::Box => 0.5,
            PixelFilter::Gaussian => 1.5,
            PixelFilter::BlackmanHarris => 2.0,
        }
    }

    /// The filter's 1-D profile at offset `x` pixels from the pixel centre
    /// (the 2-D filter is the product of the profiles of `x` and `y`);
    /// unnormalised, non-negative, zero outside `[-radius, radius]`.
    #[must_use]
    pub fn eval(self, x: f32) -> f32 {
        let r = self.radius();
        if !(x.abs() <= r) {
            return 0.0;
        }
        match self {
            PixelFilter::Box => 1.0,
            PixelFilter::Gaussian => {
                let g = |x: f32| (-x * x / (2.0 * 0.25)).exp();
                (g(x) - g(r)).max(0.0)
            }
            PixelFilter::BlackmanHarris => {
                // The window over [0, 2r], centred on 0.
                let t = 2.0 * std::f32::consts::PI * (x + r) / (2.0 * r);
                let w =
                    0.358_75 - 0.488_29 * t.cos() + 0.141_28 * (2.0 * t).cos() - 0.011_68 * (3.0 * t).cos();
                w.max(0.0)
            }
        }
    }

    /// The sampler that maps uniform offsets to this filter's distribution.
    #[must_use]
    pub fn sampler(self) -> FilterSampler {
        FilterSampler::new(self)
    }
}

impl fmt::Display for PixelFilter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown filter name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown pixel filter `{name}`{hint} (expected box, gaussian or blackman-harris)",
    name = .0,
    hint = crate::names::did_you_mean(.0, &PixelFilter::ALL.map(PixelFilter::name))
)]
pub struct FilterParseError(pub String);

impl FromStr for PixelFilter {
    type Err = FilterParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL.into_iter().find(|f| f.name() == s).ok_or_else(|| FilterParseError(s.to_string()))
    }
}

/// Anti-aliasing choices of a render (part of [`crate::RenderSettings`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Antialias {
    /// The pixel reconstruction filter, by which sample positions are drawn.
    pub filter: PixelFilter,
    /// Adaptive supersampling (POV-Ray's `antialias_threshold`): with
    /// `Some(threshold)`, every pixel first takes [`ADAPTIVE_BASE_SAMPLES`]
    /// samples; a pixel then takes the rest of its `spp` if two of its own
    /// differ by more than `threshold` in a colour channel, or if its mean
    /// differs by more than that from one of its eight neighbours' means
    /// (colours clamped to `[0, 1]` first); `None` always takes `spp`.
    pub adaptive: Option<f32>,
    /// Point-sample textures instead of filtering them over each hit's
    /// footprint (for comparison; filtering is the default).
    pub point_textures: bool,
}

/// The samples an adaptive pixel takes before it decides whether to take
/// the rest (see [`Antialias::adaptive`]).
pub const ADAPTIVE_BASE_SAMPLES: u32 = 4;

/// Bins of the tabulated 1-D distribution.
const BINS: usize = 256;

/// Inverse-CDF sampling of a [`PixelFilter`], per axis (the filters are
/// separable): the profile is tabulated as a piecewise-constant density over
/// 256 bins of `[-radius, radius]` (each bin's mass integrated by
/// Simpson's rule), and a uniform `u` is mapped through the inverse of its
/// piecewise-linear CDF. The map is monotone, so stratified uniform offsets
/// stay stratified in the filter's measure.
#[derive(Clone, Debug)]
pub struct FilterSampler {
    filter: PixelFilter,
    radius: f32,
    /// `cdf[k]`: the mass of bins `0..k`, normalised; `cdf[BINS] = 1`.
    cdf: Vec<f32>,
}

impl FilterSampler {
    fn new(filter: PixelFilter) -> Self {
        let radius = filter.radius();
        let mut cdf = Vec::with_capacity(BINS + 1);
        cdf.push(0.0f64);
        let step = 2.0 * f64::from(radius) / BINS as f64;
        let f = |x: f64| f64::from(filter.eval(x as f32));
        let mut total = 0.0;
        for k in 0..BINS {
            let a = -f64::from(radius) + k as f64 * step;
            total += step / 6.0 * (f(a) + 4.0 * f(a + step / 2.0) + f(a + step));
            cdf.push(total);
        }
        let cdf = cdf.into_iter().map(|c| if total > 0.0 { (c / total) as f32 } else { 0.0 }).collect();
        Self { filter, radius, cdf }
    }

    /// The filter sampled.
    #[must_use]
    pub fn filter(&self) -> PixelFilter {
        self.filter
    }

    /// The offset from the pixel centre, in pixels, of the sample whose
    /// uniform coordinate is `u` in `[0, 1)`: `u = ½` gives 0 (the centre).
    #[inline]
    #[must_use]
    pub fn sample(&self, u: f32) -> f32 {
        if self.filter == PixelFilter::Box {
            return u - 0.5;
        }
        let u = u.clamp(0.0, 1.0);
        // The last k with cdf[k] <= u, so that u lies in bin k.
        let k = self.cdf.partition_point(|&c| c <= u).saturating_sub(1).min(BINS - 1);
        let (c0, c1) = (self.cdf[k], self.cdf[k + 1]);
        let frac = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        let step = 2.0 * self.radius / BINS as f32;
        -self.radius + (k as f32 + frac) * step
    }

    /// The offset, within `[0, 1)²`-relative pixel coordinates, of a sample
    /// whose uniform coordinates are `(ux, uy)`: the position of the sample
    /// relative to the pixel's top-left corner (`(0.5, 0.5)` is the centre).
    /// For the box this is `(ux, uy)` itself.
    #[inline]
    #[must_use]
    pub fn offset(&self, (ux, uy): (f32, f32)) -> (f32, f32) {
        if self.filter == PixelFilter::Box {
            return (ux, uy);
        }
        (0.5 + self.sample(ux), 0.5 + self.sample(uy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ x^k f(x) dx / ∫ f(x) dx` of the continuous profile, by a fine midpoint rule.
    fn moment(f: PixelFilter, k: i32) -> f64 {
        let r = f64::from(f.radius());
        let n = 200_000;
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..n {
            let x = -r + (i as f64 + 0.5) * 2.0 * r / n as f64;
            let w = f64::from(f.eval(x as f32));
            num += x.powi(k) * w;
            den += w;
        }
        num / den
    }

    #[test]
    fn standard_deviations_are_the_documented_ones() {
        // scene-format.md and the variants' docs: box 1/√12, Gaussian 0.48
        // (σ 0.5 truncated), Blackman–Harris 0.55.
        for (f, want) in [
            (PixelFilter::Box, 1.0 / 12f64.sqrt()),
            (PixelFilter::Gaussian, 0.479),
            (PixelFilter::BlackmanHarris, 0.554),
        ] {
            let sd = moment(f, 2).sqrt();
            assert!((sd - want).abs() < 1e-3, "{}: {sd}", f.name());
        }
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for f in PixelFilter::ALL {
            assert_eq!(f.name().parse::<PixelFilter>(), Ok(f));
            assert_eq!(f.to_string(), f.name());
        }
        assert!("lanczos".parse::<PixelFilter>().is_err());
        assert_eq!(PixelFilter::default(), PixelFilter::Box);
    }

    #[test]
    fn profiles_are_symmetric_non_negative_and_vanish_at_the_radius() {
        for f in PixelFilter::ALL {
            let r = f.radius();
            assert_eq!(f.eval(r + 1e-3), 0.0);
            for i in 0..=100 {
                let x = r * i as f32 / 100.0;
                assert!(f.eval(x) >= 0.0);
                assert!((f.eval(x) - f.eval(-x)).abs() < 1e-6, "{f}: not symmetric at {x}");
            }
            if f != PixelFilter::Box {
                assert!(f.eval(r) < 1e-4 * f.eval(0.0), "{f} does not reach 0 at its radius");
                assert!(f.eval(0.0) > f.eval(0.5 * r));
            }
        }
    }

    /// Sampling `u` on a fine regular grid reproduces the filter's mean
    /// (0), variance and fourth moment.
    #[test]
    fn filter_sampling_reproduces_the_filters_moments() {
        for f in PixelFilter::ALL {
            let s = f.sampler();
            let n = 100_000;
            let xs: Vec<f64> = (0..n).map(|i| f64::from(s.sample((i as f32 + 0.5) / n as f32))).collect();
            let m = |k: i32| xs.iter().map(|x| x.powi(k)).sum::<f64>() / n as f64;
            assert!(m(1).abs() < 1e-4, "{f}: mean {}", m(1));
            let (v, want_v) = (m(2), moment(f, 2));
            assert!((v / want_v - 1.0).abs() < 0.005, "{f}: variance {v} vs {want_v}");
            let (k4, want_k4) = (m(4), moment(f, 4));
            assert!((k4 / want_k4 - 1.0).abs() < 0.01, "{f}: fourth moment {k4} vs {want_k4}");
            // Every sample lies inside the support, and u = ½ is the centre.
            assert!(xs.iter().all(|x| x.abs() <= f64::from(f.radius()) + 1e-6));
            assert!(s.sample(0.5).abs() < 1e-3);
        }
        // The box's variance is 1/12; the Gaussian's is a little under 0.25 (truncated).
        assert!((moment(PixelFilter::Box, 2) - 1.0 / 12.0).abs() < 1e-6);
        let g = moment(PixelFilter::Gaussian, 2);
        assert!(g > 0.15 && g < 0.25, "{g}");
    }

    #[test]
    fn sampling_is_monotone_so_strata_stay_strata() {
        for f in PixelFilter::ALL {
            let s = f.sampler();
            let mut last = f32::NEG_INFINITY;
            for i in 0..=1000 {
                let x = s.sample(i as f32 / 1000.0);
                assert!(x >= last, "{f}: not monotone at {i}");
                last = x;
            }
        }
        assert_eq!(PixelFilter::Box.sampler().offset((0.25, 0.75)), (0.25, 0.75));
    }
}
