//! Indexed triangle meshes.

use crate::shapes::TriangleRay;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// An indexed triangle mesh with optional per-vertex normals and uvs.
///
/// The outward geometric normal of a face follows its counter-clockwise
/// winding. The shading normal interpolates vertex normals when present
/// (turned to the geometric normal's side), else equals the geometric one.
/// uv interpolates vertex uvs when present, else is `(b1, 1 − b2)` from
/// the barycentrics, as [`crate::Triangle`]'s.
///
/// Zero-area faces are kept (so that indices stay stable) but never hit.
/// [`Intersect`] on a mesh tests every face; use `prism-bvh` to accelerate.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    indices: Vec<[u32; 3]>,
    /// Bounds of the vertices that faces use (cached).
    bounds: Aabb,
    /// Watertight and consistently oriented ([`TriangleMesh::is_closed`]).
    closed: bool,
}

impl TriangleMesh {
    /// Builds and validates a mesh.
    ///
    /// # Errors
    /// [`GeometryError::InvalidMesh`] if an index is out of range, the
    /// normal or uv arrays do not match the positions in length, or a value
    /// is not finite.
    pub fn new(
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Self, GeometryError> {
        let n = positions.len();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(GeometryError::InvalidMesh(format!("vertex {i} is not finite")));
        }
        if let Some(ns) = &normals {
            if ns.len() != n {
                return Err(GeometryError::InvalidMesh(format!("{} normals for {n} vertices", ns.len())));
            }
            if let Some(i) = ns.iter().position(|p| !p.is_finite()) {
                return Err(GeometryError::InvalidMesh(format!("normal {i} is not finite")));
            }
        }
        if let Some(uv) = &uvs {
            if uv.len() != n {
                return Err(GeometryError::InvalidMesh(format!("{} uvs for {n} vertices", uv.len())));
            }
            if let Some(i) = uv.iter().position(|p| !p.is_finite()) {
                return Err(GeometryError::InvalidMesh(format!("uv {i} is not finite")));
            }
        }
        for (f, tri) in indices.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(GeometryError::InvalidMesh(format!(
                    "face {f} uses vertex {bad}, but the mesh has {n} vertices"
                )));
            }
        }
        let bounds = indices.iter().flatten().fold(Aabb::EMPTY, |b, &i| b.grow(positions[i as usize]));
        let closed = is_closed_surface(&positions, &indices);
        let mut mesh = Self { positions, normals, uvs, indices, bounds, closed };
        mesh.closed = closed && mesh.shells_enclose_volume();
        Ok(mesh)
    }

    /// Whether every shell of the mesh encloses a volume: not a sheet
    /// whose two sides are faces of their own (a double-sided card, each
    /// face paired with its reverse), which the edge test takes for a
    /// closed surface. A shell counts where its volume is above a
    /// millionth of its area times its box's diagonal (a slab thinner than
    /// about 3·10⁻⁶ of its width does not; a cube's ratio is 0.096), far
    /// above the volume's rounding.
    fn shells_enclose_volume(&self) -> bool {
        self.shells().iter().all(|faces| {
            let volume = self.volume_of(faces.iter().copied()).abs();
            let (mut area, mut bounds) = (0.0f64, Aabb::EMPTY);
            for &f in faces {
                let [a, b, c] = self.triangle(f);
                area += 0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length();
                bounds = bounds.grow(a).grow(b).grow(c);
            }
            let diagonal = (bounds.max - bounds.min).as_dvec3().length();
            volume > 1e-6 * area * diagonal
        })
    }

    /// Whether the mesh bounds a solid: it has faces, and with vertices
    /// taken by position (so that copies split at uv or normal seams count
    /// as one), every edge of a face is shared by exactly one other face,
    /// which runs it the other way (watertight and consistently oriented),
    /// and each of its shells encloses a volume (a double-sided sheet, each
    /// face paired with its reverse, bounds none). Faces with two corners
    /// at one position are ignored. Decided once, at construction.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Vertex positions.
    #[must_use]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Vertex normals, if any.
    #[must_use]
    pub fn normals(&self) -> Option<&[Vec3]> {
        self.normals.as_deref()
    }

    /// Vertex uvs, if any.
    #[must_use]
    pub fn uvs(&self) -> Option<&[Vec2]> {
        self.uvs.as_deref()
    }

    /// Faces as vertex index triples.
    #[must_use]
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Number of faces.
    #[must_use]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the mesh has no faces.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Corners of face `f`.
    ///
    /// # Panics
    /// If `f` is not below [`TriangleMesh::len`].
    #[inline]
    #[must_use]
    pub fn triangle(&self, f: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[f];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Whether face `f` spans an area, so that a ray can hit it: its
    /// edges' cross product is not zero. (Not its squared length, which
    /// underflows to 0 for edges under about 1e-11: a model in such units
    /// would lose every face.)
    ///
    /// # Panics
    /// If `f` is not below [`TriangleMesh::len`].
    #[must_use]
    pub fn face_has_area(&self, f: usize) -> bool {
        let [a, b, c] = self.triangle(f);
        (b - a).cross(c - a) != Vec3::ZERO
    }

    /// Number of faces with zero area (never hit).
    #[must_use]
    pub fn degenerate_count(&self) -> usize {
        (0..self.len()).filter(|&f| !self.face_has_area(f)).count()
    }

    /// The volume the faces enclose: positive where they wind
    /// counter-clockwise seen from outside (face normals, `(b − a) × (c −
    /// a)`, point out of the solid), negative where they wind inward. It
    /// means a volume only for a closed mesh ([`TriangleMesh::is_closed`]).
    /// Summed in `f64` about the bounds' centre, so that a mesh far from
    /// the origin loses no precision.
    #[must_use]
    pub fn signed_volume(&self) -> f64 {
        self.volume_of(0..self.len())
    }

    /// [`TriangleMesh::signed_volume`] of the faces `faces` alone.
    fn volume_of(&self, faces: impl IntoIterator<Item = usize>) -> f64 {
        if self.bounds.is_empty() {
            return 0.0;
        }
        let o = self.bounds.center().as_dvec3();
        let sum: f64 = faces
            .into_iter()
            .map(|f| {
                let [a, b, c] = self.triangle(f).map(|p| p.as_dvec3() - o);
                a.dot(b.cross(c))
            })
            .sum();
        sum / 6.0
    }

    /// The most shells [`TriangleMesh::orient_shells`] finds the nesting of.
    pub const NESTED_SHELLS: usize = 4096;

    /// Turns each shell of a closed mesh ([`TriangleMesh::is_closed`]) to
    /// face the way its place says: a shell inside an even number of the
    /// others (none: an outer surface) outward, one inside an odd number
    /// (a hollow's cavity) inward. A shell is a set of faces joined
    /// through shared edges (vertices taken by position); which way it
    /// faces is the sign of the volume it encloses, and which shells hold
    /// it is found by a ray from a point of its surface. Past
    /// [`TriangleMesh::NESTED_SHELLS`] shells, which hold which is not
    /// looked for (it takes time in the square of their number): the
    /// shells are turned only if every one faces inward, as a solid, or
    /// several apart, turned inside out. The number of shells turned (0
    /// for an open mesh, and for one already right).
    pub fn orient_shells(&mut self) -> usize {
        if !self.closed {
            return 0;
        }
        let shells = self.shells();
        // Each shell's volume (its sign: outward or inward), box and a point
        // of its surface (the centroid of its largest face).
        let facts: Vec<(f64, Aabb, Vec3)> = shells
            .iter()
            .map(|faces| {
                let volume = self.volume_of(faces.iter().copied());
                let (mut bounds, mut point, mut largest) = (Aabb::EMPTY, Vec3::ZERO, -1.0);
                for &f in faces {
                    let [a, b, c] = self.triangle(f);
                    bounds = bounds.grow(a).grow(b).grow(c);
                    let area = (b - a).cross(c - a).length_squared();
                    if area > largest {
                        (largest, point) = (area, (a + b + c) / 3.0);
                    }
                }
                (volume, bounds, point)
            })
            .collect();
        if shells.len() > Self::NESTED_SHELLS {
            if facts.iter().all(|f| f.0 < 0.0) {
                self.reverse_faces();
                return shells.len();
            }
            return 0;
        }
        let mut turned = 0;
        for (k, faces) in shells.iter().enumerate() {
            let (volume, bounds, point) = facts[k];
            let holders = (0..shells.len())
                .filter(|&m| m != k)
                .filter(|&m| facts[m].1.contains(bounds.min, 0.0) && facts[m].1.contains(bounds.max, 0.0))
                .filter(|&m| self.holds(&shells[m], point))
                .count();
            let outward = volume > 0.0;
            if outward != (holders % 2 == 0) {
                for &f in faces {
                    self.indices[f].swap(1, 2);
                }
                turned += 1;
            }
        }
        turned
    }

    /// The faces of each shell: faces joined through shared edges, with
    /// vertices taken by position; faces with two corners at one position
    /// join nothing and belong to no shell.
    fn shells(&self) -> Vec<Vec<usize>> {
        let id = weld_by_position(&self.positions);
        let mut parent: Vec<usize> = (0..self.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut first: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
        let mut kept = Vec::new();
        for (f, tri) in self.indices.iter().enumerate() {
            let [a, b, c] = tri.map(|i| id[i as usize]);
            if a == b || b == c || a == c {
                continue;
            }
            kept.push(f);
            for (x, y) in [(a, b), (b, c), (c, a)] {
                let edge = (x.min(y), x.max(y));
                match first.get(&edge) {
                    Some(&g) => {
                        let (rf, rg) = (root(&mut parent, f), root(&mut parent, g));
                        parent[rf.max(rg)] = rf.min(rg);
                    }
                    None => {
                        first.insert(edge, f);
                    }
                }
            }
        }
        let mut by_root: std::collections::BTreeMap<usize, Vec<usize>> = std::collections::BTreeMap::new();
        for f in kept {
            by_root.entry(root(&mut parent, f)).or_default().push(f);
        }
        by_root.into_values().collect()
    }

    /// Whether the closed shell of `faces` holds `p`: an odd number of its
    /// faces crossed by a ray from `p` in a direction along no axis or
    /// diagonal (the watertight triangle test counts a crossing at a
    /// shared edge once).
    fn holds(&self, faces: &[usize], p: Vec3) -> bool {
        let ray = Ray::new(p, Vec3::new(0.381_966, 0.618_034, 0.687_122).normalize());
        let tr = TriangleRay::new(&ray);
        faces.iter().filter(|&&f| tr.intersect(&self.triangle(f)).is_some()).count() % 2 == 1
    }

    /// Turns every face over (its second and third corners swapped), so
    /// that face normals point the other way; positions, normals and uvs
    /// stay, and a closed mesh stays closed.
    pub fn reverse_faces(&mut self) {
        for tri in &mut self.indices {
            tri.swap(1, 2);
        }
    }

    /// Replaces the vertex normals by area-weighted averages of the face
    /// normals (smooth shading for meshes that come without normals).
    pub fn compute_smooth_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for f in 0..self.len() {
            let [a, b, c] = self.triangle(f);
            // The cross product's length is twice the area: area weighting.
            let n = (b - a).cross(c - a);
            for &i in &self.indices[f] {
                acc[i as usize] += n;
            }
        }
        // Vertices used by no face (or only degenerate faces) keep a zero
        // normal, which hit() replaces by the face normal.
        self.normals =
            Some(acc.into_iter().map(|n| crate::unit_or_extreme(n).unwrap_or(Vec3::ZERO)).collect());
    }

    /// The full hit record for face `f` hit at `t` with barycentrics
    /// `(b1, b2)` by a ray with direction `dir`.
    ///
    /// # Panics
    /// If `f` is not below [`TriangleMesh::len`].
    #[must_use]
    pub fn hit(&self, f: usize, t: f32, b1: f32, b2: f32, dir: Vec3) -> Hit {
        let [ia, ib, ic] = self.indices[f].map(|i| i as usize);
        let [a, b, c] = [self.positions[ia], self.positions[ib], self.positions[ic]];
        let b0 = 1.0 - b1 - b2;
        let point = b0 * a + b1 * b + b2 * c;
        // `unit` where the cross product's squared length under- or
        // overflows (edges below about 1e-11 or above 1e19).
        let cross = (b - a).cross(c - a);
        let geo_normal = crate::unit_or_extreme(cross).unwrap_or(Vec3::Y);
        let normal = match &self.normals {
            Some(ns) => {
                // The file's normals need not be unit: one whose squared
                // length leaves f32's range (`vn 6e19 0 8e19`) still counts.
                let n = crate::unit_or_extreme(b0 * ns[ia] + b1 * ns[ib] + b2 * ns[ic]).unwrap_or(geo_normal);
                if n.dot(geo_normal) < 0.0 { -n } else { n }
            }
            None => geo_normal,
        };
        let uv = match &self.uvs {
            Some(uv) => b0 * uv[ia] + b1 * uv[ib] + b2 * uv[ic],
            None => Vec2::new(b1, 1.0 - b2),
        };
        Hit { t, point, geo_normal, normal, uv, front_face: dir.dot(geo_normal) < 0.0 }
    }

    /// Closest face hit by `ray` by testing every face: `(face, t, b1, b2)`.
    #[must_use]
    pub fn intersect_brute_force(&self, ray: &Ray) -> Option<(usize, f32, f32, f32)> {
        let mut tr = TriangleRay::checked(ray)?;
        let mut best = None;
        for f in 0..self.len() {
            if let Some((t, b1, b2)) = tr.intersect(&self.triangle(f)) {
                best = Some((f, t, b1, b2));
                tr.set_t_max(t);
            }
        }
        best
    }
}

