//! `cargo xtask bless`: regenerate the golden reference images in
//! `crates/cli/tests/golden/` after an intended change. It runs the golden
//! test with `PRISM_BLESS=1`, which writes the references instead of
//! comparing; review the new images (`git diff --stat`, an image viewer)
//! before committing them.

use crate::{cargo, run_checked};
use anyhow::Result;

pub fn run(args: &[String]) -> Result<()> {
    let mut cmd = cargo();
    cmd.args(["test", "-p", "prism-cli", "--test", "golden"]).env("PRISM_BLESS", "1");
    if !args.is_empty() {
        // Optional scene names to bless only those.
        cmd.env("PRISM_BLESS_ONLY", args.join(","));
    }
    run_checked(&mut cmd)?;
    eprintln!("golden images written to crates/cli/tests/golden/; review them before committing");
    Ok(())
}
