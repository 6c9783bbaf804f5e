//! The renderer: rows in parallel, deterministic per-pixel samples.

use crate::aov::{Aov, AovRow, render_passes};
use crate::integrator::{PRE_LIGHTS, PreShadow, Tracer};
use crate::media::CameraMedia;
use crate::{Antialias, AovImages, BoundsError, Camera, PixelBounds, Scene};
use prism_geometry::Ray;
use prism_geometry::glam::{DVec3, Vec3};
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
    /// Anti-aliasing: the pixel filter, adaptive supersampling, texture
    /// filtering ([`Antialias::default`]: box, off, on).
    pub antialias: Antialias,
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
    /// When set, workers stop within a moment (before their next pixel,
    /// or within 1024 samples of one); the result is partial,
    /// a row left midway as black as a row not started.
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
    (crate::tonemap::linear_to_srgb(x) * 255.0 + 0.5) as u8
}

/// Figures about a finished render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall time in seconds.
    pub seconds: f64,
    /// Every ray traced: camera, reflection, refraction, transparency, shadow.
    pub rays: u64,
    /// Of `rays`, the beauty's camera rays: one per sample (under adaptive
    /// sampling, those taken, and for a region the first samples of a
    /// one-pixel border around it too).
    pub camera_rays: u64,
    /// Of `rays`, the shadow rays.
    pub shadow_rays: u64,
    /// Of `rays`, those traced together in packets (camera rays, their
    /// hits' shadow rays toward lights of one sample, and an area light's
    /// shadow rays, each where enabled); see [`render`].
    pub packet_rays: u64,
    /// Of `rays`, the rays the AOV passes (and the coverage test of
    /// [`crate::render_with_alpha`]) traced for themselves.
    pub aov_rays: u64,
    /// Whether the render was cancelled before the end.
    pub cancelled: bool,
    /// Samples whose radiance was not finite (NaN or infinite) and so
    /// counted as black; 0 unless something is wrong.
    pub nonfinite_samples: u64,
}

impl RenderStats {
    /// Of `rays`, the secondary rays: reflection, refraction and
    /// transparency (everything that is not a camera, shadow or AOV ray).
    #[must_use]
    pub fn secondary_rays(&self) -> u64 {
        self.rays.saturating_sub(self.camera_rays + self.shadow_rays + self.aov_rays)
    }
}

/// Renders the whole image with `settings.spp` samples per pixel: the
/// per-pixel sums of [`render_samples`] over `0..spp`, times `1 / spp`.
///
/// Sampling: with `spp = n`, pixel `(i, j)` is divided into an `m × m`
/// grid of strata, `m = ⌈√n⌉`. Sample `s` falls in stratum
/// `(s · stride) mod m²` (a fixed stride coprime with `m²`, about 0.618·m²,
/// so that the first samples spread over the pixel), at a point inside it
/// placed by Kensler's correlated multi-jitter (the sub-cell given by
/// per-pixel permutations of the stratum's row and column, jittered by a
/// hash of `(pixel index, s)`), so that a full grid is also stratified in
/// `x` and in `y` alone: a near-horizontal or near-vertical edge is
/// estimated from `m²` levels, not `m`. A pixel's samples therefore
/// depend on nothing but the pixel and the sample index: the image is the
/// same, bit for bit, for any number of threads. With `spp = 1` the single
/// sample is the pixel centre, so a 1-spp render measures the scene
/// exactly.
///
/// Under a pixel filter other than the box ([`crate::Antialias::filter`]),
/// each coordinate of that point is mapped through the filter's inverse
/// CDF ([`crate::FilterSampler`]), so samples spread over the filter's
/// support about the pixel centre, each of weight 1: a pixel is still the
/// mean of its own samples. With [`crate::Antialias::adaptive`], a pixel
/// whose first [`crate::ADAPTIVE_BASE_SAMPLES`] samples agree with each
/// other and with its neighbours' stops there.
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
    let (image, _, stats) = render_pixels(scene, settings, samples, None, true, &[], false, hooks);
    (image, stats)
}

/// Renders only the pixels of `region` (a partial render, one tile of a
/// farm job), with the AOV passes `aovs` (none if empty): an image and
/// passes of `region`'s size, whose pixel `(x, y)` is pixel
/// `(region.x0() + x, region.y0() + y)` of the full render.
///
/// Every pixel is bit for bit the same as in [`render`] and
/// [`crate::render_with_aovs`] of the whole image, for any region and any
/// number of threads: a pixel's samples depend only on the pixel's place
/// in the full image and the sample index (see [`render`]).
///
/// # Errors
/// [`BoundsError::OutOfRange`] if `region` reaches past the image.
pub fn render_region(
    scene: &Scene,
    settings: &RenderSettings,
    region: PixelBounds,
    aovs: &[Aov],
    hooks: RenderHooks<'_>,
) -> Result<(Image, AovImages, RenderStats), BoundsError> {
    let (w, h) = settings.camera.size();
    let region = region.within(w, h)?;
    let (image, passes, _, stats) = render_passes(scene, settings, aovs, Some(region), true, false, hooks);
    Ok((image, passes, stats))
}

