//! One mesh's own hierarchy (a *BLAS*): its nodes in the layout
//! [`BlasKind`] chose, its triangles copied in leaf order, and the three
//! queries over them (closest, any, every crossing) in object space.
//!
//! Every triangle is tested by prism-geometry's [`TriangleRay`], the one
//! watertight ray/triangle test.

use crate::packet::{self, Frustum, Lanes, Leaf, Rows, Soa, bits};
use crate::traverse::{self, BoxRay, Dispatch, Tree, Visit, Walker, visitor, walk_any, walk_any_by};
use crate::wide::{self, Kernel, WideBvh};
use crate::{BlasKind, BuildQuality, bvh2, cwbvh};
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use prism_geometry::glam::Vec3;
use prism_geometry::{PacketRays, Ray, TriangleMesh, TriangleRay, TriangleRays8, Triangles4};
use std::ops::ControlFlow;

/// A mesh's nodes, in one of the two layouts.
enum Nodes {
    /// obvhs's compressed wide BVH.
    Cwbvh(CwBvh),
    /// obvhs's binary BVH.
    Bvh2(Bvh2),
    /// The wide SoA layout converted from obvhs's binary BVH.
    Wide(WideBvh),
}

impl std::fmt::Debug for Nodes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // obvhs's BVH2 is not `Debug`; the node count says enough.
        let (name, nodes) = match self {
            Self::Cwbvh(b) => ("Cwbvh", b.nodes.len()),
            Self::Bvh2(b) => ("Bvh2", b.nodes.len()),
            Self::Wide(b) => ("Wide", b.node_count()),
        };
        f.debug_struct(name).field("nodes", &nodes).finish_non_exhaustive()
    }
}

/// A mesh packet's answers: per ray, its hit `(face, t, b1, b2)` as
/// [`Blas::closest`] gives it.
pub(crate) type Found<const N: usize> = [Option<(u32, f32, f32, f32)>; N];

/// `ray` moved by `offset` where it is `Some`, as
/// [`prism_geometry::Transform::ray_to_object`] moves a ray under a
/// translation alone.
#[inline(always)]
fn moved_ray(ray: &Ray, offset: Option<Vec3>) -> Ray {
    match offset {
        Some(offset) => Ray { origin: ray.origin + offset, ..*ray },
        None => *ray,
    }
}

/// One mesh's own hierarchy, with its triangles copied in leaf order.
#[derive(Debug)]
pub(crate) struct Blas {
    nodes: Nodes,
    /// Stack entries its walk can need (the tree's depth for the CWBVH
    /// and BVH2 walks).
    depth: usize,
    /// Corners of the triangle in each primitive slot.
    tris: Vec<[Vec3; 3]>,
    /// Mesh face of each primitive slot.
    faces: Vec<u32>,
    /// A face may occupy several slots (pre-split build).
    split: bool,
    /// The wide layout's leaves as SIMD blocks (slots `4i..4i + 4` in
    /// block `i`); empty for the other layouts.
    blocks: Vec<Triangles4>,
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
            blocks: Vec::new(),
        }
    }
}

/// The wide BVH's leaves as blocks of four: each run of
/// [`wide::MAX_LEAF`] slots takes its triangles from `tris` (one per slot,
/// in slot order, as [`Blas::finish`] copies them), padding left out.
fn leaf_blocks(slots: &[u32], tris: &[[Vec3; 3]]) -> Vec<Triangles4> {
    const LANES: usize = wide::MAX_LEAF as usize;
    slots
        .chunks(LANES)
        .zip(tris.chunks(LANES))
        .map(|(slots, tris)| {
            let mut lanes = [[Vec3::ZERO; 3]; LANES];
            let mut n = 0;
            for (&s, t) in slots.iter().zip(tris) {
                if s != wide::PAD {
                    lanes[n] = *t;
                    n += 1;
                }
            }
            Triangles4::new(&lanes[..n])
        })
        .collect()
}

