//! `cargo xtask fuzz [TARGET|all] [--seconds N] [--list] [-- LIBFUZZER ARGS…]`:
//! runs the cargo-fuzz (libFuzzer) targets in `fuzz/` one after another,
//! each for N seconds (default 60), from a corpus seeded with the
//! project's own scenes, meshes and images. See docs/fuzzing.md.
//!
//! The targets need `cargo install cargo-fuzz`. On a stable toolchain the
//! run sets `RUSTC_BOOTSTRAP=1` (cargo-fuzz passes `-Z` flags) and uses
//! `--sanitizer none` (AddressSanitizer needs a nightly standard library);
//! set `PRISM_FUZZ_SANITIZER=address` on nightly to use it.

use crate::{cargo, project_root, run_checked};
use anyhow::{Context, Result, bail};
use std::fs;
use std::path::{Path, PathBuf};

/// Where [`build`] puts the fuzz targets: apart from the workspace's own
/// builds (other flags, another lock file), so neither invalidates the other.
pub const BUILD_DIR: &str = "target/fuzz";

/// Builds every fuzz target without running it, as `cargo xtask ci` does:
/// a plain debug `cargo build` of `fuzz/` (no cargo-fuzz, no nightly flags,
/// no sanitizer), with `--cfg fuzzing` as cargo-fuzz sets it, so that the
/// targets and prism's crates compile and link against libFuzzer as a
/// fuzzing run would build them.
pub fn build() -> Result<()> {
    let root = project_root();
    let mut flags = std::env::var("RUSTFLAGS").unwrap_or_default();
    flags.push_str(" --cfg fuzzing");
    let mut cmd = cargo();
    cmd.arg("build")
        .arg("--manifest-path")
        .arg(root.join("fuzz/Cargo.toml"))
        .arg("--target-dir")
        .arg(root.join(BUILD_DIR))
        .arg("--bins")
        .env("RUSTFLAGS", flags.trim());
    run_checked(&mut cmd).context("building the fuzz targets (fuzz/) failed")
}

/// The targets, in the order `all` runs them.
pub const TARGETS: [&str; 3] = ["scene", "obj", "texture"];

pub fn run(args: &[String]) -> Result<()> {
    let mut targets: Vec<&str> = Vec::new();
    let mut seconds = 60u64;
    let mut extra: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--seconds" | "-s" => {
                let v = it.next().context("--seconds needs a number")?;
                seconds = v.parse().with_context(|| format!("--seconds: `{v}` is not a whole number"))?;
            }
            "--list" => {
                for t in TARGETS {
                    println!("{t}");
                }
                return Ok(());
            }
            "--" => {
                extra.extend(it.by_ref().cloned());
            }
            "all" => targets.extend(TARGETS),
            t => match TARGETS.iter().find(|x| **x == t) {
                Some(known) => targets.push(known),
                None => bail!("unknown fuzz target or flag `{t}`; targets: {}, or all", TARGETS.join(", ")),
            },
        }
    }
    if targets.is_empty() {
        targets.extend(TARGETS);
    }
    let root = project_root();
    let fuzz_dir = root.join("fuzz");
    let sanitizer = std::env::var("PRISM_FUZZ_SANITIZER").unwrap_or_else(|_| "none".into());
    for target in targets {
        let corpus = fuzz_dir.join("corpus").join(target);
        seed(&root, target, &corpus)?;
        let artifacts = fuzz_dir.join("artifacts").join(target);
        fs::create_dir_all(&artifacts)?;
        let mut cmd = cargo();
        cmd.current_dir(&fuzz_dir)
            .env("RUSTC_BOOTSTRAP", "1")
            .args(["fuzz", "run", "--release", "--debug-assertions", "--sanitizer", &sanitizer, target])
            .arg(&corpus)
            .arg("--")
            .arg(format!("-max_total_time={seconds}"))
            .arg(format!("-artifact_prefix={}/", artifacts.display()))
            .arg("-print_final_stats=1")
            .args(&extra);
        run_checked(&mut cmd).with_context(|| {
            format!(
                "fuzz target `{target}` failed; a crashing input is under {} (is cargo-fuzz installed? `cargo install cargo-fuzz`)",
                artifacts.display()
            )
        })?;
    }
    Ok(())
}

/// Copies the seed inputs for `target` into `corpus` (kept between runs).
fn seed(root: &Path, target: &str, corpus: &Path) -> Result<()> {
    fs::create_dir_all(corpus)?;
    let copy = |from: &Path, name: &str| -> Result<()> {
        let to = corpus.join(name);
        if !to.exists() {
            fs::copy(from, &to).with_context(|| format!("cannot copy seed {}", from.display()))?;
        }
        Ok(())
    };
    match target {
        "scene" => {
            for p in files(&root.join("scenes"), "toml")? {
                copy(&p, &format!("seed-{}", name(&p)))?;
            }
            for p in files(&root.join("fuzz/seeds/scene"), "toml")? {
                copy(&p, &format!("seed-extra-{}", name(&p)))?;
            }
        }
        "obj" => {
            // OBJ, then `\n#MTL\n`, then the MTL library `m.mtl` (see fuzz_targets/obj.rs).
            let mtl = fs::read(root.join("assets/gem.mtl")).unwrap_or_default();
            for p in files(&root.join("assets"), "obj")? {
                let obj = fs::read(&p)?;
                let mut with_mtl = b"mtllib m.mtl\n".to_vec();
                with_mtl.extend_from_slice(&obj);
                with_mtl.extend_from_slice(b"\n#MTL\n");
                with_mtl.extend_from_slice(&mtl);
                write_new(&corpus.join(format!("seed-{}", name(&p))), &obj)?;
                write_new(&corpus.join(format!("seed-mtl-{}", name(&p))), &with_mtl)?;
            }
            for p in files(&root.join("fuzz/seeds/obj"), "obj")? {
                copy(&p, &format!("seed-extra-{}", name(&p)))?;
            }
        }
        "texture" => {
            for p in files(&root.join("fuzz/seeds/texture"), "")? {
                copy(&p, &format!("seed-{}", name(&p)))?;
            }
        }
        _ => {}
    }
    Ok(())
}

fn write_new(path: &Path, bytes: &[u8]) -> Result<()> {
    if !path.exists() {
        fs::write(path, bytes)?;
    }
    Ok(())
}

fn name(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Files in `dir` whose extension is `ext` (any when empty), sorted; none
/// if `dir` does not exist.
fn files(dir: &Path, ext: &str) -> Result<Vec<PathBuf>> {
    let Ok(entries) = fs::read_dir(dir) else { return Ok(Vec::new()) };
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && (ext.is_empty() || p.extension().is_some_and(|e| e == ext)))
        .collect();
    v.sort();
    Ok(v)
}
