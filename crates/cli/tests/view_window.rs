//! `prism view` in a real window, under Xvfb, driven by xdotool.
//!
//! - `scenes/seed.toml` (or, until it exists, a small scene written here):
//!   `c`, save, `f`, save, `q`; the two images must differ where fog is,
//!   neither may be blank, and what was on screen must be what was saved.
//! - A scene written here: `r` reloads it; after it is broken, `r` shows
//!   the error (stderr and title) and the last good scene stays.
//!
//! Where Xvfb or xdotool is missing the window tests skip themselves with
//! the reason printed, and without ImageMagick's `import` the screen is not
//! compared with the saved images; under CI (`CI=true`, as `.ci/run` sets
//! it) each of these fails instead (`prism_testkit::skip`).
//! `.ci/install-deps.sh` installs them. Also, always: without a display
//! the viewer fails with a clear message.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_prism");
/// The whole smoke test gives up after this long (it takes a few seconds).
const BUDGET: Duration = Duration::from_secs(45);

fn on_path(tool: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(tool)).find(|p| p.is_file())
}

/// Kills and reaps its processes on every path out of the test.
#[derive(Default)]
struct Guard(Vec<Child>);

impl Drop for Guard {
    fn drop(&mut self) {
        // The viewer first (it was started last), then Xvfb.
        for child in self.0.iter_mut().rev() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// Lines of a child's stream, from a reader thread.
fn lines(stream: impl Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Waits for a line satisfying `want`, echoing every line; fails at `deadline`.
fn wait_line(rx: &Receiver<String>, deadline: Instant, what: &str, want: impl Fn(&str) -> bool) -> String {
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(line) => {
                eprintln!("  viewer: {line}");
                if want(&line) {
                    return line;
                }
            }
            Err(_) => panic!("gave up waiting for {what}"),
        }
    }
}

fn xdotool(display: &str, args: &[&str]) -> Option<String> {
    let out =
        Command::new("xdotool").args(args).env("DISPLAY", display).stderr(Stdio::null()).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display())).to_rgb8()
}

fn distinct_colours(img: &image::RgbImage) -> usize {
    let mut seen: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    seen.sort_unstable();
    seen.dedup();
    seen.len()
}

fn luma(p: [u8; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// A screenshot of window `wid`, if ImageMagick's `import` is there.
fn screenshot(display: &str, wid: &str, to: &Path) -> Option<image::RgbImage> {
    on_path("import")?;
    let ok = Command::new("import")
        .args(["-window", wid, &to.to_string_lossy()])
        .env("DISPLAY", display)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    ok.then(|| rgb(to))
}

#[test]
fn no_display_fails_clearly() {
    let out = Command::new(BIN)
        .args(["view", "scenes/seed.toml"])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("no display: set DISPLAY or use `prism render`"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    // A missing scene or a bad --save-dir is named first, display or not.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for (args, words) in [
        (&["view", "no-such.toml"][..], "no-such.toml"),
        (
            &["view", "scenes/seed.toml", "--save-dir", "README.md"],
            "--save-dir README.md: it is a file, not a directory",
        ),
    ] {
        let out = Command::new(BIN).args(args).current_dir(&root).env_remove("DISPLAY").output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains(words) && !err.contains("no display"), "{args:?}: {err}");
    }
    // A missing --save-dir is made only once a window can open.
    let gone = std::env::temp_dir().join(format!("prism-view-save-{}", std::process::id()));
    let out = Command::new(BIN)
        .args(["view", "scenes/seed.toml", "--save-dir"])
        .arg(&gone)
        .current_dir(&root)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("no display"));
    assert!(!gone.exists(), "made without a window");
}

