//! obvhs's own BVH2 and CWBVH traversals side by side on one mesh, to
//! choose the layout by measurement (docs/benchmarks.md). Release build:
//!
//! ```text
//! cargo run --release -p prism-bvh --example bvh2_vs_cwbvh -- MESH.obj [quality]
//! ```
//!
//! Rays: prism-bench's (prism-testkit's issue-7 camera at 1920×1080 and 8
//! hemisphere rays per hit, origin offset 2e-4·r); median of 5, one thread.

use obvhs::BvhBuildParams;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use prism_geometry::glam::Vec3;
use prism_testkit::bench::{incoherent_rays, offset_hit_points, primary_rays};
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
    let mesh = prism_testkit::load_obj(path.as_ref()).expect("readable OBJ");
    let tris: Vec<Triangle> = (0..mesh.len())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            Triangle { v0: a.into(), v1: b.into(), v2: c.into() }
        })
        .collect();
    let bounds = prism_geometry::Aabb::from_points(mesh.positions());
    let mut d = Duration::ZERO;
    let t0 = Instant::now();
    let bvh2 = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, params, &mut d);
    let bvh2_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t0 = Instant::now();
    let cw = obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, params, &mut d);
    let cw_ms = t0.elapsed().as_secs_f64() * 1e3;

    let to_obvhs = |r: &prism_geometry::Ray| Ray::new(r.origin.into(), r.dir.into(), r.t_min, r.t_max);
    let camera = primary_rays(bounds, 1920, 1080);
    let primary: Vec<Ray> = camera.iter().map(to_obvhs).collect();
    let closest_cw = |ray: &Ray| {
        let mut hit = RayHit::none();
        cw.ray_traverse(*ray, &mut hit, |r, id| tris[cw.primitive_indices[id] as usize].intersect(r));
        hit
    };
    // Secondary rays from the primary hits.
    let points = offset_hit_points(&camera, bounds, |r| {
        let hit = closest_cw(&to_obvhs(r));
        (hit.t < f32::INFINITY).then(|| {
            let t = &tris[hit.primitive_id as usize];
            (r.at(hit.t), Vec3::from((t.v1 - t.v0).cross(t.v2 - t.v0)).normalize())
        })
    });
    let incoherent: Vec<Ray> = incoherent_rays(&points, 8).iter().map(to_obvhs).collect();
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
