//! A CPU-native wide BVH: eight children per node with uncompressed
//! single-precision boxes in SoA form (one 256-byte block a node),
//! converted from obvhs's binary tree, and its walk with node tests in
//! portable Rust, AVX2 or AVX-512, chosen at run time ([`Kernel`]).
//!
//! obvhs's CWBVH is a GPU layout: each node visit decodes eight quantised
//! boxes. Here a node holds its children's planes as six rows of eight
//! `f32` (min x, y, z, max x, y, z), so one node test is six loads, six
//! subtractions, six products and a comparison, eight children at once.
//!
//! # The box test
//!
//! The rules are [`crate::cwbvh`]'s: `1/d` is `+inf` for both zeros, the
//! slab's near plane is chosen by the sign of `d` (`-0.0` counts as
//! positive, matching its `+inf` reciprocal), distances are `(plane -
//! origin) * inv`, and the per-axis distances are folded into `[t_min,
//! reach]` with `max`/`min` that drop a `NaN` (a ray in a face plane), so
//! that slab does not limit the interval. Unused lanes hold an inverted
//! box (`+inf` minimum, `-inf` maximum), which no ray meets: its near
//! distance is `+inf` and its far one `-inf` whatever the direction.
//!
//! Every kernel performs the same operations in the same order on each
//! lane (no fused multiply-add), so they compute bit-identical distances,
//! visit the same children in the same order and return the same hits
//! (tested in the unit tests of `lib.rs` and in `tests/blas_kinds.rs`).
//!
//! # The walk
//!
//! Front to back: the children a node test keeps are sorted by entry
//! distance (stable, so ties keep lane order); the nearest is taken next
//! and the others are pushed with their distance, and skipped when popped
//! if the ray's `reach` has since shrunk below it. Occlusion walks
//! ([`Visit::ANY`]) skip the sort. A leaf's primitives are visited as soon
//! as it is taken.
//!
//! The node test returns a lane mask and every lane's entry distance; the
//! walk reads one or two children straight from the mask (one is taken,
//! two are compared), and only three or more are compacted and sorted.
//! The order is the same either way; skipping the compaction for the
//! common one- and two-child visits measured 4–8 % faster on primary rays
//! (docs/benchmarks.md).

use crate::traverse::{BoxRay, Stack, Tree, Visit};
use obvhs::bvh2::Bvh2;
use prism_geometry::glam::Vec3A;

/// Children per node.
pub(crate) const WIDTH: usize = 8;

/// Marks a leaf reference in [`Node::child`].
pub(crate) const LEAF: u32 = 1 << 31;
/// Bits of a leaf's first primitive slot.
pub(crate) const FIRST_BITS: u32 = 27;
/// Most primitives in one leaf: one SIMD block of four triangles.
pub(crate) const MAX_LEAF: u32 = 4;
/// Marks a padding slot in [`WideBvh::slots`].
pub(crate) const PAD: u32 = u32::MAX;

/// One node: its children's boxes and references.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node {
    /// Rows `[min x, min y, min z, max x, max y, max z]`, one lane per child.
    pub(crate) planes: [[f32; WIDTH]; 6],
    /// Per lane: an inner node's index, or a leaf `LEAF | (count - 1) << 27
    /// | first slot`. Unused lanes are never hit (inverted box).
    pub(crate) child: [u32; WIDTH],
}

impl Node {
    pub(crate) const EMPTY: Self = Self {
        planes: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [0; WIDTH],
    };
}

/// Which node-test code runs: all give the same answers, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// Plain Rust over eight-lane arrays (no `unsafe`), which the compiler
    /// vectorises as the target allows (two SSE halves by default).
    Portable,
    /// AVX2 intrinsics: one 256-bit register per plane row.
    Avx2,
    /// AVX-512 (F and VL) on 256-bit vectors: mask-register comparisons
    /// and compress-stores of the children hit.
    Avx512,
}

