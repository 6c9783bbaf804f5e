//! `cargo xtask render [SCENE]`: build the release `prism` and render a scene.

use anyhow::{Result, bail};

pub fn run(_args: &[String]) -> Result<()> {
    bail!("`cargo xtask render` is being written")
}
