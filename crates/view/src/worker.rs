//! The render thread: takes [`View`]s, renders a coarse preview and then
//! refinement passes, and sends [`Frame`]s back. It never blocks the caller.
//!
//! A new view (or scene) cancels the passes in flight through the shared
//! cancel flag, which `render_samples` checks at every row. The scene is
//! only read: a view's camera, fog flag and samples are its
//! [`RenderSettings`].

use crate::ViewError;
use crate::state::{SamplePlan, View};
use prism_geometry::glam::DVec3;
use prism_shade::{Image, RenderHooks, RenderSettings, Scene, linear_to_srgb8, render_samples};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The coarse preview aims at about this many pixels (800×600 / 16).
const COARSE_TARGET_PIXELS: u64 = 30_000;
/// A coarse preview slower than this coarsens the next one.
const COARSE_SLOW_SECS: f64 = 0.040;
/// A coarse preview faster than this refines the next one.
const COARSE_FAST_SECS: f64 = 0.008;
/// The coarsest preview: one pixel per this many in each direction.
const MAX_COARSE_FACTOR: u32 = 16;
/// After the first full-size pass, frames are sent at most this often (and
/// at the last pass): converting and showing every pass would cost more
/// than it shows.
const FRAME_INTERVAL: Duration = Duration::from_millis(120);

/// What a frame shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameKind {
    /// The quick preview: one sample per pixel on a grid `factor` times
    /// coarser in each direction, upscaled.
    Coarse {
        /// The downscaling factor.
        factor: u32,
    },
    /// The mean of the first `samples_done` samples per pixel of the full
    /// image (one sample per refinement pass).
    Pass {
        /// Samples per pixel accumulated.
        samples_done: u32,
        /// Refinement passes since the previous frame of this view.
        passes: u32,
    },
}

/// An image ready for the window.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The generation of the view it shows.
    pub generation: u64,
    /// Preview or refinement pass.
    pub kind: FrameKind,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major `0x00RRGGBB`, sRGB-encoded.
    pub pixels: Vec<u32>,
    /// Seconds the rendering since the previous frame of this view took.
    pub seconds: f64,
}

impl Frame {
    /// Whether the frame has every sample of its view.
    #[must_use]
    pub fn is_final(&self, spp: u32) -> bool {
        matches!(self.kind, FrameKind::Pass { samples_done, .. } if samples_done >= spp.max(1))
    }
}

/// A request to the render thread.
struct Job {
    view: View,
    scene: Option<Arc<Scene>>,
}

#[derive(Default)]
struct Slot {
    job: Option<Job>,
    shutdown: bool,
}

struct Shared {
    slot: Mutex<Slot>,
    wake: Condvar,
    cancel: AtomicBool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// Owner of the render thread. Dropping it cancels the work in flight and
/// joins the thread.
pub struct Renderer {
    shared: Arc<Shared>,
    frames: Receiver<Frame>,
    thread: Option<JoinHandle<()>>,
}

impl Renderer {
    /// Starts the render thread over `scene` with `threads` workers
    /// (`None`: every core). Nothing is rendered until [`Renderer::submit`].
    ///
    /// # Errors
    /// [`ViewError::Threads`] if the thread pool or thread cannot start.
    pub fn new(scene: Scene, threads: Option<usize>) -> Result<Self, ViewError> {
        let mut pool = rayon::ThreadPoolBuilder::new().thread_name(|i| format!("prism-view-render-{i}"));
        if let Some(n) = threads {
            pool = pool.num_threads(n.max(1));
        }
        let pool = pool.build().map_err(|e| ViewError::Threads(e.to_string()))?;
        let shared = Arc::new(Shared {
            slot: Mutex::new(Slot::default()),
            wake: Condvar::new(),
            cancel: AtomicBool::new(false),
        });
        let (tx, frames) = mpsc::channel();
        let worker = Worker { shared: Arc::clone(&shared), tx, scene: Arc::new(scene), coarse_factor: 0 };
        let thread = std::thread::Builder::new()
            .name("prism-view-render".into())
            .spawn(move || pool.install(move || worker.run()))
            .map_err(|e| ViewError::Threads(e.to_string()))?;
        Ok(Self { shared, frames, thread: Some(thread) })
    }

    /// Renders `view` from now on, cancelling whatever was in flight.
    pub fn submit(&self, view: View) {
        self.send(Job { view, scene: None });
    }

    /// Renders `view` of a new `scene` from now on, cancelling whatever was
    /// in flight.
    pub fn submit_scene(&self, view: View, scene: Scene) {
        self.send(Job { view, scene: Some(Arc::new(scene)) });
    }