/// A render in progress checks its cancel flag every this many samples of
/// one pixel (and before each pixel).
const CANCEL_EVERY: u32 = 1024;

/// The one per-pixel sample loop behind every render: rows in parallel;
/// in each pixel, samples `samples` in increasing order, each camera ray
/// traced for the beauty sum (if `beauty`) and handed to the row's AOV
/// sink (if `aovs` is not empty; it then sees every sample, `samples`
/// being `0..spp`). Returns the per-pixel beauty *sums* (an empty image
/// without `beauty`), one AOV row per image row (empty without `aovs`),
/// and the statistics. Rows skipped or left midway after a cancel hold
/// zero sums and the AOV miss values (under adaptive sampling, a row whose
/// refine pass did not finish too). With a `region`, only its pixels are rendered, into an
/// image (and rows) of its size; each keeps its place in the full image
/// for its camera rays and samples.
/// With `alpha`, the rows' sinks also gather coverage and the
/// premultiplied beauty (from each sample's radiance).
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_pixels<'a>(
    scene: &Scene,
    settings: &RenderSettings,
    samples: Range<u32>,
    region: Option<PixelBounds>,
    beauty: bool,
    aovs: &'a [Aov],
    alpha: bool,
    hooks: RenderHooks<'_>,
) -> (Image, Vec<AovRow<'a>>, RenderStats) {
    let start = std::time::Instant::now();
    let cam = &settings.camera;
    let (w, h) = cam.size();
    let (xs, ys) = match region {
        Some(b) => (b.x0()..b.x1(), b.y0()..b.y1()),
        None => (0..w, 0..h),
    };
    let (rw, rh) = (xs.len() as u32, ys.len() as u32);
    let spp = settings.spp.max(1);
    let pattern = SamplePattern::new(spp);
    let filter = settings.antialias.filter.sampler();
    // Adaptive supersampling needs a pixel's whole run of samples, and AOVs and alpha see every sample.
    let adaptive = settings.antialias.adaptive.filter(|_| {
        beauty && aovs.is_empty() && !alpha && samples == (0..spp) && spp > crate::ADAPTIVE_BASE_SAMPLES
    });
    // Adaptive sampling's base pass: the region and a border of one pixel
    // (within the image), whose means its edge pixels compare with.
    let grow = u32::from(adaptive.is_some());
    let base_cols = xs.start.saturating_sub(grow) as usize..xs.end.saturating_add(grow).min(w) as usize;
    let base_rows = ys.start.saturating_sub(grow) as usize..ys.end.saturating_add(grow).min(h) as usize;
    // Rows the progress counts: adaptive sampling renders its base rows,
    // then refines the region's.
    let all_rows = rh + if adaptive.is_some() { base_rows.len() as u32 } else { 0 };
    let see_through = beauty && Tracer::scene_is_see_through(scene);
    let camera_media = CameraMedia::new(scene, settings);
    let choice = packet_choice(scene, see_through);
    let packets = choice.camera && beauty && aovs.is_empty() && !alpha && adaptive.is_none();
    let rays = AtomicU64::new(0);
    let [camera_rays, shadow_rays, aov_rays_all, packet_rays] = [(); 4].map(|()| AtomicU64::new(0));
    let nonfinite = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let mut pixels = vec![Vec3::ZERO; if beauty { rw as usize * rh as usize } else { 0 }];
    let mut aov_rows: Vec<AovRow<'a>> = if aovs.is_empty() && !alpha {
        Vec::new()
    } else {
        (0..rh).map(|_| AovRow::new(aovs, rw, spp, alpha).starting_at(xs.start)).collect()
    };
    // Row `j` of the full image, its pixels `cols` (`row` holds their sums).
    let render_row = |j: usize,
                      cols: Range<usize>,
                      row: &mut [Vec3],
                      mut sink: Option<&mut AovRow<'a>>,
                      mut pass: Pass<'_>| {
        let cancelled = || hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        // Checked before each pixel and every `CANCEL_EVERY` samples within
        // one, so that a cancel is seen within a moment even when one row
        // takes long (a huge `spp`); a row left midway is dropped whole.
        let sample_check = |s: u32| s % CANCEL_EVERY == CANCEL_EVERY - 1 && cancelled();
        // A row not started is black too: under adaptive sampling, the
        // refine pass's row still holds the base pass's sums.
        let stop = |row: &mut [Vec3], sink: Option<&mut AovRow<'a>>| {
            row.fill(Vec3::ZERO);
            if let Some(sink) = sink {
                *sink = AovRow::new(aovs, rw, spp, alpha).starting_at(xs.start);
            }
        };
        if cancelled() {
            return stop(row, sink);
        }
        let mut stopped = false;
        let mut tracer = Tracer::new(scene, settings, see_through, &camera_media).watching(hooks.cancel);
        tracer.packets = choice.area_shadows;
        let mut bad = 0u64;
        // Camera rays traced for the beauty (fewer than pixels × spp under adaptive sampling).
        let mut traced = 0u64;
        let row_start = j as u64 * u64::from(w);
        if packets && sink.is_none() {
            // The same camera rays in the same order, traced PACKET_SIZE at
            // a time; each sample is shaded and summed as below (bit for bit
            // the same pixels).
            let mut batch = CameraBatch { shadows: choice.camera_shadows, ..CameraBatch::default() };
            let mut sums = vec![DVec3::ZERO; row.len()];
            'pixels: for (k, i) in cols.clone().enumerate() {
                if cancelled() {
                    stopped = true;
                    break;
                }
                let pixel_pattern = pattern.pixel(row_start + i as u64);
                for s in samples.clone() {
                    if sample_check(s) {
                        stopped = true;
                        break 'pixels;
                    }
                    let (dx, dy) = filter.offset(pixel_pattern.offset(s));
                    batch.push(k, cam.ray(i as f32 + dx, j as f32 + dy));
                    if batch.is_full() {
                        batch.flush(scene, &mut tracer, &mut sums, &mut bad, &mut traced);
                    }
                }
            }
            batch.flush(scene, &mut tracer, &mut sums, &mut bad, &mut traced);
            for (px, sum) in row.iter_mut().zip(&sums) {
                *px = sum.as_vec3();
            }
        } else {
            'pixels: for (k, i) in cols.clone().enumerate() {
                if cancelled() {
                    stopped = true;
                    break;
                }
                let index = row_start + i as u64;
                // Summed in f64: past ~10⁵ samples an f32 sum drifts
                // (a constant 0.7 averaged 0.72 over 3 M samples).
                let mut sum = DVec3::ZERO;
                let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                let pixel_pattern = pattern.pixel(index);
                let run = match &pass {
                    Pass::All => samples.clone(),
                    Pass::Base(_) => 0..crate::ADAPTIVE_BASE_SAMPLES,
                    Pass::Refine(refine) => {
                        let Some(px) = row.get_mut(k) else { continue };
                        if !refine.get(k).copied().unwrap_or(false) {
                            // Flat: the base samples' mean stands for all `spp`.
                            *px *= spp as f32 / crate::ADAPTIVE_BASE_SAMPLES as f32;
                            continue;
                        }
                        // The sum goes on from the base samples', in order.
                        sum = px.as_dvec3();
                        crate::ADAPTIVE_BASE_SAMPLES..spp
                    }
                };
                for s in run {
                    if sample_check(s) {
                        stopped = true;
                        break 'pixels;
                    }
                    let (dx, dy) = filter.offset(pixel_pattern.offset(s));
                    let ray = cam.ray(i as f32 + dx, j as f32 + dy);
                    let mut l = Vec3::ZERO;
                    if beauty {
                        l = tracer.trace_camera(&ray);
                        traced += 1;
                        if !l.is_finite() {
                            bad += 1;
                            l = Vec3::ZERO;
                        }
                        sum += l.as_dvec3();
                        if let Pass::Base(_) = pass {
                            let c = l.clamp(Vec3::ZERO, Vec3::ONE);
                            (lo, hi) = (lo.min(c), hi.max(c));
                        }
                    }
                    if let Some(sink) = sink.as_deref_mut() {
                        sink.sample(scene, &ray, l);
                    }
                }
                if let Some(px) = row.get_mut(k) {
                    *px = sum.as_vec3();
                }
                if let Pass::Base(ranges) = &mut pass
                    && let Some(r) = ranges.get_mut(k)
                {
                    *r = [lo, hi];
                }
                if let Some(sink) = sink.as_deref_mut() {
                    sink.end_pixel(scene, cam, i as u32, j as u32);
                }
            }
        }
        // A path given up midway (the tracer saw the cancel) left its pixel
        // unfinished, even where the loops above then ran to the row's end.
        if stopped || tracer.gave_up() {
            // As a row skipped after the cancel: zero sums, the AOV miss values.
            return stop(row, sink);
        }
        let aov_rays = sink.map_or(0, |s| s.rays);
        rays.fetch_add(tracer.rays + aov_rays, Ordering::Relaxed);
        camera_rays.fetch_add(traced, Ordering::Relaxed);
        shadow_rays.fetch_add(tracer.shadow_rays, Ordering::Relaxed);
        packet_rays.fetch_add(tracer.packet_rays, Ordering::Relaxed);
        aov_rays_all.fetch_add(aov_rays, Ordering::Relaxed);
        if bad > 0 {
            nonfinite.fetch_add(bad, Ordering::Relaxed);
        }
        let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(p) = hooks.progress {
            p(done as u32, all_rows);
        }
    };
    let row_len = rw as usize;
    let (x0, y0) = (xs.start as usize, ys.start as usize);
    let cols = x0..xs.end as usize;
    // A row is the unit of work: more workers than rows only wait, and
    // thousands of idle ones cost more than the render (each looks for
    // work in every other's queue).
    let threads = settings.threads.map(|n| n.min(rh.max(1) as usize));
    in_pool(threads, || match (beauty, aov_rows.is_empty()) {
        (true, true) => {
            match adaptive {
                None => {
                    pixels
                        .par_chunks_mut(row_len)
                        .enumerate()
                        .for_each(|(r, row)| render_row(y0 + r, cols.clone(), row, None, Pass::All));
                }
                Some(threshold) => {
                    // The base pass covers a border of one pixel around a
                    // region too, so that its pixels on the edge compare
                    // with the same neighbours as in the full image.
                    let (bx, by) = (base_cols.clone(), base_rows.clone());
                    let mut sums = vec![Vec3::ZERO; bx.len() * by.len()];
                    let mut ranges = vec![[Vec3::ZERO; 2]; sums.len()];
                    sums.par_chunks_mut(bx.len()).zip(ranges.par_chunks_mut(bx.len())).enumerate().for_each(
                        |(r, (row, g))| render_row(by.start + r, bx.clone(), row, None, Pass::Base(g)),
                    );
                    let flags = refine_flags(&sums, &ranges, bx.len(), threshold);
                    drop(ranges);
                    let refine = if sums.len() == pixels.len() {
                        // The whole image: no border, the buffers as they are.
                        pixels = sums;
                        flags
                    } else {
                        let mut refine = Vec::with_capacity(pixels.len());
                        for (r, row) in pixels.chunks_mut(row_len).enumerate() {
                            let from = (y0 - by.start + r) * bx.len() + (x0 - bx.start);
                            row.copy_from_slice(&sums[from..from + row_len]);
                            refine.extend_from_slice(&flags[from..from + row_len]);
                        }
                        refine
                    };
                    pixels.par_chunks_mut(row_len).zip(refine.par_chunks(row_len)).enumerate().for_each(
                        |(r, (row, f))| render_row(y0 + r, cols.clone(), row, None, Pass::Refine(f)),
                    );
                }
            }
        }
        (true, false) => pixels
            .par_chunks_mut(row_len)
            .zip(aov_rows.par_iter_mut())
            .enumerate()
            .for_each(|(r, (row, sink))| render_row(y0 + r, cols.clone(), row, Some(sink), Pass::All)),
        (false, false) => {
            aov_rows
                .par_iter_mut()
                .enumerate()
                .for_each(|(r, sink)| render_row(y0 + r, cols.clone(), &mut [], Some(sink), Pass::All));
        }
        // Nothing asked for.
        (false, true) => {}
    });
    let stats = RenderStats {
        seconds: start.elapsed().as_secs_f64(),
        rays: rays.into_inner(),
        camera_rays: camera_rays.into_inner(),
        shadow_rays: shadow_rays.into_inner(),
        packet_rays: packet_rays.into_inner(),
        aov_rays: aov_rays_all.into_inner(),
        cancelled: hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed)),
        nonfinite_samples: nonfinite.into_inner(),
    };
    (Image { width: rw, height: rh, pixels }, aov_rows, stats)
}

