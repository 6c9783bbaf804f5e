//! Helpers shared by the CLI's integration tests.
#![allow(dead_code)] // each test binary uses its own subset

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

/// A small scene that renders in a blink: a red sphere on a plane.
pub const GOOD: &str = r#"[render]
width = 32
height = 18
spp = 1

[camera]
position = [0, 1, 5]
look_at = [0, 1, 0]

[[lights]]
position = [3, 5, 4]

[materials.red]
color = [0.8, 0.1, 0.1]

[[objects]]
type = "plane"

[[objects]]
type = "sphere"
center = [0, 1, 0]
radius = 1
material = "red"
"#;

/// The `prism` binary, to run in `dir`.
pub fn prism_cmd(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_prism"));
    c.current_dir(dir);
    c
}

/// Runs `prism ARGS` in `dir`.
pub fn prism(dir: &Path, args: &[&str]) -> Output {
    prism_cmd(dir).args(args).output().expect("run prism")
}

/// Lossy text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Files in `dir` (names), sorted.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// 1-based number of the first line of `text` containing `needle` (0 if none).
pub fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).map_or(0, |i| i + 1)
}

/// Asserts that a failed run printed one clean error: after any
/// `warning: ` lines, `error: ` first, and only once; no panic text.
pub fn assert_clean_failure(name: &str, out: &Output) {
    let err = text(&out.stderr);
    assert!(!out.status.success(), "{name}: expected failure, got success\n{err}");
    assert!(!err.contains("panicked") && !err.contains("RUST_BACKTRACE"), "{name}: {err}");
    let first = err.lines().find(|l| !l.starts_with("warning: "));
    assert!(first.is_some_and(|l| l.starts_with("error: ")), "{name}: `error: ` first\n{err}");
    assert_eq!(err.lines().filter(|l| l.starts_with("error: ")).count(), 1, "{name}: one error\n{err}");
}

/// A 2×2 PNG.
pub fn png_bytes() -> Vec<u8> {
    let img = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x * 200) as u8, (y * 200) as u8, 30]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).expect("encode png");
    out.into_inner()
}