impl Kernel {
    /// Every kernel, plainest first.
    pub const ALL: [Self; 3] = [Self::Portable, Self::Avx2, Self::Avx512];

    /// Whether the running CPU can run this kernel.
    #[must_use]
    pub fn supported(self) -> bool {
        match self {
            Self::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => {
                is_x86_feature_detected!("avx2")
                    && is_x86_feature_detected!("fma")
                    && is_x86_feature_detected!("bmi1")
                    && is_x86_feature_detected!("bmi2")
                    && is_x86_feature_detected!("lzcnt")
                    && is_x86_feature_detected!("popcnt")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                Self::Avx2.supported()
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The kernel new hierarchies use: [`Kernel::Avx2`] where the CPU has
    /// it, else [`Kernel::Portable`]; `PRISM_BVH_NO_SIMD` forces the
    /// portable one, and the environment variable `PRISM_BVH_KERNEL`
    /// (`portable`, `avx2`, `avx512`) names another that the CPU runs.
    /// AVX2 is the default because it measured fastest on every single-ray
    /// set of the machine of docs/benchmarks.md ("The intrinsics node
    /// tests inlined"): 12–26 % ahead of the portable kernel (vectorised
    /// by the compiler inside the AVX2 build) and 5–30 % ahead of AVX-512.
    #[must_use]
    pub fn detect() -> Self {
        if std::env::var_os("PRISM_BVH_NO_SIMD").is_some() {
            return Self::Portable;
        }
        let named = std::env::var("PRISM_BVH_KERNEL").ok();
        let fallback = if Self::Avx2.supported() { Self::Avx2 } else { Self::Portable };
        Self::ALL
            .into_iter()
            .find(|k| named.as_deref() == Some(k.name()) && k.supported())
            .unwrap_or(fallback)
    }

    /// A short lower-case name (`"portable"`, `"avx2"`, `"avx512"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Portable => "portable",
            Self::Avx2 => "avx2",
            Self::Avx512 => "avx512",
        }
    }
}

/// Walks run per kernel, counted in test builds so that a test can prove
/// that a kernel the CPU has was exercised.
#[cfg(test)]
pub(crate) static WALKS: [std::sync::atomic::AtomicUsize; 3] =
    [const { std::sync::atomic::AtomicUsize::new(0) }; 3];

/// The wide tree: nodes (root first), its primitive slots and the kernel
/// its walks use.
#[derive(Clone, Debug)]
pub(crate) struct WideBvh {
    nodes: Vec<Node>,
    /// Per slot: the primitive's index (as given to the build), or
    /// [`PAD`]. Every leaf starts at a multiple of four, so that leaf
    /// `first / 4` is one block of four.
    pub slots: Vec<u32>,
    kernel: Kernel,
}

impl Default for WideBvh {
    fn default() -> Self {
        Self { nodes: Vec::new(), slots: Vec::new(), kernel: Kernel::Portable }
    }
}

impl WideBvh {
    /// Converts obvhs's binary tree: each wide node takes its binary
    /// node's two children and repeatedly opens the inner child with the
    /// largest surface until it has eight (or only leaves). Leaves keep
    /// their primitives, each leaf in a block of four slots ([`WideBvh::slots`]).
    /// `None` if a leaf holds more than [`MAX_LEAF`] primitives or the slots
    /// do not fit the reference's 27 bits.
    pub fn from_bvh2(bvh: &Bvh2, kernel: Kernel) -> Option<Self> {
        let mut nodes = Vec::with_capacity(bvh.nodes.len() / 4 + 1);
        let mut slots = Vec::with_capacity(bvh.primitive_indices.len() * 2);
        if !bvh.nodes.is_empty() {
            convert(bvh, 0, &mut nodes, &mut slots)?;
        }
        let mut w = Self { nodes, slots, kernel: Kernel::Portable };
        w.set_kernel(kernel);
        Some(w)
    }

