//! The thin window layer: minifb input to [`Action`]s, frames to the
//! screen. Everything it decides is in [`ViewerState`]; rendering, saving
//! and reloading run on other threads, so this loop never waits on them.

use crate::state::{Action, Key, Outcome, ViewerState, drag_action, key_action};
use crate::worker::{FrameKind, Renderer};
use crate::{SceneLoader, SceneSetup, ViewError, ViewOptions, save_png_atomic};
use minifb::{InputCallback, MouseButton, MouseMode, Window, WindowOptions};
use std::path::PathBuf;
use std::sync::mpsc::{self, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// Re-send the image this often even without a new frame (after the window
/// was covered, say).
const REFRESH: Duration = Duration::from_millis(250);
/// Poll interval of the input while nothing new arrives.
const IDLE_TICK: Duration = Duration::from_millis(4);
/// Longest wait for the previous view's first frame before a drag moves
/// the camera again.
const DRAG_MAX_WAIT: Duration = Duration::from_millis(100);
/// One mouse-wheel notch moves this fraction of the way to the target.
const WHEEL_DOLLY: f32 = 0.1;

/// Results of the helper threads.
enum Event {
    Saved(Result<PathBuf, ViewError>),
    Loaded(Result<Box<SceneSetup>, String>),
}

/// Every key press, in order, as the window system reports it (also
/// presses released before the next poll, which polling the key state
/// would miss, e.g. from `xdotool key`).
#[derive(Clone, Default)]
struct KeyQueue(Arc<Mutex<Vec<(minifb::Key, Instant)>>>);

impl KeyQueue {
    fn take(&self) -> Vec<(minifb::Key, Instant)> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(PoisonError::into_inner))
    }
}

impl InputCallback for KeyQueue {
    fn add_char(&mut self, _uni_char: u32) {}

    fn set_key_state(&mut self, key: minifb::Key, state: bool) {
        if state {
            self.0.lock().unwrap_or_else(PoisonError::into_inner).push((key, Instant::now()));
        }
    }
}

fn map_key(k: minifb::Key) -> Option<Key> {
    use minifb::Key as M;
    Some(match k {
        M::F => Key::F,
        M::C => Key::C,
        M::S => Key::S,
        M::R => Key::R,
        M::Q => Key::Q,
        M::Escape => Key::Escape,
        M::W => Key::W,
        M::A => Key::A,
        M::D => Key::D,
        M::X => Key::X,
        M::Left => Key::Left,
        M::Right => Key::Right,
        M::Up => Key::Up,
        M::Down => Key::Down,
        M::PageUp => Key::PageUp,
        M::PageDown => Key::PageDown,
        M::Home => Key::Home,
        _ => return None,
    })
}

fn window_error(e: &minifb::Error) -> ViewError {
    let msg = e.to_string();
    if !msg.contains("XOpenDisplay") {
        return ViewError::Window(msg);
    }
    // DISPLAY is set (`check_display` ran first) but names no X server
    // that answers: saying "set DISPLAY" would mislead.
    match std::env::var("DISPLAY") {
        Ok(d) if !d.is_empty() => ViewError::Window(format!(
            "no X server answers at DISPLAY={d}; start one there, point DISPLAY at one, or use `prism render`"
        )),
        _ => ViewError::NoDisplay,
    }
}