impl Blas {
    /// The hierarchy over `mesh`'s faces of non-zero area (the others can
    /// never be hit).
    pub fn build(mesh: &TriangleMesh, quality: BuildQuality, layout: BlasKind, kernel: Kernel) -> Self {
        let kept: Vec<u32> = (0..mesh.len()).filter(|&f| mesh.face_has_area(f)).map(|f| f as u32).collect();
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
            BlasKind::Wide => {
                let aabbs = tris.iter().map(obvhs::triangle::Triangle::aabb).collect();
                let Some((w, split)) = WideBvh::build(aabbs, Some(&tris), quality, wide::MAX_LEAF, kernel)
                else {
                    // Too many triangles for the wide layout's references.
                    return Self::build(mesh, quality, BlasKind::Cwbvh, kernel);
                };
                let (need, order) = (w.stack_need(), w.order());
                let mut blas = Self::finish(mesh, Nodes::Wide(w), need, split, &kept, &order);
                if let Nodes::Wide(w) = &blas.nodes {
                    blas.blocks = leaf_blocks(&w.slots, &blas.tris);
                }
                return blas;
            }
        };
        Self::finish(mesh, nodes, depth, split, &kept, &order)
    }

    /// The hierarchy with its triangles copied in slot order (`order`:
    /// the index into `kept` of each slot).
    fn finish(
        mesh: &TriangleMesh,
        nodes: Nodes,
        depth: usize,
        split: bool,
        kept: &[u32],
        order: &[u32],
    ) -> Self {
        let faces: Vec<u32> = order.iter().map(|&i| kept[i as usize]).collect();
        let tris = faces.iter().map(|&f| mesh.triangle(f as usize)).collect();
        Self { nodes, depth, tris, faces, split, blocks: Vec::new() }
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
            Nodes::Wide(b) => b.node_count(),
        }
    }

    /// Selects the node-test kernel of a wide hierarchy (`false` if the CPU
    /// cannot run it; other layouts ignore it).
    pub fn set_kernel(&mut self, kernel: Kernel) -> bool {
        match &mut self.nodes {
            Nodes::Wide(b) => b.set_kernel(kernel),
            _ => kernel.supported(),
        }
    }

    /// Walks the hierarchy, whichever layout it has.
    #[inline(always)]
    fn walk(&self, br: &mut BoxRay, v: impl Visit) {
        self.walk_by(Dispatch, br, v);
    }

    /// [`Blas::walk`] through `walker` ([`Walker`]).
    #[inline(always)]
    fn walk_by(&self, walker: impl Walker, br: &mut BoxRay, v: impl Visit) {
        match &self.nodes {
            Nodes::Cwbvh(b) => walk_any(b, self.depth, br, v),
            Nodes::Bvh2(b) => walk_any(b, self.depth, br, v),
            Nodes::Wide(b) => walk_any_by(walker, b, self.depth, br, v),
        }
    }

    /// Bytes held by the nodes, the primitive indices and the triangles.
    pub fn bytes(&self) -> usize {
        let nodes = match &self.nodes {
            Nodes::Cwbvh(b) => cwbvh::bytes(b),
            Nodes::Bvh2(b) => bvh2::bytes(b),
            Nodes::Wide(b) => b.bytes(),
        };
        nodes
            + self.blocks.len() * std::mem::size_of::<Triangles4>()
            + self.tris.len() * std::mem::size_of::<[Vec3; 3]>()
            + self.faces.len() * std::mem::size_of::<u32>()
    }

    /// Closest triangle hit by the object-space `ray`: `(face, t, b1, b2)`.
    /// `BRANCHLESS` picks a leaf's nearest lane without a branch per lane
    /// (for single rays, which are mostly incoherent; packets' rays take
    /// the loop), the same hit either way ([`closest_in_leaf`]).
    #[inline(always)]
    pub fn closest<const BRANCHLESS: bool>(&self, ray: &Ray) -> Option<(u32, f32, f32, f32)> {
        self.closest_by::<BRANCHLESS>(Dispatch, ray)
    }

    /// [`Blas::closest`], walked through `walker` ([`Walker`]).
    #[inline(always)]
    pub fn closest_by<const BRANCHLESS: bool>(
        &self,
        walker: impl Walker,
        ray: &Ray,
    ) -> Option<(u32, f32, f32, f32)> {
        let mut br = BoxRay::new(ray);
        let mut v = ClosestTriangle::<BRANCHLESS> {
            tris: &self.tris,
            blocks: &self.blocks,
            tr: TriangleRay::new(ray),
            found: None,
        };
        self.walk_by(walker, &mut br, &mut v);
        v.found.map(|(slot, t, b1, b2)| (self.faces[slot as usize], t, b1, b2))
    }

    /// Whether any triangle lies in the ray's interval.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_by(Dispatch, ray)
    }

    /// [`Blas::occluded`], walked through `walker` ([`Walker`]).
    #[inline(always)]
    pub fn occluded_by(&self, walker: impl Walker, ray: &Ray) -> bool {
        let mut br = BoxRay::new(ray);
        let mut v =
            AnyTriangle { tris: &self.tris, blocks: &self.blocks, tr: TriangleRay::new(ray), hit: false };
        self.walk_by(walker, &mut br, &mut v);
        v.hit
    }

    /// [`Blas::closest`] for each ray `rays[k]` of `mask`, walked together
    /// as packets ([`crate::packet`]) where the layout is wide: `found[k]`
    /// gets ray `k`'s hit, the one `closest` gives the ray in object space.
    /// `rows` says where the walk's rows and frustum come from ([`Rows`]).
    #[inline(always)]
    pub fn closest_packet<const N: usize>(
        &self,
        lanes: impl Lanes,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
        found: &mut Found<N>,
    ) {
        let offset = rows.offset();
        let Nodes::Wide(tree) = &self.nodes else {
            for k in bits(mask) {
                found[k] = self.closest::<false>(&moved_ray(&rays[k], offset));
            }
            return;
        };
        let mut soa = Soa::<N>::empty(mask);
        let fr = rows.fill(&mut soa, rays, mask);
        let mut v = ClosestTriangles {
            lanes,
            tris: &self.tris,
            blocks: &self.blocks,
            rays,
            offset,
            pr: PacketRays::new(),
            found: [None; N],
        };
        self.walk_rows::<false, N, _>(tree, lanes, fr, &mut soa, mask, &mut v, |v, k, br| {
            // A ray of no frustum reaches no packet leaf.
            let tr = TriangleRay::new(&moved_ray(&rays[k], offset));
            let mut c = ClosestTriangle::<false> { tris: v.tris, blocks: v.blocks, tr, found: v.found[k] };
            self.walk(br, &mut c);
            v.found[k] = c.found;
        });
        for k in bits(mask) {
            found[k] = v.found[k].map(|(slot, t, b1, b2)| (self.faces[slot as usize], t, b1, b2));
        }
    }

    /// [`Blas::occluded`] for each ray `rays[k]` of `mask`, walked together
    /// where the layout is wide, `rows` as for [`Blas::closest_packet`];
    /// returns the occluded rays.
    #[inline(always)]
    pub fn occluded_packet<const N: usize>(
        &self,
        lanes: impl Lanes,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
    ) -> u64 {
        let offset = rows.offset();
        let Nodes::Wide(tree) = &self.nodes else {
            return bits(mask)
                .filter(|&k| self.occluded(&moved_ray(&rays[k], offset)))
                .fold(0, |m, k| m | 1 << k);
        };
        let mut soa = Soa::<N>::empty(mask);
        let fr = rows.fill(&mut soa, rays, mask);
        let mut v = AnyTriangles {
            lanes,
            tris: &self.tris,
            blocks: &self.blocks,
            rays,
            offset,
            pr: PacketRays::new(),
            hit: 0,
        };
        self.walk_rows::<true, N, _>(tree, lanes, fr, &mut soa, mask, &mut v, |v, k, br| {
            let tr = TriangleRay::new(&moved_ray(&rays[k], offset));
            let mut c = AnyTriangle { tris: v.tris, blocks: v.blocks, tr, hit: false };
            self.walk(br, &mut c);
            v.hit |= u64::from(c.hit) << k;
        });
        v.hit & mask
    }

    /// The packet walks of the rays of `mask` over `tree`, their rows in
    /// `soa`: all under `fr` where the caller has a frustum that bounds
    /// them; otherwise [`packet::plan`]'s groups, each under its own
    /// frustum, and the rays of no group each by `alone(visitor, k, box
    /// ray)`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn walk_rows<const ANY: bool, const N: usize, V>(
        &self,
        tree: &WideBvh,
        lanes: impl Lanes,
        fr: Option<Frustum>,
        soa: &mut Soa<N>,
        mask: u64,
        v: &mut V,
        mut alone: impl FnMut(&mut V, usize, &mut BoxRay),
    ) where
        for<'v> &'v mut V: Leaf<N>,
    {
        if let Some(fr) = fr {
            tree.walk_packet::<ANY, N>(lanes, self.depth, &fr, soa, mask, &mut *v);
            return;
        }
        for &(m, fr) in &packet::plan(soa, mask) {
            match fr {
                Some(fr) => tree.walk_packet::<ANY, N>(lanes, self.depth, &fr, soa, m, &mut *v),
                None => {
                    for k in bits(m) {
                        alone(v, k, &mut soa.box_ray(k));
                    }
                }
            }
        }
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

/// A mesh's packet walks ([`Blas::closest_packet`],
/// [`Blas::occluded_packet`]) as functions of their own, one per packet
/// size and [`Lanes`] kind, which the top level calls at each mesh
/// instance it reaches.
///
/// Not inlined: a top-level packet query reaches a mesh through several
/// paths (one object alone, a whole packet, a gathered small or full
/// packet), and inlining a mesh walk into each of them, per packet size
/// and per ray type, made one function of prism-bvh so large that
/// compiling it took most of CI's time. One call per mesh instance a
/// packet reaches costs nothing next to the walk behind it.
pub(crate) trait MeshPackets: Lanes {
    /// [`Blas::closest_packet`] with these lanes.
    fn closest<const N: usize>(
        self,
        blas: &Blas,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
        found: &mut Found<N>,
    );

    /// [`Blas::occluded_packet`] with these lanes.
    fn occluded<const N: usize>(self, blas: &Blas, rays: &[Ray; N], mask: u64, rows: Rows<'_, N>) -> u64;
}

impl MeshPackets for packet::Portable {
    #[inline(never)]
    fn closest<const N: usize>(
        self,
        blas: &Blas,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
        found: &mut Found<N>,
    ) {
        blas.closest_packet(self, rays, mask, rows, found);
    }

    #[inline(never)]
    fn occluded<const N: usize>(self, blas: &Blas, rays: &[Ray; N], mask: u64, rows: Rows<'_, N>) -> u64 {
        blas.occluded_packet(self, rays, mask, rows)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The mesh packet walks compiled for AVX2.
    use super::{Blas, Found, MeshPackets};
    use crate::packet::Rows;
    use crate::packet::x86::Avx2;
    use prism_geometry::Ray;

    impl MeshPackets for Avx2 {
        #[inline(always)]
        fn closest<const N: usize>(
            self,
            blas: &Blas,
            rays: &[Ray; N],
            mask: u64,
            rows: Rows<'_, N>,
            found: &mut Found<N>,
        ) {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract), which is every feature
            // `closest` is compiled for.
            unsafe { closest(self, blas, rays, mask, rows, found) }
        }

        #[inline(always)]
        fn occluded<const N: usize>(self, blas: &Blas, rays: &[Ray; N], mask: u64, rows: Rows<'_, N>) -> u64 {
            // SAFETY: as in `closest` above.
            unsafe { occluded(self, blas, rays, mask, rows) }
        }
    }

    /// [`Blas::closest_packet`] compiled for AVX2. `inline(never)`: an
    /// AVX2 caller would otherwise take it in whole at each call.
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    #[inline(never)]
    fn closest<const N: usize>(
        lanes: Avx2,
        blas: &Blas,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
        found: &mut Found<N>,
    ) {
        blas.closest_packet(lanes, rays, mask, rows, found);
    }

    /// [`Blas::occluded_packet`] compiled for AVX2.
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    #[inline(never)]
    fn occluded<const N: usize>(
        lanes: Avx2,
        blas: &Blas,
        rays: &[Ray; N],
        mask: u64,
        rows: Rows<'_, N>,
    ) -> u64 {
        blas.occluded_packet(lanes, rays, mask, rows)
    }
}

/// A packet's closest-hit walk over one mesh's triangles: each ray that
/// meets a leaf tests it as [`ClosestTriangle`] does (per-ray state in flat
/// arrays, cheaper to set up than a visitor per ray). The rays'
/// [`TriangleRay`]s are made eight at a time ([`PacketRays`]) where one of
/// the eight first reaches a leaf (many rays of a packet reach none).
struct ClosestTriangles<'a, const N: usize, L> {
    lanes: L,
    tris: &'a [[Vec3; 3]],
    blocks: &'a [Triangles4],
    rays: &'a [Ray; N],
    /// Where `rays` are world-space rays on an instance placed by a
    /// translation alone: what moves them into object space.
    offset: Option<Vec3>,
    pr: PacketRays<N>,
    found: [Option<(u32, f32, f32, f32)>; N],
}

impl<const N: usize, L: Lanes> Leaf<N> for &mut ClosestTriangles<'_, N, L> {
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, meet: u64, soa: &mut Soa<N>, _: &Frustum) -> u64 {
        let reach = soa.reach_mut();
        self.pr.prepare_moved(self.rays, meet, self.offset);
        if let Some(block) = self.blocks.get(first as usize / 4)
            && meet.count_ones() >= GROUP_MIN
        {
            let (mut g, mut lane) = (TriangleRays8::empty(), [0u8; 8]);
            let mut rest = meet;
            while rest != 0 {
                rest &= !self.pr.group(rest, &mut g, &mut lane);
                let nearest = self.lanes.closest8(&mut g, block);
                for i in bits(u64::from(nearest.lanes)) {
                    let Some((j, t, b1, b2)) = nearest.get(i) else { continue };
                    let k = usize::from(lane[i & 7]);
                    if let Some(found) = self.found.get_mut(k) {
                        self.pr.set_t_max(k, t);
                        packet::narrow(reach, k, t);
                        *found = Some((first + j as u32, t, b1, b2));
                    }
                }
            }
            return 0;
        }
        for k in bits(meet) {
            if let Some(found) = self.found.get_mut(k) {
                let mut tr = self.pr.ray(k);
                let Some(r) = reach.get_mut(k) else { continue };
                closest_in_leaf::<false>(self.tris, self.blocks, &mut tr, found, first, count, r);
                // The ray's interval ends at its nearest hit so far (set
                // again, unchanged, where this leaf held none nearer).
                if let Some((_, t, _, _)) = *found {
                    self.pr.set_t_max(k, t);
                }
            }
        }
        0
    }
}

