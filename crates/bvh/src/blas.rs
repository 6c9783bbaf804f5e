//! One mesh's own hierarchy (a *BLAS*): its nodes in the layout
//! [`BlasKind`] chose, its triangles copied in leaf order, and the three
//! queries over them (closest, any, every crossing) in object space.
//!
//! Every triangle is tested by prism-geometry's [`TriangleRay`], the one
//! watertight ray/triangle test.

use crate::traverse::{self, BoxRay, Tree, Visit, visitor, walk_any};
use crate::{BlasKind, BuildQuality, bvh2, cwbvh};
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use prism_geometry::glam::Vec3;
use prism_geometry::{Ray, TriangleMesh, TriangleRay};
use std::ops::ControlFlow;

/// A mesh's nodes, in one of the two layouts.
enum Nodes {
    /// obvhs's compressed wide BVH.
    Cwbvh(CwBvh),
    /// obvhs's binary BVH.
    Bvh2(Bvh2),
}

impl std::fmt::Debug for Nodes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // obvhs's BVH2 is not `Debug`; the node count says enough.
        let (name, nodes) = match self {
            Self::Cwbvh(b) => ("Cwbvh", b.nodes.len()),
            Self::Bvh2(b) => ("Bvh2", b.nodes.len()),
        };
        f.debug_struct(name).field("nodes", &nodes).finish_non_exhaustive()
    }
}

/// One mesh's own hierarchy, with its triangles copied in leaf order.
#[derive(Debug)]
pub(crate) struct Blas {
    nodes: Nodes,
    /// Depth of the tree, for sizing the walk's stack.
    depth: usize,
    /// Corners of the triangle in each primitive slot.
    tris: Vec<[Vec3; 3]>,
    /// Mesh face of each primitive slot.
    faces: Vec<u32>,
    /// A face may occupy several slots (pre-split build).
    split: bool,
}

impl Default for Blas {
    /// No triangles: nothing to hit (an unused mesh's).
    fn default() -> Self {
        Self {
            nodes: Nodes::Cwbvh(CwBvh::default()),
            depth: 0,
            tris: Vec::new(),
            faces: Vec::new(),
            split: false,
        }
    }
}

impl Blas {
    /// The hierarchy over `mesh`'s faces of non-zero area (the others can
    /// never be hit).
    pub fn build(mesh: &TriangleMesh, quality: BuildQuality, layout: BlasKind) -> Self {
        let kept: Vec<u32> = (0..mesh.len())
            .filter(|&f| {
                let [a, b, c] = mesh.triangle(f);
                (b - a).cross(c - a).length_squared() != 0.0
            })
            .map(|f| f as u32)
            .collect();
        let tris: Vec<obvhs::triangle::Triangle> = kept
            .iter()
            .map(|&f| {
                let [a, b, c] = mesh.triangle(f as usize);
                obvhs::triangle::Triangle { v0: a.into(), v1: b.into(), v2: c.into() }
            })
            .collect();
        let (nodes, depth, split, order) = match layout {
            BlasKind::Cwbvh => {
                let b = cwbvh::build_tris(&tris, quality, true);
                let (depth, split, order) =
                    (traverse::depth(&b), b.uses_spatial_splits, b.primitive_indices.clone());
                (Nodes::Cwbvh(b), depth, split, order)
            }
            BlasKind::Bvh2 => {
                let aabbs = tris.iter().map(obvhs::triangle::Triangle::aabb).collect();
                let b = bvh2::build(aabbs, Some(&tris), quality.params());
                let (depth, split, order) =
                    (traverse::depth(&b), b.uses_spatial_splits, b.primitive_indices.clone());
                (Nodes::Bvh2(b), depth, split, order)
            }
        };
        let faces: Vec<u32> = order.iter().map(|&i| kept[i as usize]).collect();
        let tris = faces.iter().map(|&f| mesh.triangle(f as usize)).collect();
        Self { nodes, depth, tris, faces, split }
    }

    /// Whether the mesh has no hierarchy (nothing to hit).
    pub fn is_empty(&self) -> bool {
        self.node_count() == 0
    }

    /// Nodes of its hierarchy.
    pub fn node_count(&self) -> usize {
        match &self.nodes {
            Nodes::Cwbvh(b) => b.node_count(),
            Nodes::Bvh2(b) => b.node_count(),
        }
    }

    /// Walks the hierarchy, whichever layout it has.
    #[inline(always)]
    fn walk(&self, br: &mut BoxRay, v: impl Visit) {
        match &self.nodes {
            Nodes::Cwbvh(b) => walk_any(b, self.depth, br, v),
            Nodes::Bvh2(b) => walk_any(b, self.depth, br, v),
        }
    }