pub(crate) fn run(opts: ViewOptions, loader: Arc<SceneLoader>, setup: SceneSetup) -> Result<(), ViewError> {
    // The loader applied the overrides: the window has the image's size,
    // and keeps it through reloads.
    let SceneSetup { scene, settings } = setup;
    let (w, h) = settings.camera.size();
    let threads = settings.threads;
    let mut state = ViewerState::new(settings, scene.fog.is_some());
    if opts.overrides.fog == Some(true) && !state.fog_available() {
        state.set_message(Some("this scene has no fog".into()));
    }
    // A scene read from standard input is read once: no reload, and its
    // snapshots are named as `prism render` names its image.
    let from_stdin = prism_scene::is_stdin_path(&opts.scene);
    let name = if from_stdin {
        "stdin".to_owned()
    } else {
        opts.scene.file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
    };
    let save_dir = opts.save_dir.clone().unwrap_or_else(|| PathBuf::from("."));
    let verbose = opts.verbose;
    if state.settings().antialias.adaptive.is_some() {
        let why = "adaptive sampling is not used by the viewer (its passes take one sample each); `prism render` applies it";
        errln!("prism view: {why}");
        state.set_message(Some("adaptive sampling is not used here".into()));
    }

    let mut title = state.title(&name);
    let mut window = Window::new(&title, w as usize, h as usize, WindowOptions::default())
        .map_err(|e| window_error(&e))?;
    // Made once the window is open: a run that cannot open one leaves no
    // folder behind.
    if let Some(dir) = &opts.save_dir {
        crate::save_dir_ready(dir)?;
    }
    window.set_target_fps(0);
    let keys = KeyQueue::default();
    window.set_input_callback(Box::new(keys.clone()));
    let renderer = Renderer::new(scene, threads)?;
    let started = Instant::now();
    renderer.submit(state.view());

    let (events_tx, events) = mpsc::channel::<Event>();
    let mut buffer = vec![0u32; w as usize * h as usize];
    let mut last_blit: Option<Instant> = None;
    let mut reloading = false;
    let mut drag: Option<(f32, f32)> = None;
    let mut next_save = 1u32;
    // Snapshots being written, which the viewer waits for before it exits.
    let mut saving = 0usize;
    let mut first_frame_logged = false;
    let mut render_dead = false;
    let mut have_image = false;

    'main: while window.is_open() {
        // Input.
        let now = Instant::now();
        let mut actions: Vec<(Action, Instant)> =
            keys.take().into_iter().filter_map(|(k, at)| Some((key_action(map_key(k)?)?, at))).collect();
        // A drag moves the camera only once the previous move is on screen
        // (or after DRAG_MAX_WAIT): restarting at every mouse event would
        // cancel each preview before it is shown.
        if window.get_mouse_down(MouseButton::Left) {
            if let Some((x, y)) = window.get_mouse_pos(MouseMode::Pass) {
                let (px, py) = *drag.get_or_insert((x, y));
                let shown = state.changed_at().is_none_or(|t| t.elapsed() >= DRAG_MAX_WAIT);
                if shown && let Some(a) = drag_action(x - px, y - py) {
                    actions.push((a, now));
                    drag = Some((x, y));
                }
            }
        } else {
            drag = None;
        }
        if let Some((_, dy)) = window.get_scroll_wheel()
            && dy != 0.0
            && dy.is_finite()
        {
            actions.push((Action::Dolly(dy.signum() * WHEEL_DOLLY), now));
        }
        let mut restart = false;
        for (a, at) in actions {
            match state.apply_at(a, at) {
                Outcome::Nothing => {}
                Outcome::Restart => restart = true,
                Outcome::Save if !have_image => {
                    state.set_message(Some("nothing to save yet".into()));
                }
                Outcome::Save => {
                    let (path, n) = crate::next_snapshot_path(&save_dir, &name, next_save);
                    next_save = n + 1;
                    spawn_save(path, w, h, buffer.clone(), events_tx.clone());
                    saving += 1;
                }
                Outcome::Reload if reloading => {}
                Outcome::Reload if from_stdin => {
                    state.set_message(Some("a scene read from standard input cannot be reloaded".into()));
                }
                Outcome::Reload => {
                    reloading = true;
                    state.set_message(Some("reloading...".into()));
                    spawn_reload(Arc::clone(&loader), opts.scene.clone(), events_tx.clone());
                }
                Outcome::Quit => break 'main,
            }
        }
        if restart {
            // Only the last view of this batch matters.
            renderer.submit(state.view());
        }

        // Results of saves and reloads.
        while let Ok(ev) = events.try_recv() {
            match ev {
                Event::Saved(result) => {
                    saving = saving.saturating_sub(1);
                    state.set_message(Some(saved(result)));
                }
                Event::Loaded(result) => {
                    reloading = false;
                    let prepared = result.and_then(|setup| {
                        let settings = setup.settings.with_size(w, h).map_err(|e| e.to_string())?;
                        Ok((setup.scene, settings))
                    });
                    match prepared {
                        Ok((scene, settings)) => {
                            state.scene_reloaded(settings, scene.fog.is_some());
                            renderer.submit_scene(state.view(), scene);
                            outln!("reloaded {}", opts.scene.display());
                            state.set_message(None);
                        }
                        Err(msg) => {
                            errln!("prism view: reload failed, keeping the last good scene: {msg}");
                            state.set_message(Some(format!("reload failed: {msg}")));
                        }
                    }
                }
            }
        }

        // Finished frames of the current view (stale ones are dropped).
        let mut shown = None;
        while let Some(frame) = renderer.try_frame() {
            if !state.accept(frame.generation) || frame.width != w || frame.height != h {
                continue;
            }
            if let FrameKind::Pass { samples_done, passes } = frame.kind {
                state.pass_shown(frame.generation, samples_done, passes, frame.seconds);
            }
            buffer = frame.pixels;
            have_image = true;
            shown = Some((frame.generation, frame.kind, frame.seconds));
        }

        if !renderer.is_running() && !render_dead {
            render_dead = true;
            errln!("prism view: the render thread stopped unexpectedly; the image is no longer updated");
            state.set_message(Some("render thread stopped".into()));
        }

        // Present.
        if shown.is_some() || last_blit.is_none_or(|t| t.elapsed() >= REFRESH) {
            window
                .update_with_buffer(&buffer, w as usize, h as usize)
                .map_err(|e| ViewError::Window(e.to_string()))?;
            last_blit = Some(Instant::now());
        } else {
            window.update();
        }
        if let Some((generation, kind, seconds)) = shown {
            let latency = state.frame_presented(generation);
            if verbose {
                if let Some(l) = latency {
                    errln!(
                        "prism view: latency gen={generation} key-to-frame={:.1} ms",
                        l.as_secs_f64() * 1000.0
                    );
                } else if !first_frame_logged {
                    errln!(
                        "prism view: first frame after {:.1} ms",
                        started.elapsed().as_secs_f64() * 1000.0
                    );
                }
                let what = match kind {
                    FrameKind::Coarse { factor } => format!("coarse/{factor}"),
                    FrameKind::Pass { passes, .. } => format!("passes+{passes}"),
                };
                errln!(
                    "prism view: frame gen={generation} {what} samples={}/{} render={:.1} ms",
                    state.samples_done(),
                    state.settings().spp,
                    seconds * 1000.0
                );
                if state.converged() && matches!(kind, FrameKind::Pass { .. }) {
                    errln!("prism view: converged gen={generation}");
                }
            }
            first_frame_logged = true;
        }
        let t = state.title(&name);
        if t != title {
            window.set_title(&t);
            title = t;
        }
        if shown.is_none() {
            std::thread::sleep(IDLE_TICK);
        }
    }
    // Snapshots asked for just before quitting are finished (and said),
    // not cut off with their temporary files left behind.
    while saving > 0 {
        match events.recv_timeout(SAVE_WAIT) {
            Ok(Event::Saved(result)) => {
                saving -= 1;
                saved(result);
            }
            Ok(Event::Loaded(_)) => {}
            Err(_) => break,
        }
    }
    Ok(())
}

