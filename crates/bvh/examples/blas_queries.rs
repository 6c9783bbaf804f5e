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
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Ray, Transform, TriangleMesh};
use std::sync::Arc;

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
    fn hemisphere(&mut self, n: Vec3) -> Vec3 {
        let z = 1.0 - 2.0 * self.f32();
        let phi = std::f32::consts::TAU * self.f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        if d.dot(n) < 0.0 { -d } else { d }
    }
}

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
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) = tobj::load_obj(&args[1], &opts).expect("readable OBJ");
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        positions.extend(m.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        indices.extend(m.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
    }
    let mesh = TriangleMesh::new(positions, None, None, indices).expect("valid mesh");
    let n: u32 = args[2].parse().expect("grid size");
    let extent = Aabb::from_points(mesh.positions()).extent();
    let mut objects = Vec::new();
    for ix in 0..n.max(1) {
        for iy in 0..n.max(1) {
            for iz in 0..n.max(1) {
                let offset = 1.25 * Vec3::new(ix as f32, iy as f32, iz as f32) * extent;
                objects.push(Object::Mesh { mesh: 0, transform: Transform::translate(offset).unwrap() });
            }
        }
    }
    let options = BuildOptions::default();
    let accel = Accel::build_with(vec![Arc::new(mesh)], objects, options).unwrap();
    let w = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(480);
    let h = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(270);
    let b = accel.bounds();
    let (c, r) = (b.center(), (b.max - b.min).length() / 2.0);
    let primary = primary_rays(b, w, h);
    let rays: Vec<Ray> = if args[3] == "primary" {
        primary
    } else {
        let mut points = Vec::new();
        for ray in &primary {
            if let Some(h) = accel.closest_hit(ray) {
                let n =
                    if h.hit.geo_normal.dot(ray.dir) > 0.0 { -h.hit.geo_normal } else { h.hit.geo_normal };
                points.push((h.hit.point + n * (2e-4 * r), n));
            }
        }
        if args[3] == "incoherent" {
            let mut rng = Rng(0x5eed_0007);
            points
                .iter()
                .flat_map(|&(p, n)| (0..8).map(move |_| (p, n)))
                .map(|(p, n)| Ray::new(p, rng.hemisphere(n)))
                .collect()
        } else {
            let light = c + r * Vec3::new(1.0, 2.0, 1.5);
            points
                .iter()
                .map(|&(p, _)| {
                    let to = light - p;
                    let dist = to.length();
                    Ray::with_interval(p, to / dist, 0.0, dist)
                })
                .collect()
        }
    };
    // With `BLAS_QUERIES_SKIP` set, everything but the timed set: the
    // difference of the two instruction counts is the set's.
    let skip = std::env::var_os("BLAS_QUERIES_SKIP").is_some();
    let hits = if skip { 0 } else { run_set(&accel, &rays, args[3] == "shadow") };
    println!("{} {} {}: {} rays, {} hits", options.mesh_layout.name(), args[3], n, rays.len(), hits);
}
