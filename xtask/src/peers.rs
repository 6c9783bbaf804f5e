//! `cargo xtask bench --vs-peers`: prism beside its peers on one machine,
//! runs alternating, ratios printed (../shared/peers/README.md).
//!
//! ```text
//! cargo xtask bench --vs-peers [--rounds 2] [--threads 1,2] [--reps 3] [--scenes bunny,kitchen,grid]
//!                               [--embree-robust]
//! ```
//!
//! * Embree (ray throughput): `target/peers/embree_bench`, built by
//!   `bash ../shared/peers/embree/build.sh target/peers` when missing. Per
//!   scene, round and thread count it runs Embree (single rays and 8-wide
//!   packets, `--quality high --device-config frequency_level=simd256`) and
//!   then `prism-bench --rays peer` on the same mesh and rays (the primary
//!   rays of the same camera, and the peer's own incoherent and shadow
//!   sets, made by prism-testkit as the peer makes them); the best of the
//!   rounds counts on each side, and the ratio is prism / the better of
//!   Embree's two modes. Each side's hit counts are printed beside each
//!   other: on the same rays they agree but for a few grazing rays.
//!
//!   `--embree-robust` also runs Embree with `RTC_SCENE_FLAG_ROBUST` (its
//!   `--robust`), in the same round right after the default run: robust
//!   box traversal and no accuracy-reducing shortcuts, the mode closest
//!   to prism's watertight test (Embree's own triangle test is still not
//!   fully watertight there, embree/embree#387). The table then gets a
//!   second ratio, prism / the better of Embree's robust modes. The
//!   issue's aim is the first ratio; the second says how much of a gap
//!   is Embree's default trading accuracy for speed.
//! * POV-Ray (the seed scene): `povray` on `../shared/peers/povray/seed_scene.pov`
//!   (1280×720, 2×2 supersampling, 2 threads) alternating with `prism render
//!   scenes/seed.toml --threads 2` (4 spp); whole-process wall times, the
//!   best of the rounds, ratio POV-Ray / prism. Beside it, the ratio of
//!   the render phases alone: POV-Ray's reported trace time against
//!   prism's render time (`--stats-json`), which leaves out POV-Ray's
//!   fixed ~0.7 s of start-up and shut-down and prism's scene loading and
//!   image writing.
//!
//! A peer that cannot be found or built is skipped with the reason.

use crate::{cargo, project_root, run_checked};
use anyhow::{Context, Result, bail};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

struct Options {
    rounds: usize,
    threads: Vec<usize>,
    reps: usize,
    scenes: Vec<String>,
    /// Also run Embree in its robust mode (`--embree-robust`).
    robust: bool,
}

fn parse(args: &[String]) -> Result<Options> {
    let mut o = Options {
        rounds: 2,
        threads: vec![1, 2],
        reps: 3,
        scenes: ["bunny", "kitchen", "grid"].map(String::from).to_vec(),
        robust: false,
    };
    let mut it = args.iter().filter(|a| *a != "--vs-peers");
    while let Some(a) = it.next() {
        let mut value = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--rounds" => o.rounds = value()?.parse::<usize>().context("--rounds")?.max(1),
            "--reps" => o.reps = value()?.parse::<usize>().context("--reps")?.max(1),
            "--threads" => {
                o.threads =
                    value()?.split(',').map(str::parse).collect::<Result<_, _>>().context("--threads")?;
            }
            "--scenes" => o.scenes = value()?.split(',').map(String::from).collect(),
            "--embree-robust" => o.robust = true,
            other => bail!("unknown --vs-peers argument {other:?}"),
        }
    }
    Ok(o)
}

