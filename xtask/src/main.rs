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
use std::process::{Command, ExitCode};

/// Reports an error as one line (no backtrace, whatever `RUST_BACKTRACE`
/// says) and exits with the failed command's own code where there is one
/// (2 for a usage error of `prism`), else 1.
fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(exit_code(&e))
        }
    }
}

/// The exit code for `e`: a failed command's own (1–255), else 1.
fn exit_code(e: &anyhow::Error) -> u8 {
    e.downcast_ref::<Failed>()
        .and_then(|f| f.status.code())
        .and_then(|c| u8::try_from(c).ok())
        .filter(|&c| c != 0)
        .unwrap_or(1)
}

/// A command that [`run_checked`] ran and that failed.
#[derive(Debug)]
pub struct Failed {
    /// How it ended (`exit status: 1`, `signal: 9`…).
    status: std::process::ExitStatus,
    /// The command line, as `Debug` shows it.
    command: String,
}

impl std::fmt::Display for Failed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "command failed ({}): {}", self.status, self.command)
    }
}

impl std::error::Error for Failed {}

fn run() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let cmd = args.next();
    let rest: Vec<String> = args.collect();
    // Paths the user gives are theirs, relative to where cargo ran
    // (`cargo xtask` works from any folder of the workspace); the commands
    // themselves run from the root.
    let _ = INVOKED.set(std::env::current_dir()?);
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
         bless [SCENE…]          re-render the golden reference images (all, or these) after an intended change\n  \
         fuzz [TARGET] [--seconds N]  run the cargo-fuzz targets (scene, obj, texture); see docs/fuzzing.md\n  \
         man [DIR]               write the man pages of prism (clap_mangen) into DIR (default target/man)\n  \
         rmse A.png B.png        RMSE of two images (sRGB values in [0, 1]), whole and by thirds\n  \
                                 [--diff OUT.png] [--worst-rows N]: the difference ×8; the rows with most error\n  \
         ci                      fmt --check, clippy -D warnings, tests (with tidy), docs, fuzz build: what CI runs\n"
    );
}

/// The folder `cargo xtask` was run from.
static INVOKED: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();

/// `path` as the user gave it, relative to the folder `cargo xtask` was
/// run from (the root before [`run`] knows it).
pub fn user_path(path: impl AsRef<Path>) -> PathBuf {
    let path = path.as_ref();
    match INVOKED.get() {
        Some(dir) if path.is_relative() => dir.join(path),
        _ => path.to_path_buf(),
    }
}

/// The folder `cargo xtask` was run from.
pub fn invoked_dir() -> PathBuf {
    INVOKED.get().cloned().unwrap_or_else(project_root)
}

/// Whether `args` ask for help (`-h`, `--help`).
pub fn wants_help(args: &[String]) -> bool {
    args.iter().any(|a| a == "-h" || a == "--help")
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
        return Err(Failed { status, command: format!("{cmd:?}") }.into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{exit_code, run_checked};

    #[test]
    fn a_failed_command_passes_its_exit_code_on() {
        let e = run_checked(std::process::Command::new("sh").args(["-c", "exit 3"])).unwrap_err();
        assert_eq!(exit_code(&e), 3);
        assert!(e.to_string().starts_with("command failed (exit status: 3): "), "{e}");
        assert_eq!(exit_code(&anyhow::anyhow!("no command")), 1);
        run_checked(std::process::Command::new("sh").args(["-c", "exit 0"])).unwrap();
    }
}
