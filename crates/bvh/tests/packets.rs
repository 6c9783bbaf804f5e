//! Packet queries (`closest_hit_packet`, `closest_record_packet`,
//! `occluded_packet`) against the single-ray queries, ray by ray: the same
//! object, triangle and hit bit for bit, on random scenes of every shape
//! kind, on the shared meshes, with every layout and node kernel, for
//! coherent packets (a camera's pixel block, shadow rays toward one point
//! and toward an area light's samples), spread ones, mixed octants, and
//! packets with unusable rays, zero direction components and every kind of
//! interval.

mod common;

use common::{Rng, random_scene};
use prism_bvh::{Accel, BlasKind, BuildOptions, Kernel, Object, PACKET_SIZE, SceneHit};
use prism_geometry::glam::Vec3;
use prism_geometry::{Instance, Ray, Transform};
use std::sync::Arc;

/// Checks both packet queries against the single-ray ones for `rays`.
fn compare(accel: &Accel, rays: &[Ray]) -> Result<usize, String> {
    let mut hits = vec![None; rays.len()];
    accel.closest_hit_packet(rays, &mut hits);
    let mut occluded = vec![false; rays.len()];
    accel.occluded_packet(rays, &mut occluded);
    let mut records = vec![None; rays.len()];
    accel.closest_record_packet(rays, &mut records);
    let mut n = 0;
    for (k, ray) in rays.iter().enumerate() {
        let single = accel.closest_hit(ray);
        if !same(accel, ray, &hits[k], &single) {
            return Err(format!("ray {k}: packet {:?}\nsingle {single:?}\nray {ray:?}", hits[k]));
        }
        // The records, packed and single, resolve to the single hit (up
        // to a tie, as `same` allows) and name what they resolve to.
        for (what, r) in [("packet", records[k]), ("single", accel.closest_record(ray))] {
            let resolved = r.and_then(|r| accel.resolve(r));
            let names = r.zip(resolved).is_none_or(|(r, h)| {
                r.object() == h.object
                    && r.triangle().unwrap_or(SceneHit::NO_TRIANGLE) == h.triangle
                    && r.t().to_bits() == h.hit.t.to_bits()
            });
            if !same(accel, ray, &resolved, &single) || !names || r.is_some() != resolved.is_some() {
                return Err(format!("ray {k}: {what} record {r:?}\nsingle {single:?}\nray {ray:?}"));
            }
        }
        if occluded[k] != accel.occluded(ray) {
            return Err(format!(
                "ray {k}: occluded_packet {} but occluded {}: {ray:?}",
                occluded[k], !occluded[k]
            ));
        }
        n += usize::from(single.is_some());
    }
    Ok(n)
}

/// The same hit: equal in every field, or a tie (another primitive at the
/// very same `t`, which the two walks may visit in another order), where
/// brute force crosses `a`'s primitive at that `t` indeed (so a hit
/// reported under a wrong object or triangle does not pass as a tie).
fn same(accel: &Accel, ray: &Ray, a: &Option<SceneHit>, b: &Option<SceneHit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            (a.object, a.triangle) == (b.object, b.triangle) && a == b
                || (a.object, a.triangle) != (b.object, b.triangle)
                    && a.hit.t.to_bits() == b.hit.t.to_bits()
                    && common::crosses_at(accel, ray, a)
        }
        _ => false,
    }
}