    /// The primitive of each slot, padding slots repeating the one before
    /// (they are never visited).
    pub fn order(&self) -> Vec<u32> {
        let mut last = 0;
        self.slots
            .iter()
            .map(|&s| {
                if s != PAD {
                    last = s;
                }
                last
            })
            .collect()
    }

    /// Builds obvhs's binary tree over `aabbs` (pre-splitting `tris` if the
    /// quality asks for it) with leaves of at most `max_leaf` primitives
    /// (clamped to `1..=`[`MAX_LEAF`]: the mesh BLAS takes four, the top
    /// level one), and converts it; `None` as [`WideBvh::from_bvh2`]. Also
    /// says whether the build pre-split (a primitive may then sit in
    /// several leaves).
    pub fn build(
        aabbs: Vec<obvhs::aabb::Aabb>,
        tris: Option<&[obvhs::triangle::Triangle]>,
        quality: crate::BuildQuality,
        max_leaf: u32,
        kernel: Kernel,
    ) -> Option<(Self, bool)> {
        let mut p = quality.params();
        p.max_prims_per_leaf = max_leaf.clamp(1, MAX_LEAF);
        let b = crate::bvh2::build(aabbs, tris, p);
        Some((Self::from_bvh2(&b, kernel)?, b.uses_spatial_splits))
    }

    /// Selects the kernel its walks use; refused (`false`) when the CPU
    /// cannot run it.
    pub fn set_kernel(&mut self, kernel: Kernel) -> bool {
        let ok = kernel.supported();
        if ok {
            self.kernel = kernel;
        }
        ok
    }

    /// The nodes, root first.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Bytes held by the nodes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.slots.len() * std::mem::size_of::<u32>()
    }

    /// Stack entries a walk can need: a node pushes at most `WIDTH - 1`.
    pub fn stack_need(&self) -> usize {
        crate::traverse::depth(self) * (WIDTH - 1) + 1
    }
}

/// Appends the wide node for binary node `src` (and its subtree); returns
/// its index.
fn convert(bvh: &Bvh2, src: usize, nodes: &mut Vec<Node>, slots: &mut Vec<u32>) -> Option<u32> {
    let at = nodes.len();
    nodes.push(Node::EMPTY);
    let root = bvh.nodes.get(src)?;
    // The children so far, and the surface of each that can be opened (an
    // inner node); `None` for a leaf.
    let inner_area = |k: usize| bvh.nodes.get(k).filter(|n| !n.is_leaf()).map(|n| n.aabb().half_area());
    let mut kids = [0usize; WIDTH];
    let mut area = [None; WIDTH];
    let mut len = if root.is_leaf() {
        kids[0] = src;
        1
    } else {
        kids[..2].copy_from_slice(&[root.first_index as usize, root.first_index as usize + 1]);
        2
    };
    for (a, &k) in area.iter_mut().zip(&kids[..len]) {
        *a = inner_area(k);
    }
    while len < WIDTH {
        // The widest inner child; the last of equals, as `Iterator::max_by`.
        let mut widest: Option<(usize, f32)> = None;
        for (i, a) in area[..len].iter().enumerate() {
            if let Some(a) = *a
                && widest.is_none_or(|(_, w)| a.total_cmp(&w).is_ge())
            {
                widest = Some((i, a));
            }
        }
        let Some((i, _)) = widest else { break };
        let first = bvh.nodes[kids[i]].first_index as usize;
        kids.copy_within(i + 1..len, i + 2);
        area.copy_within(i + 1..len, i + 2);
        (kids[i], kids[i + 1]) = (first, first + 1);
        (area[i], area[i + 1]) = (inner_area(first), inner_area(first + 1));
        len += 1;
    }
    let mut node = Node::EMPTY;
    for (lane, &k) in kids[..len].iter().enumerate() {
        let n = bvh.nodes.get(k)?;
        let b = n.aabb();
        for axis in 0..3 {
            node.planes[axis][lane] = b.min[axis];
            node.planes[axis + 3][lane] = b.max[axis];
        }
        node.child[lane] = if n.is_leaf() {
            let count = n.prim_count;
            let first = u32::try_from(slots.len()).ok()?;
            if count > MAX_LEAF || u64::from(first) + u64::from(MAX_LEAF) > 1 << FIRST_BITS {
                return None;
            }
            let prims =
                bvh.primitive_indices.get(n.first_index as usize..(n.first_index + count) as usize)?;
            slots.extend_from_slice(prims);
            slots.resize(slots.len() + (MAX_LEAF - count) as usize, PAD);
            LEAF | (count - 1) << FIRST_BITS | first
        } else {
            convert(bvh, k, nodes, slots)?
        };
    }
    nodes[at] = node;
    u32::try_from(at).ok()
}

