//! Shared helpers of prism-bvh's tests: random scenes and rays, and
//! comparisons against the brute-force reference. (The generator, OBJ
//! loading and the shared meshes are prism-testkit's.)

#![allow(dead_code)]

pub use prism_testkit::Rng;

use prism_bvh::{Accel, Object, SceneHit};
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{
    Cone, Cuboid, Cylinder, Disk, Instance, Plane, Ray, Shape, Shear, Sphere, Transform, Triangle,
    TriangleMesh,
};
use std::ops::ControlFlow;
use std::sync::Arc;

pub fn random_transform(rng: &mut Rng) -> Transform {
    let mut t = Transform::IDENTITY;
    if rng.below(2) == 0 {
        t = t.then(&Transform::rotate_axis(rng.unit(), rng.range(0.0, 6.3)).unwrap());
    }
    if rng.below(3) == 0 {
        t = t.then(&Transform::scale(rng.vec_in(Vec3::splat(0.3), Vec3::splat(2.0))).unwrap());
    }
    if rng.below(4) == 0 {
        t = t.then(
            &Transform::shear(Shear { xy: rng.range(-0.8, 0.8), zx: rng.range(-0.5, 0.5), ..Shear::NONE })
                .unwrap(),
        );
    }
    t.then(&Transform::translate(rng.vec_in(Vec3::splat(-10.0), Vec3::splat(10.0))).unwrap())
}

pub fn random_shape(rng: &mut Rng, kind: usize) -> Shape {
    let c = rng.vec_in(Vec3::splat(-1.0), Vec3::splat(1.0));
    let s = rng.range(0.2, 2.0);
    match kind % 7 {
        0 => Sphere::new(c, s).unwrap().into(),
        1 => Cuboid::new(c - Vec3::splat(s) * rng.vec_in(Vec3::splat(0.1), Vec3::ONE), c + Vec3::splat(s))
            .unwrap()
            .into(),
        2 => Cylinder::new(c, s, rng.range(0.1, 3.0)).unwrap().into(),
        3 => Cone::new(c, s, rng.range(0.1, 3.0)).unwrap().into(),
        4 => Disk::new(c, rng.unit(), s).unwrap().into(),
        5 => Triangle::new([c, c + rng.unit() * s, c + rng.unit() * s])
            .unwrap_or_else(|_| Triangle::new([c, c + Vec3::X, c + Vec3::Y]).unwrap())
            .into(),
        _ => Plane::new(c * 10.0, rng.unit()).unwrap().into(),
    }
}

/// A small random mesh: a noisy grid, with shared edges, a few
/// zero-area faces, and a few repeated faces.
pub fn random_mesh(rng: &mut Rng, n: usize) -> TriangleMesh {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            positions.push(Vec3::new(u * 2.0 - 1.0, rng.range(-0.3, 0.3), v * 2.0 - 1.0));
            uvs.push(Vec2::new(u, v));
        }
    }
    let mut indices = Vec::new();
    let w = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * w + i;
            indices.push([a, a + 1, a + w + 1]);
            indices.push([a, a + w + 1, a + w]);
        }
    }
    // Zero-area faces and a repeated face.
    indices.push([0, 0, 1]);
    indices.push([0, 1, 2]); // collinear along the first row? (not if noisy)
    indices.push([3, 3, 3]);
    indices.push(indices[0]);
    let mut m = TriangleMesh::new(positions, None, Some(uvs), indices).unwrap();
    m.compute_smooth_normals();
    m
}