#[test]
fn view_takes_the_limit_flags_its_messages_name() {
    // An error says "raise it with --max-side": `view` takes that flag, as
    // render does. Raised, the scene loads, and the viewer goes on to find
    // no display.
    let dir = tempfile::tempdir().unwrap();
    let scene =
        "[render]\nwidth = 20000\nheight = 100\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    std::fs::write(dir.path().join("wide.toml"), scene).unwrap();
    let view = |args: &[&str]| {
        let out = Command::new(BIN)
            .arg("view")
            .args(args)
            .current_dir(dir.path())
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    for (args, flag, raised) in [
        (&["wide.toml"][..], "--max-side", &["--max-side", "20000"][..]),
        (
            &["wide.toml", "--width", "16000", "--height", "16000"],
            "--max-pixels",
            &["--max-pixels", "256000000"],
        ),
        (&["wide.toml", "--width", "64", "--spp", "70000"], "--max-spp", &["--max-spp", "70000"]),
    ] {
        let (code, err) = view(args);
        assert_eq!(code, Some(1), "{args:?}: {err}");
        assert!(err.contains(&format!("(raise it with {flag})")), "{args:?}: {err}");
        let (code, err) = view(&[args, raised].concat());
        assert_eq!(code, Some(1), "{args:?} {raised:?}: {err}");
        assert!(err.contains("no display") && !err.contains("over the limit"), "{args:?} {raised:?}: {err}");
    }
}

#[test]
fn bad_arguments_are_usage_errors() {
    let out = Command::new(BIN).args(["view", "x.toml", "--width", "zero"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("invalid value 'zero' for '--width <W>'"));
}

/// A small foggy scene: chequered floor, a mirror sphere, two matte ones.
const TEST_SCENE: &str = r#"
[render]
width = 320
height = 240
spp = 2
background = [0.05, 0.05, 0.1]

[camera]
position = [0, 1.5, 4]
look_at = [0, 0, -8]
fov = 50

[[lights]]
position = [8, 12, 4]

[fog]
mode = "linear"
start = 2
end = 40
color = [1, 1, 1]

[materials.floor]
texture = { type = "checker", a = [0.8, 0.8, 0.8], b = [0.1, 0.1, 0.4], size = 1 }

[materials.mirror]
color = [0.1, 0.2, 0.8]
reflectivity = 0.7

[materials.red]
color = [0.9, 0.2, 0.1]
specular = 0.5

[[objects]]
type = "plane"
point = [0, -1, 0]
material = "floor"

[[objects]]
type = "sphere"
center = [0, 0.5, -8]
radius = 1.5
material = "mirror"

[[objects]]
type = "sphere"
center = [-3, 0, -5]
radius = 1
material = "red"
"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("prism-view-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Xvfb and one viewer, killed when dropped.
struct Session {
    guard: Guard,
    display: String,
    wid: String,
    out: Receiver<String>,
    err: Receiver<String>,
    deadline: Instant,
}

impl Session {
    /// Starts Xvfb and the viewer, waits for the first view to converge
    /// and focuses the window.
    fn start(test: &str, scene: &Path, save_dir: &Path) -> Self {
        let deadline = Instant::now() + BUDGET;
        let mut guard = Guard::default();
        // Xvfb picks a free display and writes its number to stdout.
        let mut xvfb = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "640x480x24", "-nolisten", "tcp"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let xvfb_out = xvfb.stdout.take().unwrap();
        guard.0.push(xvfb);
        let number = wait_line(&lines(xvfb_out), deadline, "Xvfb's display number", |l| {
            l.trim().parse::<u32>().is_ok()
        });
        let display = format!(":{}", number.trim());
        let mut args = vec!["view".to_string(), scene.to_string_lossy().into_owned()];
        args.extend(
            [
                "--width",
                "240",
                "--height",
                "180",
                "--spp",
                "2",
                "--threads",
                "2",
                "--fog",
                "--verbose",
                "--save-dir",
            ]
            .map(String::from),
        );
        args.push(save_dir.to_string_lossy().into_owned());
        eprintln!("{test}: DISPLAY={display} prism {}", args.join(" "));
        let mut viewer = Command::new(BIN)
            .args(&args)
            .env("DISPLAY", &display)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let out = lines(viewer.stdout.take().unwrap());
        let err = lines(viewer.stderr.take().unwrap());
        guard.0.push(viewer);
        wait_line(&err, deadline, "the first view to converge", |l| l.contains("converged gen=1"));
        let wid = loop {
            if let Some(w) = xdotool(&display, &["search", "--name", "prism view"])
                && let Some(first) = w.lines().next()
            {
                break first.to_string();
            }
            assert!(Instant::now() < deadline, "the window never appeared");
            std::thread::sleep(Duration::from_millis(50));
        };
        xdotool(&display, &["windowfocus", "--sync", &wid]).expect("xdotool windowfocus");
        Self { guard, display, wid, out, err, deadline }
    }

    fn key(&self, key: &str) {
        xdotool(&self.display, &["key", key]).unwrap_or_else(|| panic!("xdotool key {key}"));
    }

    fn wait_err(&self, what: &str, want: impl Fn(&str) -> bool) -> String {
        wait_line(&self.err, self.deadline, what, want)
    }

    fn wait_out(&self, what: &str, want: impl Fn(&str) -> bool) -> String {
        wait_line(&self.out, self.deadline, what, want)
    }

    /// Presses `s` and returns the saved file.
    fn save(&self) -> PathBuf {
        self.key("s");
        let saved = self.wait_out("the saved path", |l| l.starts_with("saved "));
        PathBuf::from(saved.trim_start_matches("saved "))
    }

    fn title(&self) -> String {
        xdotool(&self.display, &["getwindowname", &self.wid]).unwrap_or_default()
    }

    /// Presses `q` and checks the viewer exits cleanly.
    fn quit(mut self) {
        self.key("q");
        self.exits_cleanly();
    }

    /// Presses `s` and `q` at once, and checks that the viewer exits
    /// cleanly having finished the snapshot (not cut it off, its
    /// temporary file left); returns the saved file.
    fn save_and_quit(mut self) -> PathBuf {
        xdotool(&self.display, &["key", "--delay", "0", "s", "q"]).expect("xdotool key s q");
        self.exits_cleanly();
        let saved = self.wait_out("the last saved path", |l| l.starts_with("saved "));
        PathBuf::from(saved.trim_start_matches("saved "))
    }

    fn exits_cleanly(&mut self) {
        let viewer = self.guard.0.last_mut().unwrap();
        let status = loop {
            if let Some(s) = viewer.try_wait().unwrap() {
                break s;
            }
            assert!(Instant::now() < self.deadline, "the viewer did not quit on q");
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(status.success(), "viewer exit: {status}");
    }
}

/// Whether Xvfb and xdotool are on PATH. Where one is missing this
/// [`prism_testkit::skip`]s: prints why and returns false, or under CI fails.
fn window_tools_present(test: &str) -> bool {
    let missing: Vec<&str> = ["Xvfb", "xdotool"].into_iter().filter(|t| on_path(t).is_none()).collect();
    if missing.is_empty() {
        return true;
    }
    prism_testkit::skip(&format!("{test}: {} not on PATH (run .ci/install-deps.sh)", missing.join(" and ")));
    false
}

#[test]
fn fog_keys_in_a_real_window() {
    if !window_tools_present("fog_keys_in_a_real_window") {
        return;
    }
    let dir = temp_dir("fog");
    let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml");
    let scene = if seed.is_file() {
        seed
    } else {
        println!("note: scenes/seed.toml is missing; using a small foggy test scene");
        let p = dir.join("foggy.toml");
        std::fs::write(&p, TEST_SCENE).unwrap();
        p
    };
    let session = Session::start("fog_keys_in_a_real_window", &scene, &dir);

    // c, wait for that view to converge, screenshot, save; then f.
    session.key("c");
    session.wait_err("the view after c", |l| l.contains("converged gen=2"));
    let clear_shot = screenshot(&session.display, &session.wid, &dir.join("screen-clear.png"));
    let clear_path = session.save();
    assert!(session.title().contains("fog off"), "{}", session.title());
    session.key("f");
    session.wait_err("the view after f", |l| l.contains("converged gen=3"));
    let foggy_shot = screenshot(&session.display, &session.wid, &dir.join("screen-foggy.png"));
    let foggy_path = session.save();
    assert!(session.title().contains("fog on"), "{}", session.title());
    session.quit();

    // The saved images: complete PNGs, not blank, and different where fog is.
    let (clear, foggy) = (rgb(&clear_path), rgb(&foggy_path));
    assert_eq!(clear.dimensions(), (240, 180));
    assert_eq!(foggy.dimensions(), (240, 180));
    assert!(distinct_colours(&clear) > 64, "the fog-free image is blank");
    assert!(distinct_colours(&foggy) > 64, "the foggy image is blank");
    let mut changed = 0usize;
    let (mut lum_clear, mut lum_foggy) = (0.0, 0.0);
    for (a, b) in clear.pixels().zip(foggy.pixels()) {
        if a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 8) {
            changed += 1;
            lum_clear += luma(a.0);
            lum_foggy += luma(b.0);
        }
    }
    let total = 240 * 180;
    let n = changed.max(1) as f64;
    eprintln!(
        "fog changed {changed} of {total} pixels; mean luma {:.1} -> {:.1}",
        lum_clear / n,
        lum_foggy / n
    );
    assert!(changed * 20 > total, "fog changed only {changed} of {total} pixels");
    assert!(lum_foggy > lum_clear, "fog should lighten toward its colour, as the report's");

    // What was on screen is what was saved.
    match (clear_shot, foggy_shot) {
        (Some(a), Some(b)) => {
            for (shot, saved, what) in [(a, &clear, "fog off"), (b, &foggy, "fog on")] {
                assert_eq!(shot.dimensions(), saved.dimensions(), "{what}");
                let off = shot.pixels().zip(saved.pixels()).filter(|(x, y)| x.0 != y.0).count();
                assert!(off * 100 < total, "{what}: the screen differs from the saved image in {off} pixels");
            }
        }
        _ => prism_testkit::skip(
            "fog_keys_in_a_real_window: no screenshots (ImageMagick's `import` is not on PATH or could not \
             capture the window), so only the saved images were compared, not the screen",
        ),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn reload_in_a_real_window_keeps_the_last_good_scene() {
    if !window_tools_present("reload_in_a_real_window_keeps_the_last_good_scene") {
        return;
    }
    let dir = temp_dir("reload");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, TEST_SCENE).unwrap();
    let session = Session::start("reload_in_a_real_window_keeps_the_last_good_scene", &scene, &dir);
    let before = rgb(&session.save());

    // A good edit: the red sphere turns green.
    std::fs::write(&scene, TEST_SCENE.replace("[0.9, 0.2, 0.1]", "[0.1, 0.9, 0.1]")).unwrap();
    session.key("r");
    session.wait_out("the reload", |l| l.starts_with("reloaded "));
    session.wait_err("the reloaded view", |l| l.contains("converged gen=2"));
    let green = rgb(&session.save());
    assert_ne!(before, green, "the edit shows");

    // A broken edit: the error is shown, the green scene stays.
    std::fs::write(&scene, "[render]\nwidth = \"wide\"\n").unwrap();
    session.key("r");
    let msg = session.wait_err("the reload error", |l| l.contains("reload failed"));
    assert!(msg.contains("scene.toml"), "the error names the file: {msg}");
    let deadline = Instant::now() + Duration::from_secs(5);
    while !session.title().contains("reload failed") {
        assert!(Instant::now() < deadline, "the title does not show the error: {}", session.title());
        std::thread::sleep(Duration::from_millis(20));
    }
    let after = rgb(&session.save());
    assert_eq!(after, green, "the last good scene stays");
    let last = session.save_and_quit();
    assert_eq!(rgb(&last), green, "a snapshot asked for as the viewer quits is written whole");
    let hidden: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "temporary files left: {hidden:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_display_no_server_answers_at_is_named() {
    // A display number no test starts a server on.
    // A save folder to make: not made by a run that opens no window.
    let dir = temp_dir("no-server");
    let snaps = dir.join("snaps/a");
    let out = Command::new(BIN)
        .args(["view", "scenes/seed.toml", "--save-dir"])
        .arg(&snaps)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."))
        .env("DISPLAY", ":7391")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot open a window: no X server answers at DISPLAY=:7391"), "{err}");
    assert!(!err.contains("set DISPLAY") && !err.contains("panicked"), "{err}");
    assert!(!dir.join("snaps").exists(), "the save folder was made");
    let _ = std::fs::remove_dir_all(&dir);
}
