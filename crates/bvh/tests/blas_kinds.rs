//! The BVH2, CWBVH and wide mesh hierarchies (`BlasKind`) give the same
//! answers: bit for bit between the walks, and as brute force, on random
//! rays including axis-parallel ones (`+0.0`/`-0.0` components), restricted
//! intervals and rays spawned a few ULPs off a surface. The wide layout's
//! node-test kernels (`Kernel`: portable, AVX2, AVX-512, each where this
//! CPU has it) agree exactly: same hit record, same crossings in the same
//! order.

mod common;

use common::{Rng, compare_all, compare_closest, random_mesh, random_ray, random_scene};
use prism_bvh::{Accel, BlasKind, BuildOptions, BuildQuality, Kernel, Object, SceneHit};
use prism_geometry::glam::Vec3;
use prism_geometry::{Ray, Transform, TriangleMesh};
use std::ops::ControlFlow;
use std::sync::Arc;

fn build(meshes: &[Arc<TriangleMesh>], objects: &[Object], q: BuildQuality, kind: BlasKind) -> Accel {
    let options = BuildOptions { mesh_quality: q, mesh_layout: kind, ..BuildOptions::default() };
    Accel::build_with(meshes.to_vec(), objects.to_vec(), options).unwrap()
}

/// The wide layout, once per kernel this CPU runs (portable first).
fn wides(meshes: &[Arc<TriangleMesh>], objects: &[Object], q: BuildQuality) -> Vec<Accel> {
    Kernel::ALL
        .into_iter()
        .filter(|k| k.supported())
        .map(|k| {
            let mut a = build(meshes, objects, q, BlasKind::Wide);
            assert!(a.set_kernel(k), "{}", k.name());
            a
        })
        .collect()
}

/// Every kernel of `wides` answers `ray` exactly as the first: the same
/// hit record, occlusion answer and crossings in the same order.
fn kernels_agree(wides: &[Accel], ray: &Ray) {
    let all = |a: &Accel| {
        let mut v = Vec::new();
        a.for_each_hit(ray, |h| {
            v.push(*h);
            ControlFlow::Continue(())
        });
        v
    };
    let first = &wides[0];
    let (hit, occluded, crossings) = (first.closest_hit(ray), first.occluded(ray), all(first));
    for w in &wides[1..] {
        let h = w.closest_hit(ray);
        assert_eq!(h.map(|h| h.hit.t.to_bits()), hit.map(|h| h.hit.t.to_bits()), "{ray:?}");
        assert_eq!(h, hit, "{ray:?}");
        assert_eq!(w.occluded(ray), occluded, "{ray:?}");
        assert_eq!(all(w), crossings, "{ray:?}");
    }
}

/// Every crossing as sorted `(object, triangle, t bits)`.
fn crossings(accel: &Accel, ray: &Ray) -> Vec<(u32, u32, u32)> {
    let mut v = Vec::new();
    accel.for_each_hit(ray, |h| {
        v.push((h.object, h.triangle, h.hit.t.to_bits()));
        ControlFlow::Continue(())
    });
    v.sort_unstable();
    v
}

/// The two layouts agree on `ray`: the same `t` bit for bit, the same
/// primitive unless another one is hit at exactly that `t`, the same
/// occlusion answer and the same crossings.
fn agree(a: &Accel, b: &Accel, ray: &Ray) -> Option<SceneHit> {
    let (ha, hb) = (a.closest_hit(ray), b.closest_hit(ray));
    match (&ha, &hb) {
        (None, None) => {}
        (Some(x), Some(y)) => {
            assert_eq!(x.hit.t.to_bits(), y.hit.t.to_bits(), "t differs for {ray:?}:\n{x:?}\n{y:?}");
            if (x.object, x.triangle) != (y.object, y.triangle) {
                // An exact tie: both primitives are crossed at this t.
                let all = crossings(a, ray);
                for h in [x, y] {
                    assert!(
                        all.contains(&(h.object, h.triangle, h.hit.t.to_bits())),
                        "different primitive, not a tie, for {ray:?}:\n{x:?}\n{y:?}"
                    );
                }
            } else {
                assert_eq!(x, y, "{ray:?}");
            }
        }
        _ => panic!("hit/miss differs for {ray:?}:\n{ha:?}\n{hb:?}"),
    }
    assert_eq!(a.occluded(ray), b.occluded(ray), "occlusion differs for {ray:?}");
    assert_eq!(crossings(a, ray), crossings(b, ray), "crossings differ for {ray:?}");
    ha
}

/// Spawned rays off `h`: back along the normal's side, and a bounce.
fn spawned(rng: &mut Rng, h: &SceneHit, toward: Vec3) -> [Ray; 2] {
    [
        Ray::spawn_to(h.hit.point, h.hit.geo_normal, toward),
        Ray::spawn(h.hit.point, h.hit.geo_normal, rng.direction()),
    ]
}

