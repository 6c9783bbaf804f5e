//! The renderer: rows in parallel, deterministic per-pixel samples.

use crate::aov::{Aov, AovRow};
use crate::integrator::Tracer;
use crate::{Camera, Scene};
use prism_geometry::glam::Vec3;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// The per-render choices: everything a render (or one view of the
/// viewer) may choose without changing the scene. A [`Scene`] is immutable
/// scene data (geometry, materials, lights, the fog's medium); the camera,
/// whether the fog is applied, and the sampling live here, so that two
/// renders of one scene, or a viewer's changing views, share it as `&Scene`.
///
/// `prism_scene` fills one with the scene file's values and the command
/// line's overrides applied once (`LoadedScene::settings`). No `Default`:
/// every caller states its settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The camera, which also fixes the image size.
    pub camera: Camera,
    /// Whether the scene's fog ([`Scene::fog`]) is applied; without fog in
    /// the scene this changes nothing.
    pub fog: bool,
    /// Samples per pixel (stratified), at least 1.
    pub spp: u32,
    /// Maximum recursion depth of reflection/refraction/transparency rays:
    /// 0 traces camera and shadow rays only. Values above
    /// [`crate::MAX_DEPTH_LIMIT`] act as that limit.
    pub max_depth: u32,
    /// Secondary rays whose weight on the pixel (the product of the
    /// coefficients and fog along their path, largest channel) falls below
    /// this are not traced; rays of weight 0 never are.
    pub min_contribution: f32,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
}

impl RenderSettings {
    /// The same settings with the camera at another image size (the
    /// viewer's window, its coarse preview).
    ///
    /// # Errors
    /// As [`Camera::with_size`].
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, crate::ShadeError> {
        Ok(Self { camera: self.camera.with_size(width, height)?, ..self.clone() })
    }
}

/// Callbacks and cancellation for a render in progress.
#[derive(Clone, Copy, Default)]
pub struct RenderHooks<'a> {
    /// Called with `(rows done, rows in all)` as rows finish (from workers).
    pub progress: Option<&'a (dyn Fn(u32, u32) + Sync)>,
    /// When set, workers stop at the next row; the result is partial.
    pub cancel: Option<&'a AtomicBool>,
}

/// A linear-radiance image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major linear RGB.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// 8-bit sRGB-encoded RGB bytes (clamped to `[0, 1]` first).
    #[must_use]
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels.iter().flat_map(|p| p.to_array().map(linear_to_srgb8)).collect()
    }
}

/// The sRGB transfer function applied to a linear value, to 8 bits.
#[must_use]
pub fn linear_to_srgb8(x: f32) -> u8 {
    let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
    let s = if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Figures about a finished render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall time in seconds.
    pub seconds: f64,
    /// Every ray traced: camera, reflection, refraction, transparency, shadow.
    pub rays: u64,
    /// Whether the render was cancelled before the end.
    pub cancelled: bool,
    /// Samples whose radiance was not finite (NaN or infinite) and so
    /// counted as black; 0 unless something is wrong.
    pub nonfinite_samples: u64,
}

/// Renders the whole image with `settings.spp` samples per pixel: the
/// per-pixel sums of [`render_samples`] over `0..spp`, times `1 / spp`.
///
/// Sampling: with `spp = n`, pixel `(i, j)` is divided into an `m × m`
/// grid of strata, `m = ⌈√n⌉`. Sample `s` falls in stratum
/// `(s · stride) mod m²` (a fixed stride coprime with `m²`, about 0.618·m²,
/// so that the first samples spread over the pixel), at a point jittered
/// inside it by a hash of `(pixel index, s)`. A pixel's samples therefore
/// depend on nothing but the pixel and the sample index: the image is the
/// same, bit for bit, for any number of threads. With `spp = 1` the single
/// sample is the pixel centre, so a 1-spp render measures the scene
/// exactly.
pub fn render(scene: &Scene, settings: &RenderSettings, hooks: RenderHooks<'_>) -> (Image, RenderStats) {
    let (mut image, stats) = render_samples(scene, settings, 0..settings.spp.max(1), hooks);
    scale_to_mean(&mut image, settings.spp);
    (image, stats)
}

/// Turns per-pixel sums of `spp` samples into means (times `1 / spp`).
pub(crate) fn scale_to_mean(image: &mut Image, spp: u32) {
    let inv = 1.0 / spp.max(1) as f32;
    for p in &mut image.pixels {
        *p *= inv;
    }
}