/// How long the viewer waits, when it is closed, for a snapshot being
/// written.
const SAVE_WAIT: Duration = Duration::from_secs(60);

/// Reports a finished snapshot (or why it failed) on the terminal; the
/// same words for the window's title.
fn saved(result: Result<PathBuf, ViewError>) -> String {
    match result {
        Ok(path) => {
            outln!("saved {}", path.display());
            format!("saved {}", path.display())
        }
        Err(e) => {
            errln!("prism view: {e}");
            e.to_string()
        }
    }
}

fn spawn_save(path: PathBuf, w: u32, h: u32, pixels: Vec<u32>, tx: Sender<Event>) {
    let err_tx = tx.clone();
    let spawned = std::thread::Builder::new().name("prism-view-save".into()).spawn(move || {
        let result = save_png_atomic(&path, w, h, &pixels).map(|()| path);
        let _ = tx.send(Event::Saved(result));
    });
    if let Err(e) = spawned {
        let _ = err_tx.send(Event::Saved(Err(ViewError::Threads(e.to_string()))));
    }
}

fn spawn_reload(loader: Arc<SceneLoader>, path: PathBuf, tx: Sender<Event>) {
    let err_tx = tx.clone();
    let spawned = std::thread::Builder::new().name("prism-view-load".into()).spawn(move || {
        let _ = tx.send(Event::Loaded(loader(&path).map(Box::new)));
    });
    if let Err(e) = spawned {
        let _ = err_tx.send(Event::Loaded(Err(format!("cannot start the loader thread: {e}"))));
    }
}