/// What one pass over a row renders of each pixel.
enum Pass<'p> {
    /// Every sample of the render's range.
    All,
    /// Adaptive sampling's base samples, recording each pixel's range of
    /// (clamped) sample colours `[lo, hi]`.
    Base(&'p mut [[Vec3; 2]]),
    /// The rest of the samples of the pixels marked here (their sums go on
    /// from the base samples'); the others' base mean is scaled to `spp`.
    Refine(&'p [bool]),
}

/// POV-Ray's adaptive criterion over the base samples' sums `sums` (rows
/// of `width`) and colour ranges: a pixel takes the rest of its samples
/// when its own samples differ by more than `threshold` in some channel,
/// or when its base mean differs by more than that from one of its eight
/// neighbours' (an edge its own samples happened to miss, such as a
/// horizon crossing the pixel's top few percent). Colours clamped to
/// `[0, 1]`.
fn refine_flags(sums: &[Vec3], ranges: &[[Vec3; 2]], width: usize, threshold: f32) -> Vec<bool> {
    let base = crate::ADAPTIVE_BASE_SAMPLES as f32;
    let mean: Vec<Vec3> = sums.iter().map(|s| (*s / base).clamp(Vec3::ZERO, Vec3::ONE)).collect();
    let height = mean.len().checked_div(width).unwrap_or(0);
    let differs = |a: Vec3, b: Vec3| (a - b).abs().max_element() > threshold;
    (0..mean.len())
        .map(|p| {
            let [lo, hi] = ranges.get(p).copied().unwrap_or([Vec3::ZERO; 2]);
            if differs(hi, lo) {
                return true;
            }
            let (x, y) = (p % width, p / width);
            (y.saturating_sub(1)..(y + 2).min(height)).any(|ny| {
                (x.saturating_sub(1)..(x + 2).min(width))
                    .any(|nx| mean.get(ny * width + nx).is_some_and(|&m| differs(m, mean[p])))
            })
        })
        .collect()
}

/// Which rays a render traces in packets (prism_bvh's `closest_hit_packet`
/// and `occluded_packet`). Only where the scene has mesh instances (else
/// the queries go ray by ray anyway). The image is the same bit for bit in
/// every case; only the speed differs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct PacketChoice {
    /// A pixel row's camera rays, a packet at a time.
    camera: bool,
    /// With them, the shadow rays from a packet's hits toward each point,
    /// spot and directional light, one packet per light
    /// ([`Tracer::camera_shadows`]).
    camera_shadows: bool,
    /// An area light's shadow rays from one shading point.
    area_shadows: bool,
}