/// A packet's occlusion walk over one mesh's triangles: collects the
/// occluded rays in `hit` (and reports them done). A ray's
/// [`TriangleRay`] is made eight at a time, as in [`ClosestTriangles`].
struct AnyTriangles<'a, const N: usize, L> {
    lanes: L,
    tris: &'a [[Vec3; 3]],
    blocks: &'a [Triangles4],
    rays: &'a [Ray; N],
    /// Where `rays` are world-space rays on an instance placed by a
    /// translation alone: what moves them into object space.
    offset: Option<Vec3>,
    pr: PacketRays<N>,
    hit: u64,
}

impl<const N: usize, L: Lanes> Leaf<N> for &mut AnyTriangles<'_, N, L> {
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, meet: u64, _: &mut Soa<N>, _: &Frustum) -> u64 {
        let mut done = 0u64;
        self.pr.prepare_moved(self.rays, meet, self.offset);
        match self.blocks.get(first as usize / 4) {
            Some(block) if meet.count_ones() >= GROUP_MIN => {
                let (mut g, mut lane) = (TriangleRays8::empty(), [0u8; 8]);
                let mut rest = meet;
                while rest != 0 {
                    rest &= !self.pr.group(rest, &mut g, &mut lane);
                    let hit = self.lanes.occluded8(&g, block);
                    done |= bits(u64::from(hit)).fold(0u64, |m, i| m | 1 << (lane[i & 7] & 63));
                }
            }
            _ => {
                for k in bits(meet) {
                    let tr = self.pr.ray(k);
                    done |= u64::from(any_in_leaf(self.tris, self.blocks, &tr, first, count)) << k;
                }
            }
        }
        self.hit |= done;
        done
    }
}

