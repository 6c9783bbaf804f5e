//! Our own walk over obvhs's binary BVH (BVH2) nodes, for the per-mesh
//! hierarchies.
//!
//! obvhs builds the tree (PLOC, reinsertion, leaf collapsing: leaves of up
//! to `max_prims_per_leaf` triangles, 48-byte nodes with full-precision
//! boxes, the two children of a node adjacent); this module walks it with
//! the same rules as [`crate::cwbvh`]'s walk, which obvhs's own
//! `Bvh2::ray_traverse*` do not keep:
//!
//! * the near distance is clamped to the ray's `t_min` (obvhs ignores
//!   `t_min` and accepts any box whose far side is ahead of `0`);
//! * zero direction components (`+0.0` or `-0.0`) get an infinite
//!   reciprocal, and a slab that gives `NaN` (the ray lies in the box's
//!   face plane) does not limit the interval: the lane-wise `min`/`max`
//!   below keep a `NaN` only where the next step replaces it by the ray's
//!   own `t_min`/`t_max`;
//! * the far distance is widened by `1 + 2γ₃` (Ize, "Robust BVH Ray
//!   Traversal", JCGT 2013), so rounding in the slab distances never culls
//!   a box that the watertight triangle test would hit;
//! * front to back: the nearer child (by its entry distance) is taken
//!   first, a leaf child's triangles are tested at once, the farther inner
//!   child is pushed with its entry distance and skipped when popped if
//!   the ray's `t_max` has since shrunk below it;
//! * every comparison with `t_max` uses [`BoxRay::reach`], `t_max` widened
//!   the same way.
//!
//! The walk calls the same [`Visit`] as the CWBVH walk, with slots indexing
//! `primitive_indices` (the caller keeps its triangles in that order). The
//! two siblings' boxes are tested together (their horizontal reductions
//! share shuffles); the stack is [`crate::traverse`]'s. Measured against
//! the CWBVH walk it runs more instructions for every query kind (docs/benchmarks.md), so it is an option
//! (`BlasKind::Bvh2`), not the default.

use crate::traverse::{BoxRay, FAR_SCALE, Stack, Tree, Visit};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb as ObAabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;
use prism_geometry::glam::Vec3A;

/// Builds a BVH2 over `aabbs` as obvhs's `build_bvh2` does (PLOC,
/// reinsertion, leaf collapsing, reinsertion), optionally pre-splitting
/// the triangles `tris`, without obvhs's (slow) debug validation.
pub(crate) fn build(
    aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    p: BvhBuildParams,
) -> Bvh2 {
    let mut bvh = collapsed_tree(aabbs, tris, &p);
    if !bvh.nodes.is_empty() {
        ReinsertionOptimizer::default().run(
            &mut bvh,
            p.reinsertion_batch_ratio * p.post_collapse_reinsertion_batch_ratio_multiplier,
            None,
        );
    }
    bvh
}

/// [`ploc_tree`] with its leaves collapsed to at most
/// `p.max_prims_per_leaf` primitives, without the second reinsertion of
/// [`build`]. The wide layout starts from this: its conversion chooses
/// leaves and lanes by its own surface-area plan. The second reinsertion
/// was about 4 % of the 216-bunny grid's build instructions, and with it
/// the kitchen's traversal took up to 4 % more instructions and the
/// other meshes ±1 % (docs/benchmarks.md).
pub(crate) fn collapsed_tree(
    aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    p: &BvhBuildParams,
) -> Bvh2 {
    let mut bvh = ploc_tree(aabbs, tris, p);
    if !bvh.nodes.is_empty() {
        collapse(&mut bvh, p.max_prims_per_leaf.clamp(1, 255), p.collapse_traversal_cost);
    }
    bvh
}

