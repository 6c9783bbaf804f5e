//! The viewer's state machine: plain data, no window, no threads.
//!
//! Every user input becomes an [`Action`]; [`ViewerState::apply`] turns it
//! into an [`Outcome`]. Any change of what is rendered (camera, fog, scene)
//! bumps the [generation](ViewerState::generation); frames of an older
//! generation are stale and are dropped by [`ViewerState::accept`].

use crate::motion::{dolly, orbit, translate};
use prism_shade::{Camera, RenderSettings};
use std::ops::Range;
use std::time::Instant;

/// Orbit step of one arrow-key press, in radians (5°).
pub const KEY_ORBIT_STEP: f32 = 5.0 * std::f32::consts::PI / 180.0;
/// Orbit per pixel of mouse drag, in radians (0.25°).
pub const DRAG_ORBIT_PER_PIXEL: f32 = 0.25 * std::f32::consts::PI / 180.0;
/// Move step of one W/A/D/X/PageUp/PageDown press, as a fraction of the
/// eye's distance to the point looked at.
pub const KEY_MOVE_FRACTION: f32 = 0.05;

/// The keys the viewer understands, independent of the window crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    /// `f`: fog on.
    F,
    /// `c`: fog off.
    C,
    /// `s`: save the current image as PNG.
    S,
    /// `r`: reload the scene file.
    R,
    /// `q`: quit.
    Q,
    /// `Esc`: quit.
    Escape,
    /// `w`: move forward.
    W,
    /// `a`: move left.
    A,
    /// `d`: move right.
    D,
    /// `x`: move back (`s` saves, as the issue asks).
    X,
    /// Left arrow: orbit left.
    Left,
    /// Right arrow: orbit right.
    Right,
    /// Up arrow: orbit up.
    Up,
    /// Down arrow: orbit down.
    Down,
    /// Page Up: move up.
    PageUp,
    /// Page Down: move down.
    PageDown,
    /// Home: back to the scene file's camera.
    Home,
}

/// What the user asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Turn fog on (the report's `f`).
    FogOn,
    /// Turn fog off (the report's `c`).
    FogOff,
    /// Save the image on screen.
    Save,
    /// Reload the scene file.
    Reload,
    /// Close the viewer.
    Quit,
    /// Orbit the eye around the point looked at: `yaw` about the up vector,
    /// `pitch` toward it (radians; positive pitch looks from higher up).
    Orbit {
        /// Radians about the up vector (positive: counter-clockwise seen from above).
        yaw: f32,
        /// Radians toward the up vector.
        pitch: f32,
    },
    /// Move eye and target together, in units of the eye–target distance.
    Move {
        /// Along the view direction.
        forward: f32,
        /// Along the camera's right.
        right: f32,
        /// Along the camera's up.
        up: f32,
    },
    /// Move the eye toward the target (positive) or away (negative) by this
    /// fraction of their distance (the mouse wheel).
    Dolly(f32),
    /// Back to the scene file's camera.
    ResetCamera,
}

/// The action of a key, if it has one.
#[must_use]
pub fn key_action(key: Key) -> Option<Action> {
    let m = KEY_MOVE_FRACTION;
    let s = KEY_ORBIT_STEP;
    Some(match key {
        Key::F => Action::FogOn,
        Key::C => Action::FogOff,
        Key::S => Action::Save,
        Key::R => Action::Reload,
        Key::Q | Key::Escape => Action::Quit,
        Key::W => Action::Move { forward: m, right: 0.0, up: 0.0 },
        Key::X => Action::Move { forward: -m, right: 0.0, up: 0.0 },
        Key::A => Action::Move { forward: 0.0, right: -m, up: 0.0 },
        Key::D => Action::Move { forward: 0.0, right: m, up: 0.0 },
        Key::PageUp => Action::Move { forward: 0.0, right: 0.0, up: m },
        Key::PageDown => Action::Move { forward: 0.0, right: 0.0, up: -m },
        Key::Left => Action::Orbit { yaw: -s, pitch: 0.0 },
        Key::Right => Action::Orbit { yaw: s, pitch: 0.0 },
        Key::Up => Action::Orbit { yaw: 0.0, pitch: s },
        Key::Down => Action::Orbit { yaw: 0.0, pitch: -s },
        Key::Home => Action::ResetCamera,
    })
}