/// The fewest rays at a leaf that a packet walk ([`AnyTriangles`],
/// [`ClosestTriangles`]) tests eight at a time ([`TriangleRays8`]) rather
/// than one by one.
const GROUP_MIN: u32 = 5;

/// The nearest hit of `tr` among the leaf's slots `first..first + count`
/// (a wide leaf's block at once, [`TriangleRay::intersect4`] or, with
/// `BRANCHLESS`, [`TriangleRay::intersect4_branchless`], the same hit; else
/// slot by slot in order): narrows `tr` and the box test's `reach` (a
/// [`BoxRay`]'s or a packet lane's, see [`traverse::reach_of`]) and
/// records it in `found`. Single rays take the branchless pick, packets
/// the loop (see `intersect4_branchless`).
#[inline(always)]
fn closest_in_leaf<const BRANCHLESS: bool>(
    tris: &[[Vec3; 3]],
    blocks: &[Triangles4],
    tr: &mut TriangleRay,
    found: &mut Option<(u32, f32, f32, f32)>,
    first: u32,
    count: u32,
    reach: &mut f32,
) {
    let Some(block) = blocks.get(first as usize / 4) else {
        for slot in first..first + count {
            closest_in_slot(tris, tr, found, slot, reach);
        }
        return;
    };
    let hit = if BRANCHLESS { tr.intersect4_branchless(block) } else { tr.intersect4(block) };
    if let Some((lane, t, b1, b2)) = hit {
        tr.set_t_max(t);
        *reach = traverse::reach_of(t);
        *found = Some((first + lane as u32, t, b1, b2));
    }
}