/// The binary tree both layouts start from: optional pre-splitting of
/// `tris` (when `p.pre_split`), a PLOC build over `aabbs`, then one pass of
/// reinsertion. Empty input gives an empty tree.
pub(crate) fn ploc_tree(
    mut aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    p: &BvhBuildParams,
) -> Bvh2 {
    if aabbs.is_empty() {
        return Bvh2::default();
    }
    let mut indices: Vec<u32> = (0..aabbs.len() as u32).collect();
    let mut split = false;
    if let (true, Some(tris)) = (p.pre_split, tris) {
        let (mut largest, mut total) = (0.0f32, 0.0f32);
        for a in &aabbs {
            let h = a.half_area();
            largest = largest.max(h);
            total += h;
        }
        let avg = total / aabbs.len() as f32;
        obvhs::splits::split_aabbs_preset(&mut aabbs, &mut indices, tris, avg, largest);
        split = true;
    }
    let mut bvh = PlocBuilder::with_capacity(aabbs.len()).build(
        p.ploc_search_distance,
        &aabbs,
        indices,
        p.sort_precision,
        p.search_depth_threshold,
    );
    bvh.uses_spatial_splits = split;
    ReinsertionOptimizer::default().run(&mut bvh, p.reinsertion_batch_ratio, None);
    bvh
}

/// Bytes held by the nodes and the primitive indices.
pub(crate) fn bytes(bvh: &Bvh2) -> usize {
    bvh.nodes.len() * std::mem::size_of::<Bvh2Node>()
        + bvh.primitive_indices.len() * std::mem::size_of::<u32>()
}

/// Lane-wise `_mm_min_ps(a, b)`: `b` where either is `NaN`.
#[inline(always)]
fn min_ps(a: Vec3A, b: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of the x86-64 baseline.
        unsafe { core::arch::x86_64::_mm_min_ps(a.into(), b.into()).into() }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let m = |a: f32, b: f32| if a < b { a } else { b };
        Vec3A::new(m(a.x, b.x), m(a.y, b.y), m(a.z, b.z))
    }
}

/// Lane-wise `_mm_max_ps(a, b)`: `b` where either is `NaN`.
#[inline(always)]
fn max_ps(a: Vec3A, b: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of the x86-64 baseline.
        unsafe { core::arch::x86_64::_mm_max_ps(a.into(), b.into()).into() }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let m = |a: f32, b: f32| if a > b { a } else { b };
        Vec3A::new(m(a.x, b.x), m(a.y, b.y), m(a.z, b.z))
    }
}

/// The ray as the box test wants it.
#[derive(Clone, Copy)]
struct Slabs {
    origin: Vec3A,
    inv: Vec3A,
    t_min: Vec3A,
}

impl Slabs {
    /// Entry distance of `node`'s box, and whether the ray's interval
    /// (up to `t_max`) meets it.
    ///
    /// Per axis: `lo`/`hi` are the distances to the two planes. With an
    /// infinite reciprocal, a plane through the origin gives `NaN`: at `lo`
    /// (then `hi` is `+inf`), `min_ps(hi, lo)` keeps it as the near value
    /// and `max_ps(near, t_min)` turns it into `t_min`; at `hi` (then `lo`
    /// is `-inf`), `max_ps(lo, hi)` keeps it as the far value and
    /// `min_ps(far, t_max)` turns it into `t_max`. Either way the slab does
    /// not limit the interval, and no `NaN` reaches the reductions.
    #[inline(always)]
    fn test(&self, node: &Bvh2Node, t_max: f32) -> (bool, f32) {
        let b = node.aabb();
        let lo = (b.min - self.origin) * self.inv;
        let hi = (b.max - self.origin) * self.inv;
        let near = max_ps(min_ps(hi, lo), self.t_min).max_element();
        let far = min_ps(max_ps(lo, hi) * FAR_SCALE, Vec3A::splat(t_max)).min_element();
        (near <= far, near)
    }

