//! `cargo xtask man [DIR]`: the man pages of `prism` (`prism.1`,
//! `prism-render.1`, …), generated from its command-line definition by
//! clap_mangen (the binary's hidden `prism man DIR`), into DIR (default
//! `target/man`). Read one with `man -l target/man/prism-render.1`.

use crate::{cargo, run_checked};
use anyhow::Result;
use std::path::PathBuf;

pub fn run(args: &[String]) -> Result<()> {
    let dir = match args.first() {
        Some(d) => PathBuf::from(d),
        None => std::env::var_os("CARGO_TARGET_DIR")
            .map_or_else(|| PathBuf::from("target"), PathBuf::from)
            .join("man"),
    };
    run_checked(cargo().args(["run", "--quiet", "-p", "prism-cli", "--", "man"]).arg(&dir))
}