    /// Bytes held by the nodes, the primitive indices and the triangles.
    pub fn bytes(&self) -> usize {
        let nodes = match &self.nodes {
            Nodes::Cwbvh(b) => cwbvh::bytes(b),
            Nodes::Bvh2(b) => bvh2::bytes(b),
        };
        nodes
            + self.tris.len() * std::mem::size_of::<[Vec3; 3]>()
            + self.faces.len() * std::mem::size_of::<u32>()
    }

    /// Closest triangle hit by the object-space `ray`: `(face, t, b1, b2)`.
    #[inline(always)]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32, f32, f32)> {
        let mut br = BoxRay::new(ray);
        let mut v = ClosestTriangle { tris: &self.tris, tr: TriangleRay::new(ray), found: None };
        self.walk(&mut br, &mut v);
        v.found.map(|(slot, t, b1, b2)| (self.faces[slot as usize], t, b1, b2))
    }

    /// Whether any triangle lies in the ray's interval.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let mut br = BoxRay::new(ray);
        let mut v = AnyTriangle { tris: &self.tris, tr: TriangleRay::new(ray), hit: false };
        self.walk(&mut br, &mut v);
        v.hit
    }

    /// Calls `f(face, t, b1, b2)` for every triangle crossing in the
    /// interval, each face once, until `f` breaks.
    pub fn crossings(
        &self,
        ray: &Ray,
        mut f: impl FnMut(u32, f32, f32, f32) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let tr = TriangleRay::new(ray);
        let mut br = BoxRay::new(ray);
        let mut flow = ControlFlow::Continue(());
        let mut seen: Vec<u32> = Vec::new();
        self.walk(
            &mut br,
            visitor(|slot, _| {
                if let Some((t, b1, b2)) = tr.intersect(&self.tris[slot as usize]) {
                    let face = self.faces[slot as usize];
                    if self.split {
                        if seen.contains(&face) {
                            return true;
                        }
                        seen.push(face);
                    }
                    flow = f(face, t, b1, b2);
                }
                flow.is_continue()
            }),
        );
        flow
    }
}

/// The closest-hit walk over one mesh's triangles.
struct ClosestTriangle<'a> {
    tris: &'a [[Vec3; 3]],
    tr: TriangleRay,
    /// `(slot, t, b1, b2)` of the nearest hit so far.
    found: Option<(u32, f32, f32, f32)>,
}

impl Visit for &mut ClosestTriangle<'_> {
    #[inline(always)]
    fn visit(&mut self, slot: u32, br: &mut BoxRay) -> bool {
        if let Some((t, b1, b2)) = self.tr.intersect(&self.tris[slot as usize]) {
            self.tr.set_t_max(t);
            br.set_t_max(t);
            self.found = Some((slot, t, b1, b2));
        }
        true
    }
}

/// The occlusion walk over one mesh's triangles (stops at the first hit).
struct AnyTriangle<'a> {
    tris: &'a [[Vec3; 3]],
    tr: TriangleRay,
    hit: bool,
}

impl Visit for &mut AnyTriangle<'_> {
    #[inline(always)]
    fn visit(&mut self, slot: u32, _: &mut BoxRay) -> bool {
        self.hit = self.tr.intersect(&self.tris[slot as usize]).is_some();
        !self.hit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::wavy_grid;
    use prism_geometry::glam::Vec2;

    /// obvhs's own validation (skipped by our builds, as it is slow) on
    /// meshes built at every quality, in both layouts.
    #[test]
    fn built_hierarchies_validate() {
        let (positions, indices) = wavy_grid(30, [7.0, 5.0, 0.2]);
        let uvs = positions.iter().map(|p| Vec2::new(p.x, p.z)).collect();
        let mesh = TriangleMesh::new(positions, None, Some(uvs), indices).unwrap();
        let tris: Vec<obvhs::triangle::Triangle> = (0..mesh.len())
            .map(|f| {
                let [a, b, c] = mesh.triangle(f);
                obvhs::triangle::Triangle { v0: a.into(), v1: b.into(), v2: c.into() }
            })
            .collect();
        for q in BuildQuality::ALL {
            for layout in [BlasKind::Cwbvh, BlasKind::Bvh2] {
                let blas = Blas::build(&mesh, q, layout);
                match &blas.nodes {
                    Nodes::Cwbvh(b) => {
                        assert_eq!(layout, BlasKind::Cwbvh);
                        b.validate(&tris, false);
                    }
                    Nodes::Bvh2(b) => {
                        assert_eq!(layout, BlasKind::Bvh2);
                        b.validate(&tris, false, blas.split);
                    }
                }
                assert!(blas.depth >= 1 && blas.depth <= traverse::INLINE_STACK);
                assert_eq!(blas.tris.len(), blas.faces.len());
                let mut faces = blas.faces.clone();
                faces.sort_unstable();
                faces.dedup();
                assert_eq!(
                    faces.len(),
                    mesh.len(),
                    "{} {}: every face is in a leaf",
                    q.name(),
                    layout.name()
                );
            }
        }
    }
}