/// A random scene of every shape kind plus mesh instances.
pub fn random_scene(rng: &mut Rng, n_objects: usize) -> (Vec<Arc<TriangleMesh>>, Vec<Object>) {
    let meshes: Vec<Arc<TriangleMesh>> = (0..3).map(|k| Arc::new(random_mesh(rng, 2 + 3 * k))).collect();
    let mut objects = Vec::new();
    for i in 0..n_objects {
        let kind = i % 9;
        if kind < 7 {
            // Planes are rarer (one in 7 of the shapes would cover everything).
            let kind = if kind == 6 && rng.below(4) != 0 { rng.below(6) } else { kind };
            objects.push(Object::Shape(Instance::new(random_shape(rng, kind), random_transform(rng))));
        } else {
            objects.push(Object::Mesh {
                mesh: rng.below(meshes.len()) as u32,
                transform: random_transform(rng),
            });
        }
    }
    (meshes, objects)
}

/// A random ray around `centre` (within `size`), sometimes with a
/// restricted interval.
pub fn random_ray(rng: &mut Rng, centre: Vec3, size: f32) -> Ray {
    let o = centre + rng.vec_in(Vec3::splat(-size), Vec3::splat(size));
    let target = centre + rng.vec_in(Vec3::splat(-size * 0.5), Vec3::splat(size * 0.5));
    let d = if rng.below(3) == 0 { rng.direction() } else { (target - o).normalize_or(Vec3::X) };
    let mut r = Ray::new(o, d);
    match rng.below(6) {
        0 => r.t_max = rng.range(0.0, 2.0 * size / d.length()),
        1 => r.t_min = rng.range(0.0, size / d.length()),
        _ => {}
    }
    r
}

fn hit_finite(h: &SceneHit) -> bool {
    let x = &h.hit;
    x.t.is_finite()
        && x.point.is_finite()
        && x.normal.is_finite()
        && x.geo_normal.is_finite()
        && x.uv.is_finite()
}

/// Relative tolerance on the `t` of every crossing between the two paths
/// ([`compare_all`]); closest hits must agree exactly ([`compare_closest`]).
pub const T_TOL: f32 = 1e-5;

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= T_TOL * a.abs().max(b.abs()).max(1.0)
}

/// Whether brute force finds a crossing of `h`'s object and triangle at
/// exactly `h`'s `t`.
pub fn crosses_at(accel: &Accel, ray: &Ray, h: &SceneHit) -> bool {
    let mut found = false;
    accel.for_each_hit_brute_force(ray, |c| {
        found = (c.object, c.triangle, c.hit.t.to_bits()) == (h.object, h.triangle, h.hit.t.to_bits());
        if found { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    });
    found
}

/// Compares the hierarchy's closest hit with brute force's: both miss, or
/// both hit the same object and triangle at the same `t` (both paths run
/// the same intersection code, so `t` is equal bit for bit). Where two
/// primitives are crossed at exactly the same `t`, either may win; the
/// hierarchy's choice must then be crossed at that `t` indeed. Also checks
/// that `occluded` agrees. Returns a description of the first mismatch.
pub fn compare_closest(accel: &Accel, ray: &Ray) -> Result<Option<SceneHit>, String> {
    let fast = accel.closest_hit(ray);
    let slow = accel.closest_hit_brute_force(ray);
    match (&fast, &slow) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            if !hit_finite(a) {
                return Err(format!("non-finite hit {a:?} for {ray:?}"));
            }
            if a.hit.t.to_bits() != b.hit.t.to_bits() {
                return Err(format!("t differs: bvh {a:?}\nbrute {b:?}\nray {ray:?}"));
            }
            if (a.object, a.triangle) != (b.object, b.triangle) && !crosses_at(accel, ray, a) {
                return Err(format!("different primitive, not a tie: bvh {a:?}\nbrute {b:?}\nray {ray:?}"));
            }
        }
        _ => return Err(format!("hit/miss differs: bvh {fast:?}\nbrute {slow:?}\nray {ray:?}")),
    }
    if accel.occluded(ray) != fast.is_some() {
        return Err(format!("occluded() = {} but closest_hit = {fast:?} for {ray:?}", accel.occluded(ray)));
    }
    Ok(fast)
}