/// The hit of `tr` on slot `slot`, if nearer: narrows `tr` and `reach`
/// (as [`closest_in_leaf`]) and records it in `found`.
#[inline(always)]
fn closest_in_slot(
    tris: &[[Vec3; 3]],
    tr: &mut TriangleRay,
    found: &mut Option<(u32, f32, f32, f32)>,
    slot: u32,
    reach: &mut f32,
) {
    if let Some((t, b1, b2)) = tris.get(slot as usize).and_then(|v| tr.intersect(v)) {
        tr.set_t_max(t);
        *reach = traverse::reach_of(t);
        *found = Some((slot, t, b1, b2));
    }
}

/// Whether `tr` hits any triangle of the leaf's slots.
#[inline(always)]
fn any_in_leaf(tris: &[[Vec3; 3]], blocks: &[Triangles4], tr: &TriangleRay, first: u32, count: u32) -> bool {
    match blocks.get(first as usize / 4) {
        Some(block) => tr.occludes4(block),
        None => (first..first + count).any(|slot| any_in_slot(tris, tr, slot)),
    }
}

/// Whether `tr` hits the triangle of slot `slot`.
#[inline(always)]
fn any_in_slot(tris: &[[Vec3; 3]], tr: &TriangleRay, slot: u32) -> bool {
    tris.get(slot as usize).is_some_and(|v| tr.intersect(v).is_some())
}

