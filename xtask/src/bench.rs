//! `cargo xtask bench`: release-built benchmarks.
//!
//! ```text
//! cargo xtask bench [BVH ARGS…]         acceleration-structure benchmark (prism-bench)
//! cargo xtask bench --scene SCENE […]   render benchmark (not written yet)
//! ```
//!
//! The BVH part builds the `prism-bench` binary in release mode and runs it
//! from the project root with `--data ../shared/data` unless `--data` is
//! given. Arguments pass through: `--mesh PATH [--grid N]`, `--reps N`,
//! `--threads 1,2`, `--quality NAME`, `--width W --height H`. JSON lines go
//! to stdout, the table to stderr. See docs/benchmarks.md.

use crate::{cargo, project_root, run_checked};
use anyhow::{Result, bail};

pub fn run(args: &[String]) -> Result<()> {
    if args.iter().any(|a| a == "--scene") { render(args) } else { bvh(args) }
}

/// The acceleration-structure benchmark: bunny, kitchen, bunny grid (or
/// `--mesh PATH [--grid N]`).
fn bvh(args: &[String]) -> Result<()> {
    let root = project_root();
    run_checked(cargo().current_dir(&root).args(["build", "--release", "-p", "prism-bench"]))?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), Into::into);
    let exe = target.join("release").join(format!("prism-bench{}", std::env::consts::EXE_SUFFIX));
    let mut cmd = std::process::Command::new(exe);
    cmd.current_dir(&root);
    if !args.iter().any(|a| a == "--data") {
        cmd.arg("--data").arg(root.join("..").join("shared").join("data"));
    }
    cmd.args(args);
    run_checked(&mut cmd)
}

/// The render benchmark over a scene file (`--scene`): a later step.
fn render(_args: &[String]) -> Result<()> {
    bail!("the render benchmark (`cargo xtask bench --scene …`) is not written yet")
}
