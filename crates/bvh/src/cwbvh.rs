//! Our own walk over obvhs's compressed wide BVH (CWBVH) nodes.
//!
//! obvhs builds the nodes; this module traverses them. It follows obvhs's
//! `traverse!` macro (same node groups, same child order by ray octant) but
//! with a box test of its own:
//!
//! * the near distance is clamped to the ray's `t_min`, not to obvhs's fixed
//!   `1e-4`, so a ray spawned a few ULPs off a surface with `t_min = 0` still
//!   finds geometry closer than `1e-4` (and a ray with a long, non-unit
//!   direction is not blind over its first `1e-4` units of `t`);
//! * zero direction components (`+0.0` or `-0.0`) get an infinite
//!   reciprocal, and the slab distances are computed as `(plane - origin) *
//!   inv` so that a ray lying exactly in a box's face plane gives `NaN`,
//!   which the min/max order below discards (the slab then does not limit
//!   the interval). obvhs's `safe_inverse` instead clamps the reciprocal to
//!   `±1/EPSILON` (a ray in a face plane then misses the box) and gives
//!   `-0.0` a negative reciprocal while ordering slabs by `dir < 0`, which
//!   culls every box for such rays;
//! * a box is culled only when its entry lies beyond [`BoxRay::reach`]
//!   (`t_max` widened by a few ULPs), not `t_max` itself: the entry
//!   distance may round past the `t` the triangle test gives for a
//!   triangle on the box's face, and a coincident face hit first (a few
//!   ULPs farther) would otherwise hide the nearer one;
//! * the traversal stack is sized from the tree's measured depth
//!   ([`crate::traverse`]).

use crate::traverse::{BoxRay, Stack, Tree, Visit};
use crate::{BuildQuality, bvh2};
use obvhs::aabb::Aabb as ObAabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use prism_geometry::glam::{Vec3, Vec3A, Vec4};