/// The orbit of a mouse drag by `(dx, dy)` pixels: dragging right turns
/// the scene right (the eye moves left), dragging down looks from higher up.
#[must_use]
pub fn drag_action(dx: f32, dy: f32) -> Option<Action> {
    if !(dx.is_finite() && dy.is_finite()) || (dx == 0.0 && dy == 0.0) {
        return None;
    }
    Some(Action::Orbit { yaw: -dx * DRAG_ORBIT_PER_PIXEL, pitch: dy * DRAG_ORBIT_PER_PIXEL })
}

/// What the window layer must do after an action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Nothing changed (e.g. `f` while fog is already on).
    Nothing,
    /// The view changed: cancel the passes in flight and render anew.
    Restart,
    /// Save the image on screen.
    Save,
    /// Reload the scene file.
    Reload,
    /// Close the window.
    Quit,
}

/// What to render: a snapshot of the state for the render thread.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// The generation this view belongs to.
    pub generation: u64,
    /// The render's choices: the camera (at window size), fog on/off,
    /// samples per pixel, depth, cut-off. The scene itself is never
    /// changed by a view.
    pub settings: RenderSettings,
}

/// The viewer's state.
#[derive(Clone, Debug)]
pub struct ViewerState {
    /// The user's current choices: camera, fog on/off (only ever on when
    /// the scene has fog), samples.
    settings: RenderSettings,
    file_camera: Camera,
    fog_available: bool,
    generation: u64,
    changed_at: Option<Instant>,
    samples_done: u32,
    passes: u32,
    total_passes: u64,
    pass_rate: f64,
    message: Option<String>,
}

impl ViewerState {
    /// A fresh state for a scene loaded with `settings` (its camera
    /// already at window size, its fog flag the file's or the command
    /// line's); `fog_available` says whether the scene has fog at all.
    #[must_use]
    pub fn new(settings: RenderSettings, fog_available: bool) -> Self {
        Self {
            file_camera: settings.camera,
            settings: RenderSettings { fog: settings.fog && fog_available, ..settings },
            fog_available,
            generation: 1,
            changed_at: None,
            samples_done: 0,
            passes: 0,
            total_passes: 0,
            pass_rate: 0.0,
            message: None,
        }
    }

    /// The current camera.
    #[must_use]
    pub fn camera(&self) -> Camera {
        self.settings.camera
    }

    /// Whether fog is on (always false for a scene without fog).
    #[must_use]
    pub fn fog_on(&self) -> bool {
        self.settings.fog
    }

    /// Whether the scene has fog to toggle.
    #[must_use]
    pub fn fog_available(&self) -> bool {
        self.fog_available
    }