#[test]
fn random_scenes_agree_across_layouts_and_with_brute_force() {
    for (seed, q) in [(1u64, BuildQuality::Medium), (2, BuildQuality::Fastest), (3, BuildQuality::VerySlow)] {
        let mut rng = Rng::new(seed * 977);
        let (meshes, objects) = random_scene(&mut rng, 40);
        let cw = build(&meshes, &objects, q, BlasKind::Cwbvh);
        let b2 = build(&meshes, &objects, q, BlasKind::Bvh2);
        let wide = wides(&meshes, &objects, q);
        let c = b2.bounds().center();
        let size = b2.bounds().extent().max_element().max(1.0);
        let mut hits = 0;
        for _ in 0..4000 {
            let ray = random_ray(&mut rng, c, size);
            let hit = agree(&cw, &b2, &ray);
            agree(&cw, &wide[0], &ray);
            kernels_agree(&wide, &ray);
            compare_closest(&b2, &ray).unwrap();
            compare_all(&b2, &ray).unwrap();
            compare_closest(&wide[0], &ray).unwrap();
            compare_all(&wide[0], &ray).unwrap();
            if let Some(h) = hit {
                hits += 1;
                for r in spawned(&mut rng, &h, c + Vec3::new(1.0, 2.0, 1.5) * size) {
                    agree(&cw, &b2, &r);
                    agree(&cw, &wide[0], &r);
                    kernels_agree(&wide, &r);
                    compare_closest(&b2, &r).unwrap();
                    compare_closest(&wide[0], &r).unwrap();
                }
            }
        }
        assert!(hits > 500, "{hits}");
    }
}

/// Many instances of one dense mesh, rays of every kind, 100k of them.
#[test]
fn dense_mesh_agrees_across_layouts() {
    let mut rng = Rng::new(42);
    let mesh = Arc::new(random_mesh(&mut rng, 60));
    let mut objects = Vec::new();
    for k in 0..6 {
        let t = Transform::translate(Vec3::new(k as f32 * 1.5, (k % 2) as f32 * 0.1, 0.0)).unwrap();
        objects.push(Object::Mesh { mesh: 0, transform: t });
    }
    objects.push(Object::Mesh { mesh: 0, transform: Transform::rotate_y(0.6) });
    let meshes = vec![mesh];
    for q in [BuildQuality::Medium, BuildQuality::Slow] {
        let cw = build(&meshes, &objects, q, BlasKind::Cwbvh);
        let b2 = build(&meshes, &objects, q, BlasKind::Bvh2);
        let wide = wides(&meshes, &objects, q);
        let c = b2.bounds().center();
        let size = b2.bounds().extent().max_element();
        let mut hits = 0;
        for k in 0..50_000 {
            let ray = random_ray(&mut rng, c, size);
            agree(&cw, &wide[0], &ray);
            kernels_agree(&wide, &ray);
            if let Some(h) = agree(&cw, &b2, &ray) {
                hits += 1;
                for r in spawned(&mut rng, &h, c + Vec3::Y * size * 2.0) {
                    agree(&cw, &b2, &r);
                    agree(&cw, &wide[0], &r);
                    kernels_agree(&wide, &r);
                }
                if k % 50 == 0 {
                    compare_closest(&b2, &ray).unwrap();
                    compare_closest(&wide[0], &ray).unwrap();
                }
            }
        }
        assert!(hits > 2000, "{hits}");
    }
}

/// Rays per shared mesh for the cross-layout comparison (issue 7 asks for
/// 100,000 random rays on the real meshes). Brute force on every one of
/// them would take minutes, so every ray is checked between the two
/// independent walks (CWBVH and BVH2) and every 200th hit also against
/// brute force (`meshes.rs` checks more rays that way).
///
/// The comparison allows `t` to differ by 1e-5 relative: the kitchen has
/// coincident faces of opposite orientation (z-fighting), and the
/// watertight test's own rounding gives their `t` values up to a few tens
/// of ULPs apart for the same point. The box tests look a few ULPs past
/// `t_max` (`BoxRay::reach`), which covers the slab distances' rounding but
/// not that much: the two walks (exact float boxes against quantised
/// ones) may then keep different faces of such a pair; either is a hit on
/// that surface. (Against brute force, `meshes.rs` finds no such case on
/// its rays with the default CWBVH, and the check below compares exactly.)
const MESH_RAYS: usize = 100_000;

/// The two layouts agree within rounding: the same hit or miss, `t` within
/// 1e-5 relative, the same occlusion answer.
fn agree_close(a: &Accel, b: &Accel, ray: &Ray) -> Option<SceneHit> {
    let (ha, hb) = (a.closest_hit(ray), b.closest_hit(ray));
    match (&ha, &hb) {
        (None, None) => {}
        (Some(x), Some(y)) => {
            let tol = 1e-5 * x.hit.t.abs().max(1.0);
            assert!((x.hit.t - y.hit.t).abs() <= tol, "t differs for {ray:?}:\n{x:?}\n{y:?}");
        }
        _ => panic!("hit/miss differs for {ray:?}:\n{ha:?}\n{hb:?}"),
    }
    assert_eq!(a.occluded(ray), b.occluded(ray), "occlusion differs for {ray:?}");
    ha
}