    fn send(&self, job: Job) {
        let mut slot = self.shared.lock();
        slot.job = Some(job);
        // Under the lock, so the worker clears it only when it takes this job.
        self.shared.cancel.store(true, Ordering::Relaxed);
        drop(slot);
        self.shared.wake.notify_all();
    }

    /// Whether the render thread still runs (false after a panic in it).
    #[must_use]
    pub fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// The next finished frame, if one is waiting (never blocks).
    #[must_use]
    pub fn try_frame(&self) -> Option<Frame> {
        self.frames.try_recv().ok()
    }

    /// The next finished frame, waiting at most `timeout`.
    #[must_use]
    pub fn frame_timeout(&self, timeout: Duration) -> Option<Frame> {
        self.frames.recv_timeout(timeout).ok()
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        let mut slot = self.shared.lock();
        slot.shutdown = true;
        self.shared.cancel.store(true, Ordering::Relaxed);
        drop(slot);
        self.shared.wake.notify_all();
        if let Some(t) = self.thread.take() {
            // A panic in the worker has already been reported; nothing to add.
            let _ = t.join();
        }
    }
}

struct Worker {
    shared: Arc<Shared>,
    tx: Sender<Frame>,
    /// Shared and read-only: a view changes only its settings.
    scene: Arc<Scene>,
    /// 0 until the first preview picks one.
    coarse_factor: u32,
}

impl Worker {
    fn run(mut self) {
        while let Some(job) = self.next_job() {
            if let Some(scene) = job.scene {
                self.scene = scene;
            }
            if self.render_view(&job.view).is_err() {
                // The window is gone.
                return;
            }
        }
    }

    /// Waits for the next job; `None` on shutdown.
    fn next_job(&self) -> Option<Job> {
        let mut slot = self.shared.lock();
        loop {
            if slot.shutdown {
                return None;
            }
            if let Some(job) = slot.job.take() {
                self.shared.cancel.store(false, Ordering::Relaxed);
                return Some(job);
            }
            slot = self.shared.wake.wait(slot).unwrap_or_else(PoisonError::into_inner);
        }
    }

    fn cancelled(&self) -> bool {
        self.shared.cancel.load(Ordering::Relaxed)
    }

    /// Renders one view to the end, or until cancelled. `Err` when the
    /// receiver is gone.
    fn render_view(&mut self, view: &View) -> Result<(), mpsc::SendError<Frame>> {
        let (w, h) = view.settings.camera.size();
        let hooks = RenderHooks { progress: None, cancel: Some(&self.shared.cancel) };

        // Inside our own pool already: a render must not build another.
        let settings = RenderSettings { threads: None, ..view.settings.clone() };

        // The coarse preview.
        if self.coarse_factor == 0 {
            self.coarse_factor = initial_coarse_factor(w, h);
        }
        let factor = self.coarse_factor;
        if factor > 1 {
            let (cw, ch) = (w.div_ceil(factor), h.div_ceil(factor));
            if let Ok(small) = settings.with_size(cw, ch) {
                let one = RenderSettings { spp: 1, ..small };
                let (image, stats) = render_samples(&self.scene, &one, 0..1, hooks);
                if stats.cancelled || self.cancelled() {
                    return Ok(());
                }
                self.coarse_factor = adapt_coarse_factor(factor, stats.seconds, initial_coarse_factor(w, h));
                let pixels = upscale(&to_pixels(&image, 1.0), cw, ch, w, h);
                let kind = FrameKind::Coarse { factor };
                let generation = view.generation;
                self.tx.send(Frame {
                    generation,
                    kind,
                    width: w,
                    height: h,
                    pixels,
                    seconds: stats.seconds,
                })?;
            }
        }

        // Refinement passes at full size, one sample each.
        let spp = settings.spp.max(1);
        let mut acc = Accumulator::new(w, h);
        let mut since = Instant::now();
        let mut passes = 0;
        for range in SamplePlan::new(spp) {
            if self.cancelled() {
                return Ok(());
            }
            let (image, stats) = render_samples(&self.scene, &settings, range.clone(), hooks);
            if stats.cancelled || self.cancelled() {
                return Ok(());
            }
            acc.add(&image, range.end);
            passes += 1;
            if acc.samples == 1 || acc.samples >= spp || since.elapsed() >= FRAME_INTERVAL {
                // `render` scales the sums by this same f32 factor.
                let pixels = to_pixels(&acc.sum(), 1.0 / acc.samples as f32);
                let kind = FrameKind::Pass { samples_done: acc.samples, passes };
                let seconds = since.elapsed().as_secs_f64();
                self.tx.send(Frame {
                    generation: view.generation,
                    kind,
                    width: w,
                    height: h,
                    pixels,
                    seconds,
                })?;
                since = Instant::now();
                passes = 0;
            }
        }
        Ok(())
    }
}

/// The first preview factor: about [`COARSE_TARGET_PIXELS`] pixels, at
/// least 1.
fn initial_coarse_factor(w: u32, h: u32) -> u32 {
    let mut f = 1;
    while f < MAX_COARSE_FACTOR && u64::from(w.div_ceil(f)) * u64::from(h.div_ceil(f)) > COARSE_TARGET_PIXELS
    {
        f *= 2;
    }
    f
}

/// Coarsens the preview after a slow one, refines it after a fast one, but
/// never below `finest` (the initial factor: the preview is there to be
/// quick, the first full pass follows at once).
fn adapt_coarse_factor(factor: u32, seconds: f64, finest: u32) -> u32 {
    if seconds > COARSE_SLOW_SECS {
        (factor * 2).min(MAX_COARSE_FACTOR)
    } else if seconds < COARSE_FAST_SECS && factor > finest {
        factor / 2
    } else {
        factor
    }
}

/// Running per-pixel sums of refinement passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    width: u32,
    height: u32,
    /// Per-pixel sums of every sample so far, in f64 as `render` sums a
    /// pixel's samples: passes of one sample each, added in order, give
    /// its sums bit for bit.
    sums: Vec<DVec3>,
    /// Samples per pixel summed.
    pub samples: u32,
}

