//! `prism-bench`: build time, memory and rays per second of prism's
//! acceleration structure on fixed, reproducible ray sets (issue 7).
//!
//! Run it through `cargo xtask bench` (release build). One JSON line per
//! measurement goes to stdout; a readable table goes to stderr.
//!
//! ```text
//! prism-bench [--data DIR] [--mesh PATH [--grid N]] [--reps N]
//!             [--threads 1,2] [--quality NAME] [--width W --height H]
//!             [--rays issue7|peer] [--queries NAME,…]
//! ```
//!
//! `--rays peer` makes the incoherent and shadow sets as the Embree peer's
//! benchmark makes them (`../shared/peers/embree/bench.cpp`; `cargo xtask
//! bench --vs-peers` passes it), so that both sides trace the same rays;
//! the default, `issue7`, keeps the sets every earlier number in
//! docs/benchmarks.md was measured on.
//!
//! Without `--mesh`: the Stanford bunny, the kitchen, and a 6×6×6 grid of
//! bunny instances, from `DIR` (default `../shared/data`).
//!
//! The closest-hit sets (`primary`, `primary-packet`, `incoherent`,
//! `incoherent-packet`) ask
//! for hit records (`Accel::closest_record`: object, triangle, `t`,
//! barycentrics), as Embree's `rtcIntersect` answers, not for the shading
//! hit the renderer then builds with `Accel::resolve`.

use prism_bvh::PACKET_SIZE;
use prism_bvh::{Accel, BuildOptions, BuildQuality, Object};
use prism_geometry::{Aabb, Ray, Transform, TriangleMesh};
use prism_testkit::bench::{
    grid_offsets, incoherent_rays, offset_hit_points, peer_secondary_rays, primary_rays, shadow_rays,
    tile_order,
};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

type Error = Box<dyn std::error::Error>;

/// A query over a slice of rays: how many count as hits.
type Query<'a> = &'a (dyn Fn(&[Ray]) -> usize + Sync);

struct Options {
    data: PathBuf,
    mesh: Option<PathBuf>,
    grid: Option<u32>,
    reps: usize,
    threads: Vec<usize>,
    quality: Option<BuildQuality>,
    width: u32,
    height: u32,
    /// Ray sets to run (all when empty).
    queries: Vec<String>,
    /// Which secondary ray sets (`--rays`).
    rays: RaySets,
}

/// The secondary (incoherent and shadow) ray sets.
#[derive(Clone, Copy, PartialEq, Eq)]
enum RaySets {
    /// Issue 7's: eight hemisphere rays per hit point, hit points in the
    /// primary set's 8×8-pixel tile order, one shadow ray per point.
    Issue7,
    /// The Embree peer's, made as it makes them
    /// ([`prism_testkit::bench::peer_secondary_rays`]): what
    /// `cargo xtask bench --vs-peers` traces on both sides.
    Peer,
}

/// The ray sets and queries the harness runs, in order.
const QUERIES: [&str; 6] =
    ["primary", "primary-packet", "incoherent", "incoherent-packet", "shadow", "shadow-packet"];

