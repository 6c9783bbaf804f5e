//! obvhs's own BVH2 and CWBVH traversals side by side on one mesh, to
//! choose the layout by measurement (docs/benchmarks.md). Release build:
//!
//! ```text
//! cargo run --release -p prism-bvh --example bvh2_vs_cwbvh -- MESH.obj [quality]
//! ```
//!
//! Rays: the issue-7 camera (1920×1080) and 8 hemisphere rays per hit
//! (origin offset 2e-4·r), as in prism-bench; median of 5, one thread.

use obvhs::BvhBuildParams;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use prism_geometry::glam::{Vec3, Vec3A};
use std::time::{Duration, Instant};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: bvh2_vs_cwbvh MESH.obj [fastest|fast|medium|slow|very-slow]");
        return;
    };
    let params = match args.get(2).map(String::as_str) {
        Some("fastest") => BvhBuildParams::fastest_build(),
        Some("fast") => BvhBuildParams::fast_build(),
        Some("slow") => BvhBuildParams::slow_build(),
        Some("very-slow") => BvhBuildParams::very_slow_build(),
        _ => BvhBuildParams::medium_build(),
    };
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) = tobj::load_obj(path, &opts).expect("readable OBJ");
    let mut tris = Vec::new();
    for m in &models {
        let p = |i: u32| {
            let i = i as usize * 3;
            Vec3A::new(m.mesh.positions[i], m.mesh.positions[i + 1], m.mesh.positions[i + 2])
        };
        for t in m.mesh.indices.chunks_exact(3) {
            tris.push(Triangle { v0: p(t[0]), v1: p(t[1]), v2: p(t[2]) });
        }
    }
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for t in &tris {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let mut d = Duration::ZERO;
    let t0 = Instant::now();
    let bvh2 = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, params, &mut d);
    let bvh2_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t0 = Instant::now();
    let cw = obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, params, &mut d);
    let cw_ms = t0.elapsed().as_secs_f64() * 1e3;

    // Camera.
    let (w, h) = (1920u32, 1080u32);
    let c = Vec3::from((lo + hi) * 0.5);
    let r = Vec3::from(hi - lo).length() / 2.0;
    let vfov = 40f32.to_radians();
    let eye = c + Vec3::new(0.0, 0.0, r / (vfov / 2.0).sin());
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (vfov / 2.0).tan();
    let mut primary = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let sx = (2.0 * (i as f32 + 0.5) / w as f32 - 1.0) * tan * w as f32 / h as f32;
            let sy = (1.0 - 2.0 * (j as f32 + 0.5) / h as f32) * tan;
            let dir = (fwd + sx * right + sy * up).normalize();
            primary.push(Ray::new(eye.into(), dir.into(), 0.0, f32::INFINITY));
        }
    }
    let closest_cw = |ray: &Ray| {
        let mut hit = RayHit::none();
        cw.ray_traverse(*ray, &mut hit, |r, id| tris[cw.primitive_indices[id] as usize].intersect(r));
        hit
    };
    // Secondary rays from the primary hits.
    let mut s = 0x5eed_0007_u64;
    let mut rnd = move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut incoherent = Vec::new();
    for ray in &primary {
        let hit = closest_cw(ray);
        if hit.t == f32::INFINITY {
            continue;
        }
        let t = &tris[hit.primitive_id as usize];
        let mut n = Vec3::from((t.v1 - t.v0).cross(t.v2 - t.v0)).normalize();
        if n.dot(ray.direction.into()) > 0.0 {
            n = -n;
        }
        let p = Vec3::from(ray.origin + ray.direction * hit.t) + n * (2e-4 * r);
        for _ in 0..8 {
            let z = 1.0 - 2.0 * rnd();
            let phi = std::f32::consts::TAU * rnd();
            let q = (1.0 - z * z).max(0.0).sqrt();
            let mut d = Vec3::new(q * phi.cos(), q * phi.sin(), z);
            if d.dot(n) < 0.0 {
                d = -d;
            }
            incoherent.push(Ray::new(p.into(), d.into(), 0.0, f32::INFINITY));
        }
    }
    let time = |rays: &[Ray], f: &dyn Fn(&Ray) -> bool| {
        let mut v: Vec<(f64, usize)> = (0..5)
            .map(|_| {
                let t = Instant::now();
                let n = rays.iter().filter(|r| f(r)).count();
                (t.elapsed().as_secs_f64(), n)
            })
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        (rays.len() as f64 / v[2].0 / 1e6, v[2].1)
    };
    let cw_hit = |r: &Ray| closest_cw(r).t < f32::INFINITY;
    let b2_hit = |r: &Ray| {
        let mut hit = RayHit::none();
        bvh2.ray_traverse(*r, &mut hit, |r, id| tris[bvh2.primitive_indices[id] as usize].intersect(r));
        hit.t < f32::INFINITY
    };
    // prism-bvh's own CWBVH walk over the same triangles and rays.
    let positions: Vec<Vec3> = tris.iter().flat_map(|t| [t.v0.into(), t.v1.into(), t.v2.into()]).collect();
    let indices = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    let mesh = prism_geometry::TriangleMesh::new(positions, None, None, indices).expect("valid mesh");
    let accel = prism_bvh::Accel::build(
        vec![std::sync::Arc::new(mesh)],
        vec![prism_bvh::Object::Mesh { mesh: 0, transform: prism_geometry::Transform::IDENTITY }],
    )
    .expect("builds");
    let prism_hit = |r: &Ray| {
        let ray = prism_geometry::Ray::with_interval(r.origin.into(), r.direction.into(), r.tmin, r.tmax);
        accel.closest_hit(&ray).is_some()
    };
    println!(
        "build: BVH2 {bvh2_ms:.0} ms, CWBVH {cw_ms:.0} ms (obvhs builders, debug validation off in release)"
    );
    for (name, rays) in [("primary", &primary), ("incoherent", &incoherent)] {
        let (a, ha) = time(rays, &b2_hit);
        let (b, hb) = time(rays, &cw_hit);
        let (c, hc) = time(rays, &prism_hit);
        println!(
            "{name:<11} {} rays: obvhs BVH2 {a:.2} Mrays/s ({ha} hits), obvhs CWBVH {b:.2} ({hb} hits), \
             prism-bvh CWBVH {c:.2} ({hc} hits)",
            rays.len()
        );
    }
}
