//! `cargo xtask ci`: everything a commit must pass.

use crate::{cargo, run_checked};
use anyhow::Result;

pub fn run(_args: &[String]) -> Result<()> {
    run_checked(cargo().args(["fmt", "--all", "--check"]))?;
    run_checked(cargo().args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;
    run_checked(cargo().args(["test", "--workspace"]))?;
    run_checked(cargo().args(["doc", "--workspace", "--no-deps"]).env("RUSTDOCFLAGS", "-D warnings"))?;
    eprintln!("xtask ci: all checks passed");
    Ok(())
}
