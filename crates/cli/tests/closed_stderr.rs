//! A closed standard error (`prism render s.toml 2>&1 | head -1`, or a
//! parent that closed the pipe's read end) loses prism's diagnostics but
//! nothing else: the render still writes its image, and the exit status is
//! the one it would have been (0, or 1 after an error), never a panic's 101.

mod common;

use common::{GOOD, listing, prism_cmd};
use std::fs;
use std::path::Path;
use std::process::{ExitStatus, Stdio};

/// Runs `prism ARGS` in `dir` with standard error a pipe whose read end is
/// already closed: every write to it fails with EPIPE.
fn run_with_closed_stderr(dir: &Path, args: &[&str]) -> ExitStatus {
    let (reader, writer) = std::io::pipe().expect("make a pipe");
    drop(reader);
    prism_cmd(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::from(writer))
        .status()
        .expect("run prism")
}

#[test]
fn a_render_with_stderr_closed_writes_its_image_and_exits_0() {
    let dir = tempfile::tempdir().unwrap();
    // 8-bit colours warn, and without --quiet the `rendering …` line goes
    // to standard error too.
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "color = [200, 20, 20]");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let status = run_with_closed_stderr(dir.path(), &["render", "s.toml", "-o", "img.png", "--threads", "1"]);
    assert_eq!(status.code(), Some(0), "{status:?}");
    let img = image::open(dir.path().join("img.png")).expect("the image is written").to_rgb8();
    assert_eq!((img.width(), img.height()), (32, 18));
    // `--stats-json -` sends the closing line to standard error as well.
    let status = run_with_closed_stderr(
        dir.path(),
        &["render", "s.toml", "-o", "out/two.png", "--threads", "1", "--stats-json", "-"],
    );
    assert_eq!(status.code(), Some(0), "{status:?}");
    assert!(dir.path().join("out/two.png").is_file(), "the image is written");
    assert_eq!(listing(dir.path()), ["img.png", "out", "s.toml"], "no temporary file is left");
}

#[test]
fn an_error_with_stderr_closed_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let status = run_with_closed_stderr(dir.path(), &["render", "missing.toml", "-o", "img.png"]);
    assert_eq!(status.code(), Some(1), "{status:?}");
    let status = run_with_closed_stderr(dir.path(), &["info", "missing.toml"]);
    assert_eq!(status.code(), Some(1), "{status:?}");
    assert!(listing(dir.path()).is_empty(), "nothing is written");
}