/// The packet kinds a renderer makes, around a scene of centre `c` and
/// size `size`.
fn packets(rng: &mut Rng, c: Vec3, size: f32) -> Vec<Vec<Ray>> {
    let mut all: Vec<Vec<Ray>> = Vec::new();
    // A camera's 8×8 pixel block: one origin, directions over a small cone.
    let eye = c + rng.unit() * size * 2.0;
    let look = (c + rng.vec_in(Vec3::splat(-size), Vec3::splat(size)) * 0.4 - eye).normalize_or(Vec3::X);
    let (u, v) = look.any_orthonormal_pair();
    let spread = rng.range(0.002, 0.05);
    all.push(
        (0..64)
            .map(|k| {
                let (i, j) = ((k % 8) as f32 + rng.f32(), (k / 8) as f32 + rng.f32());
                Ray::new(eye, look + (i - 4.0) * spread * u + (j - 4.0) * spread * v)
            })
            .collect(),
    );
    // Shadow rays from a patch of points toward one light.
    let light = c + rng.unit() * size * 1.5;
    let patch = c + rng.vec_in(Vec3::splat(-size), Vec3::splat(size)) * 0.5;
    all.push(
        (0..32)
            .map(|_| {
                let p = patch + rng.vec_in(Vec3::splat(-0.05), Vec3::splat(0.05)) * size;
                Ray::spawn_to(p, Vec3::Y, light)
            })
            .collect(),
    );
    // One point toward the 16 samples of a quad light.
    let p = c + rng.vec_in(Vec3::splat(-size), Vec3::splat(size)) * 0.5;
    let (e1, e2) = (rng.unit() * size * 0.3, rng.unit() * size * 0.3);
    all.push(
        (0..16)
            .map(|k| {
                let q = light + e1 * ((k % 4) as f32 + 0.5) / 4.0 + e2 * ((k / 4) as f32 + 0.5) / 4.0;
                Ray::spawn_to(p, Vec3::Z, q)
            })
            .collect(),
    );
    // Incoherent rays: mixed octants, some packets larger than one chunk.
    let n = [1, 3, 17, 64, 100][rng.below(5)];
    all.push((0..n).map(|_| common::random_ray(rng, c, size)).collect());
    // A coherent packet with odd members: unusable rays, zero direction
    // components of both signs, bounded and unbounded intervals.
    let mut odd: Vec<Ray> = all[0].clone();
    odd[3] = Ray::new(eye, Vec3::ZERO);
    odd[5] = Ray::new(Vec3::splat(f32::NAN), look);
    odd[9].dir.x = 0.0;
    odd[10].dir.y = -0.0;
    odd[11].t_max = size * rng.f32();
    odd[12].t_min = size * rng.f32();
    odd[13].t_max = f32::INFINITY;
    odd[14].t_min = odd[14].t_max;
    odd[15] = Ray { t_min: 1.0, t_max: 0.5, ..odd[15] };
    for r in odd.iter_mut().skip(40) {
        // Axis-parallel members.
        r.dir = Vec3::new(0.0, 0.0, -look.z.signum());
    }
    all.push(odd);
    all
}

fn check_scene(accel: &Accel, rng: &mut Rng, what: &str) -> usize {
    let b = accel.bounds();
    let (c, size) =
        if b.is_empty() { (Vec3::ZERO, 10.0) } else { (b.center(), b.extent().max_element() * 0.6) };
    let mut hits = 0;
    for (p, rays) in packets(rng, c, size).iter().enumerate() {
        hits += compare(accel, rays).unwrap_or_else(|e| panic!("{what}, packet {p}: {e}"));
        // Spawned again off the hits: the secondary rays of a pixel block.
        let mut found = vec![None; rays.len()];
        accel.closest_hit_packet(rays, &mut found);
        let d = rng.unit();
        let next: Vec<Ray> =
            found.iter().flatten().map(|h| Ray::spawn(h.hit.point, h.hit.geo_normal, d)).collect();
        hits += compare(accel, &next).unwrap_or_else(|e| panic!("{what}, packet {p} spawned: {e}"));
    }
    hits
}

#[test]
fn random_scenes_agree_with_single_rays() {
    let mut hits = 0;
    for seed in 0..60 {
        let mut rng = Rng::new(1000 + seed);
        let n = 1 + rng.below(150);
        let (meshes, objects) = random_scene(&mut rng, n);
        for layout in [BlasKind::Wide, BlasKind::Cwbvh] {
            let options = BuildOptions { mesh_layout: layout, ..BuildOptions::default() };
            let accel = Accel::build_with(meshes.clone(), objects.clone(), options).unwrap();
            for _ in 0..4 {
                hits += check_scene(&accel, &mut rng, &format!("scene {seed} {}", layout.name()));
            }
        }
    }
    eprintln!("{hits} hits compared");
    assert!(hits > 1000, "the packets should mostly hit something ({hits})");
}

