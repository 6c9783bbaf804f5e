//! `cargo xtask bench`: release-built benchmarks.
//!
//! ```text
//! cargo xtask bench                     both: BVH benchmark, then the seed render
//! cargo xtask bench [BVH ARGS…]         acceleration-structure benchmark (prism-bench)
//! cargo xtask bench --vs-peers [--rounds 2] [--threads 1,2] [--reps 3] [--scenes bunny,kitchen,grid]
//!                   [--embree-robust]   prism beside Embree and POV-Ray (`peers.rs`)
//! cargo xtask bench --scene SCENE [--threads 1,2] [--reps 5] [--width 1280] [--height 720] [--spp 4]
//!                                       render benchmark (release `prism render`)
//! ```
//!
//! The render part builds the `prism` binary in release mode and runs
//! `prism render SCENE --threads N` (`--reps` times per thread count, output
//! to a temporary directory), parsing its closing line (`…, 0.47 s, 7.87 M
//! rays, 16.72 M rays/s`); it reports the medians of the render time and
//! of the rays per second, and of the whole process's wall time (scene
//! loading and PNG writing included). Defaults: `scenes/seed.toml` at
//! 1280×720, 4 samples per pixel, 1 and 2 threads, 5 repetitions.
//!
//! The BVH part builds the `prism-bench` binary in release mode and runs it
//! from the project root with `--data ../shared/data` unless `--data` is
//! given. Arguments pass through (`--mesh` and `--data` paths are taken
//! from the folder `cargo xtask` ran in): `--mesh PATH [--grid N]`, `--reps N`,
//! `--threads 1,2`, `--quality NAME`, `--width W --height H`, `--queries
//! primary,primary-packet,incoherent,incoherent-packet,shadow,shadow-packet` (a subset of the
//! ray sets, e.g. to profile one). JSON lines go to stdout, the table to
//! stderr. See docs/benchmarks.md.

use crate::{cargo, project_root, run_checked};

/// `cargo xtask bench --help`'s own part.
const USAGE: &str = "\
cargo xtask bench                     both: BVH benchmark, then the seed render
cargo xtask bench [BVH ARGS…]         acceleration-structure benchmark (prism-bench)
cargo xtask bench --vs-peers [--rounds 2] [--threads 1,2] [--reps 3] [--scenes bunny,kitchen,grid]
                  [--embree-robust]   prism beside Embree and POV-Ray (docs/benchmarks.md)
cargo xtask bench --scene SCENE [--threads 1,2] [--reps 5] [--width 1280] [--height 720] [--spp 4]
                                      render benchmark (release `prism render`)
";
use anyhow::{Context, Result, bail};
use std::path::Path;
use std::time::Instant;

pub fn run(args: &[String]) -> Result<()> {
    if args.iter().any(|a| a == "--help" || a == "-h") {
        // This module's own usage, then prism-bench's (the BVH arguments).
        eprintln!("{USAGE}\nThe BVH benchmark's own arguments (prism-bench --help):");
        return bvh(&["--help".to_owned()]);
    }
    if args.iter().any(|a| a == "--vs-peers") {
        return crate::peers::run(args);
    }
    if args.is_empty() {
        bvh(args)?;
        return render(&[]);
    }
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
    cmd.args(user_paths(args));
    run_checked(&mut cmd)
}

/// `args` with the values of `--mesh` and `--data` made relative to the
/// folder `cargo xtask` was run from (prism-bench runs from the root).
fn user_paths(args: &[String]) -> Vec<std::ffi::OsString> {
    let mut out = Vec::with_capacity(args.len());
    let mut path_next = false;
    for a in args {
        out.push(if path_next { crate::user_path(a).into_os_string() } else { a.into() });
        path_next = a == "--mesh" || a == "--data";
    }
    out
}

