//! What the two walks ([`crate::cwbvh`] and [`crate::bvh2`]) share: the
//! ray as the box tests want it, the callback a walk calls per primitive,
//! the traversal stack, and the tree depth that sizes it.

use crate::wide::WideBvh;
use prism_geometry::Ray;
use prism_geometry::glam::{Vec3A, Vec4};
use std::mem::MaybeUninit;

/// A ray prepared for box tests.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay {
    pub origin: Vec3A,
    /// `1/dir` per axis, `+inf` for both zeros (see [`crate::cwbvh`]).
    pub inv: Vec3A,
    pub t_min: f32,
    /// The ray's `t_max` widened by [`FAR_SCALE`]: see [`BoxRay::reach`].
    reach: f32,
}

/// `1 + 2γ₃` with `γ₃ = 3u / (1 - 3u)`, `u = 2⁻²⁴`, rounded up (to
/// `1 + 2⁻²¹`): the widening of far distances in Ize, "Robust BVH Ray
/// Traversal" (JCGT 2013), which bounds the rounding of a slab distance.
pub(crate) const FAR_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// How far the box tests look for a ray whose interval ends at `t_max`:
/// see [`BoxRay::reach`].
#[inline(always)]
pub(crate) fn reach_of(t_max: f32) -> f32 {
    t_max * FAR_SCALE
}

impl BoxRay {
    /// `inv` is `1/d` per axis with `+inf` for both zeros (slab order uses
    /// `d < 0`): one vector division, whose quotients are those of three
    /// scalar ones bit for bit, with the zeros' then replaced.
    #[inline(always)]
    ///
    /// `origin` and `dir` are read as the ray's two 16-byte halves
    /// ([`Ray`] is `repr(C)`: `origin, t_min` and `dir, t_max`), one load
    /// each, the fourth lane then dropped; built from three scalars each,
    /// they took several inserts per vector.
    pub fn new(ray: &Ray) -> Self {
        let (o, d) = halves(ray);
        let (o, d) = (Vec3A::from_vec4(o), Vec3A::from_vec4(d));
        let inv = Vec3A::select(d.cmpeq(Vec3A::ZERO), Vec3A::INFINITY, Vec3A::ONE / d);
        Self { origin: o, inv, t_min: ray.t_min, reach: reach_of(ray.t_max) }
    }
}

/// A ray's two 16-byte halves as vectors: `(origin, t_min)` and `(dir,
/// t_max)`. [`Ray`] is `repr(C)` with its fields in this order, so each
/// compiles to one 16-byte load.
#[inline(always)]
pub(crate) fn halves(ray: &Ray) -> (Vec4, Vec4) {
    (ray.origin.extend(ray.t_min), ray.dir.extend(ray.t_max))
}

impl BoxRay {
    /// Child order by octant, as obvhs's `ray_get_octant_inv4`: bit `a`
    /// of each byte set where axis `a` (x as bit 2, z as bit 0) points the
    /// positive way, by the sign of `inv` (a zero direction component,
    /// either sign, has `inv = +inf` and counts as positive). Only the
    /// CWBVH walk reads it, once a walk: made on demand, not with every
    /// box ray (a tenth of a kitchen camera packet's set-up).
    #[inline(always)]
    pub fn oct_inv4(&self) -> u32 {
        let pos = !self.inv.cmplt(Vec3A::ZERO).bitmask() & 7;
        ((pos & 1) << 2 | (pos & 2) | pos >> 2) * 0x0101_0101
    }

    /// A box ray from its parts (a packet's lanes, see
    /// [`crate::packet::Soa::box_ray`]); `reach` as [`BoxRay::reach`].
    #[inline(always)]
    pub(crate) fn from_parts(origin: Vec3A, inv: Vec3A, t_min: f32, reach: f32) -> Self {
        Self { origin, inv, t_min, reach }
    }

    /// How far the box tests look: `t_max` widened by [`FAR_SCALE`]. A
    /// box's entry distance may round a few ULPs past the `t` the triangle
    /// test computes for a triangle lying on the box's face; compared with
    /// `t_max` itself, such a box would be culled whenever `t_max` had
    /// just been set by a coincident face a few ULPs farther (z-fighting
    /// faces), and the walk would return the farther face. Visiting it
    /// costs little: the triangle test then decides exactly.
    /// Kept with the ray (a product per hit, not per box test).
    #[inline(always)]
    pub fn reach(&self) -> f32 {
        self.reach
    }

    /// Narrows the interval to `t_max` (after a closer hit).
    #[inline(always)]
    pub fn set_t_max(&mut self, t_max: f32) {
        self.reach = reach_of(t_max);
    }

    /// The reach itself, for a leaf test that narrows it
    /// ([`reach_of`] the new `t_max`).
    #[inline(always)]
    pub(crate) fn reach_mut(&mut self) -> &mut f32 {
        &mut self.reach
    }
}

