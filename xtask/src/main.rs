//! Project automation: `cargo xtask <command>`.
//!
//! Commands: `render [SCENE] [prism flags…]`, `assets [--check]`,
//! `bench […]`, `bless`, `fuzz [TARGET] [--seconds N]`, `man [DIR]`, `rmse A B`, `ci`. Each lives in its own module with a
//! `run(args)` entry point; this file only dispatches.

mod assets;
mod bench;
mod bless;
mod ci;
mod fuzz;
mod man;
mod peers;
mod render;
mod rmse;
#[cfg(test)]
mod tidy;

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let cmd = args.next();
    let rest: Vec<String> = args.collect();
    std::env::set_current_dir(project_root())?;
    match cmd.as_deref() {
        Some("ci") => ci::run(&rest),
        Some("render") => render::run(&rest),
        Some("assets") => assets::run(&rest),
        Some("bench") => bench::run(&rest),
        Some("bless") => bless::run(&rest),
        Some("fuzz") => fuzz::run(&rest),
        Some("man") => man::run(&rest),
        Some("rmse") => rmse::run(&rest),
        Some("help" | "-h" | "--help") | None => {
            print_help();
            Ok(())
        }
        Some(other) => {
            print_help();
            bail!("unknown xtask command `{other}`")
        }
    }
}

fn print_help() {
    eprintln!(
        "cargo xtask <command>\n\n\
         commands:\n  \
         render [SCENE] [ARGS…]  build prism (release) and render SCENE (default scenes/seed.toml)\n  \
         assets [--check]        regenerate (or check) the generated files under assets/\n  \
         bench [ARGS…]           BVH and render benchmarks (release); see docs/benchmarks.md\n  \
         bless                   re-render the golden reference images after an intended change\n  \
         fuzz [TARGET] [--seconds N]  run the cargo-fuzz targets (scene, obj, texture); see docs/fuzzing.md\n  \
         man [DIR]               write the man pages of prism (clap_mangen) into DIR (default target/man)\n  \
         rmse A.png B.png        RMSE of two images (sRGB values in [0, 1]), whole and by thirds\n  \
                                 [--diff OUT.png] [--worst-rows N]: the difference ×8; the rows with most error\n  \
         ci                      fmt --check, clippy -D warnings, tests (with tidy), docs, fuzz build: what CI runs\n"
    );
}

/// The workspace root, found from this crate's manifest directory.
pub fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map(Path::to_path_buf).unwrap_or_default()
}

/// The cargo that invoked us (or `cargo`).
pub fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

/// Runs `cmd`, failing with its rendering if it exits non-zero.
pub fn run_checked(cmd: &mut Command) -> Result<()> {
    eprintln!("$ {cmd:?}");
    let status = cmd.status()?;
    if !status.success() {
        bail!("command failed ({status}): {cmd:?}");
    }
    Ok(())
}
