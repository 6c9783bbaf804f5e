//! The prism interactive viewer: a window that renders a scene
//! progressively and reacts at once to the keys.
//!
//! A quick coarse preview comes first (one sample per pixel on a grid 4–16
//! times coarser, upscaled; coarser when it is slow), then full-size
//! refinement passes of one sample each accumulate toward the scene's
//! samples per pixel: the finished image is `prism render`'s, bit for bit.
//! Rendering runs on worker threads; the window thread only polls input and
//! shows finished frames. Any change (fog toggle, camera move, reload)
//! cancels the passes in flight through the renderer's cancel flag and
//! starts over with a new preview. `--verbose` prints each frame and the
//! time from a key press to the first frame of its new view.
//!
//! | key | effect |
//! |---|---|
//! | `f` / `c` | fog on / off (the report's keys, without its delay) |
//! | `s` | save the image on screen as PNG (atomically; the path is printed) |
//! | `r` | reload the scene file (on error the last good scene stays) |
//! | arrows, mouse drag | orbit the camera about the point looked at |
//! | `w` / `x`, `a` / `d`, PgUp / PgDn | move forward / back, left / right, up / down |
//! | mouse wheel | move toward / away from the point looked at |
//! | `Home` | back to the scene file's camera |
//! | `Esc`, `q` | quit |
//!
//! The state machine ([`ViewerState`]) and the render thread ([`Renderer`])
//! need no display and are tested without one; the window layer is thin.

#![warn(missing_docs)]

pub mod demo;
mod save;
mod state;
mod window;
mod worker;

pub use save::{next_snapshot_path, save_png_atomic};
pub use state::{
    Action, DRAG_ORBIT_PER_PIXEL, KEY_MOVE_FRACTION, KEY_ORBIT_STEP, Key, Outcome, SamplePlan, View,
    ViewerState, drag_action, key_action,
};
pub use worker::{Accumulator, Frame, FrameKind, Renderer, pixels_to_rgb8, to_pixels, upscale};

use prism_shade::{RenderSettings, Scene, ShadeError};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why the viewer stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// There is no X display to open a window on.
    #[error("no display: set DISPLAY or use `prism render`")]
    NoDisplay,
    /// The window system refused the window.
    #[error("cannot open a window: {0}")]
    Window(String),
    /// The scene file could not be loaded.
    #[error("{}", scene_message(path, message))]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// Why (the loader's message, with file, line and column where known).
        message: String,
    },
    /// The requested view is invalid (e.g. a zero width).
    #[error("invalid view: {0}")]
    Camera(#[from] ShadeError),
    /// The render threads could not start.
    #[error("cannot start render threads: {0}")]
    Threads(String),
    /// A snapshot could not be saved.
    #[error("cannot save {}: {reason}", path.display())]
    Save {
        /// The PNG file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// The loader's message, prefixed with the file unless it names it already.
fn scene_message(path: &Path, message: &str) -> String {
    let shown = path.display().to_string();
    if message.contains(&shown) {
        message.to_string()
    } else {
        format!("cannot load scene {shown}: {message}")
    }
}

/// How to view a scene. Every `Option` left `None` takes the scene file's
/// value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Window width in pixels (only one of width/height given keeps the
    /// scene's aspect ratio).
    pub width: Option<u32>,
    /// Window height in pixels.
    pub height: Option<u32>,
    /// Samples per pixel to refine toward.
    pub spp: Option<u32>,
    /// Render threads (`None`: every core).
    pub threads: Option<usize>,
    /// Maximum recursion depth of reflection and refraction rays.
    pub max_depth: Option<u32>,
    /// Fog at start: `Some(true)` on, `Some(false)` off.
    pub fog: Option<bool>,
    /// Where `s` saves snapshots (`None`: the current directory).
    pub save_dir: Option<PathBuf>,
    /// Print timings (key-to-frame latency, every frame) to stderr.
    pub verbose: bool,
}

impl ViewOptions {
    /// Options that view `scene` as its file says.
    #[must_use]
    pub fn new(scene: impl Into<PathBuf>) -> Self {
        Self { scene: scene.into(), ..Self::default() }
    }
}

/// A loaded scene and the render settings its file asks for.
#[derive(Debug)]
pub struct SceneSetup {
    /// The scene (its camera carries the file's image size).
    pub scene: Scene,
    /// The file's render settings.
    pub settings: RenderSettings,
}

/// Loads a scene file; the error is a message for the user (with file,
/// line and column where known). Called again on every `r`.
pub type SceneLoader = dyn Fn(&Path) -> Result<SceneSetup, String> + Send + Sync;

/// Loads a scene file (TOML, or an OBJ mesh as a scene of its own:
/// [`prism_scene::load_path`]) with the prism scene loader, with the size, sample
/// and fog overrides of `opts` (checked against the loader's limits, as
/// `prism render` does; `--fog` on a scene without fog adds the loader's
/// default fog). Warnings go to stderr.
///
/// # Errors
/// The loader's message (file, line and column).
pub fn load_scene_file(path: &Path, opts: &ViewOptions) -> Result<SceneSetup, String> {
    let overrides = prism_scene::Overrides {
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        max_depth: opts.max_depth,
        fog: opts.fog,
        ..prism_scene::Overrides::default()
    };
    let options = prism_scene::LoadOptions { overrides, ..prism_scene::LoadOptions::default() };
    // A TOML scene, or an OBJ mesh as a scene of its own.
    let loaded = prism_scene::load_path(path, &options).map_err(|e| e.to_string())?;
    for w in &loaded.warnings {
        eprintln!("prism view: warning: {w}");
    }
    Ok(SceneSetup { scene: loaded.scene, settings: loaded.settings })
}

/// The loader [`run`] uses: [`load_scene_file`] with `opts`.
#[must_use]
pub fn file_loader(opts: &ViewOptions) -> Arc<SceneLoader> {
    let opts = opts.clone();
    Arc::new(move |path: &Path| load_scene_file(path, &opts))
}

/// Opens the viewer on `opts.scene` and runs until the window is closed
/// (or `Esc`/`q`).
///
/// # Errors
/// [`ViewError::NoDisplay`] without a display, [`ViewError::Scene`] if the
/// scene cannot be loaded at start (later reload errors are shown in the
/// window instead), and the other [`ViewError`]s if the window or the
/// threads cannot start.
pub fn run(opts: ViewOptions) -> Result<(), ViewError> {
    let loader = file_loader(&opts);
    run_with_loader(opts, loader)
}

/// [`run`] with another scene loader (tests, built-in scenes).
///
/// # Errors
/// As [`run`].
pub fn run_with_loader(opts: ViewOptions, loader: Arc<SceneLoader>) -> Result<(), ViewError> {
    check_display()?;
    let setup =
        loader(&opts.scene).map_err(|message| ViewError::Scene { path: opts.scene.clone(), message })?;
    window::run(opts, loader, setup)
}

/// `Ok` if an X display is named in the environment.
///
/// # Errors
/// [`ViewError::NoDisplay`] if `DISPLAY` is unset or empty.
pub fn check_display() -> Result<(), ViewError> {
    match std::env::var_os("DISPLAY") {
        Some(d) if !d.is_empty() => Ok(()),
        _ => Err(ViewError::NoDisplay),
    }
}

/// The window size for a scene of `scene_w × scene_h` given the overrides:
/// one override alone keeps the aspect ratio.
#[must_use]
pub fn window_size(scene_w: u32, scene_h: u32, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let aspect = |num: u32, a: u32, b: u32| {
        ((u64::from(num) * u64::from(a) + u64::from(b) / 2) / u64::from(b.max(1))).max(1)
    };
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, u32::try_from(aspect(w, scene_h, scene_w)).unwrap_or(u32::MAX)),
        (None, Some(h)) => (u32::try_from(aspect(h, scene_w, scene_h)).unwrap_or(u32::MAX), h),
        (None, None) => (scene_w, scene_h),
    }
}