/// Renders samples `samples` (of `settings.spp` per pixel) and returns the
/// per-pixel *sums*, so that passes over disjoint ranges add up to the full
/// render (progressive refinement in the viewer).
///
/// Each pixel sums its samples in increasing sample order starting from
/// zero, so one-sample passes `0..1`, `1..2`, … added in that order to a
/// zeroed buffer give exactly the sums [`render`] uses (then multiply by
/// `1 / spp` as it does); passes of several samples agree with it up to
/// float rounding of the additions. Sample `s` is the same whatever the
/// passes, and the same on any number of threads.
pub fn render_samples(
    scene: &Scene,
    settings: &RenderSettings,
    samples: Range<u32>,
    hooks: RenderHooks<'_>,
) -> (Image, RenderStats) {
    let (image, _, stats) = render_pixels(scene, settings, samples, true, &[], hooks);
    (image, stats)
}

/// The one per-pixel sample loop behind every render: rows in parallel;
/// in each pixel, samples `samples` in increasing order, each camera ray
/// traced for the beauty sum (if `beauty`) and handed to the row's AOV
/// sink (if `aovs` is not empty; it then sees every sample, `samples`
/// being `0..spp`). Returns the per-pixel beauty *sums* (an empty image
/// without `beauty`), one AOV row per image row (empty without `aovs`),
/// and the statistics. Rows skipped after a cancel hold zero sums and the
/// AOV miss values.
pub(crate) fn render_pixels<'a>(
    scene: &Scene,
    settings: &RenderSettings,
    samples: Range<u32>,
    beauty: bool,
    aovs: &'a [Aov],
    hooks: RenderHooks<'_>,
) -> (Image, Vec<AovRow<'a>>, RenderStats) {
    let start = std::time::Instant::now();
    let cam = &settings.camera;
    let (w, h) = cam.size();
    let spp = settings.spp.max(1);
    let pattern = SamplePattern::new(spp);
    let see_through = beauty && Tracer::scene_is_see_through(scene);
    let rays = AtomicU64::new(0);
    let nonfinite = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let mut pixels = vec![Vec3::ZERO; if beauty { w as usize * h as usize } else { 0 }];
    let mut aov_rows: Vec<AovRow<'a>> =
        if aovs.is_empty() { Vec::new() } else { (0..h).map(|_| AovRow::new(aovs, w, spp)).collect() };
    let render_row = |j: usize, row: &mut [Vec3], mut sink: Option<&mut AovRow<'a>>| {
        if hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return;
        }
        let mut tracer = Tracer::new(scene, settings, see_through);
        let mut bad = 0u64;
        let row_start = j as u64 * u64::from(w);
        for i in 0..w as usize {
            let index = row_start + i as u64;
            let mut sum = Vec3::ZERO;
            for s in samples.clone() {
                let (dx, dy) = pattern.offset(index, s);
                let ray = cam.ray(i as f32 + dx, j as f32 + dy);
                if beauty {
                    let l = tracer.trace_camera(&ray);
                    if l.is_finite() {
                        sum += l;
                    } else {
                        bad += 1;
                    }
                }
                if let Some(sink) = sink.as_deref_mut() {
                    sink.sample(scene, &ray);
                }
            }
            if let Some(px) = row.get_mut(i) {
                *px = sum;
            }
            if let Some(sink) = sink.as_deref_mut() {
                sink.end_pixel(scene, cam, i as u32, j as u32);
            }
        }
        let aov_rays = sink.map_or(0, |s| s.rays);
        rays.fetch_add(tracer.rays + aov_rays, Ordering::Relaxed);
        if bad > 0 {
            nonfinite.fetch_add(bad, Ordering::Relaxed);
        }
        let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(p) = hooks.progress {
            p(done as u32, h);
        }
    };
    let row_len = w as usize;
    in_pool(settings.threads, || match (beauty, aov_rows.is_empty()) {
        (true, true) => {
            pixels.par_chunks_mut(row_len).enumerate().for_each(|(j, row)| render_row(j, row, None));
        }
        (true, false) => pixels
            .par_chunks_mut(row_len)
            .zip(aov_rows.par_iter_mut())
            .enumerate()
            .for_each(|(j, (row, sink))| render_row(j, row, Some(sink))),
        (false, false) => {
            aov_rows.par_iter_mut().enumerate().for_each(|(j, sink)| render_row(j, &mut [], Some(sink)));
        }
        // Nothing asked for.
        (false, true) => {}
    });
    let stats = RenderStats {
        seconds: start.elapsed().as_secs_f64(),
        rays: rays.into_inner(),
        cancelled: hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed)),
        nonfinite_samples: nonfinite.into_inner(),
    };
    (Image { width: w, height: h, pixels }, aov_rows, stats)
}