/// The packets a render uses. By default, and with
/// `PRISM_PACKETS=camera`: camera rays, which measured 3–18 % faster than
/// single rays on every mesh scene tried (one bunny, the kitchen, a grid of
/// 36 bunny instances, `scenes/mesh.toml`), and in a scene with nothing
/// see-through their hits' shadow rays, which cut the bunny scene's render
/// instructions by 4.4 % (docs/benchmarks.md, issue 11). A see-through
/// scene would trace the occluded ones again for their crossings; that
/// measured 0.6 % more instructions on `scenes/mesh.toml`, so it packs only
/// with `all`. `shadow` packs only an area light's shadow rays, `all`
/// everything, and `0` (or any other value) nothing: area-light shadow
/// packets measured 35 % slower under a quad light.
fn packet_choice(scene: &Scene, see_through: bool) -> PacketChoice {
    if !scene.accel.packets_pay() {
        return PacketChoice::default();
    }
    match std::env::var("PRISM_PACKETS").as_deref() {
        Err(_) | Ok("camera") => {
            PacketChoice { camera: true, camera_shadows: !see_through, area_shadows: false }
        }
        Ok("shadow") => PacketChoice { area_shadows: true, ..PacketChoice::default() },
        Ok("all") => PacketChoice { camera: true, camera_shadows: true, area_shadows: true },
        _ => PacketChoice::default(),
    }
}