/// Applies the options to a freshly loaded scene: window size, samples,
/// depth, threads and, at start, fog (for loaders that do not apply them
/// themselves; applying them twice changes nothing). Returns the scene (camera at `size`) and the
/// effective settings.
///
/// # Errors
/// [`ViewError::Camera`] if the size is empty.
pub fn prepare(
    setup: SceneSetup,
    opts: &ViewOptions,
    size: (u32, u32),
    initial_fog: bool,
) -> Result<(Scene, RenderSettings), ViewError> {
    let SceneSetup { mut scene, mut settings } = setup;
    scene.camera = scene.camera.with_size(size.0, size.1)?;
    if let Some(spp) = opts.spp {
        settings.spp = spp;
    }
    settings.spp = settings.spp.max(1);
    if let Some(depth) = opts.max_depth {
        settings.max_depth = depth;
    }
    if opts.threads.is_some() {
        settings.threads = opts.threads;
    }
    if initial_fog && let (Some(fog), Some(on)) = (scene.fog.as_mut(), opts.fog) {
        fog.enabled = on;
    }
    Ok((scene, settings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_size_keeps_aspect_with_one_override() {
        assert_eq!(window_size(800, 600, None, None), (800, 600));
        assert_eq!(window_size(800, 600, Some(400), None), (400, 300));
        assert_eq!(window_size(800, 600, None, Some(300)), (400, 300));
        assert_eq!(window_size(800, 600, Some(10), Some(20)), (10, 20));
        assert_eq!(window_size(800, 600, Some(1), None), (1, 1));
    }

    #[test]
    fn scene_errors_name_the_file_once() {
        let e = ViewError::Scene { path: "a.toml".into(), message: "a.toml:3:1: bad".into() };
        assert_eq!(e.to_string(), "a.toml:3:1: bad");
        let e = ViewError::Scene { path: "a.toml".into(), message: "bad".into() };
        assert_eq!(e.to_string(), "cannot load scene a.toml: bad");
    }

    #[test]
    fn no_display_is_an_error_not_a_panic() {
        // The message names the way out.
        let msg = ViewError::NoDisplay.to_string();
        assert!(msg.contains("DISPLAY") && msg.contains("prism render"), "{msg}");
    }

    #[test]
    fn prepare_applies_overrides() {
        let setup = demo::demo_scene(64, 48).unwrap();
        let opts = ViewOptions {
            spp: Some(3),
            threads: Some(1),
            fog: Some(false),
            max_depth: Some(2),
            ..ViewOptions::new("x")
        };
        let (scene, settings) = prepare(setup, &opts, (32, 24), true).unwrap();
        assert_eq!((scene.camera.width(), scene.camera.height()), (32, 24));
        assert_eq!(settings.spp, 3);
        assert_eq!(settings.threads, Some(1));
        assert_eq!(settings.max_depth, 2);
        assert!(!scene.fog.unwrap().enabled);
        let bad = prepare(demo::demo_scene(64, 48).unwrap(), &opts, (0, 24), true);
        assert!(matches!(bad, Err(ViewError::Camera(_))));
    }
}
