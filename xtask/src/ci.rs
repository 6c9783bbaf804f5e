//! `cargo xtask ci`: everything a commit must pass, and exactly what CI
//! (`.ci/run`) runs: rustfmt (the workspace and `fuzz/`), clippy with
//! warnings denied, every test (including the tidy tests of
//! `xtask/src/tidy.rs`), the docs (public, then with private items) with
//! warnings denied, a build of the fuzz targets, and `cargo publish
//! --dry-run -p prism-geometry`.

use crate::{cargo, fuzz, run_checked};
use anyhow::Result;
use std::time::Instant;

pub fn run(args: &[String]) -> Result<()> {
    match args {
        [] => {}
        _ if crate::wants_help(args) => {
            eprintln!(
                "cargo xtask ci: fmt --check, clippy -D warnings, every test (with tidy), the docs, the fuzz build and the\n\
                 geometry crate's publish dry run: what CI runs (.ci/run). It takes no arguments."
            );
            return Ok(());
        }
        _ => anyhow::bail!("cargo xtask ci takes no arguments, got {args:?} (see cargo xtask ci --help)"),
    }
    let start = Instant::now();
    let step =
        |name: &str, t: Instant| eprintln!("xtask ci: {name} passed ({:.0} s)", t.elapsed().as_secs_f64());

    let t = Instant::now();
    run_checked(cargo().args(["fmt", "--all", "--check"]))?;
    // fuzz/ is outside the workspace, so `--all` does not reach it.
    run_checked(cargo().args(["fmt", "--manifest-path", "fuzz/Cargo.toml", "--all", "--check"]))?;
    step("fmt", t);

    let t = Instant::now();
    run_checked(cargo().args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;
    step("clippy", t);

    let t = Instant::now();
    run_checked(cargo().args(["test", "--workspace"]))?;
    step("tests", t);

    let t = Instant::now();
    run_checked(cargo().args(["doc", "--workspace", "--no-deps"]).env("RUSTDOCFLAGS", "-D warnings"))?;
    // The private items' docs too: their links break as easily, and a
    // public-only build does not read them.
    run_checked(
        cargo()
            .args(["doc", "--workspace", "--no-deps", "--document-private-items"])
            .env("RUSTDOCFLAGS", "-D warnings"),
    )?;
    step("docs", t);

    let t = Instant::now();
    fuzz::build()?;
    step("fuzz build", t);

    // prism-geometry is published on its own: its package (metadata,
    // README, sources) must build alone from crates.io dependencies.
    // `--allow-dirty` so that the check also runs before a commit; it
    // needs the crates.io index (network).
    let t = Instant::now();
    run_checked(cargo().args(["publish", "--dry-run", "-p", "prism-geometry", "--allow-dirty"]))?;
    step("prism-geometry publish dry run", t);

    eprintln!("xtask ci: all checks passed in {:.0} s", start.elapsed().as_secs_f64());
    Ok(())
}