/// The closest-hit walk over one mesh's triangles (`BRANCHLESS`: as
/// [`closest_in_leaf`]).
struct ClosestTriangle<'a, const BRANCHLESS: bool> {
    tris: &'a [[Vec3; 3]],
    blocks: &'a [Triangles4],
    tr: TriangleRay,
    /// `(slot, t, b1, b2)` of the nearest hit so far.
    found: Option<(u32, f32, f32, f32)>,
}

impl<const BRANCHLESS: bool> Visit for &mut ClosestTriangle<'_, BRANCHLESS> {
    #[inline(always)]
    fn visit(&mut self, slot: u32, br: &mut BoxRay) -> bool {
        closest_in_slot(self.tris, &mut self.tr, &mut self.found, slot, br.reach_mut());
        true
    }

    /// A wide leaf's block at once: the same hit as visiting its slots in
    /// order ([`closest_in_leaf`]).
    #[inline(always)]
    fn visit_leaf(&mut self, first: u32, count: u32, br: &mut BoxRay) -> bool {
        closest_in_leaf::<BRANCHLESS>(
            self.tris,
            self.blocks,
            &mut self.tr,
            &mut self.found,
            first,
            count,
            br.reach_mut(),
        );
        true
    }
}

/// The occlusion walk over one mesh's triangles (stops at the first hit).
struct AnyTriangle<'a> {
    tris: &'a [[Vec3; 3]],
    blocks: &'a [Triangles4],
    tr: TriangleRay,
    hit: bool,
}

impl Visit for &mut AnyTriangle<'_> {
    const ANY: bool = true;

    #[inline(always)]
    fn visit(&mut self, slot: u32, _: &mut BoxRay) -> bool {
        self.hit = any_in_slot(self.tris, &self.tr, slot);
        !self.hit
    }

    #[inline(always)]
    fn visit_leaf(&mut self, first: u32, count: u32, _: &mut BoxRay) -> bool {
        self.hit = any_in_leaf(self.tris, self.blocks, &self.tr, first, count);
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
            for layout in [BlasKind::Cwbvh, BlasKind::Bvh2, BlasKind::Wide] {
                let blas = Blas::build(&mesh, q, layout, Kernel::Portable);
                match &blas.nodes {
                    Nodes::Cwbvh(b) => {
                        assert_eq!(layout, BlasKind::Cwbvh);
                        b.validate(&tris, false);
                    }
                    Nodes::Bvh2(b) => {
                        assert_eq!(layout, BlasKind::Bvh2);
                        b.validate(&tris, false, blas.split);
                    }
                    Nodes::Wide(w) => {
                        assert_eq!(layout, BlasKind::Wide);
                        // A pre-split leaf bounds only its part of a triangle.
                        w.validate(|s| {
                            let t = blas.tris.get(s).filter(|_| !blas.split)?;
                            Some((t[0].min(t[1]).min(t[2]).to_array(), t[0].max(t[1]).max(t[2]).to_array()))
                        });
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