#[test]
fn shared_meshes_agree_across_layouts() {
    for (name, path) in prism_testkit::shared_meshes() {
        let meshes = vec![Arc::new(prism_testkit::load_obj(&path).unwrap())];
        let objects = vec![Object::Mesh { mesh: 0, transform: Transform::IDENTITY }];
        let cw = build(&meshes, &objects, BuildQuality::Medium, BlasKind::Cwbvh);
        let b2 = build(&meshes, &objects, BuildQuality::Medium, BlasKind::Bvh2);
        let wide = wides(&meshes, &objects, BuildQuality::Medium);
        let mut rng = Rng::new(7 + name.len() as u64);
        let c = b2.bounds().center();
        let size = b2.bounds().extent().max_element();
        let mut hits = 0;
        for k in 0..MESH_RAYS {
            let ray = random_ray(&mut rng, c, size);
            agree_close(&cw, &wide[0], &ray);
            kernels_agree(&wide, &ray);
            if let Some(h) = agree_close(&cw, &b2, &ray) {
                hits += 1;
                for r in spawned(&mut rng, &h, c + Vec3::new(1.0, 2.0, 1.5) * size) {
                    agree_close(&cw, &b2, &r);
                    agree_close(&cw, &wide[0], &r);
                    kernels_agree(&wide, &r);
                }
                if k % 200 == 0 {
                    compare_closest(&b2, &ray).unwrap();
                    compare_closest(&wide[0], &ray).unwrap();
                }
            }
        }
        eprintln!("{name}: {MESH_RAYS} rays, {hits} hits agree across layouts");
        assert!(hits > MESH_RAYS / 10, "{name}: {hits}");
    }
}

/// Meshes far from unit size: builds weigh boxes by their area in `f32`,
/// which overflows for coordinates near 10²⁰ (obvhs's CWBVH conversion
/// then panicked on an OBJ file with three corners at 10²⁰ beside unit
/// triangles) and underflows for tiny ones. Every layout and quality
/// builds them (at a power-of-two scale) and answers as brute force, each
/// with the same `t` as the wide layout of the default quality.
#[test]
fn meshes_far_from_unit_size_build_and_agree_with_brute_force() {
    let mut rng = Rng::new(20_261_207);
    let base = random_mesh(&mut rng, 6);
    // (where the far triangle reaches, the scale of the rest): mixed
    // sizes, the largest float, all large, all tiny, and unit size.
    let cases = [
        (1e20f32, 1.0f32),
        (3e38, 1.0),
        (2f32.powi(50), 2f32.powi(45)),
        (2f32.powi(-40), 2f32.powi(-40)),
        (1.0, 1.0),
    ];
    for (far, scale) in cases {
        // The unit mesh scaled, with one triangle reaching `far`.
        let mut positions: Vec<Vec3> = base.positions().iter().map(|p| *p * scale).collect();
        let mut indices = base.indices().to_vec();
        let n = positions.len() as u32;
        positions.extend([Vec3::new(far, 0.0, 0.0), Vec3::new(0.0, far, 0.0), Vec3::new(0.0, 0.0, far)]);
        indices.push([n, n + 2, n + 1]);
        let mesh = Arc::new(TriangleMesh::new(positions, None, None, indices).unwrap());
        let objects = [Object::Mesh { mesh: 0, transform: Transform::IDENTITY }];
        let reference = build(std::slice::from_ref(&mesh), &objects, BuildQuality::Medium, BlasKind::Wide);
        for q in BuildQuality::ALL {
            for kind in [BlasKind::Wide, BlasKind::Cwbvh, BlasKind::Bvh2] {
                let accel = build(std::slice::from_ref(&mesh), &objects, q, kind);
                let mut hits = 0;
                for k in 0..200 {
                    // Toward the unit part from around it, and toward the far triangle.
                    let o = rng.unit() * 3.0 * scale;
                    let target = if k % 4 == 0 {
                        Vec3::splat(far / 3.0)
                    } else {
                        Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0)) * scale
                    };
                    let ray = Ray::new(o, target - o);
                    let hit = compare_closest(&accel, &ray)
                        .unwrap_or_else(|e| panic!("far {far}, scale {scale}, {q:?}, {kind:?}: {e}"));
                    let same = reference.closest_hit(&ray);
                    assert_eq!(hit.map(|h| h.hit.t.to_bits()), same.map(|h| h.hit.t.to_bits()), "{ray:?}");
                    hits += usize::from(hit.is_some());
                }
                assert!(hits > 100, "far {far}, scale {scale}, {q:?}, {kind:?}: {hits} hits of 200");
            }
        }
    }
}
