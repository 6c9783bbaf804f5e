//! The hierarchy against brute force on random scenes of every shape kind
//! (spheres, planes, boxes, cylinders, cones, disks, triangles, instanced
//! meshes, all under random affine transforms).

mod common;

use common::{Rng, compare_all, compare_closest, random_ray, random_scene, random_shape, random_transform};
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Instance, Ray, Sphere, Transform};

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

/// A scene whose top level holds one object (each shape kind, and a mesh
/// instance, under a random transform, sometimes over a plane) is tested
/// without walking the top level. Its closest hits, occlusion and
/// crossings match brute force; its occlusion packets match its single
/// rays; and its closest hits and occlusion, single and packed, match bit
/// for bit those of the same scene with a far, tiny sphere added (which
/// makes the queries walk the top level).
#[test]
fn single_object_scenes_match_brute_force_and_the_walked_top_level() {
    let mut compared = 0;
    for seed in 0..48u64 {
        let mut rng = Rng::new(1000 + seed);
        let (meshes, mut objects) = random_scene(&mut rng, 9);
        let one = match seed % 8 {
            7 => objects.swap_remove(8),
            kind => Object::Shape(Instance::new(
                random_shape(&mut rng, kind as usize % 6),
                random_transform(&mut rng),
            )),
        };
        let mut objects = vec![one];
        if seed % 3 == 0 {
            objects.push(Object::Shape(Instance::new(random_shape(&mut rng, 6), Transform::IDENTITY)));
        }
        let sole = Accel::build(meshes.clone(), objects.clone()).unwrap();
        let far = Sphere::new(Vec3::splat(1.0e4), 1.0e-3).unwrap();
        objects.push(Object::Shape(Instance::new(far.into(), Transform::IDENTITY)));
        let walked = Accel::build(meshes, objects).unwrap();
        let b = sole.bounds();
        let (c, size) =
            if b.is_empty() { (Vec3::ZERO, 10.0) } else { (b.center(), b.extent().max_element() * 0.6) };
        let rays: Vec<Ray> = (0..1_000).map(|_| random_ray(&mut rng, c, size)).collect();
        let (mut packed, mut packed_walked) = (vec![false; rays.len()], vec![false; rays.len()]);
        sole.occluded_packet(&rays, &mut packed);
        walked.occluded_packet(&rays, &mut packed_walked);
        assert_eq!(packed, packed_walked, "scene {seed}: occlusion packets");
        for (k, &ray) in rays.iter().enumerate() {
            assert_eq!(packed[k], sole.occluded(&ray), "scene {seed}, ray {k}: {ray:?}");
            let hit = compare_closest(&sole, &ray).unwrap_or_else(|e| panic!("scene {seed}, ray {k}: {e}"));
            if k % 10 == 0 {
                compare_all(&sole, &ray).unwrap_or_else(|e| panic!("scene {seed}, ray {k}: {e}"));
            }
            assert_eq!(hit, walked.closest_hit(&ray), "scene {seed}, ray {k}: {ray:?}");
            assert_eq!(sole.occluded(&ray), walked.occluded(&ray), "scene {seed}, ray {k}: {ray:?}");
            if let Some(h) = hit {
                let r2 = Ray::spawn(h.hit.point, h.hit.geo_normal, rng.unit());
                assert_eq!(sole.closest_hit(&r2), walked.closest_hit(&r2), "scene {seed}, spawned {k}");
                compared += 1;
            }
        }
    }
    assert!(compared > 5_000, "the rays should often hit: {compared}");
}
