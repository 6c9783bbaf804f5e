//! `cargo xtask bench`: release-built benchmarks.

use anyhow::{Result, bail};

pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask bench` is being written")
}