/// `_mm_min_ps(a, b)` on one lane: `b` when either is `NaN`.
#[inline(always)]
fn min_ps(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// `_mm_max_ps(a, b)` on one lane: `b` when either is `NaN`.
#[inline(always)]
fn max_ps(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Near and far distances to one child's slab along one axis, from its
/// quantised planes `lo` and `hi`, the node's scale `e`, the offset `o`
/// (node origin minus ray origin) and the ray's reciprocal `inv`.
///
/// Ordered by `min`/`max` rather than by the sign of the direction, which
/// for incoherent rays is an unpredictable branch. The values are the
/// same as choosing by sign: both distances are computed as before, and
/// for finite ones `min`/`max` pick what the sign would. With `inv = +inf`
/// (zero direction) a plane through the origin gives `NaN`, and the
/// operand order keeps it exactly where the sign choice put it: [`min_ps`]
/// and [`max_ps`] return the second operand when either is `NaN`, so `NaN`
/// at `lo` (then `hi` gives `+inf`) stays the near value and `NaN` at `hi`
/// (then `lo` gives `-inf`) stays the far value, which the caller then
/// ignores.
#[inline(always)]
fn slab(lo: u8, hi: u8, e: f32, o: f32, inv: f32) -> (f32, f32) {
    let (t_lo, t_hi) = ((f32::from(lo) * e + o) * inv, (f32::from(hi) * e + o) * inv);
    (min_ps(t_hi, t_lo), max_ps(t_lo, t_hi))
}

/// Which children of `node` the ray's interval meets: obvhs's hit mask
/// (leaf primitive bits in the low 24 bits, inner-node bits above).
///
/// Written per child over fixed arrays of eight, which the compiler turns
/// into SIMD (two SSE halves, or one AVX register where the target has
/// it). Every `max_ps`/`min_ps` keeps a possible `NaN` in its first
/// operand, so a `NaN` slab (ray in the face plane) is ignored.
#[inline(always)]
pub(crate) fn intersect_node(node: &CwBvhNode, ray: &BoxRay, oct_inv4: u32) -> u32 {
    let ext = node.compute_extent();
    let po = Vec3A::from(node.p) - ray.origin;
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let reach = ray.reach();
    let mut near = [0.0f32; 8];
    let mut far = [0.0f32; 8];
    for k in 0..8 {
        let (nx, fx) = slab(node.child_min_x[k], node.child_max_x[k], ext.x, po.x, ray.inv.x);
        let (ny, fy) = slab(node.child_min_y[k], node.child_max_y[k], ext.y, po.y, ray.inv.y);
        let (nz, fz) = slab(node.child_min_z[k], node.child_max_z[k], ext.z, po.z, ray.inv.z);
        near[k] = max_ps(nx, max_ps(ny, max_ps(nz, ray.t_min)));
        far[k] = min_ps(fx, min_ps(fy, min_ps(fz, reach)));
    }
    let half = |v: &[f32; 8], i: usize| Vec4::new(v[i], v[i + 1], v[i + 2], v[i + 3]);
    let mut mask =
        half(&near, 0).cmple(half(&far, 0)).bitmask() | (half(&near, 4).cmple(half(&far, 4)).bitmask() << 4);
    let mut hit_mask = 0u32;
    while mask != 0 {
        let k = mask.trailing_zeros();
        mask &= mask - 1;
        let child_bits = ((child_bits8 >> (k * 8)) as u32) & 0xff;
        let bit_index = ((bit_index8 >> (k * 8)) as u32) & 0xff;
        hit_mask |= child_bits << bit_index;
    }
    hit_mask
}

#[inline(always)]
fn firstbithigh(v: u32) -> u32 {
    31 - v.leading_zeros()
}

impl Tree for CwBvh {
    /// A node group: (base index, hit mask), as in obvhs.
    type Entry = (u32, u32);

    fn node_count(&self) -> usize {
        self.nodes.len()
    }

    fn inner_children(&self, i: usize, mut f: impl FnMut(usize)) {
        let Some(node) = self.nodes.get(i) else { return };
        for ch in 0..8 {
            if !node.is_child_empty(ch) && !node.is_leaf(ch) {
                f(node.child_node_index(ch) as usize);
            }
        }
    }

    /// Front to back approximately: children in the ray's octant order.
    #[inline(always)]
    fn walk<S: Stack<(u32, u32)>>(&self, stack: &mut S, ray: &mut BoxRay, mut prim: impl Visit) {
        let bvh = self;
        if bvh.nodes.is_empty() {
            return;
        }
        let oct_inv4 = ray.oct_inv4();
        // (base index, mask) pairs as in obvhs: bit 31 stands for the root.
        let mut current: (u32, u32) = (0, 0x8000_0000);
        let mut prims: (u32, u32) = (0, 0);
        loop {
            while prims.1 != 0 {
                let local = firstbithigh(prims.1);
                prims.1 &= !(1u32 << local);
                if !prim.visit(prims.0 + local, ray) {
                    return;
                }
            }
            if current.1 & 0xff00_0000 != 0 {
                let hits_imask = current.1;
                let child_index_offset = firstbithigh(hits_imask);
                let child_index_base = current.0;
                current.1 &= !(1u32 << child_index_offset);
                if current.1 & 0xff00_0000 != 0 {
                    stack.push(current);
                }
                let slot_index = (child_index_offset - 24) ^ (oct_inv4 & 0xff);
                let relative_index = (hits_imask & !(0xffff_ffffu32 << slot_index)).count_ones();
                let Some(node) = bvh.nodes.get((child_index_base + relative_index) as usize) else {
                    return;
                };
                let hitmask = intersect_node(node, ray, oct_inv4);
                current = (node.child_base_idx, (hitmask & 0xff00_0000) | u32::from(node.imask));
                prims = (node.primitive_base_idx, hitmask & 0x00ff_ffff);
            } else {
                current = (0, 0);
            }
            if prims.1 == 0 && current.1 & 0xff00_0000 == 0 {
                match stack.pop() {
                    Some(g) => current = g,
                    None => return,
                }
            }
        }
    }
}

/// Converts a prism box to an obvhs one.
#[inline]
pub(crate) fn to_obvhs(min: Vec3, max: Vec3) -> obvhs::aabb::Aabb {
    obvhs::aabb::Aabb::new(Vec3A::from(min), Vec3A::from(max))
}

/// Bytes held by the nodes and the primitive indices.
pub(crate) fn bytes(bvh: &CwBvh) -> usize {
    bvh.nodes.len() * std::mem::size_of::<CwBvhNode>()
        + bvh.primitive_indices.len() * std::mem::size_of::<u32>()
}

/// Builds a CWBVH over triangles (`tris`, which may pre-split) or boxes.
/// Unlike obvhs's helpers this never runs the (slow) debug validation.
pub(crate) fn build_tris(
    tris: &[obvhs::triangle::Triangle],
    quality: BuildQuality,
    allow_split: bool,
) -> CwBvh {
    let aabbs: Vec<ObAabb> = tris.iter().map(obvhs::triangle::Triangle::aabb).collect();
    build(aabbs, Some(tris).filter(|_| allow_split), quality)
}

/// Builds a CWBVH over `aabbs` (pre-splitting `tris` if given and the
/// quality asks for it) from [`bvh2::ploc_tree`]'s binary tree.
pub(crate) fn build(
    aabbs: Vec<ObAabb>,
    tris: Option<&[obvhs::triangle::Triangle]>,
    quality: BuildQuality,
) -> CwBvh {
    if aabbs.is_empty() {
        return CwBvh::default();
    }
    let p = quality.params();
    // Boxes far from unit size are built at a power-of-two scale: a node's
    // origin `p` is multiplied back, and its children's exponents `e`
    // (the grid step is `2^(e - 127)`) raised by the same power.
    let scale = bvh2::Pow2Scale::of(&aabbs);
    let (aabbs, tris) = scale.inputs(aabbs, tris);
    let bvh2 = bvh2::ploc_tree(aabbs, tris.as_deref(), &p);
    let mut cw = bvh2_to_cwbvh(&bvh2, p.max_prims_per_leaf.clamp(1, 3), true, false);
    if !scale.is_one() {
        let k = scale.exponent();
        for node in &mut cw.nodes {
            node.p = scale.up(node.p.into()).into();
            for e in &mut node.e {
                *e = (i32::from(*e) + k).clamp(1, 254) as u8;
            }
        }
    }
    cw
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The old choice by direction sign, which `slab` replaces.
    fn slab_by_sign(lo: u8, hi: u8, e: f32, o: f32, inv: f32, neg: bool) -> (f32, f32) {
        let (near, far) = if neg { (hi, lo) } else { (lo, hi) };
        ((f32::from(near) * e + o) * inv, (f32::from(far) * e + o) * inv)
    }

    /// `slab` gives bit-for-bit the values the sign choice gave, `NaN`s
    /// (planes through the origin of a ray with a zero component) included.
    #[test]
    fn slab_matches_choice_by_sign() {
        let dirs = [1.0f32, -1.0, 0.0, -0.0, 3e-7, -3e-7, 1e30, -1e30, 0.37, -2.5];
        let qs = [0u8, 1, 7, 128, 254, 255];
        let e = 0.125f32;
        let mut checked = 0;
        for &d in &dirs {
            let inv = if d == 0.0 { f32::INFINITY } else { 1.0 / d };
            for &lo in &qs {
                for &hi in qs.iter().filter(|&&h| h >= lo) {
                    // Offsets putting the origin on either plane, between, or outside.
                    for o in [-f32::from(lo) * e, -f32::from(hi) * e, -0.5 * f32::from(hi) * e, 1.0, -40.0] {
                        let got = slab(lo, hi, e, o, inv);
                        let want = slab_by_sign(lo, hi, e, o, inv, d < 0.0);
                        assert_eq!(
                            (got.0.to_bits(), got.1.to_bits()),
                            (want.0.to_bits(), want.1.to_bits()),
                            "d {d} lo {lo} hi {hi} o {o}: {got:?} vs {want:?}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 500);
    }
}
