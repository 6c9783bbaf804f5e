//! The hierarchy against brute force on the shared real meshes (skipped
//! with a printed reason when `../shared/data` is absent, failed under CI:
//! see prism-testkit).

mod common;

use common::{Rng, compare_all, compare_closest};
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Ray, Transform};
use rayon::prelude::*;
use std::sync::Arc;

/// Rays per mesh. Brute force tests every triangle per ray (up to 69k),
/// so this is kept to a few hundred primary rays per mesh, each followed
/// by a spawned secondary ray when it hits.
const RAYS: usize = 400;

#[test]
fn shared_meshes_match_brute_force() {
    for (name, path) in prism_testkit::shared_meshes() {
        let mesh = Arc::new(prism_testkit::load_obj(&path).unwrap());
        let b = prism_geometry::Intersect::bounds(&*mesh);
        let size = b.extent().max_element();
        // The mesh as is, and a second, rotated and scaled instance beside it.
        let second = Transform::rotate_y(0.7)
            .then(&Transform::scale(Vec3::splat(0.8)).unwrap())
            .then(&Transform::translate(Vec3::new(size * 1.1, 0.0, 0.0)).unwrap());
        let objects = vec![
            Object::Mesh { mesh: 0, transform: Transform::IDENTITY },
            Object::Mesh { mesh: 0, transform: second },
        ];
        let accel = Accel::build(vec![mesh], objects).unwrap();
        let sb = accel.bounds();
        let (c, half) = (sb.center(), sb.extent() * 0.5);
        let results: Vec<(usize, usize)> = (0..RAYS)
            .into_par_iter()
            .map(|k| {
                let mut rng = Rng::new(k as u64 * 7 + name.len() as u64);
                // From outside toward a point of the box, or from inside it.
                let o = if k % 4 == 0 {
                    c + half * rng.vec_in(Vec3::splat(-1.0), Vec3::ONE)
                } else {
                    c + rng.unit() * half.length() * 2.0
                };
                let target = c + half * rng.vec_in(Vec3::splat(-0.8), Vec3::splat(0.8));
                let d = if k % 5 == 0 { rng.direction() } else { (target - o).normalize_or(Vec3::X) };
                let ray = Ray::new(o, d);
                let hit = compare_closest(&accel, &ray).unwrap_or_else(|e| panic!("{name}, ray {k}: {e}"));
                let mut n = compare_all(&accel, &ray).unwrap_or_else(|e| panic!("{name}, ray {k}: {e}"));
                let mut hits = 0;
                if let Some(h) = hit {
                    hits = 1;
                    // Spawned off the surface: toward a light, and a bounce.
                    let light = c + Vec3::new(1.0, 2.0, 1.5) * half.length();
                    let shadow = Ray::spawn_to(h.hit.point, h.hit.geo_normal, light);
                    compare_closest(&accel, &shadow)
                        .unwrap_or_else(|e| panic!("{name}, shadow ray {k}: {e}"));
                    let bounce = Ray::spawn(h.hit.point, h.hit.geo_normal, rng.unit());
                    compare_closest(&accel, &bounce)
                        .unwrap_or_else(|e| panic!("{name}, bounce ray {k}: {e}"));
                    n += compare_all(&accel, &bounce)
                        .unwrap_or_else(|e| panic!("{name}, bounce ray {k}: {e}"));
                }
                (hits, n)
            })
            .collect();
        let hits: usize = results.iter().map(|r| r.0).sum();
        let crossings: usize = results.iter().map(|r| r.1).sum();
        eprintln!(
            "{name}: {} triangles, {RAYS} rays, {hits} hits, {crossings} crossings agree",
            accel.stats().stored_triangles
        );
        assert!(hits > RAYS / 4, "{name}: rays aimed at the mesh should mostly hit");
    }
}