pub fn run(args: &[String]) -> Result<()> {
    let o = parse(args)?;
    let root = project_root();
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let shared = root.join("..").join("shared");
    match embree_peer(&root, &target, &shared) {
        Ok(peer) => {
            run_checked(cargo().current_dir(&root).args(["build", "--release", "-p", "prism-bench"]))?;
            let bench = target.join("release").join(format!("prism-bench{}", std::env::consts::EXE_SUFFIX));
            vs_embree(&root, &peer, &bench, &shared.join("data"), &o)?;
        }
        Err(why) => eprintln!("skipping Embree: {why}"),
    }
    match povray_peer(&shared) {
        Ok(pov) => {
            run_checked(cargo().current_dir(&root).args(["build", "--release", "-p", "prism-cli"]))?;
            let prism = target.join("release").join(format!("prism{}", std::env::consts::EXE_SUFFIX));
            vs_povray(&root, &pov, &prism, &shared.join("peers").join("povray"), o.rounds)?;
        }
        Err(why) => eprintln!("skipping POV-Ray: {why}"),
    }
    Ok(())
}

/// The Embree benchmark binary, built if missing; `Err` says why not.
fn embree_peer(root: &Path, target: &Path, shared: &Path) -> Result<PathBuf, String> {
    let exe = target.join("peers").join("embree_bench");
    if exe.is_file() {
        return Ok(exe);
    }
    let script = shared.join("peers").join("embree").join("build.sh");
    if !script.is_file() {
        return Err(format!("{} is missing and there is no {}", exe.display(), script.display()));
    }
    let status = Command::new("bash")
        .current_dir(root)
        .arg(&script)
        .arg(target.join("peers"))
        .status()
        .map_err(|e| format!("cannot run bash {}: {e}", script.display()))?;
    if !status.success() || !exe.is_file() {
        return Err(format!("bash {} failed ({status})", script.display()));
    }
    Ok(exe)
}

/// `povray` and the seed scene's POV file; `Err` says why not.
fn povray_peer(shared: &Path) -> Result<PathBuf, String> {
    let pov = shared.join("peers").join("povray").join("seed_scene.pov");
    if !pov.is_file() {
        return Err(format!("no {}", pov.display()));
    }
    match Command::new("povray").arg("--version").output() {
        Ok(_) => Ok(pov),
        Err(e) => Err(format!("cannot run povray ({e}); apt-get install povray")),
    }
}

/// The string or number value of `key` in a flat one-line JSON object.
fn json_field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let start = line.find(&format!("\"{key}\":"))? + key.len() + 3;
    let rest = line[start..].trim_start();
    if let Some(s) = rest.strip_prefix('"') {
        return s.split('"').next();
    }
    rest.split([',', '}']).next().map(str::trim)
}