    /// [`Slabs::test`] for two sibling boxes at once: the same values, with
    /// the two horizontal reductions shared (no `NaN` reaches them, so
    /// their order does not matter).
    #[inline(always)]
    fn test2(&self, a: &Bvh2Node, b: &Bvh2Node, t_max: f32) -> ((bool, f32), (bool, f32)) {
        #[cfg(target_arch = "x86_64")]
        {
            use core::arch::x86_64::{
                __m128, _mm_cmple_ps, _mm_cvtss_f32, _mm_max_ps, _mm_min_ps, _mm_movemask_ps, _mm_shuffle_ps,
                _mm_unpackhi_ps,
            };
            let (ba, bb) = (a.aabb(), b.aabb());
            let near_far = |bx: &obvhs::aabb::Aabb| {
                let lo = (bx.min - self.origin) * self.inv;
                let hi = (bx.max - self.origin) * self.inv;
                let near: __m128 = max_ps(min_ps(hi, lo), self.t_min).into();
                let far: __m128 = min_ps(max_ps(lo, hi) * FAR_SCALE, Vec3A::splat(t_max)).into();
                (near, far)
            };
            let (na, fa) = near_far(ba);
            let (nb, fb) = near_far(bb);
            // SAFETY: SSE is part of the x86-64 baseline.
            unsafe {
                // [ax, ay, bx, by] against [az, az, bz, bz], then lanes 0/1
                // and 2/3 against each other: lane 0 is a's, lane 2 b's.
                let xy = |u: __m128, v: __m128| _mm_shuffle_ps::<0b01_00_01_00>(u, v);
                let zz = |u: __m128, v: __m128| _mm_shuffle_ps::<0b10_10_10_10>(u, v);
                let n = _mm_max_ps(xy(na, nb), zz(na, nb));
                let n = _mm_max_ps(n, _mm_shuffle_ps::<0b10_11_00_01>(n, n));
                let f = _mm_min_ps(xy(fa, fb), zz(fa, fb));
                let f = _mm_min_ps(f, _mm_shuffle_ps::<0b10_11_00_01>(f, f));
                let hit = _mm_movemask_ps(_mm_cmple_ps(n, f));
                let near_b = _mm_cvtss_f32(_mm_unpackhi_ps(n, n));
                ((hit & 1 != 0, _mm_cvtss_f32(n)), (hit & 4 != 0, near_b))
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            (self.test(a, t_max), self.test(b, t_max))
        }
    }
}

/// Calls `prim` for each slot of leaf `node`; `false` if it stopped.
#[inline(always)]
fn leaf(node: &Bvh2Node, ray: &mut BoxRay, prim: &mut impl Visit) -> bool {
    let first = node.first_index;
    for slot in first..first + node.prim_count {
        if !prim.visit(slot, ray) {
            return false;
        }
    }
    true
}

impl Tree for Bvh2 {
    /// An inner node to visit, with its entry distance.
    type Entry = (u32, f32);

    fn node_count(&self) -> usize {
        self.nodes.len()
    }

    fn inner_children(&self, i: usize, mut f: impl FnMut(usize)) {
        if let Some(node) = self.nodes.get(i)
            && !node.is_leaf()
        {
            f(node.first_index as usize);
            f(node.first_index as usize + 1);
        }
    }

    /// Front to back: the nearer child first; the farther inner child is
    /// pushed with its entry distance and skipped when popped if `t_max`
    /// has since shrunk below it.
    #[inline(always)]
    fn walk<S: Stack<(u32, f32)>>(&self, stack: &mut S, ray: &mut BoxRay, mut prim: impl Visit) {
        let bvh = self;
        let nodes = bvh.nodes.as_slice();
        let Some(root) = nodes.first() else { return };
        let s = Slabs { origin: ray.origin, inv: ray.inv, t_min: Vec3A::splat(ray.t_min) };
        if !s.test(root, ray.reach()).0 {
            return;
        }
        if root.is_leaf() {
            leaf(root, ray, &mut prim);
            return;
        }
        let mut current = root.first_index as usize;
        loop {
            let (Some(a), Some(b)) = (nodes.get(current), nodes.get(current + 1)) else { return };
            let ((hit_a, near_a), (hit_b, near_b)) = s.test2(a, b, ray.reach());
            let ((first, hit_first), (second, hit_second, near_second)) = if near_b < near_a {
                ((b, hit_b), (a, hit_a, near_a))
            } else {
                ((a, hit_a), (b, hit_b, near_b))
            };
            let mut next = None;
            if hit_first {
                if first.is_leaf() {
                    if !leaf(first, ray, &mut prim) {
                        return;
                    }
                } else {
                    next = Some(first.first_index);
                }
            }
            // The first child's triangles may have moved `t_max` in front.
            if hit_second && near_second <= ray.reach() {
                if second.is_leaf() {
                    if !leaf(second, ray, &mut prim) {
                        return;
                    }
                } else if next.is_some() {
                    stack.push((second.first_index, near_second));
                } else {
                    next = Some(second.first_index);
                }
            }
            current = match next {
                Some(n) => n as usize,
                None => loop {
                    match stack.pop() {
                        Some((n, near)) if near <= ray.reach() => break n as usize,
                        Some(_) => {}
                        None => return,
                    }
                },
            };
        }
    }
}