/// What a walk calls for each primitive slot it reaches: `visit(slot,
/// ray)` may shrink the ray's interval ([`BoxRay::set_t_max`]) and
/// returns `false` to stop the walk.
///
/// Closures implement it; the hot queries use named types instead, whose
/// `#[inline(always)]` method is sure to be compiled into its caller (a
/// closure big enough is left out of line, and then misses the features a
/// `#[target_feature]` caller is compiled with).
pub(crate) trait Visit {
    /// Whether any hit will do (an occlusion query): walks that order
    /// children front to back may then skip the ordering.
    const ANY: bool = false;

    fn visit(&mut self, slot: u32, ray: &mut BoxRay) -> bool;

    /// Visits the `count` slots from `first` (a wide BVH's leaf, whose
    /// slots start at a multiple of four): as many calls of
    /// [`Visit::visit`], in order, unless the visitor tests the block at
    /// once with the same result. A loop, not `Iterator::all`: its closure
    /// was compiled out of line, for the baseline target even inside a
    /// walk compiled for AVX-512 (`wide::x86::InAvx512`).
    #[inline(always)]
    fn visit_leaf(&mut self, first: u32, count: u32, ray: &mut BoxRay) -> bool {
        let mut slot = first;
        while slot < first + count {
            if !self.visit(slot, ray) {
                return false;
            }
            slot += 1;
        }
        true
    }
}

impl<F: FnMut(u32, &mut BoxRay) -> bool> Visit for F {
    #[inline(always)]
    fn visit(&mut self, slot: u32, ray: &mut BoxRay) -> bool {
        self(slot, ray)
    }
}

/// `f` as a [`Visit`] (pins down the closure's signature for inference).
#[inline(always)]
pub(crate) fn visitor<F: FnMut(u32, &mut BoxRay) -> bool>(f: F) -> F {
    f
}

/// The stack interface the walks need.
pub(crate) trait Stack<T> {
    fn push(&mut self, v: T);
    fn pop(&mut self) -> Option<T>;
}

/// Stack entries kept inline (on the call stack); a tree needing more
/// (never seen in practice: a binary or CWBVH walk pushes at most one entry
/// per level, a wide walk seven) walks with a heap stack.
pub(crate) const INLINE_STACK: usize = 256;

/// Fixed-capacity stack, left uninitialised: zeroing it cost a `memset`
/// per walk (about 2 % of a query's instructions), and with nothing to
/// zero its capacity costs nothing.
pub(crate) struct InlineStack<T, const N: usize> {
    data: [MaybeUninit<T>; N],
    len: usize,
}

impl<T, const N: usize> InlineStack<T, N> {
    #[inline(always)]
    pub fn new() -> Self {
        Self { data: [const { MaybeUninit::uninit() }; N], len: 0 }
    }
}

impl<T: Copy, const N: usize> Stack<T> for InlineStack<T, N> {
    #[inline(always)]
    fn push(&mut self, v: T) {
        // The caller sized N from the tree depth, so this never overflows;
        // if it did, `get_mut` keeps it memory-safe (the entry is dropped).
        if let Some(slot) = self.data.get_mut(self.len) {
            slot.write(v);
            self.len += 1;
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        let slot = self.data.get(self.len)?;
        // SAFETY: every entry below `len` was written by `push` (`len` grows
        // only after a write), and `T: Copy` has no drop to run twice.
        Some(unsafe { slot.assume_init() })
    }
}

impl<T> Stack<T> for Vec<T> {
    #[inline(always)]
    fn push(&mut self, v: T) {
        Vec::push(self, v);
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        Vec::pop(self)
    }
}

/// A hierarchy this crate walks (obvhs's CWBVH and BVH2 nodes).
pub(crate) trait Tree {
    /// What the walk keeps on its stack.
    type Entry: Copy;

    /// Number of nodes (node 0 is the root).
    fn node_count(&self) -> usize;

    /// Calls `f` with the index of each child of node `i` that is an inner
    /// node (nothing for a leaf or an index out of range).
    fn inner_children(&self, i: usize, f: impl FnMut(usize));

    /// Walks the tree front to back for `ray`, calling `prim.visit(slot,
    /// ray)` for each primitive slot (an index into the tree's
    /// `primitive_indices`) of each leaf whose box the ray's interval
    /// meets. The callback may shrink the ray's interval; it returns `false` to
    /// stop the walk. `stack` must hold [`depth`] entries.
    fn walk<S: Stack<Self::Entry>>(&self, stack: &mut S, ray: &mut BoxRay, prim: impl Visit);