/// The render benchmark over a scene file (`--scene`, default the seed).
fn render(args: &[String]) -> Result<()> {
    let root = project_root();
    // The default is the root's seed (prism runs from the root); a scene
    // given is the user's path.
    let mut scene = "scenes/seed.toml".to_string();
    let (mut width, mut height, mut spp, mut reps) = (1280u32, 720u32, 4u32, 5usize);
    let mut threads = vec![1usize, 2];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--scene" => scene = crate::user_path(value()?).display().to_string(),
            "--width" => width = value()?.parse().context("--width")?,
            "--height" => height = value()?.parse().context("--height")?,
            "--spp" => spp = value()?.parse().context("--spp")?,
            "--reps" => reps = value()?.parse::<usize>().context("--reps")?.max(1),
            "--threads" => {
                threads =
                    value()?.split(',').map(str::parse).collect::<Result<_, _>>().context("--threads")?;
            }
            other => bail!("unknown render-benchmark argument {other:?}"),
        }
    }
    run_checked(cargo().current_dir(&root).args(["build", "--release", "-p", "prism-cli"]))?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), Into::into);
    let exe = target.join("release").join(format!("prism{}", std::env::consts::EXE_SUFFIX));
    let out_dir = std::env::temp_dir().join(format!("prism-bench-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir)?;
    let out = out_dir.join("bench.png");
    let timed = time_renders(&exe, &root, &scene, &out, [width, height, spp], &threads, reps);
    // The folder goes whether the renders worked or not.
    let _ = std::fs::remove_dir_all(&out_dir);
    let mut rows = Vec::new();
    for (&n, runs) in threads.iter().zip(timed?) {
        let median = |f: fn(&Run) -> f64| {
            let mut v: Vec<f64> = runs.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (render_s, mrays, process_s) =
            (median(|r| r.seconds), median(|r| r.mrays_per_s), median(|r| r.process));
        let rays = runs[0].mrays * 1e6;
        println!(
            "{{\"bench\":\"render\",\"scene\":{scene:?},\"width\":{width},\"height\":{height},\"spp\":{spp},\"threads\":{n},\"reps\":{reps},\"render_s\":{render_s},\"process_s\":{process_s:.3},\"rays\":{rays:.0},\"mrays_per_s\":{mrays}}}"
        );
        rows.push((n, render_s, process_s, rays, mrays));
    }
    eprintln!("\nrender {scene} {width}x{height}, {spp} spp, median of {reps}");
    eprintln!("{:>7} {:>10} {:>11} {:>10} {:>9}", "threads", "render s", "process s", "M rays", "Mrays/s");
    for (n, render_s, process_s, rays, mrays) in rows {
        eprintln!("{n:>7} {render_s:>10.2} {process_s:>11.3} {:>10.2} {mrays:>9.2}", rays / 1e6);
    }
    Ok(())
}

/// `reps` renders of `scene` for each thread count of `threads`.
fn time_renders(
    exe: &Path,
    root: &Path,
    scene: &str,
    out: &Path,
    size: [u32; 3],
    threads: &[usize],
    reps: usize,
) -> Result<Vec<Vec<Run>>> {
    threads
        .iter()
        .map(|&n| (0..reps).map(|_| render_once(exe, root, scene, out, size, n)).collect())
        .collect()
}

/// One render's figures: its closing line and the process's wall time.
struct Run {
    seconds: f64,
    mrays: f64,
    mrays_per_s: f64,
    process: f64,
}

fn render_once(
    exe: &Path,
    root: &Path,
    scene: &str,
    out: &Path,
    size: [u32; 3],
    threads: usize,
) -> Result<Run> {
    let start = Instant::now();
    let output = std::process::Command::new(exe)
        .current_dir(root)
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args([
            "--width",
            &size[0].to_string(),
            "--height",
            &size[1].to_string(),
            "--spp",
            &size[2].to_string(),
        ])
        .args(["--threads", &threads.to_string()])
        .output()
        .with_context(|| format!("running {}", exe.display()))?;
    let process = start.elapsed().as_secs_f64();
    let text =
        String::from_utf8_lossy(&output.stderr).into_owned() + &String::from_utf8_lossy(&output.stdout);
    if !output.status.success() {
        bail!("prism render failed ({}):\n{text}", output.status);
    }
    parse_closing_line(&text)
        .map(|(seconds, mrays, mrays_per_s)| Run { seconds, mrays, mrays_per_s, process })
        .with_context(|| format!("no closing line (`…, S s, R M rays, X M rays/s`) in:\n{text}"))
}

/// `(seconds, M rays, M rays/s)` from the last line of the form
/// `OUT: W×H, N spp, 0.47 s, 7.87 M rays, 16.72 M rays/s`.
fn parse_closing_line(text: &str) -> Option<(f64, f64, f64)> {
    text.lines().rev().find_map(|line| {
        let parts: Vec<&str> = line.trim().rsplitn(4, ", ").collect();
        let [rate, rays, secs, _] = parts.as_slice() else { return None };
        Some((
            secs.strip_suffix(" s")?.parse().ok()?,
            rays.strip_suffix(" M rays")?.parse().ok()?,
            rate.strip_suffix(" M rays/s")?.parse().ok()?,
        ))
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn mesh_and_data_paths_are_the_users() {
        let args: Vec<String> =
            ["--mesh", "m.obj", "--grid", "2", "--data", "d"].iter().map(|s| s.to_string()).collect();
        // As `main` does; the same folder in every test that sets it.
        let _ = crate::INVOKED.set(std::env::current_dir().unwrap());
        let dir = crate::invoked_dir();
        let out = super::user_paths(&args);
        assert_eq!(out[1], dir.join("m.obj").into_os_string());
        assert_eq!(out[3], "2");
        assert_eq!(out[5], dir.join("d").into_os_string());
        assert_eq!(out[0], "--mesh");
    }

    #[test]
    fn closing_line() {
        let text = "progress\nout/seed.png: 1280×720, 4 spp, 0.47 s, 7.87 M rays, 16.72 M rays/s\n";
        assert_eq!(super::parse_closing_line(text), Some((0.47, 7.87, 16.72)));
        assert_eq!(super::parse_closing_line("nothing"), None);
    }
}