impl Accumulator {
    /// An empty accumulator for a `w × h` image.
    #[must_use]
    pub fn new(w: u32, h: u32) -> Self {
        Self { width: w, height: h, sums: vec![DVec3::ZERO; w as usize * h as usize], samples: 0 }
    }

    /// Adds a pass of per-pixel sums; `samples_done` is the number of
    /// samples per pixel summed after it.
    pub fn add(&mut self, pass: &Image, samples_done: u32) {
        for (a, p) in self.sums.iter_mut().zip(&pass.pixels) {
            *a += p.as_dvec3();
        }
        self.samples = samples_done;
    }

    /// The per-pixel sums so far, rounded to f32 (as `render_samples`
    /// returns them).
    #[must_use]
    pub fn sum(&self) -> Image {
        Image {
            width: self.width,
            height: self.height,
            pixels: self.sums.iter().map(|p| p.as_vec3()).collect(),
        }
    }

    /// The mean image so far (as `render` returns it once complete).
    #[must_use]
    pub fn mean(&self) -> Image {
        let inv = 1.0 / self.samples.max(1) as f32;
        Image {
            width: self.width,
            height: self.height,
            pixels: self.sums.iter().map(|p| p.as_vec3() * inv).collect(),
        }
    }
}

/// `0x00RRGGBB` sRGB pixels of `image` scaled by `scale` (exactly as
/// [`Image::to_srgb8`] encodes the scaled values).
#[must_use]
pub fn to_pixels(image: &Image, scale: f32) -> Vec<u32> {
    image
        .pixels
        .par_iter()
        .with_min_len(4096)
        .map(|p| {
            let [r, g, b] = (*p * scale).to_array().map(|c| u32::from(linear_to_srgb8(c)));
            (r << 16) | (g << 8) | b
        })
        .collect()
}

/// Nearest-neighbour upscaling of a `sw × sh` image to `w × h`.
#[must_use]
pub fn upscale(small: &[u32], sw: u32, sh: u32, w: u32, h: u32) -> Vec<u32> {
    let (sw, sh, w, h) = (sw as usize, sh as usize, w as usize, h as usize);
    let mut out = vec![0; w * h];
    if sw == 0 || sh == 0 || small.len() < sw * sh {
        return out;
    }
    let cols: Vec<usize> = (0..w).map(|x| (x * sw / w).min(sw - 1)).collect();
    for (y, row) in out.chunks_mut(w).enumerate() {
        let src = &small[(y * sh / h).min(sh - 1) * sw..][..sw];
        for (px, &sx) in row.iter_mut().zip(&cols) {
            *px = src[sx];
        }
    }
    out
}