/// Compares every crossing (as sorted (object, triangle, t) lists), and
/// the lazy crossings with the hits: `for_each_crossing` reports the
/// crossings of `for_each_hit` in the same order with the same `t` and
/// side. `for_each_hit` builds its hits with `crossing_hit`, so the check
/// of those hits is against brute force's eager ones: the same side, and
/// for an analytic shape the same hit, bit for bit.
pub fn compare_all(accel: &Accel, ray: &Ray) -> Result<usize, String> {
    let mut fast = Vec::new();
    accel.for_each_hit(ray, |h| {
        fast.push(*h);
        ControlFlow::Continue(())
    });
    let mut lazy = Vec::new();
    accel.for_each_crossing(ray, |c| {
        lazy.push((c.object, c.triangle, c.t.to_bits(), c.front_face, accel.crossing_hit(ray, c)));
        ControlFlow::Continue(())
    });
    let eager: Vec<_> =
        fast.iter().map(|h| (h.object, h.triangle, h.hit.t.to_bits(), h.hit.front_face, Some(*h))).collect();
    if lazy != eager {
        return Err(format!("crossings and hits differ for {ray:?}:\nlazy  {lazy:?}\nhits  {eager:?}"));
    }
    // Each object's first crossing, asked of it alone, is the nearest the
    // walk reports for it (the same `t` and side; of a mesh's triangles
    // meeting at that `t`, any), and its hit is that crossing's.
    for object in 0..accel.objects().len() as u32 {
        let nearest = lazy
            .iter()
            .filter(|c| c.0 == object)
            .min_by(|a, b| f32::from_bits(a.2).total_cmp(&f32::from_bits(b.2)));
        let first = accel.first_crossing_of(object, ray);
        let same = match (first, nearest) {
            (None, None) => true,
            // A shape's is that crossing, hit and all; a mesh's is one of
            // the walk's crossings at that `t` (coincident faces, as a
            // wall modelled from both sides, tie with opposite sides).
            (Some(f), Some(n)) if f.triangle == SceneHit::NO_TRIANGLE => {
                f.t.to_bits() == n.2 && f.front_face == n.3 && accel.crossing_hit(ray, &f) == n.4
            }
            (Some(f), Some(n)) => {
                f.t.to_bits() == n.2
                    && lazy
                        .iter()
                        .any(|c| c.0 == object && c.1 == f.triangle && c.2 == n.2 && c.3 == f.front_face)
            }
            _ => false,
        };
        if !same {
            return Err(format!(
                "object {object}'s first crossing {first:?}, its nearest in the walk {nearest:?}, for {ray:?}"
            ));
        }
    }
    if let Some(h) = fast.iter().find(|h| !hit_finite(h)) {
        return Err(format!("non-finite crossing {h:?} for {ray:?}"));
    }
    let mut slow = Vec::new();
    accel.for_each_hit_brute_force(ray, |h| {
        slow.push(*h);
        ControlFlow::Continue(())
    });
    let key = |a: &SceneHit, b: &SceneHit| {
        (a.object, a.triangle).cmp(&(b.object, b.triangle)).then(a.hit.t.total_cmp(&b.hit.t))
    };
    fast.sort_by(key);
    slow.sort_by(key);
    let same = |a: &SceneHit, b: &SceneHit| {
        (a.object, a.triangle, a.hit.front_face) == (b.object, b.triangle, b.hit.front_face)
            && close(a.hit.t, b.hit.t)
            && (a.triangle != SceneHit::NO_TRIANGLE || a.hit == b.hit)
    };
    if fast.len() != slow.len() || fast.iter().zip(&slow).any(|(a, b)| !same(a, b)) {
        return Err(format!("crossings differ for {ray:?}:\nbvh   {fast:?}\nbrute {slow:?}"));
    }
    for t in fast.iter().map(|h| h.hit.t) {
        if !(t >= ray.t_min && t <= ray.t_max) {
            return Err(format!("crossing at t = {t} outside the ray interval {ray:?}"));
        }
    }
    Ok(fast.len())
}
