//! The renderer: tiles in parallel, deterministic per-pixel samples.
//!
//! (Placeholder integrator: normal shading only; the Whitted integrator
//! replaces `radiance` without changing this API.)

use crate::Scene;
use prism_geometry::glam::Vec3;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// How to render. No `Default`: every caller states its settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel (stratified), at least 1.
    pub spp: u32,
    /// Maximum recursion depth of reflection/refraction rays.
    pub max_depth: u32,
    /// Rays whose weight on the pixel falls below this are not traced.
    pub min_contribution: f32,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
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
}

/// Renders the whole image with `settings.spp` samples per pixel.
pub fn render(scene: &Scene, settings: &RenderSettings, hooks: RenderHooks<'_>) -> (Image, RenderStats) {
    let (mut image, stats) = render_samples(scene, settings, 0..settings.spp.max(1), hooks);
    let inv = 1.0 / settings.spp.max(1) as f32;
    for p in &mut image.pixels {
        *p *= inv;
    }
    (image, stats)
}

/// Renders samples `samples` (of `settings.spp` per pixel) and returns the
/// per-pixel *sums*, so that passes over disjoint ranges add up to the full
/// render exactly (progressive refinement in the viewer).
pub fn render_samples(
    scene: &Scene,
    settings: &RenderSettings,
    samples: Range<u32>,
    hooks: RenderHooks<'_>,
) -> (Image, RenderStats) {
    let start = std::time::Instant::now();
    let cam = &scene.camera;
    let (w, h) = (cam.width(), cam.height());
    let rays = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let mut pixels = vec![Vec3::ZERO; w as usize * h as usize];
    let work = |pixels: &mut [Vec3]| {
        pixels.par_chunks_mut(w as usize).enumerate().for_each(|(j, row)| {
            if hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return;
            }
            for (i, px) in row.iter_mut().enumerate() {
                for _s in samples.clone() {
                    let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
                    rays.fetch_add(1, Ordering::Relaxed);
                    *px += match scene.accel.closest_hit(&ray) {
                        Some(h) => 0.5 * (h.hit.normal + Vec3::ONE),
                        None => scene.background,
                    };
                }
            }
            let done = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
            if let Some(p) = hooks.progress {
                p(done as u32, h);
            }
        });
    };
    match settings.threads {
        Some(n) => match rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build() {
            Ok(pool) => pool.install(|| work(&mut pixels)),
            Err(_) => work(&mut pixels),
        },
        None => work(&mut pixels),
    }
    let cancelled = hooks.cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    let stats = RenderStats { seconds: start.elapsed().as_secs_f64(), rays: rays.into_inner(), cancelled };
    (Image { width: w, height: h, pixels }, stats)
}
