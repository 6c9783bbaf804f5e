//! One query kind over prism-bench's ray sets, for instruction counts
//! under `valgrind --tool=cachegrind` (noise-free on a loaded machine,
//! unlike wall time). Release build:
//!
//! ```text
//! cargo build --release -p prism-bvh --example blas_queries
//! PRISM_BVH_BLAS=bvh2 valgrind --tool=cachegrind --cache-sim=no \
//!     target/release/examples/blas_queries MESH.obj GRID primary|incoherent|shadow [W H]
//! ```
//!
//! and again with `BLAS_QUERIES_SKIP=1` (the same run without the traced
//! set): the difference of the two `I refs` is the set's instruction count.
//!
//! The rays are prism-bench's (issue-7 camera, 8 hemisphere rays per hit
//! from the offset hit point, shadow segments to the light), at W×H
//! (default 480×270, a sixteenth of the benchmark's pixels). Only the
//! chosen set is traced; the layout comes from `PRISM_BVH_BLAS`.

use prism_bvh::{Accel, BuildOptions, Object};
use prism_geometry::{Aabb, Ray, Transform};
use prism_testkit::bench::{grid_offsets, incoherent_rays, offset_hit_points, primary_rays, shadow_rays};
use std::sync::Arc;

/// Traces `rays` with the query; kept out of line for `--toggle-collect`.
#[inline(never)]
fn run_set(accel: &Accel, rays: &[Ray], shadow: bool) -> usize {
    if shadow {
        rays.iter().filter(|r| accel.occluded(r)).count()
    } else {
        rays.iter().filter(|r| accel.closest_hit(r).is_some()).count()
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: blas_queries MESH.obj GRID primary|incoherent|shadow [W H]");
        return;
    }
    let mesh = prism_testkit::load_obj(args[1].as_ref()).expect("readable OBJ");
    let n: u32 = args[2].parse().expect("grid size");
    let extent = Aabb::from_points(mesh.positions()).extent();
    let objects: Vec<Object> = grid_offsets(extent, n)
        .into_iter()
        .map(|offset| Object::Mesh {
            mesh: 0,
            transform: Transform::translate(offset).expect("finite offset"),
        })
        .collect();
    let options = BuildOptions::default();
    let accel = Accel::build_with(vec![Arc::new(mesh)], objects, options).unwrap();
    let w = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(480);
    let h = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(270);
    let b = accel.bounds();
    let primary = primary_rays(b, w, h);
    let rays: Vec<Ray> = if args[3] == "primary" {
        primary
    } else {
        let points =
            offset_hit_points(&primary, b, |r| accel.closest_hit(r).map(|h| (h.hit.point, h.hit.geo_normal)));
        if args[3] == "incoherent" { incoherent_rays(&points, 8) } else { shadow_rays(&points, b) }
    };
    // With `BLAS_QUERIES_SKIP` set, everything but the timed set: the
    // difference of the two instruction counts is the set's.
    let skip = std::env::var_os("BLAS_QUERIES_SKIP").is_some();
    let hits = if skip { 0 } else { run_set(&accel, &rays, args[3] == "shadow") };
    println!("{} {} {}: {} rays, {} hits", options.mesh_layout.name(), args[3], n, rays.len(), hits);
}
