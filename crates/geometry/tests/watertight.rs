//! Watertightness: rays aimed exactly at the shared edges and vertices of
//! closed meshes never pass through them.

use prism_geometry::glam::Vec3;
use prism_geometry::{Intersect, Ray, TriangleMesh, TriangleRay};
use std::collections::HashMap;

/// A cube [−n, n]³ with each face split into an n×n... grid of integer
/// vertices (exact in f32), two triangles per cell, wound outward.
fn grid_cube(n: i32) -> TriangleMesh {
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut vid = |p: [i32; 3], positions: &mut Vec<Vec3>| {
        *index.entry(p).or_insert_with(|| {
            positions.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
            (positions.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        for sign in [-1, 1] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in -n..n {
                for j in -n..n {
                    let corner = |a: i32, b: i32| {
                        let mut p = [0; 3];
                        p[axis] = sign * n;
                        p[u] = a;
                        p[v] = b;
                        p
                    };
                    let q = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)]
                        .map(|c| vid(c, &mut positions));
                    // (u × v) = +axis: counter-clockwise seen from +axis.
                    if sign > 0 {
                        faces.push([q[0], q[1], q[2]]);
                        faces.push([q[0], q[2], q[3]]);
                    } else {
                        faces.push([q[0], q[2], q[1]]);
                        faces.push([q[0], q[3], q[2]]);
                    }
                }
            }
        }
    }
    TriangleMesh::new(positions, None, None, faces).unwrap()
}

/// An icosphere: an icosahedron subdivided `levels` times, vertices on the
/// unit sphere (rounded), edges shared by index.
fn icosphere(levels: u32) -> TriangleMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut m = |a: u32, b: u32, p: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push((p[a as usize] + p[b as usize]).normalize());
                (p.len() - 1) as u32
            })
        };
        f = f
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (m(a, b, &mut p), m(b, c, &mut p), m(c, a, &mut p));
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    TriangleMesh::new(p, None, None, f).unwrap()
}

/// Every crossing of the mesh by the ray, as distinct surface points
/// (faces sharing the crossed edge or vertex report the same point), with
/// whether each is an entry.
fn crossings(mesh: &TriangleMesh, ray: &Ray) -> Vec<(f32, bool)> {
    let tr = TriangleRay::new(ray);
    let mut hits: Vec<(f32, bool)> = (0..mesh.len())
        .filter_map(|f| {
            let [a, b, c] = mesh.triangle(f);
            let (t, ..) = tr.intersect(&[a, b, c])?;
            Some((t, ray.dir.dot((b - a).cross(c - a)) < 0.0))
        })
        .collect();
    hits.sort_by(|x, y| x.0.total_cmp(&y.0));
    hits.dedup_by(|x, y| (x.0 - y.0).abs() <= 1e-4 * y.0.max(1.0) && x.1 == y.1);
    hits
}

/// Aims rays at `target` (a point on the mesh) from many outside origins
/// through the interior; each must enter and leave.
fn assert_closed_at(
    mesh: &TriangleMesh,
    target: Vec3,
    center: Vec3,
    inside: impl Fn(Vec3) -> bool,
    seed: &mut u32,
) {
    let mut rnd = || {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 17;
        *seed ^= *seed << 5;
        (*seed as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    for _ in 0..12 {
        // Directions toward the inside: roughly from target away from centre.
        let jitter = Vec3::new(rnd(), rnd(), rnd()) * 0.6;
        let origin = target + ((target - center).normalize() + jitter) * 5.0;
        let dir = target - origin;
        // Only rays that go on into the solid (not ones that touch a corner).
        if !inside(target + 0.05 * dir) {
            continue;
        }
        let ray = Ray::new(origin, dir);
        let c = crossings(mesh, &ray);
        let nearest = mesh.intersect(&ray);
        assert!(nearest.is_some(), "ray at {target} from {origin} slipped through");
        assert!((nearest.unwrap().t - 1.0).abs() < 1e-3, "first hit is not the aimed point: {:?}", nearest);
        assert!(
            c.len() >= 2 && c.len().is_multiple_of(2),
            "{} crossings at {target} from {origin}: {c:?}",
            c.len()
        );
        assert!(c[0].1 && !c[c.len() - 1].1, "first must enter, last must leave: {c:?}");
        for w in c.windows(2) {
            assert_ne!(w[0].1, w[1].1, "entries and exits alternate: {c:?}");
        }
    }
}

#[test]
fn grid_cube_edges_and_vertices() {
    let mesh = grid_cube(3);
    let mut seed = 0x9e37_79b9;
    let mut targets = Vec::new();
    for f in 0..mesh.len() {
        let [a, b, c] = mesh.triangle(f);
        targets.extend([a, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), a + 0.25 * (c - a)]);
    }
    for t in targets {
        assert_closed_at(&mesh, t, Vec3::ZERO, |p| p.abs().max_element() < 3.0, &mut seed);
    }
    // Axis-aligned rays straight down shared edges and vertices.
    for x in -3..=3 {
        for z in -3..=3 {
            let (x, z) = (x as f32, z as f32);
            let ray = Ray::new(Vec3::new(x, 10.0, z), Vec3::NEG_Y);
            assert_eq!(crossings(&mesh, &ray).len(), 2, "straight down at ({x}, {z})");
            let diag = Ray::new(Vec3::new(x + 10.0, 10.0 + 0.5, z), Vec3::new(-1.0, -1.0, 0.0));
            let c = crossings(&mesh, &diag);
            if z.abs() < 3.0 {
                // The line `Y = X + 0.5 − x` runs through the cube's inside.
                assert_eq!(c.len(), 2, "diagonal at ({x}, {z}): {c:?}");
            } else {
                // In the plane of a face: it may graze it or not, but never
                // enter without leaving.
                assert!(c.is_empty() || c.len() == 2, "diagonal at ({x}, {z}): {c:?}");
            }
        }
    }
}

#[test]
fn icosphere_edges_and_vertices() {
    let mesh = icosphere(2);
    let mut seed = 0x1234_5678;
    for f in 0..mesh.len() {
        let [a, b, c] = mesh.triangle(f);
        for target in [a, b, 0.5 * (a + b), 0.5 * (b + c), 0.3 * a + 0.7 * c] {
            assert_closed_at(&mesh, target, Vec3::ZERO, |p| p.length() < 0.9, &mut seed);
        }
    }
}