fn parse(args: &[String]) -> Result<Options, Error> {
    let mut o = Options {
        data: PathBuf::from("../shared/data"),
        mesh: None,
        grid: None,
        reps: 5,
        threads: vec![1, 2],
        quality: None,
        width: 1920,
        height: 1080,
        queries: Vec::new(),
        rays: RaySets::Issue7,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--data" => o.data = value()?.into(),
            "--mesh" => o.mesh = Some(value()?.into()),
            "--grid" => o.grid = Some(value()?.parse()?),
            "--reps" => o.reps = value()?.parse::<usize>()?.max(1),
            "--threads" => {
                o.threads = value()?.split(',').map(str::parse).collect::<Result<_, _>>()?;
            }
            "--quality" => {
                let v = value()?;
                o.quality = Some(
                    BuildQuality::ALL
                        .into_iter()
                        .find(|q| q.name() == v)
                        .ok_or_else(|| format!("unknown quality {v} (fastest … very-slow)"))?,
                );
            }
            "--width" => o.width = value()?.parse()?,
            "--height" => o.height = value()?.parse()?,
            "--queries" => {
                o.queries = value()?.split(',').map(str::to_string).collect();
                if let Some(q) = o.queries.iter().find(|q| !QUERIES.contains(&q.as_str())) {
                    return Err(format!("unknown query {q} (one of {})", QUERIES.join(", ")).into());
                }
            }
            "--rays" => {
                o.rays = match value()?.as_str() {
                    "issue7" => RaySets::Issue7,
                    "peer" => RaySets::Peer,
                    v => return Err(format!("unknown ray sets {v} (issue7 or peer)").into()),
                };
            }
            "-h" | "--help" => {
                eprintln!(
                    "prism-bench [--data DIR] [--mesh PATH [--grid N]] [--reps N] [--threads 1,2] \
                     [--quality fastest|very-fast|fast|medium|slow|very-slow] [--width W --height H] \
                     [--rays issue7|peer] [--queries primary,primary-packet,incoherent,incoherent-packet,shadow,shadow-packet]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(o)
}

/// Runs `f` over `rays` on `threads` threads; returns how many it counted.
fn trace(rays: &[Ray], threads: usize, f: Query<'_>) -> usize {
    // A multiple of the packet size.
    const CHUNK: usize = 4096;
    let next = AtomicUsize::new(0);
    let work = || {
        let mut n = 0;
        loop {
            let start = next.fetch_add(CHUNK, Ordering::Relaxed);
            if start >= rays.len() {
                return n;
            }
            n += f(&rays[start..(start + CHUNK).min(rays.len())]);
        }
    };
    if threads <= 1 {
        return work();
    }
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads).map(|_| s.spawn(work)).collect();
        handles.into_iter().map(|h| h.join().unwrap_or(0)).sum()
    })
}

fn peak_rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

struct Row {
    scene: String,
    query: &'static str,
    threads: usize,
    rays: usize,
    hits: usize,
    mrays: f64,
    build_ms: f64,
    bvh_bytes: usize,
}

fn bench_scene(name: &str, accel: &Accel, o: &Options, rows: &mut Vec<Row>) {
    let stats = accel.stats();
    let b = accel.bounds();
    let t0 = Instant::now();
    // In 8×8 pixel blocks, so that the packet queries get neighbouring
    // pixels (the single-ray queries trace the same rays in the same order).
    let row_major = primary_rays(b, o.width, o.height);
    let primary = tile_order(&row_major, o.width, o.height, 8);
    let (incoherent, shadow) = match o.rays {
        RaySets::Issue7 => {
            let points = offset_hit_points(&primary, b, |r| {
                accel.closest_hit(r).map(|h| (h.hit.point, h.hit.geo_normal))
            });
            (incoherent_rays(&points, 8), shadow_rays(&points, b))
        }
        RaySets::Peer => {
            let sets = peer_secondary_rays(&row_major, b, |r| {
                accel.closest_hit(r).map(|h| (h.hit.t, h.hit.geo_normal))
            });
            eprintln!("{name}: the Embree peer's secondary rays, {} passes over the hit points", sets.copies);
            (sets.incoherent, sets.shadow)
        }
    };
    eprintln!(
        "{name}: {} triangles stored, {} as seen by rays; built in {:.1} ms, {:.1} MB; \
         {} + {} + {} rays generated in {:.1} s",
        stats.stored_triangles,
        stats.instanced_triangles,
        stats.build_seconds * 1e3,
        stats.bvh_bytes as f64 / 1e6,
        primary.len(),
        incoherent.len(),
        shadow.len(),
        t0.elapsed().as_secs_f64()
    );
    // Closest hits as records (object, triangle, t, barycentrics), as
    // Embree's bench reads them; `Accel::resolve` would build the shading
    // hit from each.
    let closest = |rays: &[Ray]| rays.iter().filter(|r| accel.closest_record(r).is_some()).count();
    let occluded = |rays: &[Ray]| rays.iter().filter(|r| accel.occluded(r)).count();
    let closest_packet = |rays: &[Ray]| {
        let mut out = [None; PACKET_SIZE];
        rays.chunks(PACKET_SIZE)
            .map(|p| {
                accel.closest_record_packet(p, &mut out);
                out[..p.len()].iter().filter(|h| h.is_some()).count()
            })
            .sum()
    };
    let occluded_packet = |rays: &[Ray]| {
        let mut out = [false; PACKET_SIZE];
        rays.chunks(PACKET_SIZE)
            .map(|p| {
                accel.occluded_packet(p, &mut out);
                out[..p.len()].iter().filter(|&&h| h).count()
            })
            .sum()
    };
    let sets: [(&'static str, &[Ray], Query<'_>); 6] = [
        ("primary", &primary, &closest),
        ("primary-packet", &primary, &closest_packet),
        ("incoherent", &incoherent, &closest),
        ("incoherent-packet", &incoherent, &closest_packet),
        ("shadow", &shadow, &occluded),
        ("shadow-packet", &shadow, &occluded_packet),
    ];
    debug_assert!(sets.iter().map(|s| s.0).eq(QUERIES), "QUERIES names the sets");
    for (query, rays, f) in sets {
        if !o.queries.is_empty() && !o.queries.iter().any(|q| q == query) {
            continue;
        }
        for &threads in &o.threads {
            let mut times = Vec::new();
            let mut hits = 0;
            for _ in 0..o.reps {
                let t = Instant::now();
                hits = trace(rays, threads, f);
                times.push(t.elapsed().as_secs_f64());
            }
            times.sort_by(f64::total_cmp);
            let median = times[times.len() / 2];
            let mrays = rays.len() as f64 / median / 1e6;
            let quality = o.quality.unwrap_or(BuildOptions::default().mesh_quality).name();
            println!(
                "{{\"scene\":\"{name}\",\"query\":\"{query}\",\"threads\":{threads},\"rays\":{},\"hits\":{hits},\
                 \"mrays_per_s\":{mrays:.3},\"build_ms\":{:.3},\"bvh_bytes\":{},\"quality\":\"{quality}\",\
                 \"median_s\":{median:.5},\"reps\":{}}}",
                rays.len(),
                stats.build_seconds * 1e3,
                stats.bvh_bytes,
                o.reps
            );
            rows.push(Row {
                scene: name.to_string(),
                query,
                threads,
                rays: rays.len(),
                hits,
                mrays,
                build_ms: stats.build_seconds * 1e3,
                bvh_bytes: stats.bvh_bytes,
            });
        }
    }
}

