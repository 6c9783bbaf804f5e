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
/// the triangles `tris`, without obvhs's (slow) debug validation. Boxes
/// far from unit size are built at a power-of-two scale ([`Pow2Scale`]).
pub(crate) fn build(
    aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    p: BvhBuildParams,
) -> Bvh2 {
    let scale = Pow2Scale::of(&aabbs);
    let (aabbs, tris) = scale.inputs(aabbs, tris);
    let mut bvh = collapsed_tree(aabbs, tris.as_deref(), &p);
    if !bvh.nodes.is_empty() {
        ReinsertionOptimizer::default().run(
            &mut bvh,
            p.reinsertion_batch_ratio * p.post_collapse_reinsertion_batch_ratio_multiplier,
            None,
        );
    }
    if !scale.is_one() {
        for node in &mut bvh.nodes {
            let b = *node.aabb();
            node.set_aabb(ObAabb { min: scale.up(b.min), max: scale.up(b.max) });
        }
    }
    bvh
}

/// The power of two a build scales its boxes by.
///
/// The builders (obvhs's PLOC, reinsertion and leaf collapsing, the wide
/// layout's plan, the CWBVH conversion) weigh boxes by their surface
/// area, in `f32`. Boxes whose coordinates reach 10²⁰ have areas past
/// `f32::MAX`: the costs became infinite or `NaN`, the wide plan found
/// leaves over its size, and obvhs's CWBVH conversion then indexed out of
/// bounds (a panic on an OBJ file with three corners at 10²⁰). Tiny ones
/// lose their areas to underflow. So where the largest coordinate lies
/// outside `[2⁻³², 2³²]`, the build runs on boxes (and triangles, for
/// pre-splitting) multiplied by `2⁻ᵏ`, which brings it just inside that
/// range, and the finished nodes' boxes are multiplied by `2ᵏ`. Both are exact for
/// normal numbers, so the boxes are those the same tree has unscaled; a
/// coordinate that the scaling down takes below the smallest normal
/// number (under 2⁻¹²⁶ · 2ᵏ) moves by less than that, far inside the
/// slab test's own rounding at that scale.
/// Ordinary scenes (coordinates within 2³², about 4 · 10⁹) are built as
/// they are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Pow2Scale(i32);

impl Pow2Scale {
    /// The largest coordinate that is built as it is, and the smallest.
    const BIG: f32 = 4_294_967_296.0;
    const SMALL: f32 = 1.0 / 4_294_967_296.0;

    /// The scale for `aabbs`: `2ᵏ` that brings their largest finite
    /// coordinate to just inside `[2⁻³², 2³²]` (1, `k = 0`, when it lies
    /// there already or is 0).
    pub(crate) fn of(aabbs: &[ObAabb]) -> Self {
        let reach = aabbs
            .iter()
            .map(|a| a.min.abs().max(a.max.abs()).max_element())
            .filter(|r| r.is_finite())
            .fold(0.0f32, f32::max);
        if reach == 0.0 || (Self::SMALL..=Self::BIG).contains(&reach) {
            return Self(0);
        }
        // Only as far as needed, to the edge of the range built as it is:
        // a small box beside a far corner then keeps a normal area (scaled
        // down to 1, a 0.01 quad beside a corner at 1e20 had a subnormal
        // one, its tie-breaking growth was lost, and PLOC merged one pair a
        // pass: 3.4 s for 20 000 quads instead of 0.02 s).
        let k = reach.log2().floor() as i32;
        Self(if reach > Self::BIG { k - 32 } else { k + 32 })
    }

    /// Whether the build runs unscaled.
    pub(crate) fn is_one(self) -> bool {
        self.0 == 0
    }

    /// `k` of the scale `2ᵏ`.
    pub(crate) fn exponent(self) -> i32 {
        self.0
    }

    /// `v · 2ⁿ`, in two steps so that neither factor overflows or is
    /// subnormal (`|n|` up to about 250).
    fn times_pow2(v: Vec3A, n: i32) -> Vec3A {
        let half = n / 2;
        v * 2f32.powi(half) * 2f32.powi(n - half)
    }

    /// A coordinate of the build's boxes at the scene's scale.
    pub(crate) fn up(self, v: Vec3A) -> Vec3A {
        if self.is_one() { v } else { Self::times_pow2(v, self.0) }
    }

    /// A scene coordinate at the build's scale.
    fn down(self, v: Vec3A) -> Vec3A {
        if self.is_one() { v } else { Self::times_pow2(v, -self.0) }
    }