impl Intersect for TriangleMesh {
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.intersect_brute_force(ray).map(|(_, t, _, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (f, t, b1, b2) = self.intersect_brute_force(ray)?;
        Some(self.hit(f, t, b1, b2, ray.dir))
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// For each vertex, the index of the first vertex at the same position
/// (bit-for-bit; `-0.0` and `0.0` are one).
#[must_use]
pub fn weld_by_position(positions: &[Vec3]) -> Vec<u32> {
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut first = std::collections::HashMap::with_capacity(positions.len());
    positions.iter().enumerate().map(|(i, &p)| *first.entry(key(p)).or_insert(i as u32)).collect()
}

/// Whether the faces close up: see [`TriangleMesh::is_closed`].
fn is_closed_surface(positions: &[Vec3], indices: &[[u32; 3]]) -> bool {
    let id = weld_by_position(positions);
    let mut edges: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    let mut faces = 0usize;
    for tri in indices {
        let [a, b, c] = tri.map(|i| id[i as usize]);
        if a == b || b == c || a == c {
            continue;
        }
        faces += 1;
        for e in [(a, b), (b, c), (c, a)] {
            *edges.entry(e).or_insert(0) += 1;
        }
    }
    faces > 0 && edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{close, close2, close3};

    /// The unit square in z = 0 as two triangles facing +Z.
    fn quad(normals: Option<Vec<Vec3>>, uvs: Option<Vec<Vec2>>) -> TriangleMesh {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        TriangleMesh::new(p, normals, uvs, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    #[test]
    fn tiny_and_huge_triangles_have_their_own_normal() {
        // Edges of 1e-12 and 1e19: the cross product's squared length
        // under- or overflows f32; the normal is still the face's (+X
        // here), not a fallback +Y.
        for s in [1e-12f32, 1e19] {
            let p = vec![Vec3::ZERO, Vec3::new(0.0, s, 0.0), Vec3::new(0.0, 0.0, s)];
            let m = TriangleMesh::new(p, None, None, vec![[0, 1, 2]]).unwrap();
            let h = m.hit(0, 1.0, 0.25, 0.25, Vec3::NEG_X);
            assert_eq!(h.geo_normal, Vec3::X, "edge {s}");
        }
    }

    #[test]
    fn diagonal_and_interior_hits() {
        let m = quad(None, None);
        for p in [
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::new(0.9, 0.1, 1.0),
            Vec3::new(0.1, 0.9, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ] {
            let h = m.intersect(&Ray::new(p, Vec3::NEG_Z)).unwrap_or_else(|| panic!("{p}"));
            close(h.t, 1.0, 1e-6);
            close3(h.point, p - Vec3::Z, 1e-6);
            assert_eq!(h.geo_normal, Vec3::Z);
            assert!(h.front_face);
        }
        assert!(m.intersect(&Ray::new(Vec3::new(1.000_001, 0.5, 1.0), Vec3::NEG_Z)).is_none());
        assert_eq!(m.bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(m.len(), 2);
        assert!(!m.is_empty());
    }

    #[test]
    fn interpolates_normals_and_uvs() {
        let ns = vec![Vec3::Z, Vec3::Z, Vec3::new(1.0, 0.0, 1.0).normalize(), Vec3::Z];
        let uvs = vec![Vec2::ZERO, Vec2::new(2.0, 0.0), Vec2::new(2.0, 2.0), Vec2::new(0.0, 2.0)];
        let m = quad(Some(ns), Some(uvs));
        let h = m.intersect(&Ray::new(Vec3::new(0.75, 0.25, 1.0), Vec3::NEG_Z)).unwrap();
        close2(h.uv, Vec2::new(1.5, 0.5), 1e-6);
        assert_eq!(h.geo_normal, Vec3::Z);
        assert!(h.normal.x > 0.0 && (h.normal.length() - 1.0).abs() < 1e-6);
        // Vertex normals pointing against the winding are turned to its side.
        let m = quad(Some(vec![Vec3::NEG_Z; 4]), None);
        let h = m.intersect(&Ray::new(Vec3::new(0.75, 0.25, -1.0), Vec3::Z)).unwrap();
        assert_eq!(h.normal, Vec3::Z);
        assert!(!h.front_face);
        // Without uvs, (b1, 1 − b2) (b1 = 0.5, b2 = 0.25 on this face).
        close2(h.uv, Vec2::new(0.5, 0.75), 1e-6);
        // Normals of any length count, those whose squares leave f32's range too.
        for scale in [1.0f32, 6e19, 1e30, 1e-30] {
            let m = quad(Some(vec![Vec3::new(0.6, 0.0, 0.8) * scale; 4]), None);
            let h = m.intersect(&Ray::new(Vec3::new(0.75, 0.25, 1.0), Vec3::NEG_Z)).unwrap();
            close3(h.normal, Vec3::new(0.6, 0.0, 0.8), 1e-6);
        }
    }

    #[test]
    fn smooth_normals_average_the_faces() {
        // A roof: two faces meeting at the ridge x = 0 with normals (∓1, 1, 0)/√2.
        let p = vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(9.0, 9.0, 9.0),
        ];
        let mut m = TriangleMesh::new(p, None, None, vec![[0, 1, 2], [1, 3, 2]]).unwrap();
        m.compute_smooth_normals();
        let ns = m.normals().unwrap();
        close3(ns[1], Vec3::Y, 1e-6);
        close3(ns[0], Vec3::new(-1.0, 1.0, 0.0).normalize(), 1e-6);
        assert_eq!(ns[4], Vec3::ZERO, "unused vertex");
        assert_eq!(m.bounds().max, Vec3::new(1.0, 1.0, 0.0), "unused vertices are not bounded");
    }

    #[test]
    fn invalid_meshes_are_rejected() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(TriangleMesh::new(p.clone(), None, None, vec![[0, 1, 3]]).is_err());
        assert!(TriangleMesh::new(p.clone(), Some(vec![Vec3::Z; 2]), None, vec![[0, 1, 2]]).is_err());
        assert!(TriangleMesh::new(p.clone(), None, Some(vec![Vec2::ZERO; 4]), vec![[0, 1, 2]]).is_err());
        assert!(TriangleMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::NAN], None, None, vec![]).is_err());
        // Degenerate faces are kept but never hit.
        let m = TriangleMesh::new(p, None, None, vec![[0, 1, 1], [0, 1, 2]]).unwrap();
        assert_eq!(m.degenerate_count(), 1);
        let h = m.intersect_brute_force(&Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z)).unwrap();
        assert_eq!(h.0, 1);
    }

    /// A unit cube with every face's corners its own vertices (as a file
    /// with per-face uvs gives them), faces counter-clockwise from outside.
    fn split_cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let c = |i: u32| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let mut p = Vec::new();
        let mut idx = Vec::new();
        for q in quads {
            let base = p.len() as u32;
            p.extend(q.map(c));
            idx.push([base, base + 1, base + 2]);
            idx.push([base, base + 2, base + 3]);
        }
        (p, idx)
    }

    #[test]
    fn closed_meshes_are_found_through_split_vertices() {
        let (p, idx) = split_cube();
        // Outward normals: the cube is a solid.
        let m = TriangleMesh::new(p.clone(), None, None, idx.clone()).unwrap();
        for f in 0..m.len() {
            let [a, b, c] = m.triangle(f);
            let n = (b - a).cross(c - a);
            assert!(n.dot((a + b + c) / 3.0 - Vec3::splat(0.5)) > 0.0, "face {f} faces inward");
        }
        assert!(m.is_closed());
        // A face missing: open.
        let open = TriangleMesh::new(p.clone(), None, None, idx[..10].to_vec()).unwrap();
        assert!(!open.is_closed());
        // One face turned over: not consistently oriented.
        let mut flipped = idx.clone();
        flipped[0] = [flipped[0][0], flipped[0][2], flipped[0][1]];
        flipped[1] = [flipped[1][0], flipped[1][2], flipped[1][1]];
        assert!(!TriangleMesh::new(p.clone(), None, None, flipped).unwrap().is_closed());
        // A face used twice: an edge shared by three faces.
        let mut doubled = idx.clone();
        doubled.push(idx[0]);
        assert!(!TriangleMesh::new(p.clone(), None, None, doubled).unwrap().is_closed());
        // A flat quad and an empty mesh are open.
        assert!(!quad(None, None).is_closed());
        // A double-sided card (each face and its reverse, in either order,
        // or cut along either diagonal) bounds no solid; a thin slab does.
        let q = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        for faces in [
            vec![[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]],
            vec![[0, 3, 2], [0, 2, 1], [0, 1, 2], [0, 2, 3]],
        ] {
            let mut card = TriangleMesh::new(q.clone(), None, None, faces).unwrap();
            assert!(!card.is_closed());
            assert_eq!(card.orient_shells(), 0);
        }
        let slab: Vec<Vec3> = p.iter().map(|v| *v * Vec3::new(1.0, 1.0, 1e-3)).collect();
        assert!(TriangleMesh::new(slab, None, None, idx.clone()).unwrap().is_closed());
        assert!(!TriangleMesh::new(Vec::new(), None, None, Vec::new()).unwrap().is_closed());
    }

    #[test]
    fn a_solid_turned_inside_out_has_a_negative_volume_until_its_faces_are_reversed() {
        let (p, idx) = split_cube();
        // The unit cube, far from the origin and scaled: volume 8.
        let p: Vec<Vec3> = p.into_iter().map(|v| v * 2.0 + Vec3::new(1e4, -3e3, 5e2)).collect();
        let m = TriangleMesh::new(p.clone(), None, None, idx.clone()).unwrap();
        assert!((m.signed_volume() - 8.0).abs() < 1e-9, "{}", m.signed_volume());
        let inward: Vec<[u32; 3]> = idx.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let mut inside_out = TriangleMesh::new(p, None, None, inward).unwrap();
        assert!(inside_out.is_closed());
        assert!((inside_out.signed_volume() + 8.0).abs() < 1e-9, "{}", inside_out.signed_volume());
        assert_eq!(m.clone().orient_shells(), 0, "outward already");
        assert_eq!(inside_out.clone().orient_shells(), 1);
        inside_out.reverse_faces();
        assert_eq!(inside_out, m);
        assert!(inside_out.is_closed());
        let mut turned = TriangleMesh::new(
            m.positions().to_vec(),
            None,
            None,
            idx.iter().map(|&[a, b, c]| [a, c, b]).collect(),
        )
        .unwrap();
        turned.orient_shells();
        assert_eq!(turned, m, "turned outward");
        // Two shells, each wound either way: a big cube and a small one,
        // apart, touching the big one at a corner, or inside it (a hollow:
        // its cavity faces inward). Each ends as its place says, and only
        // the shells that did not are turned.
        let (unit, idx) = split_cube();
        let n = unit.len() as u32;
        let two = |small: Vec3, big_in: bool, small_in: bool| {
            let mut p: Vec<Vec3> = unit.iter().map(|&v| v * 4.0).collect();
            p.extend(unit.iter().map(|&v| v + small));
            let turn = |t: [u32; 3], inward: bool| if inward { [t[0], t[2], t[1]] } else { t };
            let mut faces: Vec<[u32; 3]> = idx.iter().map(|&t| turn(t, big_in)).collect();
            faces.extend(idx.iter().map(|&t| turn(t.map(|i| i + n), small_in)));
            TriangleMesh::new(p, None, None, faces).unwrap()
        };
        // (where the small cube is, whether it is a cavity)
        for (small, cavity) in
            [(Vec3::new(10.0, 0.0, 0.0), false), (Vec3::splat(4.0), false), (Vec3::splat(1.5), true)]
        {
            let right = two(small, false, cavity);
            assert!(right.is_closed(), "{small}");
            for (big_in, small_in) in [(false, false), (true, false), (false, true), (true, true)] {
                let mut mesh = two(small, big_in, small_in != cavity);
                let wrong = usize::from(big_in) + usize::from(small_in);
                assert_eq!(mesh.orient_shells(), wrong, "{small}, {big_in}, {small_in}");
                assert_eq!(mesh, right, "{small}, {big_in}, {small_in}");
            }
        }
        // Past NESTED_SHELLS shells: all turned if all face inward, else none.
        let many = |inward: &dyn Fn(usize) -> bool| {
            let (mut p, mut faces) = (Vec::new(), Vec::new());
            for k in 0..=TriangleMesh::NESTED_SHELLS {
                let base = p.len() as u32;
                p.extend(unit.iter().map(|&v| v + Vec3::new(2.0 * k as f32, 0.0, 0.0)));
                faces.extend(idx.iter().map(|&t| {
                    let t = t.map(|i| i + base);
                    if inward(k) { [t[0], t[2], t[1]] } else { t }
                }));
            }
            TriangleMesh::new(p, None, None, faces).unwrap()
        };
        let mut all_in = many(&|_| true);
        assert_eq!(all_in.orient_shells(), TriangleMesh::NESTED_SHELLS + 1);
        assert!(all_in.signed_volume() > 0.0);
        assert_eq!(many(&|k| k == 7).orient_shells(), 0);
        // No faces, no volume.
        assert_eq!(TriangleMesh::new(Vec::new(), None, None, Vec::new()).unwrap().signed_volume(), 0.0);
    }

    #[test]
    fn weld_maps_copies_to_the_first() {
        let p = [Vec3::X, Vec3::Y, Vec3::X, Vec3::new(-0.0, 0.0, 0.0), Vec3::ZERO];
        assert_eq!(weld_by_position(&p), [0, 1, 0, 3, 3]);
    }
}