    /// The render settings (camera and fog included).
    #[must_use]
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The generation: bumped by every change of what is rendered.
    #[must_use]
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Samples per pixel shown for the current generation (0 while only the
    /// coarse preview is up).
    #[must_use]
    pub fn samples_done(&self) -> u32 {
        self.samples_done
    }

    /// Refinement passes shown for the current generation.
    #[must_use]
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// Refinement passes shown since the viewer started.
    #[must_use]
    pub fn total_passes(&self) -> u64 {
        self.total_passes
    }

    /// Whether the current generation has all its samples.
    #[must_use]
    pub fn converged(&self) -> bool {
        self.samples_done >= self.settings.spp.max(1)
    }

    /// The last error or notice, shown in the title.
    #[must_use]
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// Sets (or clears) the notice shown in the title.
    pub fn set_message(&mut self, message: Option<String>) {
        self.message = message;
    }

    /// What to render now.
    #[must_use]
    pub fn view(&self) -> View {
        View { generation: self.generation, settings: self.settings.clone() }
    }

    /// When the current generation began, if it began by a change that has
    /// not been shown yet (for the key-to-frame latency).
    #[must_use]
    pub fn changed_at(&self) -> Option<Instant> {
        self.changed_at
    }

    fn restart(&mut self, at: Instant) -> Outcome {
        self.generation += 1;
        // Several changes before a frame: the latency runs from the first.
        self.changed_at = Some(self.changed_at.map_or(at, |t| t.min(at)));
        self.samples_done = 0;
        self.passes = 0;
        Outcome::Restart
    }

    /// Applies an action happening now.
    pub fn apply(&mut self, action: Action) -> Outcome {
        self.apply_at(action, Instant::now())
    }

    /// Applies an action whose input event arrived `at` (the start of the
    /// key-to-frame latency).
    pub fn apply_at(&mut self, action: Action, at: Instant) -> Outcome {
        match action {
            Action::FogOn | Action::FogOff => {
                let on = action == Action::FogOn;
                if !self.fog_available {
                    self.message = Some("this scene has no fog".into());
                    return Outcome::Nothing;
                }
                if self.settings.fog == on {
                    return Outcome::Nothing;
                }
                self.settings.fog = on;
                self.restart(at)
            }
            Action::Save => Outcome::Save,
            Action::Reload => Outcome::Reload,
            Action::Quit => Outcome::Quit,
            Action::Orbit { yaw, pitch } => self.set_camera(orbit(&self.settings.camera, yaw, pitch), at),
            Action::Move { forward, right, up } => {
                self.set_camera(translate(&self.settings.camera, forward, right, up), at)
            }
            Action::Dolly(f) => self.set_camera(dolly(&self.settings.camera, f), at),
            Action::ResetCamera => self.set_camera(Some(self.file_camera), at),
        }
    }

    fn set_camera(&mut self, camera: Option<Camera>, at: Instant) -> Outcome {
        match camera {
            Some(c) if c != self.settings.camera => {
                self.settings.camera = c;
                self.restart(at)
            }
            _ => Outcome::Nothing,
        }
    }

    /// A scene was (re)loaded with `settings` (camera at window size, the
    /// file's fog flag and samples); `fog_available` says whether it has
    /// fog. The user's camera is kept unless the file's camera changed;
    /// the fog toggle is kept if the scene had fog before. Always starts a
    /// new generation.
    pub fn scene_reloaded(&mut self, settings: RenderSettings, fog_available: bool) -> Outcome {
        let mut camera = self.settings.camera;
        if settings.camera != self.file_camera {
            camera = settings.camera;
            self.file_camera = settings.camera;
        }
        let fog = match (fog_available, self.fog_available) {
            (false, _) => false,
            (true, false) => settings.fog,
            (true, true) => self.settings.fog,
        };
        self.fog_available = fog_available;
        self.settings = RenderSettings { camera, fog, ..settings };
        self.restart(Instant::now())
    }

    /// Whether a frame of `generation` is current (else it is stale and
    /// must not be shown).
    #[must_use]
    pub fn accept(&self, generation: u64) -> bool {
        generation == self.generation
    }

    /// A frame of the current generation is shown after `passes` more
    /// refinement passes, which took `seconds`; it has `samples_done`
    /// samples per pixel in all. Returns false (and changes nothing) for a
    /// stale generation.
    pub fn pass_shown(&mut self, generation: u64, samples_done: u32, passes: u32, seconds: f64) -> bool {
        if !self.accept(generation) {
            return false;
        }
        self.samples_done = samples_done;
        self.passes += passes;
        self.total_passes += u64::from(passes);
        if passes > 0 && seconds > 0.0 && seconds.is_finite() {
            let rate = f64::from(passes) / seconds;
            self.pass_rate = if self.pass_rate == 0.0 { rate } else { 0.7 * self.pass_rate + 0.3 * rate };
        }
        true
    }

    /// A first frame of the current generation is on screen: returns the
    /// time since the change that started it (once per generation).
    pub fn frame_presented(&mut self, generation: u64) -> Option<std::time::Duration> {
        if !self.accept(generation) {
            return None;
        }
        self.changed_at.take().map(|t| t.elapsed())
    }

    /// The window title: scene name, samples done, passes per second, fog,
    /// and the last notice or error.
    #[must_use]
    pub fn title(&self, scene_name: &str) -> String {
        let spp = self.settings.spp.max(1);
        let mut t = format!(
            "prism view - {scene_name} - {}/{spp} spp - {:.1} passes/s - fog {}",
            self.samples_done,
            self.pass_rate,
            if !self.fog_available {
                "none"
            } else if self.settings.fog {
                "on"
            } else {
                "off"
            }
        );
        if let Some(m) = &self.message {
            t.push_str(" - ");
            t.push_str(m);
        }
        t
    }
}

/// Plans the sample ranges of the refinement passes: disjoint, in order,
/// covering `0..spp` exactly, one sample each. Added in order to a zeroed
/// buffer, one-sample passes give exactly the per-pixel sums that
/// `prism_shade::render` uses, so the refined image is `render`'s bit for
/// bit. (The render thread shows a frame only every so often, not after
/// every pass.)
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SamplePlan {
    spp: u32,
    next: u32,
}

impl SamplePlan {
    /// The plan for `spp` samples per pixel (at least 1).
    #[must_use]
    pub fn new(spp: u32) -> Self {
        Self { spp: spp.max(1), next: 0 }
    }
}

impl Iterator for SamplePlan {
    type Item = Range<u32>;

