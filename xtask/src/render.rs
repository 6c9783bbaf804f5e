//! `cargo xtask render [SCENE] [prism render flags…]`: build the release
//! `prism`, render a scene (default `scenes/seed.toml`) and print the path
//! of the image.

use crate::{cargo, project_root, run_checked};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn run(args: &[String]) -> Result<()> {
    // A scene first (`-` is standard input), else the seed; paths the user
    // gives are relative to where cargo ran, the defaults to the root.
    let root = project_root();
    let (scene, rest) = match args.split_first() {
        Some((first, rest)) if first == "-" || !first.starts_with('-') => (PathBuf::from(first), rest),
        _ => (shown(root.join("scenes").join("seed.toml")), args),
    };
    run_checked(cargo().args(["build", "--release", "-p", "prism-cli"]))?;
    // Absolute (cargo, run from the root, reads a relative one from there):
    // prism runs in the user's folder.
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), |t| root.join(t));
    let bin = target.join("release").join(format!("prism{}", std::env::consts::EXE_SUFFIX));

    let mut cmd = Command::new(&bin);
    cmd.current_dir(crate::invoked_dir()).arg("render").arg(&scene).args(rest);
    if crate::wants_help(rest) {
        // prism's help alone: nothing is rendered, no image to name.
        return run_checked(&mut cmd);
    }
    let output = match output_arg(rest) {
        Some(o) => crate::user_path(o),
        None => {
            // `out/<stem>.png` under the root, as `prism render` names it
            // (`with_extension` would cut `my.scene` to `my`; standard
            // input is `stdin`).
            let mut name = if scene == Path::new("-") {
                "stdin".into()
            } else {
                scene.file_stem().context("the scene path has no file name")?.to_os_string()
            };
            name.push(".png");
            let o = shown(root.join("out").join(name));
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

/// `path` (absolute) as `prism` is given it: relative to the folder cargo
/// ran from where it lies below it (`out/seed.png` from the root, as
/// `prism render` names it), else whole.
fn shown(path: PathBuf) -> PathBuf {
    path.strip_prefix(crate::invoked_dir()).map(Path::to_path_buf).unwrap_or(path)
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
