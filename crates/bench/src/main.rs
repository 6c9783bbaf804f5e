//! `prism-bench`: build time, memory and rays per second of prism's
//! acceleration structure on fixed, reproducible ray sets (issue 7).
//!
//! Run it through `cargo xtask bench` (release build). One JSON line per
//! measurement goes to stdout; a readable table goes to stderr.
//!
//! ```text
//! prism-bench [--data DIR] [--mesh PATH [--grid N]] [--reps N]
//!             [--threads 1,2] [--quality NAME] [--width W --height H]
//! ```
//!
//! Without `--mesh`: the Stanford bunny, the kitchen, and a 6×6×6 grid of
//! bunny instances, from `DIR` (default `../shared/data`).

use prism_bvh::{Accel, BuildOptions, BuildQuality, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Ray, Transform, TriangleMesh};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

type Error = Box<dyn std::error::Error>;

/// A query over one ray: whether it counts as a hit.
type Query<'a> = &'a (dyn Fn(&Ray) -> bool + Sync);

struct Options {
    data: PathBuf,
    mesh: Option<PathBuf>,
    grid: Option<u32>,
    reps: usize,
    threads: Vec<usize>,
    quality: Option<BuildQuality>,
    width: u32,
    height: u32,
}

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
            "-h" | "--help" => {
                eprintln!(
                    "prism-bench [--data DIR] [--mesh PATH [--grid N]] [--reps N] [--threads 1,2] \
                     [--quality fastest|very-fast|fast|medium|slow|very-slow] [--width W --height H]"
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(o)
}

/// Every shape of an OBJ as one mesh (positions only, polygons
/// triangulated).
fn load_obj(path: &Path) -> Result<TriangleMesh, Error> {
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) = tobj::load_obj(path, &opts).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        positions.extend(m.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        indices.extend(m.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
    }
    Ok(TriangleMesh::new(positions, None, None, indices)?)
}

fn mesh_bounds(m: &TriangleMesh) -> Aabb {
    Aabb::from_points(m.positions())
}

/// PCG32 (fixed seed: the same rays on every run).
struct Rng(u64);

impl Rng {
    fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        x.rotate_right((old >> 59) as u32)
    }
    fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    /// Uniform on the hemisphere around `n` (uniform on the sphere, flipped).
    fn hemisphere(&mut self, n: Vec3) -> Vec3 {
        let z = 1.0 - 2.0 * self.f32();
        let phi = std::f32::consts::TAU * self.f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        if d.dot(n) < 0.0 { -d } else { d }
    }
}

/// The issue's "bbox framing" camera: one ray per pixel centre.
fn primary_rays(b: Aabb, w: u32, h: u32) -> Vec<Ray> {
    let c = b.center();
    let r = (b.max - b.min).length() / 2.0;
    let vfov = 40f32.to_radians();
    let eye = c + Vec3::new(0.0, 0.0, r / (vfov / 2.0).sin());
    let forward = (c - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (vfov / 2.0).tan();
    let aspect = w as f32 / h as f32;
    let mut rays = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let sx = (2.0 * (i as f32 + 0.5) / w as f32 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (j as f32 + 0.5) / h as f32) * tan;
            rays.push(Ray::new(eye, (forward + sx * right + sy * up).normalize()));
        }
    }
    rays
}

/// Runs `f` over `rays` on `threads` threads; returns how many it counted.
fn trace(rays: &[Ray], threads: usize, f: Query<'_>) -> usize {
    const CHUNK: usize = 4096;
    let next = AtomicUsize::new(0);
    let work = || {
        let mut n = 0;
        loop {
            let start = next.fetch_add(CHUNK, Ordering::Relaxed);
            if start >= rays.len() {
                return n;
            }
            n += rays[start..(start + CHUNK).min(rays.len())].iter().filter(|r| f(r)).count();
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
    let c = b.center();
    let r = (b.max - b.min).length() / 2.0;
    let t0 = Instant::now();
    let primary = primary_rays(b, o.width, o.height);
    // Hit points (offset along the normal turned toward the ray) for the
    // secondary sets.
    let mut points = Vec::new();
    for ray in &primary {
        if let Some(h) = accel.closest_hit(ray) {
            let n = if h.hit.geo_normal.dot(ray.dir) > 0.0 { -h.hit.geo_normal } else { h.hit.geo_normal };
            points.push((h.hit.point + n * (2e-4 * r), n));
        }
    }
    let mut rng = Rng(0x5eed_0007);
    let mut incoherent = Vec::with_capacity(points.len() * 8);
    for &(p, n) in &points {
        for _ in 0..8 {
            incoherent.push(Ray::new(p, rng.hemisphere(n)));
        }
    }
    let light = c + r * Vec3::new(1.0, 2.0, 1.5);
    let shadow: Vec<Ray> = points
        .iter()
        .map(|&(p, _)| {
            let to = light - p;
            let dist = to.length();
            Ray::with_interval(p, to / dist, 0.0, dist)
        })
        .collect();
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
    let closest = |r: &Ray| accel.closest_hit(r).is_some();
    let occluded = |r: &Ray| accel.occluded(r);
    let sets: [(&'static str, &[Ray], Query<'_>); 3] = [
        ("primary", &primary, &closest),
        ("incoherent", &incoherent, &closest),
        ("shadow", &shadow, &occluded),
    ];
    for (query, rays, f) in sets {
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
    let extent = mesh_bounds(&mesh).extent();
    let mut objects = Vec::new();
    let n = grid.unwrap_or(1).max(1);
    for ix in 0..n {
        for iy in 0..n {
            for iz in 0..n {
                let offset = 1.25 * Vec3::new(ix as f32, iy as f32, iz as f32) * extent;
                objects.push(Object::Mesh { mesh: 0, transform: Transform::translate(offset)? });
            }
        }
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
        let mesh = load_obj(&path)?;
        let accel = build(&name, mesh, grid, &o)?;
        bench_scene(&name, &accel, &o, &mut rows);
    }
    eprintln!(
        "\n{:<14} {:<11} {:>3} {:>10} {:>10} {:>9} {:>10} {:>10}",
        "scene", "query", "thr", "rays", "hits", "Mrays/s", "build ms", "BVH MB"
    );
    for r in &rows {
        eprintln!(
            "{:<14} {:<11} {:>3} {:>10} {:>10} {:>9.2} {:>10.1} {:>10.2}",
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