    fn next(&mut self) -> Option<Range<u32>> {
        if self.next >= self.spp {
            return None;
        }
        let r = self.next..self.next + 1;
        self.next = r.end;
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::glam::Vec3;

    fn settings(spp: u32) -> RenderSettings {
        RenderSettings {
            camera: camera(),
            fog: false,
            spp,
            max_depth: 5,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: Default::default(),
        }
    }

    fn camera() -> Camera {
        Camera::new(Vec3::new(0.0, 2.0, 10.0), Vec3::ZERO, Vec3::Y, 45.0, 80, 60).unwrap()
    }

    fn state() -> ViewerState {
        ViewerState::new(settings(4), true)
    }

    #[test]
    fn fog_keys_toggle_and_restart_only_on_change() {
        let mut s = state();
        let g = s.generation();
        assert!(!s.fog_on());
        assert_eq!(s.apply(key_action(Key::C).unwrap()), Outcome::Nothing, "c with fog off");
        assert_eq!(s.generation(), g);
        assert_eq!(s.apply(key_action(Key::F).unwrap()), Outcome::Restart);
        assert!(s.fog_on());
        assert_eq!(s.generation(), g + 1);
        assert!(s.view().settings.fog);
        assert_eq!(s.apply(key_action(Key::F).unwrap()), Outcome::Nothing, "f with fog on");
        assert_eq!(s.apply(key_action(Key::C).unwrap()), Outcome::Restart);
        assert!(!s.fog_on());
        assert_eq!(s.generation(), g + 2);
    }

    #[test]
    fn fog_keys_without_fog_say_so() {
        let mut s = ViewerState::new(RenderSettings { fog: true, ..settings(4) }, false);
        let g = s.generation();
        assert_eq!(s.apply(Action::FogOn), Outcome::Nothing);
        assert!(!s.fog_on());
        assert_eq!(s.generation(), g);
        assert_eq!(s.message(), Some("this scene has no fog"));
        assert!(s.title("x").contains("fog none"));
    }

    #[test]
    fn save_reload_quit_keys() {
        let mut s = state();
        let g = s.generation();
        assert_eq!(s.apply(key_action(Key::S).unwrap()), Outcome::Save);
        assert_eq!(s.apply(key_action(Key::R).unwrap()), Outcome::Reload);
        assert_eq!(s.apply(key_action(Key::Q).unwrap()), Outcome::Quit);
        assert_eq!(s.apply(key_action(Key::Escape).unwrap()), Outcome::Quit);
        assert_eq!(s.generation(), g, "none of these changes the view");
    }

    #[test]
    fn arrows_orbit_about_the_target_at_constant_distance() {
        for key in [Key::Left, Key::Right, Key::Up, Key::Down] {
            let mut s = state();
            let before = s.camera();
            assert_eq!(s.apply(key_action(key).unwrap()), Outcome::Restart, "{key:?}");
            let after = s.camera();
            assert_ne!(after.position(), before.position(), "{key:?}");
            assert_eq!(after.look_at(), before.look_at(), "{key:?}");
            let (d0, d1) = (before.position().length(), after.position().length());
            assert!((d0 - d1).abs() < 1e-4, "{key:?}: {d0} vs {d1}");
        }
        // Left then right comes back.
        let mut s = state();
        s.apply(key_action(Key::Left).unwrap());
        s.apply(key_action(Key::Right).unwrap());
        assert!((s.camera().position() - camera().position()).length() < 1e-4);
        // Up raises the eye.
        let mut s = state();
        s.apply(key_action(Key::Up).unwrap());
        assert!(s.camera().position().y > camera().position().y);
    }

    #[test]
    fn orbit_never_flips_over_the_pole() {
        let mut s = state();
        for _ in 0..100 {
            s.apply(key_action(Key::Up).unwrap());
        }
        let c = s.camera();
        let dir = (c.position() - c.look_at()).normalize();
        assert!(dir.dot(Vec3::Y) < 1.0 - 1e-5);
        assert!(dir.is_finite());
        // Further presses at the limit change nothing.
        let g = s.generation();
        assert_eq!(s.apply(key_action(Key::Up).unwrap()), Outcome::Nothing);
        assert_eq!(s.generation(), g);
    }

    #[test]
    fn wasd_moves_eye_and_target_together() {
        let cases =
            [(Key::W, 0), (Key::X, 1), (Key::A, 2), (Key::D, 3), (Key::PageUp, 4), (Key::PageDown, 5)];
        for (key, _) in cases {
            let mut s = state();
            let before = s.camera();
            assert_eq!(s.apply(key_action(key).unwrap()), Outcome::Restart, "{key:?}");
            let after = s.camera();
            let dp = after.position() - before.position();
            let dt = after.look_at() - before.look_at();
            assert!((dp - dt).length() < 1e-5, "{key:?}");
            assert!(dp.length() > 0.0, "{key:?}");
            let f = before.forward();
            match key {
                Key::W => assert!(dp.dot(f) > 0.0),
                Key::X => assert!(dp.dot(f) < 0.0),
                Key::A => assert!(dp.x < 0.0),
                Key::D => assert!(dp.x > 0.0),
                Key::PageUp => assert!(dp.y > 0.0),
                _ => assert!(dp.y < 0.0),
            }
        }
    }

    #[test]
    fn drag_and_dolly_and_reset() {
        let mut s = state();
        assert_eq!(drag_action(0.0, 0.0), None);
        assert_eq!(drag_action(f32::NAN, 1.0), None);
        assert_eq!(s.apply(drag_action(10.0, 0.0).unwrap()), Outcome::Restart);
        assert_ne!(s.camera(), camera());
        assert_eq!(s.apply(Action::Dolly(0.5)), Outcome::Restart);
        assert!(s.camera().position().length() < camera().position().length());
        assert_eq!(s.apply(Action::Dolly(5.0)), Outcome::Restart, "clamped, never past the target");
        assert!(s.camera().position().length() > 0.0);
        assert_eq!(s.apply(key_action(Key::Home).unwrap()), Outcome::Restart);
        assert_eq!(s.camera(), camera());
        assert_eq!(s.apply(Action::ResetCamera), Outcome::Nothing);
    }

    #[test]
    fn a_change_makes_frames_in_flight_stale() {
        let mut s = state();
        let old = s.generation();
        assert!(s.accept(old));
        assert!(s.pass_shown(old, 1, 1, 0.1));
        assert_eq!(s.samples_done(), 1);
        s.apply(Action::FogOn);
        assert!(!s.accept(old));
        assert!(!s.pass_shown(old, 2, 1, 0.1), "a stale pass is not counted");
        assert_eq!(s.samples_done(), 0);
        assert_eq!(s.passes(), 0);
        assert!(s.frame_presented(old).is_none());
        assert!(s.frame_presented(s.generation()).is_some(), "latency of the change");
        assert!(s.frame_presented(s.generation()).is_none(), "measured once");
        assert!(s.pass_shown(s.generation(), 4, 4, 0.2));
        assert!(s.converged());
        assert_eq!(s.passes(), 4);
        assert_eq!(s.total_passes(), 5);
        // A moving average: 10 passes/s, then 20.
        assert!(s.title("seed").contains("13.0 passes/s"), "{}", s.title("seed"));
        assert!(s.title("seed").contains("4/4 spp"));
    }

    #[test]
    fn reload_keeps_the_users_camera_unless_the_file_changed_it() {
        let mut s = state();
        s.apply(key_action(Key::Left).unwrap());
        s.apply(Action::FogOn);
        let moved = s.camera();
        let g = s.generation();
        assert_eq!(s.scene_reloaded(settings(8), true), Outcome::Restart);
        assert_eq!(s.generation(), g + 1);
        assert_eq!(s.camera(), moved);
        assert!(s.fog_on(), "the toggle survives a reload");
        assert_eq!(s.settings().spp, 8);
        let other = Camera::new(Vec3::new(5.0, 5.0, 5.0), Vec3::ZERO, Vec3::Y, 30.0, 80, 60).unwrap();
        s.scene_reloaded(RenderSettings { camera: other, fog: true, ..settings(8) }, false);
        assert_eq!(s.camera(), other);
        assert!(!s.fog_available() && !s.fog_on());
    }

    #[test]
    fn plan_covers_all_samples_once_one_sample_a_pass() {
        for spp in [0, 1, 2, 3, 4, 7, 16, 33, 100] {
            let ranges: Vec<_> = SamplePlan::new(spp).collect();
            let mut next = 0;
            for r in &ranges {
                assert_eq!(r.start, next, "spp {spp}: {ranges:?}");
                assert_eq!(r.end, r.start + 1);
                next = r.end;
            }
            assert_eq!(next, spp.max(1), "spp {spp}");
        }
        let r: Vec<_> = SamplePlan::new(3).collect();
        assert_eq!(r, vec![0..1, 1..2, 2..3]);
    }
}
