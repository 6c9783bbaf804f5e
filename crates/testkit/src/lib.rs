//! Support shared by prism's tests, examples and benchmarks.
//!
//! Not part of the renderer: only `dev-dependencies` (and the benchmark
//! binary) use it. It depends on `prism-geometry` alone, so that any crate
//! above geometry may use it without a cycle.
//!
//! # Missing tools and data
//!
//! Some tests need things the repository does not hold: the shared meshes in
//! `../shared/data`, or Xvfb and xdotool for the viewer's window test. Outside
//! CI such a test skips itself and prints why; under CI (`CI` set to anything
//! but `false` or `0`, as `.ci/run` does) it fails instead, because there a
//! skip would hide a missing install step.
//!
//! # Modules
//!
//! * [`rng`]: the PCG32 generator ([`Rng`]);
//! * [`obj`]: an OBJ file as one positions-only mesh ([`load_obj`]);
//! * [`mod@bench`]: the benchmark's framing camera and ray sets.

pub mod bench;
pub mod obj;
pub mod rng;

pub use obj::{ObjError, load_obj};
pub use rng::Rng;

use std::io::Write;
use std::path::PathBuf;

/// Whether we run under CI: the environment variable `CI` is set to
/// something other than empty, `0` or `false` (`.ci/run` exports `CI=true`).
#[must_use]
pub fn in_ci() -> bool {
    means_ci(std::env::var("CI").ok().as_deref())
}

/// Whether a value of `CI` (`None`: unset) means CI, as [`in_ci`] reads it.
fn means_ci(value: Option<&str>) -> bool {
    value.is_some_and(|v| !matches!(v.trim(), "" | "0" | "false" | "FALSE" | "False"))
}

/// Reports that a test cannot run because `reason` (what is missing, and
/// where it was looked for). Outside CI it prints `skipped: REASON` and
/// returns, and the caller returns early; under CI it panics, failing the
/// test. The line goes straight to the process's standard error, not
/// through `eprintln!`, which the test harness captures and hides for a
/// passing test: a skip must be seen in a plain `cargo test`.
///
/// # Panics
/// Under CI, always: a test whose tools or data are missing must fail there.
pub fn skip(reason: &str) {
    let line = skip_line(in_ci(), reason);
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// What [`skip`] prints, told whether it runs under CI (where it panics
/// instead).
fn skip_line(ci: bool, reason: &str) -> String {
    assert!(!ci, "CI is set but {reason}: CI must provide it (see .ci/run)");
    format!("skipped: {reason}")
}

/// `<workspace root>/../shared/data`, the shared test meshes, if present;
/// otherwise [`skip`]s (so under CI this panics) and returns `None`.
#[must_use]
pub fn shared_data() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if dir.is_dir() {
        Some(dir)
    } else {
        skip(&format!("the shared meshes are absent (looked for {})", dir.display()));
        None
    }
}

/// The real meshes of `../shared/data` the tests run on, smallest last.
pub const SHARED_MESHES: [&str; 5] =
    ["stanford-bunny.obj", "kitchen.obj", "teapot.obj", "spot.obj", "beast.obj"];

/// `(name, path)` of each of [`SHARED_MESHES`] present in
/// [`shared_data`]; each one missing (or the whole folder) is [`skip`]ped,
/// so under CI it fails the test and outside CI it is named on stderr.
#[must_use]
pub fn shared_meshes() -> Vec<(&'static str, PathBuf)> {
    let Some(dir) = shared_data() else { return Vec::new() };
    let mut found = Vec::new();
    for name in SHARED_MESHES {
        let path = dir.join(name);
        if path.is_file() {
            found.push((name, path));
        } else {
            skip(&format!("{name} is absent from {}", dir.display()));
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ci_is_any_value_but_empty_zero_or_false() {
        for v in ["true", "1", "yes", " true ", "TRUE"] {
            assert!(means_ci(Some(v)), "{v:?}");
        }
        for v in [None, Some(""), Some(" "), Some("0"), Some("false"), Some("FALSE"), Some("False")] {
            assert!(!means_ci(v), "{v:?}");
        }
    }

    #[test]
    fn a_skip_fails_under_ci_and_returns_elsewhere() {
        assert_eq!(skip_line(false, "the tool is missing"), "skipped: the tool is missing");
        let failed = std::panic::catch_unwind(|| skip_line(true, "the tool is missing"));
        let message = failed.expect_err("a skip under CI panics");
        let text = message.downcast_ref::<String>().map_or("", String::as_str);
        assert!(text.contains("CI is set but the tool is missing"), "{text}");
    }

    #[test]
    fn shared_data_is_found_or_reported() {
        // Outside CI a missing folder is skipped; under CI it must be there
        // and hold every shared mesh.
        match shared_data() {
            Some(d) => {
                let all = SHARED_MESHES.iter().all(|m| d.join(m).is_file());
                assert!(all || !in_ci(), "{} lacks some of {SHARED_MESHES:?}", d.display());
            }
            None => assert!(!in_ci()),
        }
    }
}