/// The ray as the node tests want it (from a [`BoxRay`]).
#[derive(Clone, Copy)]
struct WideRay {
    origin: [f32; 3],
    inv: [f32; 3],
    /// Row of the near and far plane per axis (by the sign of `inv`).
    near_row: [usize; 3],
    far_row: [usize; 3],
    t_min: f32,
}

impl WideRay {
    #[inline(always)]
    fn new(br: &BoxRay) -> Self {
        // Bit `a` set where `inv[a] < 0`: the max plane is then the near one.
        let neg = br.inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let neg = |a: usize| (neg >> a & 1) * 3;
        Self {
            origin: br.origin.to_array(),
            inv: br.inv.to_array(),
            near_row: [neg(0), 1 + neg(1), 2 + neg(2)],
            far_row: [3 - neg(0), 4 - neg(1), 5 - neg(2)],
            t_min: br.t_min,
        }
    }
}

/// `_mm_max_ps(a, b)` on one lane: `b` when either is `NaN`.
#[inline(always)]
pub(crate) fn max_ps(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `_mm_min_ps(a, b)` on one lane: `b` when either is `NaN`.
#[inline(always)]
pub(crate) fn min_ps(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// What a node test writes for the children the ray meets, in lane order.
struct Hits {
    /// Entry distances.
    near: [f32; WIDTH],
    /// References.
    child: [u32; WIDTH],
}

/// A node test: the entry distance of every lane, and the mask of the
/// lanes whose box the ray's `[t_min, reach]` meets.
trait NodeTest: Copy {
    fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32;

    /// Writes the lanes of `mask` to the front of `out`, in lane order;
    /// returns how many.
    #[inline(always)]
    fn compact(self, mask: u32, t_near: &[f32; WIDTH], node: &Node, out: &mut Hits) -> usize {
        compact(mask, t_near, &node.child, out)
    }
}

/// The portable node test.
#[derive(Clone, Copy)]
struct Portable;

impl NodeTest for Portable {
    #[inline(always)]
    fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        let p = &node.planes;
        let (nx, ny, nz) = (&p[r.near_row[0]], &p[r.near_row[1]], &p[r.near_row[2]]);
        let (fx, fy, fz) = (&p[r.far_row[0]], &p[r.far_row[1]], &p[r.far_row[2]]);
        let [ox, oy, oz] = r.origin;
        let [ix, iy, iz] = r.inv;
        let mut mask = 0u32;
        for k in 0..WIDTH {
            let n = max_ps((nx[k] - ox) * ix, max_ps((ny[k] - oy) * iy, max_ps((nz[k] - oz) * iz, r.t_min)));
            let f = min_ps((fx[k] - ox) * ix, min_ps((fy[k] - oy) * iy, min_ps((fz[k] - oz) * iz, reach)));
            t_near[k] = n;
            mask |= u32::from(n <= f) << k;
        }
        mask
    }
}

/// Writes the lanes set in `mask` to the front of `near`/`child`.
#[inline(always)]
fn compact(mut mask: u32, t_near: &[f32; WIDTH], lanes: &[u32; WIDTH], out: &mut Hits) -> usize {
    let mut n = 0;
    while mask != 0 {
        let k = mask.trailing_zeros() as usize & (WIDTH - 1);
        mask &= mask - 1;
        out.near[n & (WIDTH - 1)] = t_near[k];
        out.child[n & (WIDTH - 1)] = lanes[k];
        n += 1;
    }
    n
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The AVX2 and AVX-512 node tests.
    use super::{Hits, Node, NodeTest, WIDTH, WideRay};
    use core::arch::x86_64::*;

    /// The AVX2 node test. Made only inside code compiled for AVX2 that
    /// runs only where the CPU has it ([`super::WideBvh`]'s `walk_avx2`).
    #[derive(Clone, Copy)]
    pub(super) struct Avx2(());

    /// The AVX-512 node test; made only inside `walk_avx512`.
    #[derive(Clone, Copy)]
    pub(super) struct Avx512(());

    impl Avx2 {
        /// # Safety
        /// The CPU must have AVX2.
        #[inline(always)]
        pub(super) unsafe fn new() -> Self {
            Self(())
        }
    }

    impl Avx512 {
        /// # Safety
        /// The CPU must have AVX-512 F and VL (and AVX2).
        #[inline(always)]
        pub(super) unsafe fn new() -> Self {
            Self(())
        }
    }

    /// Entry and exit distances of the eight children, the lane-wise
    /// operations of [`super::Portable`] in the same order.
    ///
    /// Not a `#[target_feature]` function: such a function cannot be
    /// `#[inline(always)]`, and as a plain `#[inline]` one it was left out
    /// of line, so each node test was a call returning two `__m256`
    /// through memory, with the rows re-checked and the ray re-broadcast
    /// (perf, docs/benchmarks.md): slower than the portable kernel. As a
    /// plain `#[inline(always)]` function it is compiled into
    /// `walk_avx2`/`walk_avx512`, whose features the intrinsics inherit.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    unsafe fn distances(node: &Node, r: &WideRay, reach: f32) -> (__m256, __m256) {
        let p = &node.planes;
        let row = |i: usize| -> __m256 {
            // SAFETY: a row is eight `f32`s, 32-byte aligned (the node is
            // 64-byte aligned and each row 32 bytes long); `i < 6` is
            // checked by the indexing; the caller guarantees AVX.
            unsafe { _mm256_load_ps(p[i].as_ptr()) }
        };
        // SAFETY: the caller guarantees AVX2; the rest are
        // register operations.
        unsafe {
            let o = |a: usize| _mm256_set1_ps(r.origin[a]);
            let inv = |a: usize| _mm256_set1_ps(r.inv[a]);
            let d = |rows: &[usize; 3], a: usize| _mm256_mul_ps(_mm256_sub_ps(row(rows[a]), o(a)), inv(a));
            let near = _mm256_max_ps(
                d(&r.near_row, 0),
                _mm256_max_ps(d(&r.near_row, 1), _mm256_max_ps(d(&r.near_row, 2), _mm256_set1_ps(r.t_min))),
            );
            let far = _mm256_min_ps(
                d(&r.far_row, 0),
                _mm256_min_ps(d(&r.far_row, 1), _mm256_min_ps(d(&r.far_row, 2), _mm256_set1_ps(reach))),
            );
            (near, far)
        }
    }

    impl NodeTest for Avx2 {
        #[inline(always)]
        fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract); `t_near` holds eight
            // `f32`s (unaligned store).
            unsafe {
                let (n, f) = distances(node, r, reach);
                _mm256_storeu_ps(t_near.as_mut_ptr(), n);
                _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(n, f)) as u32
            }
        }
    }

    impl NodeTest for Avx512 {
        #[inline(always)]
        fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
            // SAFETY: an `Avx512` exists only where the CPU has AVX-512 F
            // and VL and AVX2 (its `new` is unsafe with that contract);
            // `t_near` holds eight `f32`s (unaligned store).
            unsafe {
                let (n, f) = distances(node, r, reach);
                _mm256_storeu_ps(t_near.as_mut_ptr(), n);
                u32::from(_mm256_cmp_ps_mask::<_CMP_LE_OQ>(n, f))
            }
        }

        /// The lanes of `mask` compress-stored to the front of `out`.
        #[inline(always)]
        fn compact(self, mask: u32, t_near: &[f32; WIDTH], node: &Node, out: &mut Hits) -> usize {
            let m = (mask & 0xff) as u8;
            // SAFETY: as for `test`, the token guarantees AVX-512 F and
            // VL; `t_near`, `node.child`, `out.near` and `out.child` hold
            // eight lanes each (unaligned loads); a compress-store writes
            // at most the lanes set in `m`, contiguously from the start.
            unsafe {
                let n = _mm256_loadu_ps(t_near.as_ptr());
                _mm256_mask_compressstoreu_ps(out.near.as_mut_ptr().cast(), m, n);
                let c = _mm256_loadu_si256(node.child.as_ptr().cast());
                _mm256_mask_compressstoreu_epi32(out.child.as_mut_ptr().cast(), m, c);
            }
            m.count_ones() as usize
        }
    }
}