/// The values of `PRISM_PACKETS` that the render knows (any
/// other sends every ray alone, as `0` does), for a front end to check;
/// keep the two together.
pub const PACKET_MODES: [&str; 4] = ["camera", "shadow", "all", "0"];

/// Camera rays waiting to be traced together, with the row pixel each
/// belongs to.
#[derive(Default)]
struct CameraBatch {
    rays: Vec<Ray>,
    pixel: Vec<usize>,
    hits: Vec<Option<prism_bvh::SceneHit>>,
    /// Per ray, its hit's shadows traced beforehand (when `shadows`).
    pre: Vec<[PreShadow; PRE_LIGHTS]>,
    /// Trace the hits' shadow rays toward each point, spot and
    /// directional light together ([`Tracer::camera_shadows`]).
    shadows: bool,
}

impl CameraBatch {
    fn push(&mut self, pixel: usize, ray: Ray) {
        self.rays.push(ray);
        self.pixel.push(pixel);
    }

    fn is_full(&self) -> bool {
        self.rays.len() >= prism_bvh::PACKET_SIZE
    }

    /// Traces the waiting rays as one packet and adds each one's radiance
    /// to its pixel's sum in `row`, in the order they came (a non-finite
    /// radiance counts in `bad` and adds nothing).
    fn flush(
        &mut self,
        scene: &Scene,
        tracer: &mut Tracer<'_>,
        row: &mut [DVec3],
        bad: &mut u64,
        traced: &mut u64,
    ) {
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        scene.accel.closest_hit_packet(&self.rays, &mut self.hits);
        tracer.packet_rays += self.rays.len() as u64;
        self.pre.clear();
        self.pre.resize(self.rays.len(), [PreShadow::Unknown; PRE_LIGHTS]);
        if self.shadows {
            tracer.camera_shadows(&self.hits, &mut self.pre);
        }
        for (((ray, &k), hit), &pre) in self.rays.iter().zip(&self.pixel).zip(&self.hits).zip(&self.pre) {
            let mut l = tracer.trace_camera_hit(ray, *hit, pre);
            *traced += 1;
            if !l.is_finite() {
                *bad += 1;
                l = Vec3::ZERO;
            }
            if let Some(px) = row.get_mut(k) {
                *px += l.as_dvec3();
            }
        }
        self.rays.clear();
        self.pixel.clear();
    }
}

