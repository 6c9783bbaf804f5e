//! `cargo xtask bless`: regenerate the golden reference images in
//! `crates/cli/tests/golden/` after an intended change. It runs the golden
//! test with `PRISM_BLESS=1`, which writes the references instead of
//! comparing; review the new images (`git diff --stat`, an image viewer)
//! before committing them.

use crate::{cargo, run_checked};
use anyhow::Result;

pub fn run(args: &[String]) -> Result<()> {
    // The golden scenes are the references' names.
    let dir = crate::project_root().join("crates/cli/tests/golden");
    let mut scenes: Vec<String> = std::fs::read_dir(&dir)?
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "png").then(|| p.file_stem()?.to_str().map(str::to_owned))?
        })
        .collect();
    scenes.sort();
    if crate::wants_help(args) {
        eprintln!(
            "cargo xtask bless [SCENE…]: re-render the golden references (all, or these): {}",
            scenes.join(", ")
        );
        return Ok(());
    }
    if let Some(unknown) = args.iter().find(|a| !scenes.contains(a)) {
        anyhow::bail!("no golden scene `{unknown}`; there are: {}", scenes.join(", "));
    }
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
