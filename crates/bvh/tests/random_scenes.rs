//! The hierarchy against brute force on random scenes of every shape kind
//! (spheres, planes, boxes, cylinders, cones, disks, triangles, instanced
//! meshes, all under random affine transforms).

mod common;

use common::{Rng, compare_all, compare_closest, random_ray, random_scene};
use prism_bvh::Accel;
use prism_geometry::Ray;
use prism_geometry::glam::Vec3;

/// Scenes × rays per scene: 40 × 2,500 = 100,000 primary rays (plus a
/// secondary ray spawned from each hit), compared for closest hit and
/// occlusion; every crossing is compared on one ray in ten.
const SCENES: u64 = 40;
const RAYS: usize = 2_500;

#[test]
fn random_scenes_match_brute_force() {
    let mut primary = 0;
    let mut hits = 0;
    let mut secondary = 0;
    let mut crossings = 0;
    for seed in 0..SCENES {
        let mut rng = Rng::new(seed);
        let n = 1 + rng.below(150);
        let (meshes, objects) = random_scene(&mut rng, n);
        let accel = Accel::build(meshes, objects).unwrap();
        let b = accel.bounds();
        let (c, size) =
            if b.is_empty() { (Vec3::ZERO, 10.0) } else { (b.center(), b.extent().max_element() * 0.6) };
        for k in 0..RAYS {
            let ray = random_ray(&mut rng, c, size);
            primary += 1;
            let hit = compare_closest(&accel, &ray).unwrap_or_else(|e| panic!("scene {seed}, ray {k}: {e}"));
            if k % 10 == 0 {
                crossings +=
                    compare_all(&accel, &ray).unwrap_or_else(|e| panic!("scene {seed}, ray {k}: {e}"));
            }
            if let Some(h) = hit {
                hits += 1;
                // A secondary ray spawned off the surface (t_min = 0), as the
                // shader spawns them: into either side.
                let d = rng.unit();
                let r2 = Ray::spawn(h.hit.point, h.hit.geo_normal, d);
                compare_closest(&accel, &r2).unwrap_or_else(|e| panic!("scene {seed}, spawned ray {k}: {e}"));
                secondary += 1;
            }
        }
    }
    eprintln!(
        "{primary} primary rays ({hits} hits), {secondary} spawned rays, {crossings} crossings compared"
    );
    assert!(hits > primary / 10, "the rays should mostly hit something");
}
