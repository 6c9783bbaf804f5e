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

/// `eprintln!` that never panics: with standard error closed (`prism
/// render s.toml 2>&1 | head -1`) the line is lost, and the program goes
/// on, writes its files and exits as it would have (`eprintln!` would
/// panic on the write error, exit 101). Exported for the `prism` binary,
/// which prints through the same macros.
#[doc(hidden)]
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), "{}", $crate::printable(&format!($($arg)*)));
    }};
}

/// `text` with its control characters other than line breaks and tabs
/// escaped (`\u{1b}`): a name in a scene file (a material's, a path)
/// reaches messages as written, and an escape sequence in it would
/// recolour or clear the user's terminal.
#[doc(hidden)]
#[must_use]
pub fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    let escaped = |c: char| c.is_control() && c != '\n' && c != '\t';
    if !text.chars().any(escaped) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if escaped(c) {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    out.into()
}

/// `println!` that never panics, as `errln!` (`prism info --json | head`).
#[doc(hidden)]
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

pub mod demo;
mod motion;
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
    /// A snapshot could not be saved (the error names the file).
    #[error("cannot save a snapshot: {0}")]
    Save(#[from] prism_shade::OutputError),
    /// The folder for snapshots cannot be used.
    #[error("--save-dir {}: {reason}", path.display())]
    SaveDir {
        /// The folder given.
        path: PathBuf,
        /// Why it cannot hold snapshots.
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

/// How to view a scene.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// The command line's replacements of the file's values (window size,
    /// samples, depth, threads, fog at start, camera), applied once by the
    /// loader, on every load.
    pub overrides: prism_scene::Overrides,
    /// `--set KEY=VALUE` replacements of scene values by dotted path,
    /// applied by the loader on every load ([`prism_scene::LoadOptions::sets`]).
    pub sets: Vec<String>,
    /// OBJ mode's choices (`--view`, `--light`, `--floor`) for an OBJ file;
    /// refused by the loader for a TOML scene.
    pub obj: prism_scene::ObjOptions,
    /// The limits on image size and samples (`--max-side`, `--max-pixels`,
    /// `--max-spp`), on every load.
    pub limits: prism_scene::Limits,
    /// Where the memory the process may still take comes from: asked again
    /// on every load, so that a reload's textures are checked against the
    /// room left with the last scene held ([`prism_scene::Limits::memory`]).
    /// `None`: `limits.memory` as it is.
    pub memory: Option<fn() -> Option<prism_scene::MemoryRoom>>,
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

/// A loaded scene and the per-render choices to view it with.
#[derive(Debug)]
pub struct SceneSetup {
    /// The scene (never changed by the viewer).
    pub scene: Scene,
    /// The file's render settings with the overrides applied: camera (at
    /// the window size), fog on/off, samples, depth, threads.
    pub settings: RenderSettings,
}

/// Loads a scene file; the error is a message for the user (with file,
/// line and column where known). Called again on every `r`.
pub type SceneLoader = dyn Fn(&Path) -> Result<SceneSetup, String> + Send + Sync;

/// Loads a scene file (TOML, or an OBJ mesh as a scene of its own:
/// [`prism_scene::load_path`]) with the prism scene loader and the
/// overrides of `opts` (checked against the loader's limits, as `prism
/// render` does; `--fog` on a scene without fog adds the loader's default
/// fog). Warnings go to stderr.
///
/// # Errors
/// The loader's message (file, line and column).
pub fn load_scene_file(path: &Path, opts: &ViewOptions) -> Result<SceneSetup, String> {
    let options = prism_scene::LoadOptions {
        overrides: opts.overrides,
        sets: opts.sets.clone(),
        obj: opts.obj,
        limits: prism_scene::Limits {
            memory: opts.memory.map_or(opts.limits.memory, |room| room()),
            ..opts.limits
        },
    };
    // A TOML scene, or an OBJ mesh as a scene of its own.
    let loaded = prism_scene::load_path(path, &options).map_err(|e| e.to_string())?;
    for w in &loaded.warnings {
        errln!("prism view: warning: {w}");
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
    // What is wrong with the user's files and flags first, then the display.
    let setup =
        loader(&opts.scene).map_err(|message| ViewError::Scene { path: opts.scene.clone(), message })?;
    if let Some(dir) = &opts.save_dir {
        save_dir_usable(dir)?;
    }
    check_display()?;
    // The window makes the save folder once it is open.
    window::run(opts, loader, setup)
}

/// Checks, leaving nothing behind, that `dir` (where `s` saves snapshots)
/// is a directory or could be one, and that a file can be made there: it
/// and the folders above it that exist are directories, and the deepest
/// that exists takes a new file (a probe, made and removed at once). So a
/// bad `--save-dir` is found before the window opens rather than at the
/// first snapshot.
///
/// # Errors
/// [`ViewError::SaveDir`] naming the file in the way, or why no file can
/// be made.
pub fn save_dir_usable(dir: &Path) -> Result<(), ViewError> {
    let mut at = Some(dir);
    while let Some(p) = at.filter(|p| !p.as_os_str().is_empty()) {
        match std::fs::metadata(p) {
            Ok(m) if m.is_dir() => return writable_dir(dir, p),
            Ok(_) => {
                let what = if p == dir { "it".to_owned() } else { p.display().to_string() };
                return Err(ViewError::SaveDir {
                    path: dir.to_path_buf(),
                    reason: format!("{what} is a file, not a directory"),
                });
            }
            Err(_) => at = p.parent(),
        }
    }
    Ok(())
}

/// Whether a file can be made in `existing`, the deepest folder of the
/// save folder `dir` that exists.
fn writable_dir(dir: &Path, existing: &Path) -> Result<(), ViewError> {
    let probe = existing.join(format!(".prism-view-check-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            // Best effort: the probe is empty and named for this process.
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(ViewError::SaveDir {
            path: dir.to_path_buf(),
            reason: format!("no file can be created in {} ({e})", existing.display()),
        }),
    }
}

/// Makes `dir` if it is missing, as `prism render` makes an output's
/// folder (after [`save_dir_usable`] and the display check).
///
/// # Errors
/// [`ViewError::SaveDir`] if it cannot be made.
pub fn save_dir_ready(dir: &Path) -> Result<(), ViewError> {
    save_dir_usable(dir)?;
    std::fs::create_dir_all(dir)
        .map_err(|e| ViewError::SaveDir { path: dir.to_path_buf(), reason: e.to_string() })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_but_line_breaks_and_tabs_kept() {
        assert_eq!(printable("plain\ttext\n"), "plain\ttext\n");
        assert_eq!(printable("a\u{1b}[31mRED\u{7}"), "a\\u{1b}[31mRED\\u{7}");
        assert!(matches!(printable("no escapes"), std::borrow::Cow::Borrowed(_)));
    }

    #[test]
    fn scene_errors_name_the_file_once() {
        let e = ViewError::Scene { path: "a.toml".into(), message: "a.toml:3:1: bad".into() };
        assert_eq!(e.to_string(), "a.toml:3:1: bad");
        let e = ViewError::Scene { path: "a.toml".into(), message: "bad".into() };
        assert_eq!(e.to_string(), "cannot load scene a.toml: bad");
    }

    #[test]
    fn a_save_dir_is_made_or_refused_before_the_window() {
        let tmp = tempfile::tempdir().unwrap();
        let made = tmp.path().join("a/b");
        save_dir_ready(&made).unwrap();
        assert!(made.is_dir());
        let file = tmp.path().join("f");
        std::fs::write(&file, b"").unwrap();
        let e = save_dir_ready(&file).unwrap_err().to_string();
        assert!(e.ends_with("f: it is a file, not a directory"), "{e}");
        let e = save_dir_usable(&file.join("sub")).unwrap_err().to_string();
        assert!(e.ends_with(&format!("{} is a file, not a directory", file.display())), "{e}");
        // The check alone makes nothing (its probe is gone).
        save_dir_usable(&tmp.path().join("c/d")).unwrap();
        assert!(!tmp.path().join("c").exists());
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left.len(), 2, "{left:?}");
        // A folder no file can be made in (even by root), as `prism
        // render` refuses an output there.
        #[cfg(target_os = "linux")]
        {
            let e = save_dir_usable(Path::new("/proc/prism-snapshots")).unwrap_err().to_string();
            assert!(e.contains("no file can be created in /proc"), "{e}");
        }
    }

    #[test]
    fn the_no_display_error_names_the_way_out() {
        // (Running without a display: tests/view_window.rs in prism-cli.)
        let msg = ViewError::NoDisplay.to_string();
        assert!(msg.contains("DISPLAY") && msg.contains("prism render"), "{msg}");
    }

    #[test]
    fn the_loader_applies_the_overrides_once() {
        let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml");
        let file = load_scene_file(&seed, &ViewOptions::new(&seed)).unwrap();
        assert_eq!(file.settings.camera.size(), (1280, 720));
        assert!(file.settings.fog && file.scene.fog.is_some(), "seed.toml has fog, on");
        let overrides = prism_scene::Overrides {
            width: Some(320),
            spp: Some(3),
            threads: Some(1),
            fog: Some(false),
            ..prism_scene::Overrides::default()
        };
        let setup = load_scene_file(&seed, &ViewOptions { overrides, ..ViewOptions::new(&seed) }).unwrap();
        let s = &setup.settings;
        assert_eq!(s.camera.size(), (320, 180), "--width alone keeps 16:9");
        assert_eq!((s.spp, s.threads), (3, Some(1)));
        assert!(!s.fog, "--no-fog turns the fog off");
        assert!(setup.scene.fog.is_some(), "the fog's medium stays in the scene");
        let bad = prism_scene::Overrides { width: Some(0), ..prism_scene::Overrides::default() };
        let err = load_scene_file(&seed, &ViewOptions { overrides: bad, ..ViewOptions::new(&seed) });
        assert!(err.is_err_and(|e| e.contains("--width")));
        // --set reaches the viewer's load; OBJ flags are refused for a TOML scene.
        let sets = vec!["render.spp=5".to_owned(), "fog.enabled=false".to_owned()];
        let setup = load_scene_file(&seed, &ViewOptions { sets, ..ViewOptions::new(&seed) }).unwrap();
        assert_eq!(setup.settings.spp, 5);
        assert!(!setup.settings.fog);
        let obj = prism_scene::ObjOptions { floor: true, ..prism_scene::ObjOptions::default() };
        let err = load_scene_file(&seed, &ViewOptions { obj, ..ViewOptions::new(&seed) });
        assert!(err.is_err_and(|e| e.contains("--floor")));
    }

    /// The memory a load may take is asked for again on every load (a
    /// reload's room is what is left with the last scene held), not fixed
    /// when the viewer starts.
    #[test]
    fn every_load_asks_for_the_memory_left() {
        use std::sync::atomic::{AtomicU64, Ordering};
        static ROOM: AtomicU64 = AtomicU64::new(u64::MAX);
        fn room() -> Option<prism_scene::MemoryRoom> {
            Some(prism_scene::MemoryRoom { bytes: ROOM.load(Ordering::SeqCst), limit: "the test's limit" })
        }
        let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml");
        let opts = ViewOptions { memory: Some(room), ..ViewOptions::new(&seed) };
        let loader = file_loader(&opts);
        assert!(loader(&seed).is_ok());
        // Less room now than at the first load: the planet's texture no longer fits.
        ROOM.store(1000, Ordering::SeqCst);
        let err = loader(&seed).err().unwrap_or_default();
        assert!(err.contains("gas-giant.png") && err.contains("the test's limit"), "{err}");
        ROOM.store(u64::MAX, Ordering::SeqCst);
        assert!(loader(&seed).is_ok());
    }
}