    /// The build's inputs at its scale: the boxes, and the triangles copied
    /// and scaled where there are any and the scale is not 1.
    pub(crate) fn inputs<'t>(
        self,
        mut aabbs: Vec<ObAabb>,
        tris: Option<&'t [obvhs::triangle::Triangle]>,
    ) -> (Vec<ObAabb>, Option<std::borrow::Cow<'t, [obvhs::triangle::Triangle]>>) {
        if self.is_one() {
            return (aabbs, tris.map(std::borrow::Cow::Borrowed));
        }
        for a in &mut aabbs {
            *a = ObAabb { min: self.down(a.min), max: self.down(a.max) };
        }
        let tris = tris.map(|ts| {
            let down = |v: prism_geometry::glam::Vec3A| self.down(v);
            std::borrow::Cow::Owned(
                ts.iter()
                    .map(|t| obvhs::triangle::Triangle { v0: down(t.v0), v1: down(t.v1), v2: down(t.v2) })
                    .collect(),
            )
        });
        (aabbs, tris)
    }
}

/// [`ploc_tree`] with its leaves collapsed to at most
/// `p.max_prims_per_leaf` primitives, without the second reinsertion of
/// [`build`]. The wide layout starts from this: its conversion chooses
/// leaves and lanes by its own surface-area plan. The second reinsertion
/// was about 4 % of the 216-bunny grid's build instructions, and with it
/// the kitchen's traversal took up to 4 % more instructions and the
/// other meshes ±1 % (docs/benchmarks.md).
///
/// Without pre-splitting, a set of at least `2 * PART_MIN` boxes is first
/// cut in two by a surface-area split of the box centres ([`split`]); each
/// side is built the same way, the two in parallel (`rayon::join`), and
/// the two trees are joined under a new root ([`join`]). obvhs's PLOC
/// runs its merge passes on one thread and parallelises its search only
/// for more than 4000 clusters, so one build of the bunny's 69 451
/// triangles ran only about 1.15× faster on two threads than on one
/// (docs/benchmarks.md). The cut depends
/// only on the boxes, never on the thread count, so every machine builds
/// the same tree.
pub(crate) fn collapsed_tree(
    mut aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    p: &BvhBuildParams,
) -> Bvh2 {
    if p.pre_split && tris.is_some() {
        let mut bvh = ploc_tree(aabbs, tris, p);
        if !bvh.nodes.is_empty() {
            collapse(&mut bvh, p.max_prims_per_leaf.clamp(1, 255), p.collapse_traversal_cost);
        }
        return bvh;
    }
    let mut ids: Vec<u32> = (0..aabbs.len() as u32).collect();
    part_tree(&mut aabbs, &mut ids, p)
}

/// Sets smaller than twice this many boxes are built in one piece. Each
/// cut costs some tree quality where large primitives straddle it (the
/// kitchen's walls and floor: its binary tree's surface-area cost rose
/// 1.9 % when cut in two and 5.5 % when cut in four), and lets a set of
/// `2 * PART_MIN` build on two threads. At `1 << 15` the bunny (69 451
/// triangles) is cut once and the kitchen (56 939) not at all; the
/// grid's build median fell from 33.9 to 26.3 ms (docs/benchmarks.md).
const PART_MIN: usize = 1 << 15;

/// The collapsed tree over `aabbs`, whose primitive indices are `ids`
/// (both reordered by the cuts): cut in two and built in parallel while
/// there are at least `2 * PART_MIN` boxes and [`split`] finds a cut.
fn part_tree(aabbs: &mut [ObAabb], ids: &mut [u32], p: &BvhBuildParams) -> Bvh2 {
    if aabbs.is_empty() {
        return Bvh2::default();
    }
    if aabbs.len() >= 2 * PART_MIN
        && let Some(k) = split(aabbs, ids)
    {
        let (la, ra) = aabbs.split_at_mut(k);
        let (li, ri) = ids.split_at_mut(k);
        let (l, r) = rayon::join(|| part_tree(la, li, p), || part_tree(ra, ri, p));
        return join(l, r);
    }
    let mut bvh = ploc(aabbs, (0..aabbs.len() as u32).collect(), p);
    collapse(&mut bvh, p.max_prims_per_leaf.clamp(1, 255), p.collapse_traversal_cost);
    for i in &mut bvh.primitive_indices {
        *i = ids[*i as usize];
    }
    bvh
}