impl WideBvh {
    /// The walk with node test `test` (see the module docs).
    #[inline(always)]
    fn walk_with<K: NodeTest, S: Stack<(u32, f32)>, V: Visit>(
        &self,
        test: K,
        stack: &mut S,
        ray: &mut BoxRay,
        mut prim: V,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let r = WideRay::new(ray);
        let mut cur = 0u32;
        loop {
            if cur & LEAF == 0 {
                let Some(node) = self.nodes.get(cur as usize) else { return };
                let mut t_near = [0.0f32; WIDTH];
                let mask = test.test(node, &r, ray.reach(), &mut t_near);
                if mask != 0 {
                    let k0 = mask.trailing_zeros() as usize & (WIDTH - 1);
                    let rest = mask & (mask - 1);
                    if rest == 0 {
                        // One child: no order to find.
                        cur = node.child[k0];
                        continue;
                    }
                    if rest & (rest - 1) == 0 {
                        // Two: the nearer first (the lower lane on a tie,
                        // as the stable sort below would).
                        let k1 = rest.trailing_zeros() as usize & (WIDTH - 1);
                        let (a, b) = if !V::ANY && t_near[k1] < t_near[k0] { (k1, k0) } else { (k0, k1) };
                        stack.push((node.child[b], t_near[b]));
                        cur = node.child[a];
                        continue;
                    }
                    let mut out = Hits { near: [0.0; WIDTH], child: [0; WIDTH] };
                    let n = test.compact(mask, &t_near, node, &mut out).min(WIDTH);
                    let Hits { near, child } = &mut out;
                    if !V::ANY {
                        sort(&mut near[..n], &mut child[..n]);
                    }
                    for k in (1..n).rev() {
                        stack.push((child[k], near[k]));
                    }
                    cur = child[0];
                    continue;
                }
            } else {
                let first = cur & ((1 << FIRST_BITS) - 1);
                let count = ((cur & !LEAF) >> FIRST_BITS) + 1;
                if !prim.visit_leaf(first, count, ray) {
                    return;
                }
            }
            loop {
                let Some((c, d)) = stack.pop() else { return };
                if d <= ray.reach() {
                    cur = c;
                    break;
                }
            }
        }
    }