/// Runs `f` on a pool of `threads` workers (`None`: the global pool, every
/// core; a pool that cannot be built falls back to the global one).
pub(crate) fn in_pool<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads {
        Some(n) => match rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build() {
            Ok(pool) => pool.install(f),
            Err(_) => f(),
        },
        None => f(),
    }
}

/// The image-plane position of sample `s` of pixel `(i, j)` in a render of
/// `spp` samples per pixel on an image `width` pixels wide: the point that
/// [`render`] (and [`crate::render_aovs`]) passes to [`crate::Camera::ray`].
/// It lies in `[i, i + 1) × [j, j + 1)`; with `spp = 1` it is the pixel
/// centre `(i + 0.5, j + 0.5)`. See [`render`] for the pattern.
#[must_use]
pub fn sample_position(spp: u32, width: u32, i: u32, j: u32, s: u32) -> (f32, f32) {
    let (dx, dy) = SamplePattern::new(spp).offset(u64::from(j) * u64::from(width) + u64::from(i), s);
    (i as f32 + dx, j as f32 + dy)
}

/// The stratified, hashed sample positions within a pixel.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SamplePattern {
    /// Strata per side (`⌈√spp⌉`); 0 means "pixel centre only" (spp = 1).
    m: u32,
    /// Number of strata, `m²`.
    strata: u32,
    /// Step through the strata, coprime with `strata`.
    stride: u32,
}

impl SamplePattern {
    pub(crate) fn new(spp: u32) -> Self {
        let spp = spp.max(1);
        if spp == 1 {
            return Self { m: 0, strata: 1, stride: 1 };
        }
        let mut m = (spp as f64).sqrt().ceil() as u32;
        while m.saturating_mul(m) < spp {
            m += 1;
        }
        let strata = m.saturating_mul(m);
        Self { m, strata, stride: golden_stride(strata) }
    }

    /// Offset of sample `s` of pixel number `pixel` inside its pixel, in `[0, 1)²`.
    #[inline]
    pub(crate) fn offset(&self, pixel: u64, s: u32) -> (f32, f32) {
        if self.m == 0 {
            return (0.5, 0.5);
        }
        let k = ((u64::from(s) * u64::from(self.stride)) % u64::from(self.strata)) as u32;
        let (sx, sy) = (k % self.m, k / self.m);
        let z = splitmix64((pixel << 32) ^ u64::from(s) ^ 0x5851_F42D_4C95_7F2D);
        let jx = (z >> 40) as f32 * (1.0 / 16_777_216.0);
        let jy = ((z >> 16) & 0xFF_FFFF) as f32 * (1.0 / 16_777_216.0);
        let m = self.m as f32;
        let below_one = 1.0 - f32::EPSILON / 2.0;
        (((sx as f32 + jx) / m).min(below_one), ((sy as f32 + jy) / m).min(below_one))
    }
}

/// A step through `n` items that visits each once and spreads the first
/// ones out: about 0.618 · n, made coprime with `n`.
pub(crate) fn golden_stride(n: u32) -> u32 {
    let mut stride = ((f64::from(n) * 0.618_033_988_75).round() as u32).max(1);
    while gcd(stride, n) != 1 {
        stride += 1;
    }
    stride
}

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Steele, Lea and Flood's SplitMix64 finaliser: a well-mixed 64-bit hash.
#[inline]
pub(crate) fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_is_the_centre() {
        let p = SamplePattern::new(1);
        assert_eq!(p.offset(123, 0), (0.5, 0.5));
    }

    #[test]
    fn samples_are_stratified_and_deterministic() {
        for spp in [2u32, 3, 4, 5, 9, 10, 16, 17] {
            let p = SamplePattern::new(spp);
            let m = p.m;
            assert_eq!(m, (spp as f64).sqrt().ceil() as u32);
            let mut seen = vec![false; (m * m) as usize];
            for s in 0..spp {
                let (x, y) = p.offset(77, s);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                let cell = ((y * m as f32) as u32 * m + (x * m as f32) as u32) as usize;
                assert!(!seen[cell], "spp {spp}: two samples in stratum {cell}");
                seen[cell] = true;
                assert_eq!(p.offset(77, s), (x, y));
            }
        }
        // Different pixels get different jitter.
        let p = SamplePattern::new(4);
        assert_ne!(p.offset(1, 0), p.offset(2, 0));
    }
}