/// Bins per axis of [`split`]'s surface-area sweep.
const BINS: usize = 32;

/// Cuts the boxes in two by their centres: of the planes between
/// [`BINS`] equal bins along each axis of the centres' bounds, the one
/// with the least surface-area cost (each side's box half area times its
/// count) among those that leave at least a quarter of the boxes on each
/// side, so that the two builds take similar time. Reorders `aabbs` and
/// `ids` together so that the first side comes first; returns its
/// length, or `None` (nothing moved) if no plane qualifies (the centres
/// bunch in one bin).
fn split(aabbs: &mut [ObAabb], ids: &mut [u32]) -> Option<usize> {
    let n = aabbs.len();
    let mut bounds = ObAabb::empty();
    for b in aabbs.iter() {
        bounds.extend(b.center());
    }
    let extent = bounds.diagonal();
    // Per axis and bin: the boxes' union and count.
    let mut bins = [[(ObAabb::empty(), 0usize); BINS]; 3];
    let bin = |c: f32, axis: usize| {
        let f = (c - bounds.min[axis]) / extent[axis] * BINS as f32;
        (f as usize).min(BINS - 1)
    };
    for b in aabbs.iter() {
        let c = b.center();
        for (axis, row) in bins.iter_mut().enumerate() {
            if extent[axis] > 0.0 {
                let e = &mut row[bin(c[axis], axis)];
                e.0 = e.0.union(b);
                e.1 += 1;
            }
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, row) in bins.iter().enumerate() {
        if !(extent[axis] > 0.0) {
            continue;
        }
        // Right sides' areas and counts, swept from the last bin.
        let mut right = [(0.0f32, 0usize); BINS];
        let (mut acc, mut count) = (ObAabb::empty(), 0);
        for k in (1..BINS).rev() {
            acc = acc.union(&row[k].0);
            count += row[k].1;
            right[k] = (acc.half_area(), count);
        }
        let (mut acc, mut count) = (ObAabb::empty(), 0);
        for k in 1..BINS {
            acc = acc.union(&row[k - 1].0);
            count += row[k - 1].1;
            let (ra, rc) = right[k];
            if 4 * count.min(rc) < n {
                continue;
            }
            let cost = acc.half_area() * count as f32 + ra * rc as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (_, axis, k) = best?;
    // Partition both slices: boxes whose centre falls below bin `k` first.
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        if bin(aabbs[lo].center()[axis], axis) < k {
            lo += 1;
        } else {
            hi -= 1;
            aabbs.swap(lo, hi);
            ids.swap(lo, hi);
        }
    }
    Some(lo)
}

/// The tree with `l` and `r` as the two children of a new root: the root
/// first, then the two old roots, then the rest of `l`'s nodes and of
/// `r`'s, each child reference and `r`'s leaves' primitive offsets
/// renumbered.
fn join(l: Bvh2, r: Bvh2) -> Bvh2 {
    let (nl, pl) = (l.nodes.len() as u32, l.primitive_indices.len() as u32);
    let renumber = |n: &Bvh2Node, node: &dyn Fn(u32) -> u32, prim: u32| {
        let mut n = *n;
        n.first_index = if n.is_leaf() { n.first_index + prim } else { node(n.first_index) };
        n
    };
    let in_l = |i: u32| if i == 0 { 1 } else { i + 2 };
    let in_r = |i: u32| if i == 0 { 2 } else { i + nl + 1 };
    let mut nodes = Vec::with_capacity(l.nodes.len() + r.nodes.len() + 1);
    nodes.push(Bvh2Node::new(l.nodes[0].aabb().union(r.nodes[0].aabb()), 0, 1));
    nodes.push(renumber(&l.nodes[0], &in_l, 0));
    nodes.push(renumber(&r.nodes[0], &in_r, pl));
    nodes.extend(l.nodes[1..].iter().map(|n| renumber(n, &in_l, 0)));
    nodes.extend(r.nodes[1..].iter().map(|n| renumber(n, &in_r, pl)));
    let mut primitive_indices = l.primitive_indices;
    primitive_indices.extend_from_slice(&r.primitive_indices);
    Bvh2 {
        nodes,
        primitive_indices,
        children_are_ordered_after_parents: l.children_are_ordered_after_parents
            && r.children_are_ordered_after_parents,
        max_depth: l.max_depth.max(r.max_depth) + 1,
        ..Bvh2::default()
    }
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
    let mut bvh = ploc(&aabbs, indices, p);
    bvh.uses_spatial_splits = split;
    bvh
}

/// obvhs's PLOC build over `aabbs` (primitive `i`'s index `indices[i]`),
/// then one pass of reinsertion.
///
/// PLOC sees each box grown on every side by a hair that varies with its
/// place ([`untied`]): obvhs's neighbour search takes the later of two
/// candidates of equal merge cost, so in a row of equal boxes (a strip of
/// unit quads, a polygon's zig-zag) every box's nearest was its right
/// neighbour, only the last pair was mutual, and each pass merged one
/// pair: 25 000 quads in a row took 8.8 s to build, and take 0.10 s. The
/// leaves then get their own boxes back and the tree is refitted, so the
/// tree is as tight as before (docs/benchmarks.md).
fn ploc(aabbs: &[ObAabb], indices: Vec<u32>, p: &BvhBuildParams) -> Bvh2 {
    let grown: Vec<ObAabb> = aabbs.iter().enumerate().map(|(i, b)| untied(i, b)).collect();
    // Built over positions in `aabbs`, mapped to `indices` after the refit.
    let places: Vec<u32> = (0..aabbs.len() as u32).collect();
    let mut bvh = PlocBuilder::with_capacity(aabbs.len()).build(
        p.ploc_search_distance,
        &grown,
        places,
        p.sort_precision,
        p.search_depth_threshold,
    );
    let (nodes, prims) = (&mut bvh.nodes, &mut bvh.primitive_indices);
    for node in nodes.iter_mut().filter(|n| n.is_leaf()) {
        let first = node.first_index as usize;
        let own = prims
            .get(first..first + node.prim_count as usize)
            .unwrap_or_default()
            .iter()
            .filter_map(|&k| aabbs.get(k as usize))
            .fold(ObAabb::empty(), |b, a| b.union(a));
        node.set_aabb(own);
    }
    bvh.refit_all();
    for k in &mut bvh.primitive_indices {
        *k = indices.get(*k as usize).copied().unwrap_or(*k);
    }
    ReinsertionOptimizer::default().run(&mut bvh, p.reinsertion_batch_ratio, None);
    bvh
}

/// Box `b` at place `i` grown on every side by `g · (size / 2¹⁴ +
/// |corner| / 2²⁰)`, `g` in `[0, 1)` from a multiplicative hash of `i`:
/// up to a few units in the last place of its coordinates, so that equal
/// boxes get merge costs that differ wherever they lie, and no box grows
/// by more than a hair.
fn untied(i: usize, b: &ObAabb) -> ObAabb {
    // The top 24 bits of a Fibonacci hash of the index (wrapping).
    let h = (i as u32).wrapping_mul(0x9E37_79B9) >> 8;
    let g = h as f32 * (1.0 / (1u32 << 24) as f32);
    let reach = b.min.abs().max(b.max.abs());
    let e = ((b.max - b.min) * (1.0 / 16384.0) + reach * (1.0 / 1_048_576.0)) * g;
    // An unbounded box (0 · ∞) stays as it is rather than turn NaN.
    let e = if e.is_finite() { e } else { Vec3A::ZERO };
    ObAabb { min: b.min - e, max: b.max + e }
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

#[cfg(test)]
mod tests {
    use super::*;
    use prism_testkit::Rng;

    /// A row of equal unit boxes: each grown box still holds its own and
    /// grows by a hair, and few boxes' unions with their two neighbours
    /// tie (the tie that made PLOC merge one pair a pass).
    #[test]
    fn grown_boxes_hold_their_own_and_break_ties() {
        let row: Vec<ObAabb> = (0..1000)
            .map(|i| {
                let x = i as f32;
                ObAabb { min: Vec3A::new(x, 0.0, 0.0), max: Vec3A::new(x + 1.0, 0.0, 1.0) }
            })
            .collect();
        let grown: Vec<ObAabb> = row.iter().enumerate().map(|(i, b)| untied(i, b)).collect();
        for (b, g) in row.iter().zip(&grown) {
            assert!(g.min.cmple(b.min).all() && g.max.cmpge(b.max).all());
            // Twice the bound, for the rounding of the subtractions.
            let most = 2.0 * ((b.max - b.min) * (1.0 / 16384.0) + b.max.abs() * (1.0 / 1_048_576.0));
            assert!((b.min - g.min).cmple(most).all() && (g.max - b.max).cmple(most).all());
        }
        let cost = |a: usize, b: usize| grown[a].union(&grown[b]).half_area();
        let ties = (1..999).filter(|&i| cost(i, i - 1) == cost(i, i + 1)).count();
        assert!(ties < 10, "{ties} of 998 boxes tie between their neighbours");
    }

    /// `n` boxes in three clumps of different density, and a thin sheet.
    fn boxes(n: usize, seed: u64) -> Vec<ObAabb> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|i| {
                let c = match i % 4 {
                    0 => Vec3A::new(rng.range(-10.0, -6.0), rng.range(0.0, 2.0), rng.range(0.0, 2.0)),
                    1 => Vec3A::new(rng.range(5.0, 5.5), rng.range(-1.0, 1.0), rng.range(3.0, 9.0)),
                    2 => Vec3A::new(rng.range(-20.0, 20.0), 0.25, rng.range(-20.0, 20.0)),
                    _ => Vec3A::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)),
                };
                let h = Vec3A::new(rng.range(0.0, 0.1), rng.range(0.0, 0.1), rng.range(0.0, 0.1));
                ObAabb::new(c - h, c + h)
            })
            .collect()
    }

    fn params() -> BvhBuildParams {
        let mut p = crate::BuildQuality::Medium.params();
        p.max_prims_per_leaf = 4;
        p
    }

    /// Primitives under node `k`.
    fn prims(bvh: &Bvh2, k: usize) -> u32 {
        let n = &bvh.nodes[k];
        if n.is_leaf() {
            n.prim_count
        } else {
            prims(bvh, n.first_index as usize) + prims(bvh, n.first_index as usize + 1)
        }
    }

    /// A set large enough to be cut is built into one valid tree (obvhs's
    /// own check: tight boxes, every primitive once, children after their
    /// parents), cut at the root into two sides of at least a quarter
    /// each, and the same tree node for node on one thread as on two.
    #[test]
    fn a_cut_build_is_one_valid_tree_whatever_the_threads() {
        let n = 2 * PART_MIN + 123;
        let aabbs = boxes(n, 7);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| collapsed_tree(aabbs.clone(), None, &params()))
        };
        let (one, two) = (on(1), on(2));
        let r = one.validate(&aabbs, false, true);
        assert_eq!(r.prim_count, n);
        let root = &one.nodes[0];
        let sides = [prims(&one, root.first_index as usize), prims(&one, root.first_index as usize + 1)];
        assert!(sides.iter().all(|&s| 4 * s as usize >= n), "root sides {sides:?} of {n}");
        assert_eq!(one.primitive_indices, two.primitive_indices);
        assert_eq!(one.nodes.len(), two.nodes.len());
        for (a, b) in one.nodes.iter().zip(&two.nodes) {
            assert_eq!((a.aabb(), a.prim_count, a.first_index), (b.aabb(), b.prim_count, b.first_index));
        }
    }

    /// `split` reorders boxes and ids together, leaves at least a quarter
    /// on each side, and some axis separates the two sides' centres; with
    /// every centre in one point it finds no cut and moves nothing.
    #[test]
    fn split_cuts_between_centres_and_keeps_a_quarter_each_side() {
        for seed in 0..4 {
            let n = 1000 + 37 * seed as usize;
            let before = boxes(n, seed);
            let (mut aabbs, mut ids) = (before.clone(), (0..n as u32).collect::<Vec<_>>());
            let Some(k) = split(&mut aabbs, &mut ids) else { panic!("seed {seed}: no cut") };
            assert!(4 * k >= n && 4 * (n - k) >= n, "seed {seed}: {k} of {n}");
            for (b, &i) in aabbs.iter().zip(&ids) {
                assert_eq!(*b, before[i as usize]);
            }
            let mut sorted = ids.clone();
            sorted.sort_unstable();
            assert!(sorted.iter().copied().eq(0..n as u32), "seed {seed}: ids a permutation");
            let side = |s: &[ObAabb]| s.iter().fold(ObAabb::empty(), |mut a, b| *a.extend(b.center()));
            let (l, r) = (side(&aabbs[..k]), side(&aabbs[k..]));
            assert!((0..3).any(|a| l.max[a] <= r.min[a]), "seed {seed}: sides overlap on every axis");
        }
        let same = vec![ObAabb::new(Vec3A::ONE, Vec3A::splat(2.0)); 500];
        let (mut aabbs, mut ids) = (same.clone(), (0..500).collect::<Vec<u32>>());
        assert_eq!(split(&mut aabbs, &mut ids), None);
        assert!(ids.iter().copied().eq(0..500));
    }
}