    /// [`Tree::walk`], through `walker` where this tree's walk depends on
    /// the caller's compilation ([`Walker`]; the wide tree's).
    #[inline(always)]
    fn walk_by<S: Stack<Self::Entry>>(
        &self,
        walker: impl Walker,
        stack: &mut S,
        ray: &mut BoxRay,
        prim: impl Visit,
    ) {
        let _ = walker;
        self.walk(stack, ray, prim);
    }
}

/// How a single-ray walk reaches the wide tree's node tests: [`Dispatch`]
/// through the tree's kernel ([`crate::wide::Kernel`]), each kernel's walk
/// an out-of-line function compiled for its features, which any caller
/// may call; or inline, where the caller itself is compiled for the
/// kernel (`wide::x86::InAvx512`), which spares the call and the
/// visitor's state passed through memory.
pub(crate) trait Walker: Copy {
    fn walk_wide<S: Stack<(u32, f32)>>(
        self,
        tree: &WideBvh,
        stack: &mut S,
        ray: &mut BoxRay,
        prim: impl Visit,
    );
}

/// The walk through the tree's kernel dispatch: for callers compiled for
/// any target.
#[derive(Clone, Copy)]
pub(crate) struct Dispatch;

impl Walker for Dispatch {
    #[inline(always)]
    fn walk_wide<S: Stack<(u32, f32)>>(
        self,
        tree: &WideBvh,
        stack: &mut S,
        ray: &mut BoxRay,
        prim: impl Visit,
    ) {
        tree.walk(stack, ray, prim);
    }
}

/// Depth of `tree` (root = 1, empty = 0), for sizing the walk's stack.
pub(crate) fn depth(tree: &impl Tree) -> usize {
    if tree.node_count() == 0 {
        return 0;
    }
    let mut best = 0;
    let mut todo = vec![(0usize, 1usize)];
    while let Some((i, d)) = todo.pop() {
        best = best.max(d);
        tree.inner_children(i, |c| todo.push((c, d + 1)));
    }
    best
}

/// [`Tree::walk`] with a stack that fits a tree of depth `depth`.
#[inline(always)]
pub(crate) fn walk_any<T: Tree>(tree: &T, depth: usize, ray: &mut BoxRay, prim: impl Visit) {
    walk_any_by(Dispatch, tree, depth, ray, prim);
}

/// [`walk_any`] through `walker` ([`Walker`]).
#[inline(always)]
pub(crate) fn walk_any_by<T: Tree>(
    walker: impl Walker,
    tree: &T,
    depth: usize,
    ray: &mut BoxRay,
    prim: impl Visit,
) {
    if depth <= INLINE_STACK {
        tree.walk_by(walker, &mut InlineStack::<T::Entry, INLINE_STACK>::new(), ray, prim);
    } else {
        tree.walk_by(walker, &mut Vec::with_capacity(depth), ray, prim);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::glam::Vec3;

    #[test]
    fn box_ray_reciprocals_and_octant_match_the_scalar_rules() {
        // `1/d` per axis, `+inf` for both zeros; the octant bits set where
        // an axis points the positive way (`-0.0` and `+0.0` alike).
        let inv = |d: f32| if d == 0.0 { f32::INFINITY } else { 1.0 / d };
        let dirs = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, 0.0, -0.0),
            Vec3::new(-0.0, -3.0, 0.0),
            Vec3::new(1e-38, -1e38, 7.0),
            Vec3::new(-1e-45, 0.5, -0.25),
            Vec3::new(3.0, -7.0, 11.0) / 13.0,
        ];
        for d in dirs {
            let br = BoxRay::new(&Ray::with_interval(Vec3::new(1.0, -2.0, 3.0), d, 0.5, 4.0));
            for a in 0..3 {
                assert_eq!(br.inv[a].to_bits(), inv(d[a]).to_bits(), "{d} axis {a}");
            }
            let oct = (if d.x < 0.0 { 0 } else { 0x0404_0404 })
                | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
                | (if d.z < 0.0 { 0 } else { 0x0101_0101 });
            assert_eq!(br.oct_inv4(), oct, "{d}");
            assert_eq!((br.origin, br.t_min, br.reach()), (Vec3A::new(1.0, -2.0, 3.0), 0.5, 4.0 * FAR_SCALE));
        }
    }

    #[test]
    fn inline_stack_is_last_in_first_out_and_drops_beyond_capacity() {
        let mut s = InlineStack::<(u32, f32), 3>::new();
        assert_eq!(s.pop(), None);
        for k in 0..5 {
            s.push((k, k as f32));
        }
        assert_eq!(s.pop(), Some((2, 2.0)));
        s.push((9, 9.0));
        assert_eq!(s.pop(), Some((9, 9.0)));
        assert_eq!(s.pop(), Some((1, 1.0)));
        assert_eq!(s.pop(), Some((0, 0.0)));
        assert_eq!(s.pop(), None);
    }
}
