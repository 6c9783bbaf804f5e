//! The viewer in a real window, under Xvfb, driven by xdotool: `c`, save,
//! `f`, save, `r`, `q`; the two images must differ where fog is and
//! neither may be blank. Skipped, with the reason printed, where Xvfb or
//! xdotool is missing (`.ci/install-view-deps.sh` installs them).
//!
//! Also: without a display the viewer fails with a clear message.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_prism-view");
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
    let out = Command::new(BIN).arg("--demo").env_remove("DISPLAY").output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("no display: set DISPLAY or use `prism render`"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_arguments_are_usage_errors() {
    let out = Command::new(BIN).args(["--width", "zero"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("usage: prism-view"));
}

#[test]
fn fog_keys_in_a_real_window() {
    let (Some(_), Some(_)) = (on_path("Xvfb"), on_path("xdotool")) else {
        println!(
            "SKIPPED fog_keys_in_a_real_window: Xvfb and xdotool are not on PATH (run .ci/install-view-deps.sh)"
        );
        return;
    };
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
    let number =
        wait_line(&lines(xvfb_out), deadline, "Xvfb's display number", |l| l.trim().parse::<u32>().is_ok());
    let display = format!(":{}", number.trim());
    eprintln!("Xvfb on {display}");

    let dir = std::env::temp_dir().join(format!("prism-view-smoke-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut args: Vec<String> = vec!["--demo".into()];
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
    args.push(dir.to_string_lossy().into_owned());
    eprintln!("prism-view {}", args.join(" "));
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

    // Press a key, wait for that view to converge, save it.
    let press_and_save = |key: &str, generation: u32, name: &str| -> (PathBuf, Option<image::RgbImage>) {
        xdotool(&display, &["key", key]).expect("xdotool key");
        wait_line(&err, deadline, &format!("the view after `{key}`"), |l| {
            l.contains(&format!("converged gen={generation}"))
        });
        let shot = screenshot(&display, &wid, &dir.join(format!("screen-{name}.png")));
        xdotool(&display, &["key", "s"]).expect("xdotool key s");
        let saved = wait_line(&out, deadline, "the saved path", |l| l.starts_with("saved "));
        (PathBuf::from(saved.trim_start_matches("saved ")), shot)
    };
    let (clear_path, clear_shot) = press_and_save("c", 2, "clear");
    let (foggy_path, foggy_shot) = press_and_save("f", 3, "foggy");

    // Reload, then quit.
    xdotool(&display, &["key", "r"]).expect("xdotool key r");
    wait_line(&out, deadline, "the reload", |l| l.starts_with("reloaded "));
    xdotool(&display, &["key", "q"]).expect("xdotool key q");
    let viewer = guard.0.last_mut().unwrap();
    let status = loop {
        if let Some(s) = viewer.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < deadline, "the viewer did not quit on q");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "viewer exit: {status}");
    drop(guard);

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
    eprintln!(
        "fog changed {changed} of {total} pixels; mean luma {:.1} -> {:.1}",
        lum_clear / changed.max(1) as f64,
        lum_foggy / changed.max(1) as f64
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
        _ => {
            println!("note: no screenshots (ImageMagick's `import` missing); compared the saved images only")
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