    /// [`WideBvh::walk_with`] and its visitor compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must have the features enabled here.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn walk_avx2<S: Stack<(u32, f32)>, V: Visit>(&self, stack: &mut S, ray: &mut BoxRay, prim: V) {
        // SAFETY: the caller guarantees AVX2.
        let test = unsafe { x86::Avx2::new() };
        self.walk_with(test, stack, ray, prim);
    }

    /// [`WideBvh::walk_with`] and its visitor compiled for AVX-512.
    ///
    /// # Safety
    /// The CPU must have the features enabled here.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl")]
    unsafe fn walk_avx512<S: Stack<(u32, f32)>, V: Visit>(&self, stack: &mut S, ray: &mut BoxRay, prim: V) {
        // SAFETY: the caller guarantees AVX-512 F, VL and AVX2.
        let test = unsafe { x86::Avx512::new() };
        self.walk_with(test, stack, ray, prim);
    }
}

/// Sorts `near` ascending, carrying `child` along; stable (insertion sort:
/// at most eight entries, usually two or three).
#[inline(always)]
fn sort(near: &mut [f32], child: &mut [u32]) {
    for i in 1..near.len().min(child.len()) {
        let (d, c) = (near[i], child[i]);
        let mut j = i;
        while j > 0 && d < near[j - 1] {
            near[j] = near[j - 1];
            child[j] = child[j - 1];
            j -= 1;
        }
        near[j] = d;
        child[j] = c;
    }
}