/// Runs `f` on a pool of `threads` workers (`None`: the global pool, every
/// core; a pool that cannot be built falls back to the global one): the
/// writers ([`crate::write_png`]) run in parallel on the pool they are
/// called on, so a caller that limits the render's threads limits theirs
/// the same way.
pub fn in_pool<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
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
/// [`render`] (and [`crate::render_aovs`]) passes to [`crate::Camera::ray`]
/// under the box filter (other filters map the offset within the pixel
/// through [`crate::FilterSampler::offset`]).
/// It lies in `[i, i + 1) × [j, j + 1)`; with `spp = 1` it is the pixel
/// centre `(i + 0.5, j + 0.5)`. See [`render`] for the pattern.
#[must_use]
pub fn sample_position(spp: u32, width: u32, i: u32, j: u32, s: u32) -> (f32, f32) {
    let (dx, dy) = SamplePattern::new(spp).offset(u64::from(j) * u64::from(width) + u64::from(i), s);
    (i as f32 + dx, j as f32 + dy)
}

/// The stratified, hashed sample positions within a pixel.
#[derive(Clone, Debug)]
pub(crate) struct SamplePattern {
    /// Strata per side (`⌈√spp⌉`); 0 means "pixel centre only" (spp = 1).
    m: u32,
    /// Number of strata, `m²`.
    strata: u32,
    /// Step through the strata, coprime with `strata`.
    stride: u32,
    /// The bit mask of the permutation ([`permute_keyed`]) for `m` items.
    mask: u32,
    /// The stratum `(column, row)` of sample `s`, for `s` below its length
    /// (at most [`STRATUM_TABLE`]); later samples compute theirs.
    cells: Vec<(u32, u32)>,
}

/// Longest table of sample strata kept by a [`SamplePattern`].
const STRATUM_TABLE: u32 = 4096;

/// Most strata a side whose permutations a [`PixelPattern`] tabulates
/// (256 spp); beyond it each sample computes its own.
const PERM_TABLE: usize = 16;

impl SamplePattern {
    pub(crate) fn new(spp: u32) -> Self {
        let spp = spp.max(1);
        if spp == 1 {
            return Self { m: 0, strata: 1, stride: 1, mask: 0, cells: Vec::new() };
        }
        let mut m = (spp as f64).sqrt().ceil() as u32;
        while m.saturating_mul(m) < spp {
            m += 1;
        }
        let strata = m.saturating_mul(m);
        let mut pattern =
            Self { m, strata, stride: golden_stride(strata), mask: permute_mask(m), cells: Vec::new() };
        pattern.cells = (0..strata.min(STRATUM_TABLE)).map(|s| pattern.stratum(s)).collect();
        pattern
    }

    /// The stratum `(column, row)` of sample `s` (`m > 0`).
    #[inline]
    fn stratum(&self, s: u32) -> (u32, u32) {
        let k = ((u64::from(s) * u64::from(self.stride)) % u64::from(self.strata)) as u32;
        (k % self.m, k / self.m)
    }

