//! Computed vertex normals for meshes without them: welded by position,
//! split at creases and between smoothing groups.

use crate::mesh::weld_by_position;
use crate::{GeometryError, TriangleMesh};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// The default crease angle in degrees: faces meeting at a sharper angle
/// than this keep a hard edge.
pub const DEFAULT_CREASE_DEG: f32 = 60.0;

/// Faces around one position above which [`with_computed_normals`] keeps
/// the normals it sums there for faces of the same plane and group.
const MANY_FACES: usize = 32;

/// `mesh` with computed vertex normals.
///
/// Faces are taken to meet wherever their corners share a **position**
/// (so that copies of a vertex split at uv seams, or repeated in the file,
/// still join). The normal at a corner of face `f` is the mean of the
/// normals, weighted by each face's angle at that corner (so that how a
/// surface was cut into triangles does not tilt it), of the faces around that position which may be
/// smoothed with `f`: those in the same smoothing group (`groups[f]`, one
/// per face; group 0 is "off": such a face is flat) whose normal is within
/// `crease_deg` degrees of `f`'s. Where corners of one vertex get
/// different normals, the vertex is split (positions and uvs copied); the
/// faces keep their order. Without `groups`, every face is in group 1.
///
/// # Errors
/// [`GeometryError::InvalidMesh`] if `groups` does not have one entry per
/// face, [`GeometryError::NonFinite`] if `crease_deg` is `NaN` (which
/// would smooth no corner with any face, not even its own).
pub fn with_computed_normals(
    mesh: &TriangleMesh,
    groups: Option<&[u32]>,
    crease_deg: f32,
) -> Result<TriangleMesh, GeometryError> {
    if crease_deg.is_nan() {
        return Err(GeometryError::NonFinite("crease angle"));
    }
    if let Some(g) = groups
        && g.len() != mesh.len()
    {
        return Err(GeometryError::InvalidMesh(format!(
            "{} smoothing groups for {} faces",
            g.len(),
            mesh.len()
        )));
    }
    let group = |f: usize| groups.map_or(1, |g| g[f]);
    let cos_crease = crease_deg.clamp(0.0, 180.0).to_radians().cos();
    let positions = mesh.positions();
    let indices = mesh.indices();
    let id = weld_by_position(positions);
    let unit: Vec<Vec3> = (0..mesh.len())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            crate::unit_or_extreme((b - a).cross(c - a)).unwrap_or(Vec3::ZERO)
        })
        .collect();
    // The angle of face `g` at its corner `c`.
    let angle = |g: usize, c: usize| {
        let t = indices[g];
        let p = |j: usize| positions[t[(c + j) % 3] as usize];
        let (e1, e2) = (p(1) - p(0), p(2) - p(0));
        if e1 == Vec3::ZERO || e2 == Vec3::ZERO {
            return 0.0;
        }
        // `angle_between` divides by the product of the squared lengths,
        // which underflows for edges under about 1e-10 (or overflows past
        // 1e9): a weight of 0, π or NaN. There, the same from unit edges.
        let product = e1.length_squared() * e2.length_squared();
        if (f32::MIN_POSITIVE..=f32::MAX).contains(&product) {
            e1.angle_between(e2)
        } else {
            match (crate::unit(e1), crate::unit(e2)) {
                (Some(u1), Some(u2)) => u1.angle_between(u2),
                _ => 0.0,
            }
        }
    };
    // Faces around each welded position (compressed rows).
    let mut start = vec![0u32; positions.len() + 1];
    for tri in indices {
        for &v in tri {
            start[id[v as usize] as usize + 1] += 1;
        }
    }
    for i in 0..positions.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[positions.len()] as usize];
    // Each face's angle at the position, in the same rows: computed once
    // per corner, not once per pair of faces around a vertex.
    let mut weight = vec![0f32; around.len()];
    for (f, tri) in indices.iter().enumerate() {
        for (j, &v) in tri.iter().enumerate() {
            let w = id[v as usize] as usize;
            // A face with two corners on one position (degenerate, with
            // no normal of its own) takes its first such corner's angle.
            let c = (0..3).find(|&c| id[tri[c] as usize] as usize == w).unwrap_or(j);
            around[fill[w] as usize] = f as u32;
            weight[fill[w] as usize] = angle(f, c);
            fill[w] += 1;
        }
    }
    // Normals already summed at a position of many faces, by (position,
    // group, face normal): a fan of thousands of faces around one vertex
    // (a large polygon, a cone's apex) would otherwise cost the square of
    // its faces where they share a plane.
    let mut summed: HashMap<(usize, u32, [u32; 3]), Vec3> = HashMap::new();
    let mut new_pos = Vec::with_capacity(positions.len());
    let mut new_uv = mesh.uvs().map(|_| Vec::with_capacity(positions.len()));
    let mut new_n = Vec::with_capacity(positions.len());
    let mut new_idx = Vec::with_capacity(indices.len());
    // One output vertex per (input vertex, normal).
    let mut made: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    for (f, tri) in indices.iter().enumerate() {
        let mut out = [0u32; 3];
        for (k, &v) in tri.iter().enumerate() {
            let w = id[v as usize] as usize;
            let n = if group(f) == 0 || unit[f] == Vec3::ZERO {
                unit[f]
            } else {
                let rows = start[w] as usize..start[w + 1] as usize;
                let sum = || {
                    let mut sum = Vec3::ZERO;
                    for (&g, &a) in around[rows.clone()].iter().zip(&weight[rows.clone()]) {
                        let g = g as usize;
                        if group(g) == group(f) && unit[g].dot(unit[f]) >= cos_crease {
                            sum += unit[g] * a;
                        }
                    }
                    sum.normalize_or_zero()
                };
                if rows.len() > MANY_FACES {
                    *summed.entry((w, group(f), unit[f].to_array().map(f32::to_bits))).or_insert_with(sum)
                } else {
                    sum()
                }
            };
            let key = (v, n.to_array().map(f32::to_bits));
            out[k] = *made.entry(key).or_insert_with(|| {
                new_pos.push(positions[v as usize]);
                if let (Some(dst), Some(src)) = (new_uv.as_mut(), mesh.uvs()) {
                    dst.push(src[v as usize]);
                }
                new_n.push(n);
                (new_pos.len() - 1) as u32
            });
        }
        new_idx.push(out);
    }
    let new_uv: Option<Vec<Vec2>> = new_uv;
    TriangleMesh::new(new_pos, Some(new_n), new_uv, new_idx)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring of `n` quads around the Y axis (a prism's side, radius 1),
    /// each quad with its own four vertices (uv seams everywhere).
    fn split_ring(n: usize) -> TriangleMesh {
        let mut p = Vec::new();
        let mut uv = Vec::new();
        let mut idx = Vec::new();
        for i in 0..n {
            let a = |j: usize| {
                let t = (j % n) as f32 / n as f32 * std::f32::consts::TAU;
                Vec3::new(t.sin(), 0.0, t.cos())
            };
            let base = p.len() as u32;
            p.extend([a(i), a(i + 1), a(i + 1) + Vec3::Y, a(i) + Vec3::Y]);
            uv.extend([Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
            idx.push([base, base + 1, base + 2]);
            idx.push([base, base + 2, base + 3]);
        }
        TriangleMesh::new(p, None, Some(uv), idx).unwrap()
    }

    /// The shading normal where face `f` touches `point`.
    fn normal_at(m: &TriangleMesh, f: usize, point: Vec3) -> Vec3 {
        let tri = m.indices()[f];
        let k = tri.iter().position(|&v| m.positions()[v as usize] == point).unwrap();
        m.normals().unwrap()[tri[k] as usize]
    }

    #[test]
    fn a_nan_crease_angle_is_refused() {
        let quad = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            None,
            None,
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        assert!(matches!(with_computed_normals(&quad, None, f32::NAN), Err(GeometryError::NonFinite(_))));
        let m = with_computed_normals(&quad, None, 0.0).unwrap();
        assert!(m.normals().unwrap().iter().all(|&n| n == Vec3::Z));
    }

    #[test]
    fn many_faces_around_one_vertex_get_the_normals_of_the_definition() {
        // A cone's apex shared by 200 faces, and a flat 200-gon's fan around
        // its first corner, in one mesh: above MANY_FACES, where summed
        // normals are kept. Each corner's normal must be the
        // angle-weighted mean of the faces within the crease, as documented.
        let n = 200;
        let ring = |i: usize, y: f32| {
            let t = (i % n) as f32 / n as f32 * std::f32::consts::TAU;
            Vec3::new(t.cos(), y, t.sin())
        };
        let mut p = vec![Vec3::new(0.0, 1.0, 0.0)];
        p.extend((0..n).map(|i| ring(i, 0.0)));
        let fan = p.len() as u32;
        p.extend((0..n).map(|i| ring(i, -2.0)));
        let mut idx: Vec<[u32; 3]> = (0..n as u32).map(|i| [0, 1 + (i + 1) % n as u32, 1 + i]).collect();
        idx.extend((1..n as u32 - 1).map(|i| [fan, fan + i, fan + i + 1]));
        let mesh = TriangleMesh::new(p.clone(), None, None, idx.clone()).unwrap();
        let out = with_computed_normals(&mesh, None, DEFAULT_CREASE_DEG).unwrap();
        let unit = |t: [u32; 3]| {
            let [a, b, c] = t.map(|v| p[v as usize]);
            (b - a).cross(c - a).normalize()
        };
        let angle = |t: [u32; 3], v: u32| {
            let k = t.iter().position(|&x| x == v).unwrap();
            let (o, b, c) = (p[t[k] as usize], p[t[(k + 1) % 3] as usize], p[t[(k + 2) % 3] as usize]);
            (b - o).angle_between(c - o)
        };
        let cos_crease = DEFAULT_CREASE_DEG.to_radians().cos();
        for (f, &t) in idx.iter().enumerate() {
            for v in [0, fan] {
                if !t.contains(&v) {
                    continue;
                }
                let want = idx
                    .iter()
                    .filter(|g| g.contains(&v) && unit(**g).dot(unit(t)) >= cos_crease)
                    .map(|&g| unit(g) * angle(g, v))
                    .sum::<Vec3>()
                    .normalize();
                let got = normal_at(&out, f, p[v as usize]);
                assert!((got - want).length() < 1e-5, "face {f} at {v}: {got} against {want}");
            }
        }
        // The flat fan's corners all share the plane's normal (−Y here).
        assert!((normal_at(&out, n, p[fan as usize]) - Vec3::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn smooth_across_split_vertices_within_the_crease() {
        // 12 sides: neighbours meet at 30°, within the default crease.
        let m = with_computed_normals(&split_ring(12), None, DEFAULT_CREASE_DEG).unwrap();
        let seam = m.triangle(0)[1];
        let (left, right) = (normal_at(&m, 0, seam), normal_at(&m, 2, seam));
        assert!((left - right).length() < 1e-6, "{left} vs {right}");
        // The shared normal points straight out from the axis.
        assert!((left - Vec3::new(seam.x, 0.0, seam.z).normalize()).length() < 1e-5);
        // A 30° crease angle is not sharper than 30°: still smooth; 20° is.
        let hard = with_computed_normals(&split_ring(12), None, 20.0).unwrap();
        assert!((normal_at(&hard, 0, seam) - normal_at(&hard, 2, seam)).length() > 0.1);
        // A square prism has 90° edges: hard under the default.
        let sq = with_computed_normals(&split_ring(4), None, DEFAULT_CREASE_DEG).unwrap();
        let edge = sq.triangle(0)[1];
        assert!((normal_at(&sq, 0, edge) - normal_at(&sq, 2, edge)).length() > 1.0);
    }

    #[test]
    fn smoothing_groups_decide_what_joins() {
        let ring = split_ring(12);
        // Group 0 is flat; faces of different groups do not join.
        let flat = with_computed_normals(&ring, Some(&[0; 24]), 180.0).unwrap();
        for f in 0..flat.len() {
            let [a, b, c] = flat.triangle(f);
            let n = (b - a).cross(c - a).normalize();
            assert!((normal_at(&flat, f, a) - n).length() < 1e-6);
        }
        let mut groups = [1u32; 24];
        groups[2..4].fill(2);
        let split = with_computed_normals(&ring, Some(&groups), 180.0).unwrap();
        let seam = ring.triangle(0)[1];
        assert!((normal_at(&split, 0, seam) - normal_at(&split, 2, seam)).length() > 0.1);
        assert!(with_computed_normals(&ring, Some(&[1; 3]), 60.0).is_err());
    }

    #[test]
    fn tiny_and_huge_models_get_the_same_smooth_normals() {
        // An octahedron: by symmetry each corner's smooth normal points
        // straight out. At 1e-12 the angle weights' squared lengths
        // underflowed (every normal zero, so flat shading), and the faces
        // were taken for zero-area ones.
        let corners = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        let idx =
            vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        for scale in [1.0f32, 1e-12, 1e-18, 1e12] {
            let p: Vec<Vec3> = corners.iter().map(|&c| c * scale).collect();
            let m = TriangleMesh::new(p.clone(), None, None, idx.clone()).unwrap();
            assert_eq!(m.degenerate_count(), 0, "scale {scale}");
            let out = with_computed_normals(&m, None, 180.0).unwrap();
            for (f, tri) in idx.iter().enumerate() {
                for (k, &v) in tri.iter().enumerate() {
                    let n = normal_at(&out, f, p[v as usize]);
                    assert!(
                        (n - corners[v as usize]).length() < 1e-5,
                        "scale {scale}, face {f} corner {k}: {n}"
                    );
                }
            }
        }
    }
}