impl Tree for WideBvh {
    /// A pushed child: its reference and entry distance.
    type Entry = (u32, f32);

    fn node_count(&self) -> usize {
        self.nodes.len()
    }

    fn inner_children(&self, i: usize, mut f: impl FnMut(usize)) {
        let Some(node) = self.nodes.get(i) else { return };
        for (lane, &c) in node.child.iter().enumerate() {
            if c & LEAF == 0 && node.planes[0][lane] <= node.planes[3][lane] {
                f(c as usize);
            }
        }
    }

    #[inline(always)]
    fn walk<S: Stack<(u32, f32)>>(&self, stack: &mut S, ray: &mut BoxRay, prim: impl Visit) {
        #[cfg(test)]
        WALKS[self.kernel as usize].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        match self.kernel {
            // SAFETY: `kernel` is set only through `set_kernel`, which
            // checks that the CPU has the kernel's features.
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => unsafe { self.walk_avx512(stack, ray, prim) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => unsafe { self.walk_avx2(stack, ray, prim) },
            _ => self.walk_with(Portable, stack, ray, prim),
        }
    }
}

/// What the walks assume of a converted tree, checked by the tests
/// (obvhs's own `validate` checks only its binary tree).
#[cfg(test)]
impl WideBvh {
    /// Panics unless: every node but the root is the child of exactly one
    /// lane, after its parent; a node's used lanes come first, with boxes
    /// `min <= max`, and the rest are [`Node::EMPTY`]'s; an inner node has
    /// at least two children (the root at least one); an inner lane's box
    /// holds its child's boxes; a leaf lane holds 1 to [`MAX_LEAF`]
    /// primitives in its own block of four slots, the rest of the block
    /// [`PAD`], and every block belongs to one leaf; and, where
    /// `slot_box(s)` gives slot `s`'s primitive's box, the leaf's box
    /// holds it.
    pub(crate) fn validate(&self, slot_box: impl Fn(usize) -> Option<([f32; 3], [f32; 3])>) {
        let block = MAX_LEAF as usize;
        if self.nodes.is_empty() {
            assert!(self.slots.is_empty(), "slots without nodes");
            return;
        }
        assert_eq!(self.slots.len() % block, 0, "slots in whole blocks");
        let within = |lo: [f32; 3], hi: [f32; 3], outer: ([f32; 3], [f32; 3])| {
            (0..3).all(|a| outer.0[a] <= lo[a] && hi[a] <= outer.1[a])
        };
        let lane_box = |node: &Node, lane: usize| {
            let p = &node.planes;
            ([p[0][lane], p[1][lane], p[2][lane]], [p[3][lane], p[4][lane], p[5][lane]])
        };
        // Lanes in use: those before the first unused (inverted) box.
        let used_lanes =
            |node: &Node| (0..WIDTH).take_while(|&lane| lane_box(node, lane).0[0] != f32::INFINITY).count();
        let mut node_seen = vec![false; self.nodes.len()];
        let mut block_seen = vec![false; self.slots.len() / block];
        node_seen[0] = true;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            let used = used_lanes(node);
            assert!(used >= if n == 0 { 1 } else { 2 }, "node {n}: {used} children");
            for lane in used..WIDTH {
                let (e, empty) = (lane_box(node, lane), lane_box(&Node::EMPTY, 0));
                assert!(
                    e == empty && node.child[lane] == 0,
                    "node {n} lane {lane}: a used lane after an unused one"
                );
            }
            for lane in 0..used {
                let (lo, hi) = lane_box(node, lane);
                assert!((0..3).all(|a| lo[a] <= hi[a]), "node {n} lane {lane}: box {lo:?}..{hi:?}");
                let c = node.child[lane];
                if c & LEAF != 0 {
                    let first = (c & ((1 << FIRST_BITS) - 1)) as usize;
                    let count = (((c & !LEAF) >> FIRST_BITS) + 1) as usize;
                    assert!(
                        first.is_multiple_of(block) && count <= block,
                        "node {n} lane {lane}: leaf {first}+{count}"
                    );
                    assert!(!std::mem::replace(&mut block_seen[first / block], true), "block {first} twice");
                    for s in first..first + block {
                        assert_eq!(
                            self.slots[s] == PAD,
                            s >= first + count,
                            "slot {s} of leaf {first}+{count}"
                        );
                        if let (true, Some(b)) = (s < first + count, slot_box(s)) {
                            assert!(
                                within(b.0, b.1, (lo, hi)),
                                "slot {s}'s box {b:?} outside {lo:?}..{hi:?}"
                            );
                        }
                    }
                } else {
                    let k = c as usize;
                    assert!(k > n && k < self.nodes.len(), "node {n} lane {lane}: child {k}");
                    assert!(!std::mem::replace(&mut node_seen[k], true), "node {k} has two parents");
                    let child = &self.nodes[k];
                    for l in 0..used_lanes(child) {
                        let (clo, chi) = lane_box(child, l);
                        assert!(within(clo, chi, (lo, hi)), "node {k} lane {l} outside its parent's box");
                    }
                    stack.push(k);
                }
            }
        }
        assert!(node_seen.iter().all(|&s| s), "a node no lane reaches");
        assert!(block_seen.iter().all(|&s| s), "a block no leaf holds");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_one_256_byte_block() {
        assert_eq!(std::mem::size_of::<Node>(), 256);
        assert_eq!(std::mem::align_of::<Node>(), 64);
    }