/// The RGB8 bytes of `0x00RRGGBB` pixels.
#[must_use]
pub fn pixels_to_rgb8(pixels: &[u32]) -> Vec<u8> {
    pixels.iter().flat_map(|p| [(p >> 16) as u8, (p >> 8) as u8, *p as u8]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::demo_scene;
    use prism_shade::render;

    const WAIT: Duration = Duration::from_secs(60);

    fn small_view(generation: u64, fog: bool, spp: u32) -> (Scene, View) {
        let setup = demo_scene(64, 48).unwrap();
        let settings = RenderSettings { spp, fog, threads: Some(2), ..setup.settings };
        let view = View { generation, settings };
        (setup.scene, view)
    }

    /// Frames until the final one of `generation`; panics (fails) after [`WAIT`].
    fn until_final(r: &Renderer, generation: u64, spp: u32) -> Vec<Frame> {
        let mut frames = Vec::new();
        loop {
            let f = r.frame_timeout(WAIT).expect("the renderer stalled");
            let done = f.generation == generation && f.is_final(spp);
            frames.push(f);
            if done {
                return frames;
            }
        }
    }

    #[test]
    fn passes_sum_to_the_full_render() {
        for spp in [1, 3, 4, 13] {
            let (scene, view) = small_view(1, true, spp);
            let (full, _) = render(&scene, &view.settings, RenderHooks::default());
            let mut acc = Accumulator::new(64, 48);
            for range in SamplePlan::new(spp) {
                let (pass, stats) =
                    render_samples(&scene, &view.settings, range.clone(), RenderHooks::default());
                assert!(!stats.cancelled);
                acc.add(&pass, range.end);
            }
            assert_eq!(acc.samples, spp);
            // Bit for bit.
            assert!(acc.mean() == full, "spp {spp}: the refined image differs from render's");
        }
    }

    #[test]
    fn renderer_previews_then_converges_to_render() {
        let spp = 4;
        let (scene, view) = small_view(7, true, spp);
        let reference_scene = small_view(7, true, spp).0;
        let (full, _) = render(&reference_scene, &view.settings, RenderHooks::default());
        let r = Renderer::new(scene, Some(2)).unwrap();
        r.submit(view);
        let frames = until_final(&r, 7, spp);
        // 64×48 is below the preview size: no coarse frame. The first pass
        // is shown at once; then frames as time goes, the last pass always.
        assert_eq!(frames[0].kind, FrameKind::Pass { samples_done: 1, passes: 1 });
        let mut done = 0;
        let mut passes = 0;
        for f in &frames {
            let FrameKind::Pass { samples_done, passes: p } = f.kind else { panic!("{:?}", f.kind) };
            assert!(samples_done > done);
            passes += p;
            assert_eq!(passes, samples_done);
            done = samples_done;
        }
        assert_eq!(done, spp);
        // Exactly what `prism render` writes.
        assert_eq!(frames.last().unwrap().pixels, to_pixels(&full, 1.0));
    }

    #[test]
    fn a_large_view_gets_a_coarse_preview_first() {
        let setup = demo_scene(320, 240).unwrap();
        let settings = RenderSettings { spp: 1, fog: false, threads: Some(2), ..setup.settings };
        let view = View { generation: 1, settings };
        let r = Renderer::new(setup.scene, Some(2)).unwrap();
        r.submit(view);
        let frames = until_final(&r, 1, 1);
        assert!(matches!(frames[0].kind, FrameKind::Coarse { factor: 2 }), "{:?}", frames[0].kind);
        assert_eq!(frames[0].pixels.len(), 320 * 240);
        assert_eq!(frames.len(), 2);
    }

    #[test]
    fn a_new_view_cancels_the_stale_one() {
        // A view that would take very long, then a change.
        let (scene, slow) = small_view(1, true, 100_000);
        let r = Renderer::new(scene, Some(2)).unwrap();
        r.submit(slow);
        let first = r.frame_timeout(WAIT).expect("a first frame");
        assert_eq!(first.generation, 1);
        let fast = View { generation: 2, settings: small_view(0, false, 2).1.settings };
        r.submit(fast);
        let frames = until_final(&r, 2, 2);
        let mut seen_new = false;
        for f in &frames {
            if f.generation == 2 {
                seen_new = true;
            } else {
                assert!(!seen_new, "a stale frame after the new view started");
                assert!(!f.is_final(100_000), "the stale view ran to the end");
            }
        }
        // And nothing more comes for the stale view.
        assert!(r.frame_timeout(Duration::from_millis(100)).is_none());
    }

    #[test]
    fn scene_replacement_and_fog_toggle_change_the_image() {
        let (scene, on) = small_view(1, true, 1);
        let r = Renderer::new(scene, Some(2)).unwrap();
        r.submit(on.clone());
        let with_fog = until_final(&r, 1, 1).pop().unwrap();
        r.submit(View { generation: 2, settings: RenderSettings { fog: false, ..on.settings.clone() } });
        let without = until_final(&r, 2, 1).pop().unwrap();
        let (same, _) = small_view(0, true, 1);
        r.submit_scene(View { generation: 3, ..on.clone() }, same);
        let again = until_final(&r, 3, 1).pop().unwrap();
        assert_eq!(again.pixels, with_fog.pixels, "same scene and view, same image");
        assert_ne!(without.pixels, with_fog.pixels, "fog off shows");
        // Another scene (the same without its lights) is the one rendered
        // from then on: its image, not the old one's.
        let (mut other, _) = small_view(0, true, 1);
        other.lights.clear();
        let expected = to_pixels(&render(&other, &on.settings, RenderHooks::default()).0, 1.0);
        r.submit_scene(View { generation: 4, ..on }, other);
        let replaced = until_final(&r, 4, 1).pop().unwrap();
        assert!(replaced.pixels != with_fog.pixels, "the new scene shows");
        assert!(replaced.pixels == expected, "and is rendered as `render` renders it");
    }

    /// A change while a refinement pass is running at 800×600 shows first
    /// as a coarse preview of the new view (the stale pass is abandoned,
    /// not finished first), and every frame comes within [`WAIT`]. Also
    /// prints how long each change took to show, from `submit` to the
    /// first frame of the new view (measured, not asserted). On
    /// `scenes/seed.toml` when it exists, else on the built-in scene.
    #[test]
    fn change_to_first_frame_latency_at_800x600() {
        let seed = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml");
        let (setup, name) = if seed.is_file() {
            let overrides = prism_scene::Overrides {
                width: Some(800),
                height: Some(600),
                ..prism_scene::Overrides::default()
            };
            let opts = crate::ViewOptions { overrides, ..crate::ViewOptions::new(&seed) };
            (crate::load_scene_file(&seed, &opts).unwrap(), "seed.toml")
        } else {
            (demo_scene(800, 600).unwrap(), "built-in scene")
        };
        let settings = RenderSettings { spp: 64, fog: true, threads: None, ..setup.settings };
        let r = Renderer::new(setup.scene, None).unwrap();
        r.submit(View { generation: 1, settings: settings.clone() });
        let mut times = Vec::new();
        for generation in 2..=5u64 {
            // Let a full-size pass get going, then toggle the fog.
            loop {
                let f = r.frame_timeout(WAIT).expect("a frame of the running view");
                if f.generation == generation - 1 && matches!(f.kind, FrameKind::Pass { .. }) {
                    break;
                }
            }
            std::thread::sleep(Duration::from_millis(20));
            let t = Instant::now();
            r.submit(View {
                generation,
                settings: RenderSettings { fog: generation % 2 == 1, ..settings.clone() },
            });
            let first = loop {
                let f = r.frame_timeout(WAIT).expect("a frame");
                if f.generation == generation {
                    break f;
                }
            };
            times.push(format!("{:.1} ms ({:?})", t.elapsed().as_secs_f64() * 1000.0, first.kind));
            assert!(
                matches!(first.kind, FrameKind::Coarse { factor } if factor >= 2),
                "the new view's first frame is a coarse preview: {:?}",
                first.kind
            );
        }
        eprintln!("change-to-first-frame at 800x600 on {name}, pass in flight: {}", times.join(", "));
    }

    #[test]
    fn coarse_factor_and_upscale() {
        assert_eq!(initial_coarse_factor(64, 48), 1);
        assert_eq!(initial_coarse_factor(800, 600), 4);
        assert_eq!(initial_coarse_factor(1280, 720), 8);
        assert_eq!(initial_coarse_factor(1920, 1080), 16);
        assert_eq!(initial_coarse_factor(100_000, 100_000), MAX_COARSE_FACTOR);
        assert_eq!(adapt_coarse_factor(4, 0.1, 4), 8);
        assert_eq!(adapt_coarse_factor(16, 0.1, 4), 16);
        assert_eq!(adapt_coarse_factor(8, 0.001, 4), 4);
        assert_eq!(adapt_coarse_factor(4, 0.001, 4), 4);
        assert_eq!(adapt_coarse_factor(4, 0.001, 2), 2);
        assert_eq!(adapt_coarse_factor(4, 0.02, 4), 4);
        let up = upscale(&[1, 2, 3, 4], 2, 2, 4, 3);
        assert_eq!(up, vec![1, 1, 2, 2, 1, 1, 2, 2, 3, 3, 4, 4]);
        assert_eq!(upscale(&[], 0, 0, 2, 1), vec![0, 0]);
        assert_eq!(pixels_to_rgb8(&[0x0012_3456]), vec![0x12, 0x34, 0x56]);
    }
}