/// Runs `cmd` and returns its stdout (stderr is shown only on failure).
fn stdout_of(cmd: &mut Command) -> Result<String> {
    let out = cmd.output().with_context(|| format!("running {cmd:?}"))?;
    if !out.status.success() {
        bail!("{cmd:?} failed ({}):\n{}", out.status, String::from_utf8_lossy(&out.stderr));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Embree's query names in prism's terms.
fn query_name(embree: &str) -> Option<&'static str> {
    match embree {
        "primary" => Some("primary"),
        "incoherent_hemisphere" => Some("incoherent"),
        "occlusion_to_light" => Some("shadow"),
        _ => None,
    }
}

/// (scene, query, threads) → best Mrays/s of (prism, Embree single, Embree
/// packet8, Embree robust single, Embree robust packet8); 0 where not run.
type Table = BTreeMap<(String, &'static str, usize), [f64; 5]>;

fn vs_embree(root: &Path, peer: &Path, bench: &Path, data: &Path, o: &Options) -> Result<()> {
    let bunny = data.join("stanford-bunny.obj");
    let kitchen = data.join("kitchen.obj");
    let mut table = Table::new();
    // (scene, query) → hits (occluded rays for shadow rays) of prism and
    // of Embree's default mode: the same rays give the same answers, up
    // to the few rays that graze an edge (prism's test is watertight,
    // Embree's default is not).
    let mut hits: BTreeMap<(String, &'static str), [u64; 2]> = BTreeMap::new();
    for round in 0..o.rounds {
        for scene in &o.scenes {
            let (mesh, grid) = match scene.as_str() {
                "bunny" => (&bunny, false),
                "kitchen" => (&kitchen, false),
                "grid" => (&bunny, true),
                other => bail!("unknown scene {other:?} (bunny, kitchen, grid)"),
            };
            if !mesh.is_file() {
                eprintln!("skipping {scene}: no {}", mesh.display());
                continue;
            }
            for &t in &o.threads {
                eprintln!("round {}/{}: {scene}, {t} thread(s): Embree, then prism", round + 1, o.rounds);
                let modes: &[bool] = if o.robust { &[false, true] } else { &[false] };
                for &robust in modes {
                    let mut e = Command::new(peer);
                    e.current_dir(root).arg(mesh);
                    if grid {
                        e.args(["--grid", "6", "--instances"]);
                    }
                    e.args([
                        "--quality",
                        "high",
                        "--device-config",
                        "frequency_level=simd256",
                        "--packet",
                        "0,8",
                    ])
                    .args(["--threads", &t.to_string(), "--reps", &o.reps.to_string()]);
                    if robust {
                        e.arg("--robust");
                    }
                    for line in stdout_of(&mut e)?.lines() {
                        let (Some(q), Some(mode), Some(v)) = (
                            json_field(line, "query").and_then(query_name),
                            json_field(line, "mode"),
                            json_field(line, "mrays_per_s_median").and_then(|v| v.parse::<f64>().ok()),
                        ) else {
                            continue;
                        };
                        if !robust
                            && let Some(h) = json_field(line, "hits")
                                .or_else(|| json_field(line, "occluded"))
                                .and_then(|h| h.parse().ok())
                        {
                            hits.entry((scene.clone(), q)).or_default()[1] = h;
                        }
                        let slot = usize::from(mode != "single") + 1 + if robust { 2 } else { 0 };
                        let row = table.entry((scene.clone(), q, t)).or_default();
                        row[slot] = row[slot].max(v);
                    }
                }
                let mut p = Command::new(bench);
                p.current_dir(root).arg("--mesh").arg(mesh);
                if grid {
                    p.args(["--grid", "6"]);
                }
                // The same secondary rays as the peer's (its generator, its order).
                p.args(["--threads", &t.to_string(), "--reps", &o.reps.to_string(), "--rays", "peer"]);
                for line in stdout_of(&mut p)?.lines() {
                    let (Some(q), Some(v)) = (
                        json_field(line, "query"),
                        json_field(line, "mrays_per_s").and_then(|v| v.parse::<f64>().ok()),
                    ) else {
                        continue;
                    };
                    // prism's best of its single-ray and packet queries.
                    let q = q.strip_suffix("-packet").unwrap_or(q);
                    let Some(q) = ["primary", "incoherent", "shadow"].into_iter().find(|&k| k == q) else {
                        continue;
                    };
                    if let Some(h) = json_field(line, "hits").and_then(|h| h.parse().ok()) {
                        hits.entry((scene.clone(), q)).or_default()[0] = h;
                    }
                    let row = table.entry((scene.clone(), q, t)).or_default();
                    row[0] = row[0].max(v);
                }
            }
        }
    }
    eprintln!("\nprism vs Embree 3 (best of {} alternating rounds, Mrays/s)", o.rounds);
    let robust_head = if o.robust { "  robust best  ratio (robust)" } else { "" };
    eprintln!(
        "{:<8} {:<11} {:>3} {:>9} {:>13} {:>14} {:>8}{robust_head}",
        "scene", "query", "thr", "prism", "Embree single", "Embree packet8", "ratio"
    );
    for ((scene, q, t), [prism, single, packet, r_single, r_packet]) in &table {
        let ratio = prism / single.max(*packet);
        let (mut json, mut text) = (String::new(), String::new());
        if o.robust {
            let robust = r_single.max(*r_packet);
            let ratio = prism / robust;
            json = format!(
                ",\"embree_robust_single\":{r_single:.3},\"embree_robust_packet8\":{r_packet:.3},\"ratio_robust\":{ratio:.3}"
            );
            text = format!(" {robust:>13.2} {ratio:>13.2}×");
        }
        println!(
            "{{\"bench\":\"vs-embree\",\"scene\":\"{scene}\",\"query\":\"{q}\",\"threads\":{t},\"prism\":{prism:.3},\"embree_single\":{single:.3},\"embree_packet8\":{packet:.3},\"ratio\":{ratio:.3}{json}}}"
        );
        eprintln!("{scene:<8} {q:<11} {t:>3} {prism:>9.2} {single:>13.2} {packet:>14.2} {ratio:>7.2}×{text}");
    }
    eprintln!("\nhits on the same rays (occluded rays for shadow rays): prism, Embree");
    for ((scene, q), [p, e]) in &hits {
        println!(
            "{{\"bench\":\"vs-embree-hits\",\"scene\":\"{scene}\",\"query\":\"{q}\",\"prism\":{p},\"embree\":{e}}}"
        );
        eprintln!("{scene:<8} {q:<11} {p:>10} {e:>10} ({:+})", *p as i64 - *e as i64);
    }
    Ok(())
}

fn vs_povray(root: &Path, pov: &Path, prism: &Path, pov_dir: &Path, rounds: usize) -> Result<()> {
    let out_dir = std::env::temp_dir().join(format!("prism-vs-peers-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir)?;
    let (mut best_pov, mut best_prism) = (f64::INFINITY, f64::INFINITY);
    // Render phases: POV-Ray's "Trace Time", prism's `seconds.render`.
    let (mut trace_pov, mut render_prism) = (f64::INFINITY, f64::INFINITY);
    let stats = out_dir.join("prism-stats.json");
    for round in 0..rounds {
        eprintln!("round {}/{rounds}: seed scene, POV-Ray then prism (2 threads)", round + 1);
        let mut p = Command::new("povray");
        p.current_dir(root)
            .arg(format!("+I{}", pov.display()))
            .arg(format!("+O{}", out_dir.join("pov.png").display()))
            .args(["+W1280", "+H720"])
            .arg(format!("+L{}", pov_dir.display()))
            // `-V` without `-GA`: no progress lines, but the statistics
            // (with the trace time) on stderr.
            .args(["-D", "-V", "+WT2", "+A0.0", "+AM1", "+R2", "-J"]);
        let t = Instant::now();
        let out = p.output().with_context(|| format!("running {p:?}"))?;
        best_pov = best_pov.min(t.elapsed().as_secs_f64());
        let log = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() {
            bail!("{p:?} failed ({}):\n{log}", out.status);
        }
        if let Some(s) = pov_trace_seconds(&log) {
            trace_pov = trace_pov.min(s);
        }
        let mut r = Command::new(prism);
        r.current_dir(root)
            .args(["render", "scenes/seed.toml", "--threads", "2", "-o"])
            .arg(out_dir.join("prism.png"))
            .arg("--stats-json")
            .arg(&stats);
        let t = Instant::now();
        stdout_of(&mut r)?;
        best_prism = best_prism.min(t.elapsed().as_secs_f64());
        let report =
            std::fs::read_to_string(&stats).with_context(|| format!("reading {}", stats.display()))?;
        if let Some(s) = prism_render_seconds(&report) {
            render_prism = render_prism.min(s);
        }
    }
    let _ = std::fs::remove_dir_all(&out_dir);
    let ratio = best_pov / best_prism;
    let (json, text) = if trace_pov.is_finite() && render_prism.is_finite() {
        let render_ratio = trace_pov / render_prism;
        (
            format!(
                ",\"povray_trace_s\":{trace_pov:.3},\"prism_render_s\":{render_prism:.3},\"render_ratio\":{render_ratio:.3}"
            ),
            format!(
                "\n  render phases alone: POV-Ray's trace {trace_pov:.2} s, prism's render {render_prism:.2} s: {render_ratio:.2}×"
            ),
        )
    } else {
        (
            String::new(),
            "\n  render phases: not reported (no \"Trace Time\" from POV-Ray or no render time from prism)"
                .into(),
        )
    };
    println!(
        "{{\"bench\":\"vs-povray\",\"scene\":\"scenes/seed.toml\",\"threads\":2,\"povray_s\":{best_pov:.3},\"prism_s\":{best_prism:.3},\"ratio\":{ratio:.3}{json}}}"
    );
    eprintln!(
        "\nseed scene, 1280×720, 2 threads (best of {rounds}): POV-Ray {best_pov:.2} s, prism {best_prism:.2} s: prism {ratio:.2}× faster{text}"
    );
    Ok(())
}

/// `seconds.render` of a `prism render --stats-json` report: the value of
/// `render` inside the `seconds` object, not any other key of that name.
fn prism_render_seconds(report: &str) -> Option<f64> {
    let seconds = &report[report.find("\"seconds\":")?..];
    json_field(seconds, "render")?.parse().ok()
}

/// The seconds of POV-Ray's "Trace Time" statistics line
/// (`  Trace Time:       0 hours  0 minutes  1 seconds (1.690 seconds)`).
fn pov_trace_seconds(log: &str) -> Option<f64> {
    let line = log.lines().find(|l| l.trim_start().starts_with("Trace Time:"))?;
    let inner = line.rsplit_once('(')?.1;
    inner.strip_suffix(')')?.trim().strip_suffix("seconds")?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::{json_field, parse, pov_trace_seconds, prism_render_seconds};

    #[test]
    fn povray_trace_time() {
        let log = "Render Time:\n  Photon Time:      No photons\n  Trace Time:       0 hours  0 minutes  1 seconds (1.690 seconds)\n              using 2 thread(s) with 3.213 CPU-seconds total\n";
        assert_eq!(pov_trace_seconds(log), Some(1.69));
        assert_eq!(pov_trace_seconds("  Parse Time:  0 hours  0 minutes  0 seconds (0.020 seconds)"), None);
        assert_eq!(pov_trace_seconds("  Trace Time:  garbled"), None);
    }

    #[test]
    fn render_seconds_from_prism_stats() {
        // A `render` key before `seconds` (here a made-up one) is not it.
        let stats = "{\n  \"rays\": {\"render\": 7},\n  \"seconds\": {\n    \"bvh_build\": 0.0004,\n    \"render\": 0.74081801,\n    \"total\": 0.787\n  }\n}";
        assert_eq!(prism_render_seconds(stats), Some(0.74081801));
        assert_eq!(prism_render_seconds("{\"seconds\": {\"total\": 0.7}}"), None);
        assert_eq!(prism_render_seconds("{\"render\": 0.7}"), None);
    }

    #[test]
    fn robust_embree_is_opt_in() {
        let args = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let o = parse(&args(&["--vs-peers", "--rounds", "3"])).unwrap();
        assert!(!o.robust);
        assert_eq!(o.rounds, 3);
        let o = parse(&args(&["--vs-peers", "--embree-robust", "--scenes", "grid"])).unwrap();
        assert!(o.robust);
        assert_eq!(o.scenes, ["grid"]);
        assert!(parse(&args(&["--vs-peers", "--robust"])).is_err());
    }

    #[test]
    fn json_fields_of_both_benches() {
        let e = r#"{"query":"occlusion_to_light","mode":"packet8","threads":2,"mrays_per_s_median":8.534,"hits":3}"#;
        assert_eq!(json_field(e, "query"), Some("occlusion_to_light"));
        assert_eq!(json_field(e, "mode"), Some("packet8"));
        assert_eq!(json_field(e, "mrays_per_s_median"), Some("8.534"));
        assert_eq!(json_field(e, "hits"), Some("3"));
        let p = r#"{"scene":"bunny","query":"shadow","threads":1,"mrays_per_s":1.220}"#;
        assert_eq!(json_field(p, "mrays_per_s"), Some("1.220"));
        assert_eq!(json_field(p, "threads"), Some("1"));
        assert_eq!(json_field(p, "missing"), None);
    }
}