    #[test]
    fn sort_is_stable_and_ascending() {
        let mut near = [3.0, 1.0, 2.0, 1.0, 0.5];
        let mut child = [0, 1, 2, 3, 4];
        sort(&mut near, &mut child);
        assert_eq!(near, [0.5, 1.0, 1.0, 2.0, 3.0]);
        assert_eq!(child, [4, 1, 3, 2, 0]);
    }

    /// An unused (inverted) lane is never hit, for any direction sign,
    /// zero components of either sign included, and any interval.
    #[test]
    fn empty_lanes_are_never_hit() {
        let node = Node::EMPTY;
        for d in [[1.0, 1.0, 1.0], [-1.0, 0.0, -0.0], [0.0, 0.0, 1.0], [-0.0, -0.0, -2.0], [3.0, -1.0, 0.0]] {
            let ray = prism_geometry::Ray::with_interval(
                prism_geometry::glam::Vec3::new(0.5, -2.0, 7.0),
                prism_geometry::glam::Vec3::from_array(d),
                f32::MIN,
                f32::INFINITY,
            );
            let br = BoxRay::new(&ray);
            let r = WideRay::new(&br);
            let mut t_near = [0.0; WIDTH];
            assert_eq!(Portable.test(&node, &r, br.reach(), &mut t_near), 0, "{d:?}");
        }
    }
}
