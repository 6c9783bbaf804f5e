//! `cargo xtask render [SCENE] [prism render flags…]`: build the release
//! `prism`, render a scene (default `scenes/seed.toml`) and print the path
//! of the image.

use crate::{cargo, run_checked};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn run(args: &[String]) -> Result<()> {
    let (scene, rest) = match args.split_first() {
        Some((first, rest)) if !first.starts_with('-') => (first.as_str(), rest),
        _ => ("scenes/seed.toml", args),
    };
    run_checked(cargo().args(["build", "--release", "-p", "prism-cli"]))?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
    let bin = target.join("release").join(format!("prism{}", std::env::consts::EXE_SUFFIX));

    let output = output_arg(rest).map(PathBuf::from);
    let mut cmd = Command::new(&bin);
    cmd.arg("render").arg(scene).args(rest);
    let output = match output {
        Some(o) => o,
        None => {
            // `out/<stem>.png`, as `prism render` names it (`with_extension`
            // would cut `my.scene` to `my`).
            let mut name =
                Path::new(scene).file_stem().context("the scene path has no file name")?.to_os_string();
            name.push(".png");
            let o = Path::new("out").join(name);
            cmd.arg("-o").arg(&o);
            o
        }
    };
    run_checked(&mut cmd)?;
    match std::fs::canonicalize(&output) {
        Ok(shown) => println!("image: {}", shown.display()),
        // `--frames` writes numbered files beside the name, not the name.
        Err(_) => println!("images: numbered frames named after {}", output.display()),
    }
    Ok(())
}

/// The value of `-o`/`--output` among prism's flags, if given.
fn output_arg(args: &[String]) -> Option<String> {
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "-o" || a == "--output" {
            return it.next().cloned();
        }
        if let Some(v) = a.strip_prefix("--output=") {
            return Some(v.to_string());
        }
        if let Some(v) = a.strip_prefix("-o").filter(|v| !v.is_empty() && !a.starts_with("--")) {
            return Some(v.trim_start_matches('=').to_string());
        }
    }
    None
}
