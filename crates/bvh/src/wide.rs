//! A CPU-native wide BVH: eight children per node with uncompressed
//! single-precision boxes in SoA form (one 256-byte block a node),
//! converted from obvhs's binary tree by a surface-area-optimal plan
//! ([`WideBvh::from_bvh2`]), and its walk with node tests in
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
//! lane (no fused multiply-add), so they compute the same distances
//! (bit for bit, but that the AVX kernels' single-ray tests compute
//! `(origin − plane) · (−inv)`, whose zeros may carry the other sign),
//! visit the same children in the same order and return the same hits
//! (tested in the unit tests of `lib.rs` and `packet.rs` and in
//! `tests/blas_kinds.rs`).
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

use crate::traverse::{BoxRay, Stack, Tree, Visit, Walker};
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
    /// AVX-512 (F and VL) on 256-bit vectors: AVX2's node test with a
    /// mask-register comparison, in a walk compiled for AVX-512, whose 32
    /// vector registers hold the ray's broadcasts and the leaf test's
    /// values together (the AVX2 walk spills and reloads them around each
    /// leaf). The children hit are compacted by the scalar loop: AVX-512's
    /// compress-stores measured slower (docs/benchmarks.md).
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

    /// The kernel new hierarchies use: [`Kernel::Avx512`] where the CPU
    /// has it, else [`Kernel::Avx2`] where it has that, else
    /// [`Kernel::Portable`]; `PRISM_BVH_NO_SIMD` forces the
    /// portable one, and the environment variable `PRISM_BVH_KERNEL`
    /// (`portable`, `avx2`, `avx512`) names another that the CPU runs.
    /// AVX2 measured 12–26 % ahead of the portable kernel (vectorised by
    /// the compiler inside the AVX2 build; docs/benchmarks.md, "The
    /// intrinsics node tests inlined"). AVX-512 was 5–30 % behind AVX2
    /// while it compacted the children hit with compress-stores; without
    /// them it measured level to 7 % ahead of AVX2 on the single-ray sets
    /// (section "The AVX-512 walk without compress-stores").
    #[must_use]
    pub fn detect() -> Self {
        if std::env::var_os("PRISM_BVH_NO_SIMD").is_some() {
            return Self::Portable;
        }
        let named = std::env::var("PRISM_BVH_KERNEL").ok();
        let fallback =
            [Self::Avx512, Self::Avx2].into_iter().find(|k| k.supported()).unwrap_or(Self::Portable);
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
    /// Converts obvhs's binary tree with leaves of at most `max_leaf`
    /// primitives (clamped to `1..=`[`MAX_LEAF`]), laying each wide node's
    /// lanes as the surface-area plan of [`plan`] says: which descendants
    /// of a binary node fill the lanes, and which subtrees of few enough
    /// primitives become one leaf. Each leaf takes a block of four slots
    /// ([`WideBvh::slots`]). `None` if a binary leaf holds more than
    /// `max_leaf` primitives or the slots do not fit the reference's 27
    /// bits.
    pub fn from_bvh2(bvh: &Bvh2, max_leaf: u32, kernel: Kernel) -> Option<Self> {
        let mut nodes = Vec::with_capacity(bvh.nodes.len() / 4 + 1);
        let mut slots = Vec::with_capacity(bvh.primitive_indices.len() * 2);
        if !bvh.nodes.is_empty() {
            let plan = plan(bvh, max_leaf.clamp(1, MAX_LEAF))?;
            convert(bvh, &plan, 0, &mut nodes, &mut slots)?;
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
        // Boxes far from unit size are built at a power-of-two scale.
        let scale = crate::bvh2::Pow2Scale::of(&aabbs);
        let (aabbs, tris) = scale.inputs(aabbs, tris);
        let b = crate::bvh2::collapsed_tree(aabbs, tris.as_deref(), &p);
        let mut w = Self::from_bvh2(&b, p.max_prims_per_leaf, kernel)?;
        if !scale.is_one() {
            for node in &mut w.nodes {
                for v in node.planes.iter_mut().flatten() {
                    *v = scale.up(Vec3A::splat(*v)).x;
                }
            }
        }
        Some((w, b.uses_spatial_splits))
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

/// The conversion's surface-area cost model: the cost of a node test and
/// of a leaf test, per unit of half area of the box that leads to them. A
/// leaf costs the same whatever its count, its block of four triangles
/// being tested at once. The plan hardly depends on the ratio (leaves at
/// 0.5 to 4 node tests gave the same leaves, and node counts within
/// 1.2 %: docs/benchmarks.md).
const NODE_COST: f32 = 1.0;
const LEAF_COST: f32 = 1.0;

/// How the subtree of one binary node is best laid into lanes: one entry
/// of the conversion's plan ([`plan`]).
#[derive(Clone, Copy, Debug)]
struct Choice {
    /// At `i - 1`: the least cost of the subtree as at most `i` lanes.
    cost: [f32; WIDTH],
    /// At `i - 1` for `i >= 2`: the lanes of those `i` that the left child
    /// takes (the right one takes the rest), or 0 when `i - 1` lanes cost
    /// as little. At 0: the left child's lanes in the wide node made for
    /// this node (the best split of all [`WIDTH`]).
    split: [u8; WIDTH],
    /// Whether the subtree as one lane is a leaf (else a wide node).
    leaf: bool,
    /// Primitive references in the subtree (saturating).
    prims: u32,
    /// The most lanes that lower its cost: `cost[i - 1]` is the same for
    /// every `i >= used`.
    used: u8,
}

/// Plans the conversion of `bvh` into wide nodes with leaves of at most
/// `max_leaf` primitives: for every binary node and lane budget `i` in
/// `1..=WIDTH`, the cheapest way to lay its subtree into at most `i`
/// lanes of a wide node, by the dynamic programme of Ylitie, Karras and
/// Laine ("Efficient Incoherent Ray Traversal on GPUs Through Compressed
/// Wide BVHs", HPG 2017, section 3.1) under [`NODE_COST`] and
/// [`LEAF_COST`]. A subtree of few enough primitives may become one leaf,
/// and a node's lanes take whichever descendants cost least, not only the
/// widest. `None` if a binary leaf holds more than `max_leaf` primitives
/// or a child index is out of range.
fn plan(bvh: &Bvh2, max_leaf: u32) -> Option<Vec<Choice>> {
    let n = bvh.nodes.len();
    // Parents before children: breadth first from the root.
    let mut order = Vec::with_capacity(n);
    order.push(0usize);
    let mut at = 0;
    while let Some(&k) = order.get(at) {
        at += 1;
        let node = bvh.nodes.get(k)?;
        if !node.is_leaf() {
            let first = node.first_index as usize;
            if first + 1 >= n || order.len() + 2 > n {
                return None;
            }
            order.extend([first, first + 1]);
        }
    }
    let blank = Choice { cost: [0.0; WIDTH], split: [0; WIDTH], leaf: true, prims: 0, used: 1 };
    let mut plan = vec![blank; n];
    for &k in order.iter().rev() {
        let node = &bvh.nodes[k];
        let area = node.aabb().half_area();
        if node.is_leaf() {
            if node.prim_count > max_leaf {
                return None;
            }
            plan[k] = Choice { cost: [area * LEAF_COST; WIDTH], prims: node.prim_count, ..blank };
            continue;
        }
        let (l, r) = (plan[node.first_index as usize], plan[node.first_index as usize + 1]);
        // `best[j - 1]`: the cheapest split of `j >= 2` lanes between the
        // children, and the left child's share (1 if none is finite). A
        // child given more lanes than it can use (`used`) costs no less
        // than with `used`, so only shares within both children's use
        // are tried: at the bottom of the tree, where most nodes are,
        // that is one split instead of thirty-five.
        let top = (usize::from(l.used) + usize::from(r.used)).min(WIDTH);
        let mut best = [(f32::INFINITY, 1u8); WIDTH];
        for j in 2..=top {
            let b = &mut best[j - 1];
            for kl in j.saturating_sub(usize::from(r.used)).max(1)..=(j - 1).min(usize::from(l.used)) {
                let c = l.cost[kl - 1] + r.cost[j - kl - 1];
                if c < b.0 {
                    *b = (c, kl as u8);
                }
            }
        }
        let prims = l.prims.saturating_add(r.prims);
        let as_node = area * NODE_COST + best[top - 1].0;
        let as_leaf = if prims <= max_leaf { area * LEAF_COST } else { f32::INFINITY };
        let mut c = Choice { leaf: as_leaf <= as_node, prims, ..blank };
        c.cost[0] = as_leaf.min(as_node);
        c.split[0] = best[top - 1].1;
        for (i, &b) in best.iter().enumerate().skip(1) {
            (c.cost[i], c.split[i]) = if b.0 < c.cost[i - 1] {
                c.used = i as u8 + 1;
                b
            } else {
                (c.cost[i - 1], 0)
            };
        }
        plan[k] = c;
    }
    Some(plan)
}

/// The lanes of one wide node: binary node indices, and how many.
type Lanes = ([usize; WIDTH], usize);

/// Appends the subtrees that `plan` lays into at most `lanes` lanes for
/// binary node `k`; `None` (never, for a plan made by [`plan`]) if they
/// would not fit the node's lanes.
fn lay(bvh: &Bvh2, plan: &[Choice], k: usize, mut lanes: usize, out: &mut Lanes) -> Option<()> {
    let split = |lanes: usize| plan.get(k).map_or(0, |c| c.split[lanes - 1]);
    while lanes > 1 && split(lanes) == 0 {
        lanes -= 1;
    }
    if lanes > 1 {
        let first = bvh.nodes.get(k)?.first_index as usize;
        let kl = usize::from(split(lanes));
        lay(bvh, plan, first, kl, out)?;
        lay(bvh, plan, first + 1, lanes - kl, out)
    } else {
        *out.0.get_mut(out.1)? = k;
        out.1 += 1;
        Some(())
    }
}

/// Appends the wide nodes for binary node `src` and its subtree, laid out
/// as `plan` says, each node before its subtrees and those in lane order
/// (depth first), with each leaf's slots appended where the walk reaches
/// it. The walk keeps its own list of lanes to fill rather than recurse,
/// so that a tree as deep as the fan of slivers of a long comb-shaped
/// polygon (thousands of wide levels) cannot overflow a thread's stack.
fn convert(
    bvh: &Bvh2,
    plan: &[Choice],
    src: usize,
    nodes: &mut Vec<Node>,
    slots: &mut Vec<u32>,
) -> Option<()> {
    // Each entry: a binary node to lay into one lane, and the lane
    // (wide node, lane) whose child reference it fills (`None`: the root).
    let mut todo: Vec<(usize, Option<(usize, usize)>)> = vec![(src, None)];
    while let Some((k, into)) = todo.pop() {
        let reference = if into.is_some() && plan.get(k)?.leaf {
            leaf(bvh, k, slots)?
        } else {
            let at = nodes.len();
            let root = bvh.nodes.get(k)?;
            let mut lanes: Lanes = ([0; WIDTH], 0);
            if root.is_leaf() {
                lay(bvh, plan, k, 1, &mut lanes)?;
            } else {
                let kl = usize::from(plan.get(k)?.split[0]);
                lay(bvh, plan, root.first_index as usize, kl, &mut lanes)?;
                lay(bvh, plan, root.first_index as usize + 1, WIDTH - kl, &mut lanes)?;
            }
            let mut node = Node::EMPTY;
            for (lane, &c) in lanes.0[..lanes.1].iter().enumerate() {
                let b = bvh.nodes.get(c)?.aabb();
                for axis in 0..3 {
                    node.planes[axis][lane] = b.min[axis];
                    node.planes[axis + 3][lane] = b.max[axis];
                }
            }
            nodes.push(node);
            // Last lane pushed first, so the first lane's subtree is laid next.
            todo.extend(lanes.0[..lanes.1].iter().enumerate().rev().map(|(lane, &c)| (c, Some((at, lane)))));
            u32::try_from(at).ok()?
        };
        if let Some((parent, lane)) = into {
            *nodes.get_mut(parent)?.child.get_mut(lane)? = reference;
        }
    }
    Some(())
}

/// Appends one leaf's block of slots for the primitives of the subtree of
/// binary node `k` (at most [`MAX_LEAF`]), left to right and each once (a
/// pre-split build may hold one primitive in two of its leaves); returns
/// the leaf's reference.
fn leaf(bvh: &Bvh2, k: usize, slots: &mut Vec<u32>) -> Option<u32> {
    let first = slots.len();
    let reference =
        u32::try_from(first).ok().filter(|&f| u64::from(f) + u64::from(MAX_LEAF) <= 1 << FIRST_BITS)?;
    // A subtree of at most four primitives has at most four leaves, so
    // its walk holds at most four nodes at a time.
    let mut todo = [0usize; 2 * MAX_LEAF as usize];
    let mut len = 1;
    todo[0] = k;
    while len > 0 {
        len -= 1;
        let n = bvh.nodes.get(todo[len])?;
        if n.is_leaf() {
            let range = n.first_index as usize..(n.first_index + n.prim_count) as usize;
            for &p in bvh.primitive_indices.get(range)? {
                if !slots[first..].contains(&p) {
                    slots.push(p);
                }
            }
        } else {
            *todo.get_mut(len + 1)? = n.first_index as usize;
            todo[len] = n.first_index as usize + 1;
            len += 2;
        }
    }
    let count = u32::try_from(slots.len() - first).ok().filter(|c| (1..=MAX_LEAF).contains(c))?;
    slots.resize(first + MAX_LEAF as usize, PAD);
    Some(LEAF | (count - 1) << FIRST_BITS | reference)
}

/// The ray as the node tests want it (from a [`BoxRay`]).
#[derive(Clone, Copy)]
pub(crate) struct WideRay {
    pub(crate) origin: [f32; 3],
    pub(crate) inv: [f32; 3],
    /// Row of the near and far plane per axis (by the sign of `inv`).
    pub(crate) near_row: [usize; 3],
    pub(crate) far_row: [usize; 3],
    pub(crate) t_min: f32,
}

impl WideRay {
    #[inline(always)]
    pub(crate) fn new(br: &BoxRay) -> Self {
        // Bit `a` set where `inv[a] < 0`: the max plane is then the near one.
        let neg = br.inv.cmplt(Vec3A::ZERO).bitmask() as usize & 7;
        // From a table: computed per axis, the rows took more of a
        // kitchen incoherent ray's set-up than its division (callgrind).
        let (near_row, far_row) = ROWS[neg];
        Self { origin: br.origin.to_array(), inv: br.inv.to_array(), near_row, far_row, t_min: br.t_min }
    }
}

/// Per octant (bit `a` set where axis `a` runs negative): the rows of
/// [`Node::planes`] that hold each axis's near and far planes.
pub(crate) const ROWS: [([usize; 3], [usize; 3]); 8] = {
    let mut rows = [([0; 3], [0; 3]); 8];
    let mut neg = 0;
    while neg < 8 {
        let mut a = 0;
        while a < 3 {
            let flip = (neg >> a & 1) * 3;
            rows[neg].0[a] = a + flip;
            rows[neg].1[a] = a + 3 - flip;
            a += 1;
        }
        neg += 1;
    }
    rows
};

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
pub(crate) struct Hits {
    /// Entry distances.
    near: [f32; WIDTH],
    /// References.
    child: [u32; WIDTH],
}

/// A node test: the entry distance of every lane, and the mask of the
/// lanes whose box the ray's `[t_min, reach]` meets.
pub(crate) trait NodeTest: Copy {
    fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32;
}

/// The portable node test.
#[derive(Clone, Copy)]
pub(crate) struct Portable;

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
pub(crate) mod x86 {
    //! The AVX2 and AVX-512 node tests.
    use super::{Kernel, Node, NodeTest, WIDTH, WideBvh, WideRay};
    use crate::traverse::{BoxRay, Stack, Tree, Visit, Walker};
    use core::arch::x86_64::*;

    /// The AVX2 node test. Made only inside code compiled for AVX2 that
    /// runs only where the CPU has it ([`super::WideBvh`]'s `walk_avx2`).
    #[derive(Clone, Copy)]
    pub(crate) struct Avx2(());

    /// The AVX-512 node test; made only inside `walk_avx512`.
    #[derive(Clone, Copy)]
    pub(super) struct Avx512(());

    impl Avx2 {
        /// # Safety
        /// The CPU must have AVX2.
        #[inline(always)]
        pub(crate) unsafe fn new() -> Self {
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

    /// The [`Walker`] of single-ray queries compiled for AVX-512
    /// (`Accel::closest_best_avx512`, `Accel::occluded_avx512`): a wide
    /// tree whose kernel is [`super::Kernel::Avx512`] is walked by
    /// [`WideBvh::walk_with`] compiled into the caller, any other through
    /// its dispatch. Inlined there, the closest-hit walk measured 2–12 %
    /// faster than the call to `walk_avx512` (docs/benchmarks.md, "The
    /// single-ray queries compiled for AVX-512 with their walks inline").
    #[derive(Clone, Copy)]
    pub(crate) struct InAvx512(());

    impl InAvx512 {
        /// # Safety
        /// The CPU must have AVX-512 F and VL (and AVX2).
        #[inline(always)]
        pub(crate) unsafe fn new() -> Self {
            Self(())
        }
    }

    impl Walker for InAvx512 {
        #[inline(always)]
        fn walk_wide<S: Stack<(u32, f32)>>(
            self,
            tree: &WideBvh,
            stack: &mut S,
            ray: &mut BoxRay,
            prim: impl Visit,
        ) {
            if tree.kernel != Kernel::Avx512 {
                tree.walk(stack, ray, prim);
                return;
            }
            #[cfg(test)]
            super::WALKS[Kernel::Avx512 as usize].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            // SAFETY: an `InAvx512` exists only where the CPU has AVX-512
            // F and VL and AVX2 (its `new` is unsafe with that contract).
            let test = unsafe { Avx512::new() };
            tree.walk_with(test, stack, ray, prim);
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
    /// `walk_avx2`/`walk_avx512` and the packet walks' AVX2 builds (the
    /// per-ray fold, `packet::x86::Avx2`), whose features the intrinsics
    /// inherit.
    ///
    /// `FOLDED` computes each distance as `(origin − plane) · (−inv)`
    /// ([`slab`]), for a single ray's node test: the same value (rounding
    /// to nearest is symmetric, so `origin − plane` is `−(plane − origin)`
    /// but for the sign of a zero, which no comparison sees), with each
    /// plane's load folded into the subtraction, six instructions fewer a
    /// node test. A packet's per-ray tests keep `(plane − origin) · inv`:
    /// their entry bounds must equal the portable fold's bit for bit, and
    /// their planes are loaded once for all the rays.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub(crate) unsafe fn distances<const FOLDED: bool>(
        node: &Node,
        r: &WideRay,
        reach: f32,
    ) -> (__m256, __m256) {
        let p = &node.planes;
        let (n, f) = (&r.near_row, &r.far_row);
        // SAFETY: the caller guarantees AVX2 (which `slab` needs); the
        // rest are register operations.
        unsafe {
            let near = _mm256_max_ps(
                slab::<FOLDED>(p, n[0], r, 0),
                _mm256_max_ps(
                    slab::<FOLDED>(p, n[1], r, 1),
                    _mm256_max_ps(slab::<FOLDED>(p, n[2], r, 2), _mm256_set1_ps(r.t_min)),
                ),
            );
            let far = _mm256_min_ps(
                slab::<FOLDED>(p, f[0], r, 0),
                _mm256_min_ps(
                    slab::<FOLDED>(p, f[1], r, 1),
                    _mm256_min_ps(slab::<FOLDED>(p, f[2], r, 2), _mm256_set1_ps(reach)),
                ),
            );
            (near, far)
        }
    }

    /// [`distances`] with each axis's near and far planes picked by the
    /// sign of the ray's `inv` (a blend of both planes' distances), not by
    /// its rows: for a loop over rays of mixed octants (a packet's per-ray
    /// node test), where looking up and scaling each ray's six rows took
    /// 17 of the loop's 58 instructions a ray (callgrind, bunny incoherent
    /// packets). The same distances bit for bit: the sign bit of `inv` is
    /// set exactly where `inv < 0`, the octant [`WideRay::new`] picks the
    /// rows by, as `inv` is `+inf` for a zero direction component and is
    /// never `NaN` or `-0.0` for a usable ray (finite direction). A mixed
    /// packet's per-ray rows come from its octants (`Soa::oct`), which
    /// agree with those signs for the rays it walks: a ray with an
    /// infinite reciprocal (a zero or tiny direction component) has no
    /// octant (8) and walks alone (`plan`).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub(crate) unsafe fn distances_by_sign(node: &Node, r: &WideRay, reach: f32) -> (__m256, __m256) {
        let p = &node.planes;
        // SAFETY: the caller guarantees AVX2 (which `axis` needs); the
        // rest are register operations.
        unsafe {
            let ([nx, fx], [ny, fy], [nz, fz]) = (axis(p, r, 0), axis(p, r, 1), axis(p, r, 2));
            let near = _mm256_max_ps(nx, _mm256_max_ps(ny, _mm256_max_ps(nz, _mm256_set1_ps(r.t_min))));
            let far = _mm256_min_ps(fx, _mm256_min_ps(fy, _mm256_min_ps(fz, _mm256_set1_ps(reach))));
            (near, far)
        }
    }

    /// Axis `a`'s near and far distances for [`distances_by_sign`]: both
    /// planes' [`slab`]s, swapped where `inv[a]`'s sign bit is set.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn axis(p: &[[f32; WIDTH]; 6], r: &WideRay, a: usize) -> [__m256; 2] {
        // SAFETY: the caller guarantees AVX (which `slab` needs); `a + 3 <
        // 6` for the axes 0 to 2 (checked by the indexing in `slab`).
        unsafe {
            let (lo, hi) = (slab::<false>(p, a, r, a), slab::<false>(p, a + 3, r, a));
            let sign = _mm256_set1_ps(r.inv[a]);
            [_mm256_blendv_ps(lo, hi, sign), _mm256_blendv_ps(hi, lo, sign)]
        }
    }

    /// Plane row `row`'s distances along axis `a`: `(plane − origin) ·
    /// inv`, eight lanes; with `FOLDED`, `(origin − plane) · (−inv)` (see
    /// [`distances`]). A function, not a closure in [`distances`]: a
    /// closure may be compiled out of line, for the baseline target, and
    /// the intrinsics inside it then become calls (measured: shadow rays
    /// 8× slower in the AVX-512 build of `occluded`).
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn slab<const FOLDED: bool>(p: &[[f32; WIDTH]; 6], row: usize, r: &WideRay, a: usize) -> __m256 {
        // SAFETY: a row is eight `f32`s, 32-byte aligned (the node is
        // 64-byte aligned and each row 32 bytes long); `row < 6` and `a <
        // 3` are checked by the indexing; the caller guarantees AVX.
        unsafe {
            let plane = _mm256_load_ps(p[row].as_ptr());
            let (o, inv) = (_mm256_set1_ps(r.origin[a]), r.inv[a]);
            if FOLDED {
                _mm256_mul_ps(_mm256_sub_ps(o, plane), _mm256_set1_ps(-inv))
            } else {
                _mm256_mul_ps(_mm256_sub_ps(plane, o), _mm256_set1_ps(inv))
            }
        }
    }

    impl NodeTest for Avx2 {
        #[inline(always)]
        fn test(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract); `t_near` holds eight
            // `f32`s (unaligned store).
            unsafe {
                let (n, f) = distances::<true>(node, r, reach);
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
                let (n, f) = distances::<true>(node, r, reach);
                _mm256_storeu_ps(t_near.as_mut_ptr(), n);
                u32::from(_mm256_cmp_ps_mask::<_CMP_LE_OQ>(n, f))
            }
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
                    let n = compact(mask, &t_near, &node.child, &mut out).min(WIDTH);
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
    fn walk_by<S: Stack<(u32, f32)>>(
        &self,
        walker: impl Walker,
        stack: &mut S,
        ray: &mut BoxRay,
        prim: impl Visit,
    ) {
        walker.walk_wide(self, stack, ray, prim);
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

    /// Half area as obvhs computes it ([`obvhs::aabb::Aabb::half_area`]).
    fn half_area(lo: [f32; 3], hi: [f32; 3]) -> f32 {
        let d = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        (d[0] + d[1]) * d[2] + d[0] * d[1]
    }

    /// The cost of a converted tree under the conversion's model, read
    /// from its nodes alone: the root's box (its lanes' union) for a node
    /// test, then per lane its box for a node or leaf test.
    fn wide_cost(w: &WideBvh) -> f32 {
        fn lanes(n: &Node) -> impl Iterator<Item = usize> + '_ {
            (0..WIDTH).filter(move |&l| n.planes[0][l] != f32::INFINITY)
        }
        let lane_box =
            |n: &Node, l: usize| ([0, 1, 2].map(|a| n.planes[a][l]), [3, 4, 5].map(|a| n.planes[a][l]));
        let root = &w.nodes()[0];
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for l in lanes(root) {
            let (a, b) = lane_box(root, l);
            lo = [0, 1, 2].map(|i| lo[i].min(a[i]));
            hi = [0, 1, 2].map(|i| hi[i].max(b[i]));
        }
        let mut cost = half_area(lo, hi) * NODE_COST;
        for n in w.nodes() {
            for l in lanes(n) {
                let (a, b) = lane_box(n, l);
                cost += half_area(a, b) * if n.child[l] & LEAF != 0 { LEAF_COST } else { NODE_COST };
            }
        }
        cost
    }

    /// The least cost of any wide layout of `bvh`, by trying every cut of
    /// every subtree into at most eight lanes (no dynamic programme).
    fn cheapest(bvh: &Bvh2, max_leaf: u32) -> f32 {
        let node = |k: usize| &bvh.nodes[k];
        let prims = |k: usize| {
            let mut todo = vec![k];
            let mut count = 0;
            while let Some(m) = todo.pop() {
                let n = node(m);
                if n.is_leaf() {
                    count += n.prim_count;
                } else {
                    todo.extend([n.first_index as usize, n.first_index as usize + 1]);
                }
            }
            count
        };
        // Every set of disjoint subtrees covering `k`'s, of at most eight.
        fn cuts(bvh: &Bvh2, k: usize) -> Vec<Vec<usize>> {
            let mut all = vec![vec![k]];
            let n = &bvh.nodes[k];
            if !n.is_leaf() {
                let (l, r) = (cuts(bvh, n.first_index as usize), cuts(bvh, n.first_index as usize + 1));
                for a in &l {
                    for b in r.iter().filter(|b| a.len() + b.len() <= WIDTH) {
                        all.push([a.as_slice(), b.as_slice()].concat());
                    }
                }
            }
            all
        }
        // A subtree as one lane: a leaf if it may be one, else a node.
        fn lane(bvh: &Bvh2, k: usize, max_leaf: u32, prims: &dyn Fn(usize) -> u32) -> f32 {
            let n = &bvh.nodes[k];
            let area = n.aabb().half_area();
            let as_leaf = if prims(k) <= max_leaf { area * LEAF_COST } else { f32::INFINITY };
            if n.is_leaf() { as_leaf } else { as_leaf.min(as_node(bvh, k, max_leaf, prims)) }
        }
        fn as_node(bvh: &Bvh2, k: usize, max_leaf: u32, prims: &dyn Fn(usize) -> u32) -> f32 {
            let n = &bvh.nodes[k];
            let (l, r) = (cuts(bvh, n.first_index as usize), cuts(bvh, n.first_index as usize + 1));
            let mut best = f32::INFINITY;
            for a in &l {
                for b in r.iter().filter(|b| a.len() + b.len() <= WIDTH) {
                    let c: f32 = a.iter().chain(b).map(|&m| lane(bvh, m, max_leaf, prims)).sum();
                    best = best.min(c);
                }
            }
            n.aabb().half_area() * NODE_COST + best
        }
        let root = node(0);
        if root.is_leaf() {
            root.aabb().half_area() * (NODE_COST + LEAF_COST)
        } else {
            as_node(bvh, 0, max_leaf, &prims)
        }
    }

    /// On random small trees (up to 13 boxes, leaves of 1 to 4), the
    /// converted tree holds every primitive once, passes `validate`, and
    /// costs what the cheapest of all layouts costs (found by
    /// enumeration): the plan is optimal and `convert` follows it.
    #[test]
    fn the_conversion_is_the_cheapest_layout() {
        let mut rng = prism_testkit::Rng::new(0x5eed_cafe);
        let mut leaves_merged = 0;
        for case in 0..150 {
            let count = 2 + rng.below(12);
            let max_leaf = 1 + (case % 4) as u32;
            let boxes: Vec<([f32; 3], [f32; 3])> = (0..count)
                .map(|_| {
                    let c = [0; 3].map(|_| rng.range(-10.0, 10.0));
                    let h = [0; 3].map(|_| rng.range(0.0, 2.0));
                    ([0, 1, 2].map(|a| c[a] - h[a]), [0, 1, 2].map(|a| c[a] + h[a]))
                })
                .collect();
            let aabbs = boxes
                .iter()
                .map(|(lo, hi)| obvhs::aabb::Aabb::new(Vec3A::from_array(*lo), Vec3A::from_array(*hi)))
                .collect();
            let mut p = crate::BuildQuality::Medium.params();
            p.max_prims_per_leaf = max_leaf;
            let bvh = crate::bvh2::collapsed_tree(aabbs, None, &p);
            let Some(w) = WideBvh::from_bvh2(&bvh, max_leaf, Kernel::Portable) else {
                panic!("case {case}: not converted")
            };
            w.validate(|s| boxes.get(*w.slots.get(s)? as usize).copied());
            let mut held: Vec<u32> = w.slots.iter().copied().filter(|&s| s != PAD).collect();
            held.sort_unstable();
            assert_eq!(held, (0..count as u32).collect::<Vec<_>>(), "case {case}: every primitive once");
            let binary_leaves = bvh.nodes.iter().filter(|n| n.is_leaf()).count();
            leaves_merged +=
                binary_leaves - w.nodes().iter().flat_map(|n| n.child).filter(|c| c & LEAF != 0).count();
            let (got, want) = (wide_cost(&w), cheapest(&bvh, max_leaf));
            assert!((got - want).abs() <= 1e-4 * want, "case {case}: {got} against the cheapest {want}");
        }
        assert!(leaves_merged > 0, "some plan merged binary leaves into one");
    }

    /// A binary tree that is one long chain (each inner node a leaf and
    /// the rest, as a polygon's fan of slivers builds) converts into a
    /// wide tree thousands of nodes deep on a thread of a 256 KiB stack:
    /// the conversion does not recurse per level.
    #[test]
    fn a_chain_thousands_deep_converts_on_a_small_stack() {
        const N: usize = 50_000;
        let x_box = |lo: usize, hi: usize| {
            obvhs::aabb::Aabb::new(Vec3A::new(lo as f32, 0.0, 0.0), Vec3A::new(hi as f32, 1.0, 1.0))
        };
        // Node 2j (j < N - 1): the inner node over leaves j..N, children at
        // 2j + 1 (leaf j) and 2j + 2; node 2(N - 1): leaf N - 1.
        let mut nodes = Vec::with_capacity(2 * N - 1);
        for j in 0..N - 1 {
            nodes.push(obvhs::bvh2::node::Bvh2Node::new(x_box(j, N), 0, 2 * j as u32 + 1));
            nodes.push(obvhs::bvh2::node::Bvh2Node::new(x_box(j, j + 1), 1, j as u32));
        }
        nodes.push(obvhs::bvh2::node::Bvh2Node::new(x_box(N - 1, N), 1, N as u32 - 1));
        let bvh = Bvh2 { nodes, primitive_indices: (0..N as u32).collect(), ..Bvh2::default() };
        let converted = std::thread::Builder::new()
            .stack_size(256 * 1024)
            .spawn(move || WideBvh::from_bvh2(&bvh, 1, Kernel::Portable))
            .map(|t| t.join());
        let Ok(Ok(Some(w))) = converted else { panic!("not converted: {converted:?}") };
        let depth = crate::traverse::depth(&w);
        assert!(depth > N / WIDTH, "a chain {depth} deep");
        w.validate(|s| w.slots.get(s).map(|&p| ([p as f32, 0.0, 0.0], [p as f32 + 1.0, 1.0, 1.0])));
        let held: Vec<u32> = w.slots.iter().copied().filter(|&s| s != PAD).collect();
        assert_eq!(held, (0..N as u32).collect::<Vec<_>>(), "every primitive once, in order");
    }

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