    /// The pattern of pixel number `pixel`: its permutation keys, computed
    /// once for all of its samples.
    #[inline]
    pub(crate) fn pixel(&self, pixel: u64) -> PixelPattern<'_> {
        let p = splitmix64(pixel ^ 0x2545_F491_4F6C_DD1D) as u32;
        let (kx, ky) = (p.wrapping_mul(0xa511_e9b3), p.wrapping_mul(0x63d8_3595));
        let m = self.m.max(1);
        let (rx, ry) = (kx % m, ky % m);
        // Every sample of the pixel permutes its column and its row: with
        // few strata a side, permute each column and row once here.
        let mut perm = [[0u8; PERM_TABLE]; 2];
        if self.m as usize <= PERM_TABLE {
            for i in 0..self.m {
                perm[0][i as usize] = permute_keyed(i, self.m, self.mask, kx, rx) as u8;
                perm[1][i as usize] = permute_keyed(i, self.m, self.mask, ky, ry) as u8;
            }
        }
        PixelPattern { pattern: self, seed: (pixel << 32) ^ 0x5851_F42D_4C95_7F2D, kx, ky, rx, ry, perm }
    }

    /// Offset of sample `s` of pixel number `pixel` inside its pixel, in `[0, 1)²`.
    #[inline]
    pub(crate) fn offset(&self, pixel: u64, s: u32) -> (f32, f32) {
        self.pixel(pixel).offset(s)
    }
}

/// One pixel's [`SamplePattern`]: the hash seed and permutation keys that
/// all of its samples share.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PixelPattern<'a> {
    pattern: &'a SamplePattern,
    /// `(pixel << 32) ^ constant`: sample `s` hashes `seed ^ s`.
    seed: u64,
    /// The keys of the column and row permutations, and each modulo `m`.
    kx: u32,
    ky: u32,
    rx: u32,
    ry: u32,
    /// The column (`[0]`) and row (`[1]`) permutations of `0..m`, when
    /// `m ≤ PERM_TABLE`.
    perm: [[u8; PERM_TABLE]; 2],
}