/// A mesh instanced many times (the top level's leaves then hold packets
/// of mesh instances) under every node kernel this CPU runs: turned and
/// moved, and moved alone (whose packets walk the top level's rows moved,
/// see `Transform::object_offset`), and the two mixed.
#[test]
fn instance_grid_agrees_under_every_kernel() {
    let mut rng = Rng::new(5);
    let mesh = Arc::new(common::random_mesh(&mut rng, 400));
    for placing in ["turned", "moved", "mixed"] {
        let mut objects = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let turn = match placing {
                    "turned" => true,
                    "moved" => false,
                    _ => (i + j) % 2 == 0,
                };
                let at =
                    Transform::translate(Vec3::new(i as f32 * 3.0, 0.5 * j as f32, j as f32 * 3.0)).unwrap();
                let t =
                    if turn { Transform::rotate_y(i as f32 + 0.3 * j as f32 + 0.1).then(&at) } else { at };
                assert_eq!(t.object_offset().is_some(), !turn && (i, j) != (0, 0));
                objects.push(Object::Mesh { mesh: 0, transform: t });
            }
        }
        for kernel in [Kernel::Portable, Kernel::Avx2, Kernel::Avx512] {
            let mut accel = Accel::build(vec![mesh.clone()], objects.clone()).unwrap();
            if !accel.set_kernel(kernel) {
                eprintln!("{} not run: this CPU lacks it", kernel.name());
                continue;
            }
            let mut hits = 0;
            for _ in 0..40 {
                hits += check_scene(&accel, &mut rng, &format!("{placing}, {}", kernel.name()));
            }
            assert!(hits > 500, "{placing}, {}: {hits} hits", kernel.name());
        }
    }
}

/// A scene of one mesh instance, the top level's only object (its packet
/// queries then skip the top-level walk), placed as it is or transformed,
/// alone or beside a plane (an unbounded object tested before it).
#[test]
fn one_mesh_scenes_agree_with_single_rays() {
    let mut hits = 0;
    for seed in 0..24 {
        let mut rng = Rng::new(300 + seed);
        let mesh = Arc::new(common::random_mesh(&mut rng, 60));
        let transform = if seed % 2 == 0 { Transform::IDENTITY } else { common::random_transform(&mut rng) };
        let mut objects = vec![Object::Mesh { mesh: 0, transform }];
        if seed % 3 == 0 {
            objects
                .push(Object::Shape(Instance::new(common::random_shape(&mut rng, 6), Transform::IDENTITY)));
        }
        let accel = Accel::build(vec![mesh], objects).unwrap();
        for _ in 0..6 {
            hits += check_scene(&accel, &mut rng, &format!("one mesh, seed {seed}"));
        }
    }
    assert!(hits > 1000, "the packets should mostly hit something ({hits})");
}

#[test]
fn shared_meshes_agree_with_single_rays() {
    for (name, path) in prism_testkit::shared_meshes() {
        let mesh = Arc::new(prism_testkit::load_obj(&path).unwrap());
        let accel =
            Accel::build(vec![mesh], vec![Object::Mesh { mesh: 0, transform: Transform::IDENTITY }]).unwrap();
        let mut rng = Rng::new(name.len() as u64);
        let mut hits = 0;
        for _ in 0..30 {
            hits += check_scene(&accel, &mut rng, name);
        }
        eprintln!("{name}: {hits} hits compared");
        assert!(hits > 300, "{name}: {hits} hits");
    }
}

/// Longer slices are traced a chunk at a time; `out` shorter than `rays`
/// gets only its own entries.
#[test]
fn slices_are_traced_in_chunks() {
    let mut rng = Rng::new(77);
    let (meshes, objects) = random_scene(&mut rng, 60);
    let accel = Accel::build(meshes, objects).unwrap();
    let b = accel.bounds();
    let rays: Vec<Ray> =
        (0..3 * PACKET_SIZE + 5).map(|_| common::random_ray(&mut rng, b.center(), 5.0)).collect();
    compare(&accel, &rays).unwrap();
    let mut out = vec![None; 10];
    accel.closest_hit_packet(&rays, &mut out);
    for (o, r) in out.iter().zip(&rays) {
        assert!(same(&accel, r, o, &accel.closest_hit(r)));
    }
    let mut occ = [true; 2];
    accel.occluded_packet(&[], &mut occ);
    assert_eq!(occ, [true, true], "no rays: nothing written");
}
