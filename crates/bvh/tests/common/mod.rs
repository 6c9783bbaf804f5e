//! Shared helpers: a small deterministic RNG, random scenes, OBJ loading,
//! and comparisons against the brute-force reference.

#![allow(dead_code)]

use prism_bvh::{Accel, Object, SceneHit};
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{
    Cone, Cuboid, Cylinder, Disk, Instance, Plane, Ray, Shape, Shear, Sphere, Transform, Triangle,
    TriangleMesh,
};
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;

/// PCG32, enough for reproducible test data.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        let mut r = Rng(seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407));
        r.next_u32();
        r
    }
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }
    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u32() as usize) % n.max(1)
    }
    pub fn vec_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec_in(Vec3::splat(-1.0), Vec3::splat(1.0));
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
    /// A direction, sometimes axis-parallel (with zero or negative-zero
    /// components).
    pub fn direction(&mut self) -> Vec3 {
        match self.below(10) {
            0 => {
                let axis = self.below(3);
                let mut d = [0.0f32, -0.0, 0.0];
                if self.below(2) == 0 {
                    d = [-0.0, 0.0, -0.0];
                }
                d[axis] = if self.below(2) == 0 { 1.0 } else { -1.0 };
                Vec3::from_array(d)
            }
            1 => {
                let mut v = self.unit();
                v[self.below(3)] = if self.below(2) == 0 { 0.0 } else { -0.0 };
                if v == Vec3::ZERO { Vec3::X } else { v }
            }
            // Non-unit lengths: t is in units of dir.
            2 => self.unit() * self.range(0.01, 50.0),
            _ => self.unit(),
        }
    }
}

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

/// Relative tolerance on t between the two paths (they use the same
/// intersection code, so equal primitives give equal t).
pub const T_TOL: f32 = 1e-5;

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= T_TOL * a.abs().max(b.abs()).max(1.0)
}

/// Compares closest hits; returns a description of the first mismatch.
pub fn compare_closest(accel: &Accel, ray: &Ray) -> Result<Option<SceneHit>, String> {
    let fast = accel.closest_hit(ray);
    let slow = accel.closest_hit_brute_force(ray);
    match (&fast, &slow) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            if !hit_finite(a) {
                return Err(format!("non-finite hit {a:?} for {ray:?}"));
            }
            if !close(a.hit.t, b.hit.t) {
                return Err(format!("t differs: bvh {a:?}\nbrute {b:?}\nray {ray:?}"));
            }
            // Same primitive, unless the two were hit at the same t.
            if (a.object, a.triangle) != (b.object, b.triangle)
                && a.hit.t != b.hit.t
                && !close(a.hit.t, b.hit.t)
            {
                return Err(format!("different primitive: bvh {a:?}\nbrute {b:?}"));
            }
        }
        _ => return Err(format!("hit/miss differs: bvh {fast:?}\nbrute {slow:?}\nray {ray:?}")),
    }
    if accel.occluded(ray) != fast.is_some() {
        return Err(format!("occluded() = {} but closest_hit = {fast:?} for {ray:?}", accel.occluded(ray)));
    }
    Ok(fast)
}

/// Compares every crossing (as sorted (object, triangle, t) lists).
pub fn compare_all(accel: &Accel, ray: &Ray) -> Result<usize, String> {
    let mut fast = Vec::new();
    accel.for_each_hit(ray, |h| {
        fast.push((h.object, h.triangle, h.hit.t, hit_finite(h)));
        ControlFlow::Continue(())
    });
    let mut slow = Vec::new();
    accel.for_each_hit_brute_force(ray, |h| {
        slow.push((h.object, h.triangle, h.hit.t, true));
        ControlFlow::Continue(())
    });
    let key = |a: &(u32, u32, f32, bool), b: &(u32, u32, f32, bool)| {
        (a.0, a.1).cmp(&(b.0, b.1)).then(a.2.total_cmp(&b.2))
    };
    fast.sort_by(key);
    slow.sort_by(key);
    if fast.len() != slow.len()
        || fast.iter().zip(&slow).any(|(a, b)| (a.0, a.1) != (b.0, b.1) || !close(a.2, b.2) || !a.3)
    {
        return Err(format!("crossings differ for {ray:?}:\nbvh   {fast:?}\nbrute {slow:?}"));
    }
    for (_, _, t, _) in &fast {
        if !(*t >= ray.t_min && *t <= ray.t_max) {
            return Err(format!("crossing at t = {t} outside the ray interval {ray:?}"));
        }
    }
    Ok(fast.len())
}

/// `<workspace root>/../shared/data`, if present.
pub fn data_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    d.is_dir().then_some(d)
}

/// Loads every shape of an OBJ into one mesh (positions only).
pub fn load_obj(path: &std::path::Path) -> TriangleMesh {
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        positions.extend(m.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        indices.extend(m.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
    }
    TriangleMesh::new(positions, None, None, indices).unwrap()
}