impl PixelPattern<'_> {
    /// Offset of sample `s` inside the pixel, in `[0, 1)²`.
    #[inline]
    pub(crate) fn offset(&self, s: u32) -> (f32, f32) {
        let pat = self.pattern;
        if pat.m == 0 {
            return (0.5, 0.5);
        }
        let (sx, sy) = match pat.cells.get(s as usize) {
            Some(&cell) => cell,
            None => pat.stratum(s),
        };
        let z = splitmix64(self.seed ^ u64::from(s));
        let jx = (z >> 40) as f32 * (1.0 / 16_777_216.0);
        let jy = ((z >> 16) & 0xFF_FFFF) as f32 * (1.0 / 16_777_216.0);
        // Kensler's correlated multi-jitter: within its stratum, the sample
        // sits in the sub-column given by its row and the sub-row given by
        // its column, each through a per-pixel permutation, so that the
        // samples of a full grid are also stratified in x and in y alone.
        let (px, py) = if pat.m as usize <= PERM_TABLE {
            (
                u32::from(self.perm[0][sx as usize % PERM_TABLE]),
                u32::from(self.perm[1][sy as usize % PERM_TABLE]),
            )
        } else {
            (
                permute_keyed(sx, pat.m, pat.mask, self.kx, self.rx),
                permute_keyed(sy, pat.m, pat.mask, self.ky, self.ry),
            )
        };
        let m = pat.m as f32;
        let below_one = 1.0 - f32::EPSILON / 2.0;
        let x = (sx as f32 + (py as f32 + jx) / m) / m;
        let y = (sy as f32 + (px as f32 + jy) / m) / m;
        (x.min(below_one), y.min(below_one))
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

/// Kensler's hashed permutation of `0..len` ("Correlated Multi-Jittered
/// Sampling", Pixar 2013): element `i` of the permutation keyed by `key`.
#[cfg(test)]
fn permute(i: u32, len: u32, key: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    permute_keyed(i, len, permute_mask(len), key, key % len)
}

/// The mask of [`permute_keyed`] for `len` items: `len − 1` with every bit
/// below its highest set.
fn permute_mask(len: u32) -> u32 {
    let mut w = len.saturating_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    w
}

/// Kensler's permutation (the test-only `permute`) with its per-key parts
/// given: `w = permute_mask(len)` and `rem = key % len`; `i < len`.
#[inline]
fn permute_keyed(mut i: u32, len: u32, w: u32, key: u32, rem: u32) -> u32 {
    if len <= 1 {
        return 0;
    }
    loop {
        i ^= key;
        i = i.wrapping_mul(0xe170_893d);
        i ^= key >> 16;
        i ^= (i & w) >> 4;
        i ^= key >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= key >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | key >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            // (i + rem) % len, both below len.
            let j = i + rem;
            return if j >= len { j - len } else { j };
        }
    }
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
    fn refine_flags_follow_own_range_and_neighbours() {
        let b = crate::ADAPTIVE_BASE_SAMPLES as f32;
        let flat = [Vec3::splat(0.5); 2];
        // 4×3 pixels of grey 0.5; pixel (3, 0) is white: itself and its
        // neighbours (2, 0), (2, 1), (3, 1) are refined, the rest not.
        let mut sums = vec![Vec3::splat(0.5 * b); 12];
        sums[3] = Vec3::splat(b);
        let ranges = [flat; 12];
        let f = refine_flags(&sums, &ranges, 4, 0.1);
        let on: Vec<usize> = (0..12).filter(|&p| f[p]).collect();
        assert_eq!(on, vec![2, 3, 6, 7]);
        // A pixel whose own samples differ, among flat neighbours.
        let mut ranges = [flat; 12];
        ranges[9] = [Vec3::splat(0.2), Vec3::splat(0.5)];
        let f = refine_flags(&[Vec3::splat(0.5 * b); 12], &ranges, 4, 0.1);
        assert_eq!((0..12).filter(|&p| f[p]).collect::<Vec<_>>(), vec![9]);
        // Differences under the threshold refine nothing; colours are
        // clamped to [0, 1] first (3 and 5 both count as 1).
        let mut sums = vec![Vec3::splat(0.5 * b); 12];
        sums[11] = Vec3::splat(0.55 * b);
        sums[0] = Vec3::splat(3.0 * b);
        sums[1] = Vec3::splat(5.0 * b);
        let f = refine_flags(&sums, &[flat; 12], 4, 0.1);
        assert!(!f[7] && !f[10] && !f[11], "0.05 apart, under the threshold");
        assert!(f[0] && f[1] && f[4] && f[5], "1 against 0.5");
        assert!(!f[8]);
        let f = refine_flags(&[Vec3::splat(3.0 * b), Vec3::splat(5.0 * b)], &[flat; 2], 2, 0.1);
        assert_eq!(f, [false, false], "3 and 5 both clamp to 1");
    }

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

    /// A full grid of `m²` samples is also stratified along each axis
    /// alone into `m²` strips (n-rooks), in every pixel.
    #[test]
    fn full_grids_are_multi_jittered() {
        for m in [2u32, 3, 4, 7, 16] {
            let spp = m * m;
            let p = SamplePattern::new(spp);
            for pixel in [0u64, 1, 99, 123_456] {
                let mut cols = vec![false; spp as usize];
                let mut rows = vec![false; spp as usize];
                for s in 0..spp {
                    let (x, y) = p.offset(pixel, s);
                    let (c, r) = ((x * spp as f32) as usize, (y * spp as f32) as usize);
                    assert!(!cols[c] && !rows[r], "m {m} pixel {pixel}: strip taken twice");
                    (cols[c], rows[r]) = (true, true);
                }
            }
        }
    }

    /// The per-pixel permutation table gives the offsets that permuting
    /// each sample's column and row does (`m` = 2 … 16 tabulated, 17 not).
    #[test]
    fn tabulated_permutations_match_the_computed_ones() {
        for spp in [2u32, 4, 9, 16, 100, 256, 257, 289] {
            let p = SamplePattern::new(spp);
            for pixel in [0u64, 5, 4_000_000_007] {
                let pp = p.pixel(pixel);
                for s in 0..spp {
                    let (sx, sy) = p.stratum(s);
                    let z = splitmix64(pp.seed ^ u64::from(s));
                    let jx = (z >> 40) as f32 * (1.0 / 16_777_216.0);
                    let jy = ((z >> 16) & 0xFF_FFFF) as f32 * (1.0 / 16_777_216.0);
                    let (px, py) = (permute(sx, p.m, pp.kx), permute(sy, p.m, pp.ky));
                    let m = p.m as f32;
                    let below_one = 1.0 - f32::EPSILON / 2.0;
                    let x = ((sx as f32 + (py as f32 + jx) / m) / m).min(below_one);
                    let y = ((sy as f32 + (px as f32 + jy) / m) / m).min(below_one);
                    assert_eq!(pp.offset(s), (x, y), "spp {spp} pixel {pixel} sample {s}");
                }
            }
        }
    }

    #[test]
    fn permutations_are_bijections() {
        for len in [1u32, 2, 3, 5, 16, 17, 256] {
            for key in [0u32, 1, 0xdead_beef, u32::MAX] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, key) as usize;
                    assert!(!seen[j]);
                    seen[j] = true;
                }
            }
        }
    }
}