fn build(name: &str, mesh: TriangleMesh, grid: Option<u32>, o: &Options) -> Result<Accel, Error> {
    let extent = Aabb::from_points(mesh.positions()).extent();
    let mut objects = Vec::new();
    for offset in grid_offsets(extent, grid.unwrap_or(1)) {
        objects.push(Object::Mesh { mesh: 0, transform: Transform::translate(offset)? });
    }
    let mut options = BuildOptions::default();
    if let Some(q) = o.quality {
        options.mesh_quality = q;
    }
    let accel = Accel::build_with(vec![Arc::new(mesh)], objects, options)?;
    eprintln!("{name}: peak RSS after build {:.1} MB", peak_rss_bytes().map_or(f64::NAN, |b| b as f64 / 1e6));
    Ok(accel)
}

fn run() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let o = parse(&args)?;
    let scenes: Vec<(String, PathBuf, Option<u32>)> = match &o.mesh {
        Some(p) => {
            let stem = p.file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
            let name = match o.grid {
                Some(n) => format!("{stem}-grid{n}"),
                None => stem,
            };
            vec![(name, p.clone(), o.grid)]
        }
        None => vec![
            ("bunny".into(), o.data.join("stanford-bunny.obj"), None),
            ("kitchen".into(), o.data.join("kitchen.obj"), None),
            ("bunny-grid6".into(), o.data.join("stanford-bunny.obj"), Some(6)),
        ],
    };
    let mut rows = Vec::new();
    for (name, path, grid) in scenes {
        let mesh = prism_testkit::load_obj(&path)?;
        let accel = build(&name, mesh, grid, &o)?;
        bench_scene(&name, &accel, &o, &mut rows);
    }
    eprintln!(
        "\n{:<14} {:<14} {:>3} {:>10} {:>10} {:>9} {:>10} {:>10}",
        "scene", "query", "thr", "rays", "hits", "Mrays/s", "build ms", "BVH MB"
    );
    for r in &rows {
        eprintln!(
            "{:<14} {:<14} {:>3} {:>10} {:>10} {:>9.2} {:>10.1} {:>10.2}",
            r.scene,
            r.query,
            r.threads,
            r.rays,
            r.hits,
            r.mrays,
            r.build_ms,
            r.bvh_bytes as f64 / 1e6
        );
    }
    if let Some(b) = peak_rss_bytes() {
        eprintln!("peak RSS of the whole process: {:.1} MB", b as f64 / 1e6);
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("prism-bench: {e}");
        std::process::exit(1);
    }
}
