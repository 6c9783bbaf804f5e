//! Packets of coherent rays walked through a wide BVH together: camera
//! rays of neighbouring pixels, shadow rays from one point toward an area
//! light's samples.
//!
//! # How a packet walks
//!
//! The rays of one octant (every direction component of one sign, none
//! zero) are bounded by a [`Frustum`]: per axis, the interval of their
//! origins and of their direction reciprocals. A node's eight children are
//! tested once for the whole packet by interval arithmetic: a child's
//! entry distance is bounded below by the smallest of the four corner
//! products `(plane − origin) · (1/d)` over those intervals, its exit
//! distance above by the largest. Floating-point subtraction and
//! multiplication are monotone in each operand, so the bounds hold for the
//! rounded per-ray distances too: every child a ray of the packet would
//! enter on its own, the packet enters. Inner nodes are taken front to
//! back by the packet's entry bound and skipped when it exceeds the
//! farthest reach of the rays still looking.
//!
//! The frustum only prefilters. Each child it may enter is then tested
//! against the rays that reached its parent, each with its own interval
//! and by the same operations as the single-ray node test, eight rays at a
//! time (SoA); a child no ray enters is culled, and a stack entry carries
//! the rays that enter it. At a leaf those rays test the leaf's primitives,
//! each with the single-ray leaf test, or, where at least five reach a
//! leaf of four triangles, eight rays with the same permuted axes at a
//! time against one triangle ([`Lanes::occluded8`], [`Lanes::closest8`]:
//! each lane the single-ray test's operations in the same order). A ray
//! therefore tests every primitive its single-ray walk would find
//! nearest, with the same primitive test: packet and single queries
//! return the same hits (the tests compare them), whatever the packet's
//! spread. A spread-out packet costs more box tests, never a different
//! answer.
//!
//! A node that few of the packet's rays reach (at most [`PER_RAY`]: the
//! instances of a grid of objects, deep nodes of a spread-out packet) is
//! tested ray by ray instead, each with the single-ray node test, and
//! takes as entry bound the nearest of those rays' entry distances: the
//! same children and rays as the frustum and a per-child test would keep,
//! for less work where the frustum is loose over few rays.
//!
//! A packet whose rays run into [`MIXED_OCTANTS`] or more octants
//! (secondary rays from neighbouring points into their hemispheres) is not
//! split by octant: all its rays walk together, every node tested ray by
//! ray, each ray with its own octant's planes ([`Frustum::mixed`]). Split,
//! each octant's handful of rays walked the tree alone, and the rays from
//! one point, which share the nodes around it, never met at them.
//!
//! Rays that fit no frustum (a zero direction component, whose reciprocal
//! is infinite) and octants (or a mixed packet) holding fewer than
//! [`MIN_PACKET`] rays walk alone.

use crate::traverse::{BoxRay, INLINE_STACK, InlineStack, Stack, reach_of};
use crate::wide::{FIRST_BITS, LEAF, Node, NodeTest, ROWS, WIDTH, WideBvh, WideRay, max_ps, min_ps};
use prism_geometry::glam::{Vec3, Vec3A};
use prism_geometry::{Nearest8, Ray, TriangleRays8, Triangles4};

/// Most rays in one packet (bits of its masks).
pub const PACKET: usize = 64;

/// The capacity of a small packet (an area light's shadow rays): its
/// per-ray arrays are a quarter of a full packet's to set up.
pub(crate) const SMALL_PACKET: usize = 16;

/// What a packet walk calls at each leaf it reaches, with the active rays
/// that meet the leaf's box (`meet`): tests them against the leaf's
/// primitives `first..first + count`, may shrink their reach in the walk's
/// rows `soa` ([`Soa::reach_mut`], see [`narrow`]), and returns those that
/// are done (an occlusion query's occluded rays). `fr` is the walk's
/// frustum, which bounds the rays of `meet` too.
/// Named types rather than closures, so that the call is compiled into a
/// `#[target_feature]` caller (see [`crate::traverse::Visit`]).
pub(crate) trait Leaf<const N: usize> {
    fn visit(&mut self, first: u32, count: u32, meet: u64, soa: &mut Soa<N>, fr: &Frustum) -> u64;
}

/// A top-level packet walk's rays as a mesh instance placed by a
/// translation alone sees them: the walk's rows and frustum, and the
/// offset that moves them into the instance's object space
/// (`Transform::object_offset`; see [`Soa::fill_moved`] and
/// [`Frustum::moved`]).
#[derive(Clone, Copy)]
pub(crate) struct Moved<'a, const N: usize> {
    pub world: &'a Soa<N>,
    pub fr: &'a Frustum,
    pub offset: Vec3,
}

/// Where a mesh's packet walk ([`crate::blas::Blas::closest_packet`])
/// gets its rows and frustum.
#[derive(Clone, Copy)]
pub(crate) enum Rows<'a, const N: usize> {
    /// Made from the rays, which are in object space ([`Soa::fill`]), and
    /// planned by octant ([`plan`]) unless a frustum that bounds them all
    /// is given: a top-level walk's, as it stands in object space (the
    /// rays then all of one octant, or of a mixed walk, with no zero
    /// direction component).
    Made(Option<&'a Frustum>),
    /// Moved from a top-level walk's ([`Moved`]); the rays are its
    /// world-space rays.
    Moved(Moved<'a, N>),
}

impl<const N: usize> Rows<'_, N> {
    /// What moves the rays into object space, if anything.
    #[inline(always)]
    pub(crate) fn offset(&self) -> Option<Vec3> {
        match self {
            Rows::Made(_) => None,
            Rows::Moved(m) => Some(m.offset),
        }
    }

    /// Fills `soa` (just made by [`Soa::empty`] for `mask`) with the rays
    /// of `mask`; returns the frustum that bounds all of them, where there
    /// is one, else `None` (the walk then plans).
    #[inline(always)]
    pub(crate) fn fill(&self, soa: &mut Soa<N>, rays: &[Ray], mask: u64) -> Option<Frustum> {
        match *self {
            Rows::Made(fr) => {
                soa.fill(rays, mask);
                fr.copied()
            }
            Rows::Moved(Moved { world, fr, offset }) => {
                soa.fill_moved(world, offset, mask);
                Some(fr.moved(offset))
            }
        }
    }
}

/// Ray `k`'s interval now ends at `t_max`: its reach in a walk's
/// [`Soa::reach`] row, as [`BoxRay::set_t_max`] sets a single ray's.
#[inline(always)]
pub(crate) fn narrow(reach: &mut [f32], k: usize, t_max: f32) {
    if let Some(r) = reach.get_mut(k) {
        *r = reach_of(t_max);
    }
}

/// Fewer rays of one octant than this walk one by one.
pub(crate) const MIN_PACKET: u32 = 4;

/// A node that at most this many of a packet's rays reach is tested ray
/// by ray ([`Soa::per_ray`]) rather than by the frustum. 16 took the
/// fewest instructions on the 216-bunny grid's packets (2, 4, 8, 16, 32
/// and 64 measured; docs/benchmarks.md).
const PER_RAY: u32 = 16;

/// A packet whose rays run into at least this many octants walks as one
/// mixed packet ([`Frustum::mixed`]), not octant by octant. Incoherent
/// packets measured 10-22 % faster so; 2, 3 and 5 measured alike
/// (docs/benchmarks.md, "Incoherent packets walked whole").
const MIXED_OCTANTS: usize = 3;

/// [`Soa::per_ray`]'s octant parameter for "the frustum's rows, read at
/// run time" (octants are 0–7).
const FRUSTUM_ROWS: usize = 8;

/// How a packet tests one box against eight of its rays at once: the
/// single-ray node test's operations, in its order, per ray. The portable
/// loop is what the compiler makes of it: its comparisons are gathered
/// into the mask through shuffles and 64-bit ors, a tenth of a grid
/// packet's walk (perf); [`x86::Avx2`] takes one `movmskps`.
pub(crate) trait Lanes: Copy {
    /// Bit `j` set where ray `j` (origin `o[·][j]`, reciprocal
    /// `inv[·][j]`) meets the box whose near and far planes per axis are
    /// `near` and `far`, within `[t_min[j], reach[j]]`.
    fn meet8(
        self,
        near: [f32; 3],
        far: [f32; 3],
        o: [&[f32; 8]; 3],
        inv: [&[f32; 8]; 3],
        t_min: &[f32; 8],
        reach: &[f32; 8],
    ) -> u32;

    /// The single-ray node test ([`crate::wide`]'s): the mask of the
    /// children of `node` that ray `r` meets within `[r.t_min, reach]`,
    /// with every child's entry distance in `t_near`.
    fn node(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32;

    /// The rays of `rays` that meet a triangle of `tris`:
    /// [`TriangleRays8::occluded`], bit for bit.
    fn occluded8(self, rays: &TriangleRays8, tris: &Triangles4) -> u32;

    /// Each ray's nearest hit on `tris`, narrowing its interval:
    /// [`TriangleRays8::closest`], bit for bit.
    fn closest8(self, rays: &mut TriangleRays8, tris: &Triangles4) -> Nearest8;

    /// Ray `k`'s node test result merged into a per-ray node test's
    /// running state: for each child `c` in `mask`, `met[c]` gains bit `k`
    /// and `near[c]` becomes `min_ps(t_near[c], near[c])`; the other
    /// children keep theirs.
    #[inline(always)]
    fn merge(
        self,
        mask: u32,
        k: usize,
        t_near: &[f32; WIDTH],
        near: &mut [f32; WIDTH],
        met: &mut [u64; WIDTH],
    ) {
        let mut mask = mask;
        while mask != 0 {
            let c = mask.trailing_zeros() as usize & (WIDTH - 1);
            mask &= mask - 1;
            met[c] |= 1 << k;
            near[c] = min_ps(t_near[c], near[c]);
        }
    }

    /// Ray `k`'s node test folded into a per-ray node test's running
    /// state `s`: returns the mask of the children the ray meets, and
    /// leaves `s` as [`Lanes::merge`] would, the rays met read through
    /// [`Lanes::met`].
    #[inline(always)]
    fn fold(self, node: &Node, r: &WideRay, reach: f32, k: usize, s: &mut PerRay) -> u32 {
        let mut t_near = [0.0f32; WIDTH];
        let mask = self.node(node, r, reach, &mut t_near);
        self.merge(mask, k, &t_near, &mut s.near, &mut s.met);
        mask
    }

    /// [`Lanes::fold`] for a ray of a packet of mixed octants (the rows
    /// of `r` differ from ray to ray): the same answers, and kernels that
    /// can pick each axis's planes without the rows do.
    #[inline(always)]
    fn fold_mixed(self, node: &Node, r: &WideRay, reach: f32, k: usize, s: &mut PerRay) -> u32 {
        self.fold(node, r, reach, k, s)
    }

    /// The rays that meet child `c` after the rays' [`Lanes::fold`]s.
    #[inline(always)]
    fn met(self, s: &PerRay, c: usize) -> u64 {
        s.met.get(c).copied().unwrap_or(0)
    }
}

/// The running state of a per-ray node test ([`Soa::per_ray`]): per child,
/// the smallest entry distance of the rays that meet it (`near`) and
/// those rays (`met`); per ray, the children it meets (`hits`, for
/// kernels whose [`Lanes::met`] reads it instead of `met`).
pub(crate) struct PerRay {
    near: [f32; WIDTH],
    met: [u64; WIDTH],
    hits: [u8; PACKET],
}

impl PerRay {
    #[inline(always)]
    fn new() -> Self {
        Self { near: [f32::INFINITY; WIDTH], met: [0; WIDTH], hits: [0; PACKET] }
    }
}

/// The portable eight-ray box test.
#[derive(Clone, Copy)]
pub(crate) struct Portable;

impl Lanes for Portable {
    #[inline(always)]
    fn meet8(
        self,
        near: [f32; 3],
        far: [f32; 3],
        o: [&[f32; 8]; 3],
        inv: [&[f32; 8]; 3],
        t_min: &[f32; 8],
        reach: &[f32; 8],
    ) -> u32 {
        let [ox, oy, oz] = o;
        let [ix, iy, iz] = inv;
        let mut m = 0u32;
        for j in 0..8 {
            let n = max_ps(
                (near[0] - ox[j]) * ix[j],
                max_ps((near[1] - oy[j]) * iy[j], max_ps((near[2] - oz[j]) * iz[j], t_min[j])),
            );
            let f = min_ps(
                (far[0] - ox[j]) * ix[j],
                min_ps((far[1] - oy[j]) * iy[j], min_ps((far[2] - oz[j]) * iz[j], reach[j])),
            );
            m |= u32::from(n <= f) << j;
        }
        m
    }

    #[inline(always)]
    fn node(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        crate::wide::Portable.test(node, r, reach, t_near)
    }

    #[inline(always)]
    fn occluded8(self, rays: &TriangleRays8, tris: &Triangles4) -> u32 {
        rays.occluded(tris)
    }

    #[inline(always)]
    fn closest8(self, rays: &mut TriangleRays8, tris: &Triangles4) -> Nearest8 {
        rays.closest(tris)
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) mod x86 {
    //! The AVX2 eight-ray box test.
    use super::Lanes;
    use crate::wide::{Node, NodeTest, WIDTH, WideRay};
    use core::arch::x86_64::*;
    use prism_geometry::{Nearest8, TriangleRays8, Triangles4};

    /// The AVX2 eight-ray box test. Made only inside the packet queries'
    /// AVX2 builds, which run only where the CPU has it
    /// (`Accel::closest_packets_wide`/`occluded_packets_wide`).
    #[derive(Clone, Copy)]
    pub(crate) struct Avx2(());

    impl Avx2 {
        /// # Safety
        /// The CPU must have AVX2.
        #[inline(always)]
        pub(crate) unsafe fn new() -> Self {
            Self(())
        }
    }

    /// Corner `p` (on the axes `kx`, `ky`, `kz`) sheared for eight rays
    /// (`o`: their origins, `s`: their shears), as `TriangleRay::shear`
    /// does per ray. A function (always inlined), not a closure: a
    /// closure was compiled on its own without AVX, its intrinsics then
    /// calls.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn shear8(
        [px, py, pz]: [f32; 3],
        [ox, oy, oz]: [__m256; 3],
        [sx, sy, sz]: [__m256; 3],
    ) -> (__m256, __m256, __m256) {
        // SAFETY: the caller's contract.
        unsafe {
            let z = _mm256_sub_ps(_mm256_set1_ps(pz), oz);
            let x = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(px), ox), _mm256_mul_ps(sx, z));
            let y = _mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(py), oy), _mm256_mul_ps(sy, z));
            (x, y, _mm256_mul_ps(sz, z))
        }
    }

    /// One triangle's test on eight rays, [`TriangleRays8`]'s lane
    /// operations on all lanes at once, in the same order, its
    /// comparisons as their ordered (`_OQ`) forms except `det != 0`,
    /// which holds for `NaN` (`_NEQ_UQ`); `is_finite` is `|det| < inf`
    /// (ordered).
    struct Test8 {
        t: __m256,
        b1: __m256,
        b2: __m256,
        /// The lanes that meet the triangle within their interval and need
        /// not take the scalar test.
        ok: u32,
        /// The lanes with an edge function zero or subnormal, or inside
        /// the edges with a scaled `t` past the range of `f32` products:
        /// the scalar test's.
        exact: u32,
    }

    /// Triangle `j` of `tris` against the eight rays of `rays` within
    /// their current intervals; `None` when no lane of `open` passes the
    /// edge test or needs the scalar one (most of a leaf's triangles),
    /// before the division.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    unsafe fn test8(rays: &TriangleRays8, tris: &Triangles4, j: usize, open: u32) -> Option<Test8> {
        let [kx, ky, kz] = rays.axes();
        let (t_min, t_max) = rays.interval();
        // SAFETY: the caller's contract; each load reads the eight `f32`s
        // of an `&[f32; 8]` (unaligned).
        unsafe {
            let [ox, oy, oz] = rays.origin().each_ref().map(|x| _mm256_loadu_ps(x.as_ptr()));
            let [sx, sy, sz] = rays.shear().each_ref().map(|x| _mm256_loadu_ps(x.as_ptr()));
            let v = tris.rows();
            let at = |p: &[[f32; 4]; 3]| [p[kx][j & 3], p[ky][j & 3], p[kz][j & 3]];
            let (o, sh) = ([ox, oy, oz], [sx, sy, sz]);
            let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) =
                (shear8(at(&v[0]), o, sh), shear8(at(&v[1]), o, sh), shear8(at(&v[2]), o, sh));
            let u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
            let vv = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
            let w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
            let zero = _mm256_setzero_ps();
            let or3 = |a, b, c| _mm256_or_ps(_mm256_or_ps(a, b), c);
            // Zero or subnormal (`|x| < f32::MIN_POSITIVE`, ordered).
            let magnitude = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX));
            let least = _mm256_set1_ps(f32::MIN_POSITIVE);
            let tiny = |x| _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_and_ps(x, magnitude), least);
            let is0 = or3(tiny(u), tiny(vv), tiny(w));
            let negative = or3(
                _mm256_cmp_ps::<_CMP_LT_OQ>(u, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(vv, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(w, zero),
            );
            let positive = or3(
                _mm256_cmp_ps::<_CMP_GT_OQ>(u, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(vv, zero),
                _mm256_cmp_ps::<_CMP_GT_OQ>(w, zero),
            );
            let outside = _mm256_and_ps(negative, positive);
            let exact = _mm256_movemask_ps(is0) as u32;
            if (!(_mm256_movemask_ps(outside) as u32) | exact) & open == 0 {
                return None;
            }
            let det = _mm256_add_ps(_mm256_add_ps(u, vv), w);
            let t_scaled = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(u, az), _mm256_mul_ps(vv, bz)),
                _mm256_mul_ps(w, cz),
            );
            let rcp = _mm256_div_ps(_mm256_set1_ps(1.0), det);
            let t = _mm256_mul_ps(t_scaled, rcp);
            let abs = _mm256_and_ps(det, magnitude);
            let finite = _mm256_cmp_ps::<_CMP_LT_OQ>(abs, _mm256_set1_ps(f32::INFINITY));
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(t, _mm256_loadu_ps(t_min.as_ptr())),
                _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_loadu_ps(t_max.as_ptr())),
            );
            let pass = _mm256_andnot_ps(
                outside,
                _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero), finite), inside),
            );
            // A lane inside its edges whose scaled `t` is past the range of
            // `f32` products is the scalar test's too (as in `lanes`).
            let t_abs = _mm256_and_ps(t_scaled, magnitude);
            let unsure = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_NGE_UQ>(t_abs, least),
                _mm256_cmp_ps::<_CMP_NLT_UQ>(t_abs, _mm256_set1_ps(f32::INFINITY)),
            );
            let is0 = _mm256_or_ps(is0, _mm256_andnot_ps(outside, unsure));
            let exact = _mm256_movemask_ps(is0) as u32;
            let ok = _mm256_movemask_ps(_mm256_andnot_ps(is0, pass)) as u32;
            Some(Test8 { t, b1: _mm256_mul_ps(vv, rcp), b2: _mm256_mul_ps(w, rcp), ok, exact })
        }
    }

    /// `dst`'s lanes where `take` is set replaced by `src`'s. A function
    /// (always inlined), not a closure, as [`shear8`].
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[inline(always)]
    unsafe fn blend8(dst: &mut [f32; 8], src: __m256, take: __m256) {
        // SAFETY: the caller's contract; `dst` holds eight `f32`s, read
        // and written whole (unaligned).
        unsafe {
            let d = _mm256_loadu_ps(dst.as_ptr());
            _mm256_storeu_ps(dst.as_mut_ptr(), _mm256_blendv_ps(d, src, take));
        }
    }

    impl Lanes for Avx2 {
        /// [`super::Portable`]'s operations in the same order, lane-wise
        /// (`maxps`/`minps` pick as `max_ps`/`min_ps` do, and `n <= f` is
        /// the ordered compare).
        #[inline(always)]
        fn meet8(
            self,
            near: [f32; 3],
            far: [f32; 3],
            o: [&[f32; 8]; 3],
            inv: [&[f32; 8]; 3],
            t_min: &[f32; 8],
            reach: &[f32; 8],
        ) -> u32 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract); each load reads the
            // eight `f32`s of an `&[f32; 8]` (unaligned loads).
            unsafe {
                let ld = |x: &[f32; 8]| _mm256_loadu_ps(x.as_ptr());
                let d = |plane: f32, a: usize| {
                    _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(plane), ld(o[a])), ld(inv[a]))
                };
                let n = _mm256_max_ps(
                    d(near[0], 0),
                    _mm256_max_ps(d(near[1], 1), _mm256_max_ps(d(near[2], 2), ld(t_min))),
                );
                let f = _mm256_min_ps(
                    d(far[0], 0),
                    _mm256_min_ps(d(far[1], 1), _mm256_min_ps(d(far[2], 2), ld(reach))),
                );
                _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(n, f)) as u32
            }
        }

        #[inline(always)]
        fn node(self, node: &Node, r: &WideRay, reach: f32, t_near: &mut [f32; WIDTH]) -> u32 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2, which
            // is the contract of the wide node test's token.
            let test = unsafe { crate::wide::x86::Avx2::new() };
            test.test(node, r, reach, t_near)
        }

        /// [`TriangleRays8::occluded`] with each step on all eight lanes at
        /// once ([`test8`]). Lanes with an edge function zero or subnormal,
        /// or a scaled `t` past `f32`'s range, take the scalar test, as
        /// there.
        #[inline(always)]
        fn occluded8(self, rays: &TriangleRays8, tris: &Triangles4) -> u32 {
            let used = (1u32 << rays.len().min(8)) - 1;
            let mut hit = 0u32;
            for j in 0..tris.len() {
                // SAFETY: an `Avx2` exists only where the CPU has AVX2
                // (its `new` is unsafe with that contract).
                let Some(l) = (unsafe { test8(rays, tris, j, used & !hit) }) else { continue };
                hit |= l.ok;
                hit |= rays.scalar_hits(tris, j, l.exact & used & !hit);
                if hit & used == used {
                    break;
                }
            }
            hit & used
        }

        /// [`TriangleRays8::closest`] with each step on all eight lanes at
        /// once ([`test8`]): the lanes that pass take the triangle's `t`,
        /// `b1`, `b2` and narrow their `t_max` (blends), triangle by
        /// triangle in order; the lanes with an edge function zero or
        /// subnormal, or a scaled `t` past `f32`'s range, then take the
        /// scalar test, as there.
        #[inline(always)]
        fn closest8(self, rays: &mut TriangleRays8, tris: &Triangles4) -> Nearest8 {
            let used = (1u32 << rays.len().min(8)) - 1;
            let mut out = Nearest8::default();
            for j in 0..tris.len() {
                // SAFETY: an `Avx2` exists only where the CPU has AVX2
                // (its `new` is unsafe with that contract); the loads and
                // stores read and write the eight `f32`s or `u32`s of
                // `[f32; 8]`/`[u32; 8]` arrays (unaligned).
                unsafe {
                    let Some(l) = test8(rays, tris, j, used) else { continue };
                    let ok = l.ok & used;
                    if ok != 0 {
                        let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
                        let take = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                            _mm256_and_si256(_mm256_set1_epi32(ok as i32), lane_bits),
                            lane_bits,
                        ));
                        blend8(rays.t_max_mut(), l.t, take);
                        blend8(&mut out.t, l.t, take);
                        blend8(&mut out.b1, l.b1, take);
                        blend8(&mut out.b2, l.b2, take);
                        let tri = out.triangle.as_mut_ptr().cast::<__m256i>();
                        let j8 = _mm256_set1_epi32(j as i32);
                        let d = _mm256_loadu_si256(tri);
                        let picked = _mm256_blendv_epi8(d, j8, _mm256_castps_si256(take));
                        _mm256_storeu_si256(tri, picked);
                        out.lanes |= ok;
                    }
                    rays.scalar_nearest(tris, j, l.exact & used, &mut out);
                }
            }
            out
        }

        /// The node test with its fold in registers: `near` takes the
        /// entry distances of the children met by a `minps` and a blend on
        /// the comparison's lanes, and the ray's mask goes to its byte of
        /// `s.hits`, from which [`Lanes::met`] reads each child's rays
        /// once per child. (The merge that OR-ed each ray's bit into the
        /// children's 64-bit masks took about 16 instructions a ray; this
        /// fold takes 4, a mixed bunny packet 3.3 % fewer in all.) The
        /// distances and the comparison are [`crate::wide`]'s AVX2 node
        /// test's; `minps` picks as `min_ps` does.
        #[inline(always)]
        fn fold(self, node: &Node, r: &WideRay, reach: f32, k: usize, s: &mut super::PerRay) -> u32 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract).
            unsafe { fold_distances(crate::wide::x86::distances::<false>(node, r, reach), k, s) }
        }

        /// The planes picked by the sign of each ray's `inv`
        /// ([`crate::wide::x86::distances_by_sign`]), not by its rows.
        #[inline(always)]
        fn fold_mixed(self, node: &Node, r: &WideRay, reach: f32, k: usize, s: &mut super::PerRay) -> u32 {
            // SAFETY: as in `fold`.
            unsafe { fold_distances(crate::wide::x86::distances_by_sign(node, r, reach), k, s) }
        }

        /// The rays that meet child `c`: bit `c` of every ray's byte in
        /// `hits`, shifted to the byte's top bit (16-bit lanes shifted by
        /// `7 - c`: a low byte's bits move into its high neighbour's low
        /// bits only, never into its top bit) and gathered by `pmovmskb`,
        /// 32 rays at a time.
        #[inline(always)]
        fn met(self, s: &super::PerRay, c: usize) -> u64 {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 (its
            // `new` is unsafe with that contract); `hits` holds 64 bytes,
            // read as two unaligned 32-byte vectors.
            unsafe {
                let p = s.hits.as_ptr().cast::<__m256i>();
                let (lo, hi) = (_mm256_loadu_si256(p), _mm256_loadu_si256(p.add(1)));
                let shift = _mm_cvtsi32_si128(7 - (c & (WIDTH - 1)) as i32);
                let l = _mm256_movemask_epi8(_mm256_sll_epi16(lo, shift)) as u32;
                let h = _mm256_movemask_epi8(_mm256_sll_epi16(hi, shift)) as u32;
                u64::from(l) | u64::from(h) << 32
            }
        }
    }

    /// A ray's fold from its node distances `(n, f)`: each child's entry
    /// bound lowered to `n` where the ray meets the child (a `minps` and a
    /// blend on the comparison's lanes), and the ray's child mask kept as
    /// its byte of `s.hits` and returned.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    unsafe fn fold_distances((n, f): (__m256, __m256), k: usize, s: &mut super::PerRay) -> u32 {
        // SAFETY: the caller guarantees AVX2; `s.near` holds eight `f32`s,
        // read and written whole (unaligned).
        unsafe {
            let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(n, f);
            let near = _mm256_loadu_ps(s.near.as_ptr());
            _mm256_storeu_ps(s.near.as_mut_ptr(), _mm256_blendv_ps(near, _mm256_min_ps(n, near), hit));
            let mask = _mm256_movemask_ps(hit) as u32;
            if let Some(h) = s.hits.get_mut(k) {
                *h = mask as u8;
            }
            mask
        }
    }
}

/// The rays of `mask`, lowest first.
#[inline(always)]
pub(crate) fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            k
        })
    })
}

/// The rays of `mask` by octant (entries 0–7, bit `a` of the index set when
/// axis `a` runs negative), and in entry 8 those with a zero direction
/// component (an infinite reciprocal), which fit no frustum. The reference
/// that [`plan`]'s one pass is tested against.
#[cfg(test)]
pub(crate) fn octants(br: &[BoxRay], mask: u64) -> [u64; 9] {
    let mut groups = [0u64; 9];
    for k in bits(mask) {
        let Some(b) = br.get(k) else { continue };
        // Bit `a` set when axis `a` runs negative; no frustum for an
        // infinite reciprocal.
        let o = if b.inv.is_finite() { b.inv.cmplt(Vec3A::ZERO).bitmask() as usize & 7 } else { 8 };
        groups[o] |= 1 << k;
    }
    groups
}

/// How the rays of `mask` walk: per octant, the rays and, when there are
/// at least [`MIN_PACKET`] of them, their frustum (`None`: one by one);
/// or, when they run into [`MIXED_OCTANTS`] or more octants, all of them
/// in entry 0 with [`Frustum::mixed`] (entry 8, as always, holding those
/// with a zero direction component, which walk alone). The octants are
/// the ones [`Soa::fill`] made; `octants` (a test-only reference from the
/// box rays) and `Frustum::new` are what the tests compare this with.
///
/// Compiled into each caller (`inline(always)`): as a function of its own
/// it was built without the packet queries' AVX2, and its one pass took
/// 4-9 % of a kitchen primary-packet run (perf).
#[inline(always)]
pub(crate) fn plan<const N: usize>(soa: &Soa<N>, mask: u64) -> [(u64, Option<Frustum>); 9] {
    let mut groups = [0u64; 9];
    let first = soa.oct.get(mask.trailing_zeros() as usize).copied().unwrap_or(8);
    if soa.all_in(mask, first) {
        // Most packets: one octant, found eight lanes at a time.
        groups[usize::from(first).min(8)] = mask;
    } else {
        for k in bits(mask) {
            if let Some(&o) = soa.oct.get(k) {
                groups[usize::from(o).min(8)] |= 1 << k;
            }
        }
    }
    let mut out = [(0u64, None); 9];
    let spread = groups[..8].iter().filter(|&&m| m != 0).count();
    if spread >= MIXED_OCTANTS {
        let all = mask & !groups[8];
        out[0] = (all, (all.count_ones() >= MIN_PACKET).then(Frustum::mixed));
        out[8] = (groups[8], None);
        return out;
    }
    // A loop, not `std::array::from_fn`: its closure was left out of line
    // in some builds of the packet walks (callgrind).
    for (o, (slot, &m)) in out.iter_mut().zip(&groups).enumerate() {
        *slot = if o == 8 || m.count_ones() < MIN_PACKET {
            (m, None)
        } else {
            (m, Some(soa.frustum(o as u32, m)))
        };
    }
    out
}

/// The octant of a ray (bit `a` set when axis `a` runs negative), 8 for a
/// ray with a zero direction component (see `octants`).
#[inline(always)]
fn octant(b: &BoxRay) -> usize {
    if b.inv.is_finite() { b.inv.cmplt(Vec3A::ZERO).bitmask() as usize & 7 } else { 8 }
}

/// Bounds of a packet's rays, all of one octant with finite reciprocals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frustum {
    o_lo: [f32; 3],
    o_hi: [f32; 3],
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    /// Rows of the near and far planes per axis (as [`crate::wide`]'s).
    near_row: [usize; 3],
    far_row: [usize; 3],
    /// The smallest `t_min`.
    t_min: f32,
    /// Every ray starts at the same point (a pinhole camera's rays, shadow
    /// rays from one shading point): two corner products instead of four.
    same_origin: bool,
    /// Rays of several octants walked together, every node tested ray by
    /// ray with each ray's own rows (the bounds and rows here unused).
    mixed: bool,
}

impl Frustum {
    /// Over the rays of `mask`, which `octants` puts in one octant: the
    /// reference that [`Soa::frustum`] is tested against.
    #[cfg(test)]
    pub fn new(br: &[BoxRay], mask: u64) -> Option<Self> {
        let first = br.get(mask.trailing_zeros() as usize)?.inv;
        let signs = first.cmplt(Vec3A::ZERO).bitmask();
        // Per-axis bounds as vectors: the same values as per-lane `min`
        // and `max`, as nothing here is `NaN` (finite, checked below).
        let (mut o_lo, mut o_hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let (mut inv_lo, mut inv_hi) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let mut t_min = f32::INFINITY;
        for k in bits(mask) {
            let b = br.get(k)?;
            if !b.inv.is_finite() || b.inv.cmplt(Vec3A::ZERO).bitmask() != signs {
                return None;
            }
            o_lo = o_lo.min(b.origin);
            o_hi = o_hi.max(b.origin);
            inv_lo = inv_lo.min(b.inv);
            inv_hi = inv_hi.max(b.inv);
            t_min = t_min.min(b.t_min);
        }
        Some(Self::from_bounds(signs, [o_lo, o_hi], [inv_lo, inv_hi], t_min))
    }

    /// For the rays of a packet that run into several octants, walked
    /// together: every node is tested ray by ray ([`Soa::per_ray`]) with
    /// each ray's own rows, so nothing of the frustum is read; its bounds
    /// are left empty (inverted, infinite), bounding no ray.
    #[inline(always)]
    fn mixed() -> Self {
        let none = [Vec3A::INFINITY, Vec3A::NEG_INFINITY];
        Self { mixed: true, ..Self::from_bounds(0, none, none, f32::INFINITY) }
    }

    /// The octant of the frustum's rays (bit `a` set where axis `a` runs
    /// negative), from its near rows: [`ROWS`] puts axis `a`'s near plane
    /// in row `a + 3` exactly there. (Read from the rows rather than kept
    /// as a field: a build with the field ran camera packets 2–3 % slower
    /// than one without, in one alternating run.)
    #[inline(always)]
    fn octant(&self) -> usize {
        self.near_row.iter().enumerate().fold(0, |o, (a, &row)| o | usize::from(row >= 3) << a)
    }

    /// This frustum for its rays moved by `offset` as [`Soa::fill_moved`]
    /// moves them: the origins' bounds moved (rounding is monotone, so each
    /// moved origin stays within them), the rest as it is.
    #[inline(always)]
    pub(crate) fn moved(&self, offset: Vec3) -> Self {
        if self.mixed {
            return *self;
        }
        let off = offset.to_array();
        let o_lo: [f32; 3] = std::array::from_fn(|a| self.o_lo[a] + off[a]);
        let o_hi: [f32; 3] = std::array::from_fn(|a| self.o_hi[a] + off[a]);
        Self { o_lo, o_hi, same_origin: o_lo == o_hi, ..*self }
    }

    /// From the bounds of rays of the octant `signs` (bit `a` set when
    /// axis `a` runs negative): their origins, reciprocals and smallest
    /// `t_min`.
    #[inline(always)]
    fn from_bounds(signs: u32, origin: [Vec3A; 2], inv: [Vec3A; 2], t_min: f32) -> Self {
        let (near_row, far_row) = ROWS[signs as usize & 7];
        let (o_lo, o_hi) = (origin[0].to_array(), origin[1].to_array());
        Self {
            o_lo,
            o_hi,
            inv_lo: inv[0].to_array(),
            inv_hi: inv[1].to_array(),
            near_row,
            far_row,
            t_min,
            same_origin: o_lo == o_hi,
            mixed: false,
        }
    }

    /// Writes the children the packet may enter before `reach` (entry
    /// bound, reference, lane) to the front of `out`; returns how many.
    #[inline(always)]
    fn hits(&self, node: &Node, reach: f32, out: &mut Hits) -> usize {
        if self.same_origin {
            self.hits_in::<true>(node, reach, out)
        } else {
            self.hits_in::<false>(node, reach, out)
        }
    }

    #[inline(always)]
    fn hits_in<const SAME_ORIGIN: bool>(&self, node: &Node, reach: f32, out: &mut Hits) -> usize {
        let p = &node.planes;
        let mut near = [0.0f32; WIDTH];
        let mut mask = 0u32;
        for (k, near_k) in near.iter_mut().enumerate() {
            let (mut n, mut f) = (self.t_min, reach);
            for a in 0..3 {
                let (lo, hi) = (self.inv_lo[a], self.inv_hi[a]);
                let d_hi = p[self.near_row[a]][k] - self.o_lo[a];
                let e_hi = p[self.far_row[a]][k] - self.o_lo[a];
                let (low, high) = if SAME_ORIGIN {
                    (min_ps(d_hi * lo, d_hi * hi), max_ps(e_hi * lo, e_hi * hi))
                } else {
                    let d_lo = p[self.near_row[a]][k] - self.o_hi[a];
                    let e_lo = p[self.far_row[a]][k] - self.o_hi[a];
                    (
                        min_ps(min_ps(d_lo * lo, d_lo * hi), min_ps(d_hi * lo, d_hi * hi)),
                        max_ps(max_ps(e_lo * lo, e_lo * hi), max_ps(e_hi * lo, e_hi * hi)),
                    )
                };
                n = max_ps(low, n);
                f = min_ps(high, f);
            }
            *near_k = n;
            mask |= u32::from(n <= f) << k;
        }
        let mut count = 0;
        while mask != 0 {
            let k = mask.trailing_zeros() as usize & (WIDTH - 1);
            mask &= mask - 1;
            let c = count & (WIDTH - 1);
            out.near[c] = near[k];
            out.child[c] = node.child[k];
            out.lane[c] = k as u8;
            count += 1;
        }
        count
    }
}

/// A node test's result for a packet.
struct Hits {
    near: [f32; WIDTH],
    child: [u32; WIDTH],
    lane: [u8; WIDTH],
    /// The rays that meet each child on their own.
    rays: [u64; WIDTH],
}

/// A packet's rays as its walks read them, in SoA rows (lane `k` ray
/// `k`), so that a box is tested against eight of them at a time: what
/// [`BoxRay::new`] makes of each ray, and its octant. Made from the rays
/// eight at a time ([`Soa::fill`]); one packet's walks (one per octant, see
/// [`plan`]) share it, each testing only its own rays (its farthest reach
/// is taken over every lane: see `max_reach`).
pub(crate) struct Soa<const N: usize> {
    origin: [[f32; N]; 3],
    inv: [[f32; N]; 3],
    t_min: [f32; N],
    /// `-inf` for a ray not (or no longer) in the walk.
    reach: [f32; N],
    /// Lanes to test: the highest ray's, rounded up to eight.
    len: usize,
    /// Each ray's octant (bit `a` set when axis `a` runs negative), 8 for
    /// a ray with a zero direction component (see `octants`); the rows of
    /// a [`Frustum::mixed`] walk.
    oct: [u8; N],
}

impl<const N: usize> Soa<N> {
    /// Makes the rays of `mask` among `rays` (ray `k` from `rays[k]`, as
    /// many as both hold, at most `N`). The other lanes meet nothing (reach
    /// `-inf`). Whole blocks of eight rays are made at once, by selects and
    /// vector divisions that the packet queries' AVX2 builds run eight
    /// lanes wide: the same values as [`BoxRay::new`] per ray, bit for
    /// bit (a test compares them). Made ray by ray into an array of box
    /// rays and then copied into rows, a packet's set-up took about a sixth
    /// of a kitchen packet query (docs/benchmarks.md).
    ///
    /// In two steps, [`Soa::empty`] and then this, so that the rows are
    /// made where they stay: made in one and returned, they were copied
    /// (a `memcpy` of 2 KB a packet).
    #[inline(always)]
    pub(crate) fn fill(&mut self, rays: &[Ray], mask: u64) {
        for c in 0..N / 8 {
            let live = (mask >> (8 * c)) as u8;
            if live == 0 {
                continue;
            }
            let base = 8 * c;
            match rays.get(base..base + 8) {
                Some(block) => self.set8(block, base, live),
                None => {
                    for k in bits(u64::from(live) << base) {
                        if let Some(r) = rays.get(k) {
                            self.set1(k, &BoxRay::new(r));
                        }
                    }
                }
            }
        }
    }

    /// No ray yet (every lane meets nothing), with lanes for the rays of
    /// `mask`: see [`Soa::fill`].
    #[inline(always)]
    pub(crate) fn empty(mask: u64) -> Self {
        Self {
            origin: [[0.0; N]; 3],
            inv: [[1.0; N]; 3],
            t_min: [f32::INFINITY; N],
            reach: [f32::NEG_INFINITY; N],
            len: ((64 - mask.leading_zeros() as usize).div_ceil(8) * 8).min(N),
            oct: [8; N],
        }
    }

    /// [`Soa::empty`] and [`Soa::fill`] at once.
    #[cfg(test)]
    fn new(rays: &[Ray], mask: u64) -> Self {
        let mut s = Self::empty(mask);
        s.fill(rays, mask);
        s
    }

    /// The rays of `mask` in `world`'s rows, moved into the object space
    /// of an instance placed by a translation alone: their origins plus
    /// `offset` ([`Transform::object_offset`]), the rest as they are (a
    /// translation keeps each direction, so its reciprocals and octant).
    /// Lane for lane what [`Soa::fill`] makes of the rays that
    /// [`Transform::ray_to_object`] gives (a test compares them), with
    /// each ray's reach as narrowed so far; the other lanes of their
    /// eights meet nothing. After [`Soa::empty`] with the same mask.
    ///
    /// [`Transform::object_offset`]: prism_geometry::Transform::object_offset
    /// [`Transform::ray_to_object`]: prism_geometry::Transform::ray_to_object
    #[inline(always)]
    pub(crate) fn fill_moved(&mut self, world: &Soa<N>, offset: Vec3, mask: u64) {
        let offset = offset.to_array();
        for c in 0..N / 8 {
            let live = (mask >> (8 * c)) as u8;
            if live == 0 {
                continue;
            }
            let lanes = 8 * c..8 * c + 8;
            for (a, off) in offset.into_iter().enumerate() {
                if let (Some(x), Some(w), Some(y), Some(v)) = (
                    self.origin[a].get_mut(lanes.clone()),
                    world.origin[a].get(lanes.clone()),
                    self.inv[a].get_mut(lanes.clone()),
                    world.inv[a].get(lanes.clone()),
                ) {
                    for (x, &w) in x.iter_mut().zip(w) {
                        *x = w + off;
                    }
                    y.copy_from_slice(v);
                }
            }
            if let (Some(t), Some(wt), Some(r), Some(wr), Some(o), Some(wo)) = (
                self.t_min.get_mut(lanes.clone()),
                world.t_min.get(lanes.clone()),
                self.reach.get_mut(lanes.clone()),
                world.reach.get(lanes.clone()),
                self.oct.get_mut(lanes.clone()),
                world.oct.get(lanes),
            ) {
                t.copy_from_slice(wt);
                r.copy_from_slice(wr);
                o.copy_from_slice(wo);
            }
            for k in bits(u64::from(!live) << (8 * c)) {
                if let (Some(r), Some(o)) = (self.reach.get_mut(k), self.oct.get_mut(k)) {
                    (*r, *o) = (f32::NEG_INFINITY, 8);
                }
            }
        }
    }

    /// The reach row, which leaves narrow ([`narrow`]).
    #[inline(always)]
    pub(crate) fn reach_mut(&mut self) -> &mut [f32; N] {
        &mut self.reach
    }

    /// Lanes `base..base + 8` from `block`, those of `live` (bit `i`:
    /// lane `base + i`); the others keep their nothing-meeting values.
    #[inline(always)]
    fn set8(&mut self, block: &[Ray], base: usize, live: u8) {
        let mut o = [[0.0f32; 8]; 3];
        let mut d = [[0.0f32; 8]; 3];
        let (mut t0, mut t1) = ([0.0f32; 8], [0.0f32; 8]);
        for (i, r) in block.iter().take(8).enumerate() {
            let (ro, rd) = (r.origin.to_array(), r.dir.to_array());
            for a in 0..3 {
                o[a][i] = ro[a];
                d[a][i] = rd[a];
            }
            (t0[i], t1[i]) = (r.t_min, r.t_max);
        }
        // As `BoxRay::new`: `1/d`, `+inf` for either zero.
        let inv: [[f32; 8]; 3] = std::array::from_fn(|a| {
            std::array::from_fn(|i| if d[a][i] == 0.0 { f32::INFINITY } else { 1.0 / d[a][i] })
        });
        // The octant, 8 where it fits no frustum. Every lane is made, then
        // the lanes not in `live` are put out of the walk: selects per lane
        // on the bits of `live` compiled to a branch and a scalar store
        // each.
        let oct: [u8; 8] = std::array::from_fn(|i| {
            let finite = inv[0][i].is_finite() & inv[1][i].is_finite() & inv[2][i].is_finite();
            let neg =
                u8::from(inv[0][i] < 0.0) | u8::from(inv[1][i] < 0.0) << 1 | u8::from(inv[2][i] < 0.0) << 2;
            if finite { neg } else { 8 }
        });
        let reach: [f32; 8] = std::array::from_fn(|i| reach_of(t1[i]));
        let lanes = base..base + 8;
        // The rows as slices, indexed: zipped row iterators compiled to
        // 1-11 % more instructions in the packet queries (callgrind).
        let (Some(o_rows), Some(inv_rows)) = (self.origin.get_mut(0..3), self.inv.get_mut(0..3)) else {
            return;
        };
        for a in 0..3 {
            if let (Some(x), Some(y)) = (o_rows[a].get_mut(lanes.clone()), inv_rows[a].get_mut(lanes.clone()))
            {
                x.copy_from_slice(&o[a]);
                y.copy_from_slice(&inv[a]);
            }
        }
        if let (Some(t), Some(r), Some(c)) =
            (self.t_min.get_mut(lanes.clone()), self.reach.get_mut(lanes.clone()), self.oct.get_mut(lanes))
        {
            t.copy_from_slice(&t0);
            r.copy_from_slice(&reach);
            c.copy_from_slice(&oct);
        }
        for k in bits(u64::from(!live) << base) {
            if let (Some(r), Some(c)) = (self.reach.get_mut(k), self.oct.get_mut(k)) {
                (*r, *c) = (f32::NEG_INFINITY, 8);
            }
        }
    }

    /// Lane `k` from the box ray `b` (a packet's last, partial block).
    #[inline(always)]
    fn set1(&mut self, k: usize, b: &BoxRay) {
        if k >= N {
            return;
        }
        let (o, inv) = (b.origin.to_array(), b.inv.to_array());
        for a in 0..3 {
            self.origin[a][k] = o[a];
            self.inv[a][k] = inv[a];
        }
        self.t_min[k] = b.t_min;
        self.reach[k] = b.reach();
        self.oct[k] = octant(b) as u8;
    }

    /// Whether every ray of `mask` has the octant code `oct`: eight lanes'
    /// codes at a time, as the bytes of a word. (Sorted into groups ray by
    /// ray, each step waited for the last one's store.)
    #[inline(always)]
    fn all_in(&self, mask: u64, oct: u8) -> bool {
        let pattern = u64::from(oct) * 0x0101_0101_0101_0101;
        for c in 0..N / 8 {
            let live = (mask >> (8 * c)) as u8;
            if live == 0 {
                continue;
            }
            let Some(codes) = self.oct.get(8 * c..).and_then(<[u8]>::first_chunk::<8>) else { return false };
            let lanes = if live == 0xff {
                u64::MAX
            } else {
                u64::from_le_bytes(std::array::from_fn(|i| if live >> i & 1 == 1 { 0xff } else { 0 }))
            };
            if (u64::from_le_bytes(*codes) ^ pattern) & lanes != 0 {
                return false;
            }
        }
        true
    }

    /// Ray `k`'s box ray as it stands (its reach narrowed by any hit so
    /// far), for a ray that walks alone.
    #[inline(always)]
    pub(crate) fn box_ray(&self, k: usize) -> BoxRay {
        let k = k.min(N - 1);
        BoxRay::from_parts(
            Vec3A::new(self.origin[0][k], self.origin[1][k], self.origin[2][k]),
            Vec3A::new(self.inv[0][k], self.inv[1][k], self.inv[2][k]),
            self.t_min[k],
            self.reach[k],
        )
    }

    /// The frustum of the rays of `m`, all of the octant `signs` (as
    /// [`plan`] groups them): their bounds taken eight lanes at a time.
    /// Through `<[_; 3]>::map`, whose closures the compiler leaves out of
    /// line: the six calls written out (inlined) made kitchen shadow
    /// packets 8 % slower, and this function out of line (`inline(never)`)
    /// 20 % (docs/benchmarks.md).
    #[inline(always)]
    fn frustum(&self, signs: u32, m: u64) -> Frustum {
        let [(ox_lo, ox_hi), (oy_lo, oy_hi), (oz_lo, oz_hi)] = self.origin.each_ref().map(|r| bounds(r, m));
        let [(ix_lo, ix_hi), (iy_lo, iy_hi), (iz_lo, iz_hi)] = self.inv.each_ref().map(|r| bounds(r, m));
        Frustum::from_bounds(
            signs,
            [Vec3A::new(ox_lo, oy_lo, oz_lo), Vec3A::new(ox_hi, oy_hi, oz_hi)],
            [Vec3A::new(ix_lo, iy_lo, iz_lo), Vec3A::new(ix_hi, iy_hi, iz_hi)],
            bounds(&self.t_min, m).0,
        )
    }

    /// The rays that meet lane `lane` of `node` within their own `[t_min,
    /// reach]`, by the single-ray node test, eight rays at a time; only
    /// the eights holding a ray of `want` are tested (the others' bits are
    /// left clear). Skipping the rest measured +22 % on primary and +40 %
    /// on shadow packets over the 216-bunny grid, whose instance leaves see
    /// few rays of a packet.
    #[inline(always)]
    fn meet(&self, lanes: impl Lanes, fr: &Frustum, node: &Node, lane: usize, want: u64) -> u64 {
        let p = &node.planes;
        let l = lane & (WIDTH - 1);
        let (nr, fr) = (fr.near_row, fr.far_row);
        let near = [p[nr[0]][l], p[nr[1]][l], p[nr[2]][l]];
        let far = [p[fr[0]][l], p[fr[1]][l], p[fr[2]][l]];
        /// The `c`th eight lanes of `x`.
        #[inline(always)]
        fn eight<const N: usize>(x: &[f32; N], c: usize) -> Option<&[f32; 8]> {
            x.get(c * 8..)?.first_chunk()
        }
        let mut mask = 0u64;
        let groups = (self.len / 8).min(N / 8);
        // Only the eights holding a ray of `want`, found from its set
        // bits: a loop over every eight that skipped the empty ones spent
        // a fifth of a grid shadow packet's instructions on the loop and
        // the test (callgrind).
        let mut w = want;
        while w != 0 {
            let c = w.trailing_zeros() as usize / 8;
            if c >= groups {
                break;
            }
            w &= !(0xFFu64 << (c * 8));
            let [ox, oy, oz] = &self.origin;
            let [ix, iy, iz] = &self.inv;
            let (Some(ox), Some(oy), Some(oz), Some(ix), Some(iy), Some(iz), Some(t_min), Some(reach)) = (
                eight(ox, c),
                eight(oy, c),
                eight(oz, c),
                eight(ix, c),
                eight(iy, c),
                eight(iz, c),
                eight(&self.t_min, c),
                eight(&self.reach, c),
            ) else {
                break;
            };
            let m = lanes.meet8(near, far, [ox, oy, oz], [ix, iy, iz], t_min, reach);
            mask |= u64::from(m) << (c * 8);
        }
        mask
    }

    /// The children of `node` that the rays of `want` meet, each ray by
    /// the single-ray node test, written to the front of `out` in lane
    /// order with the rays that meet them and, as entry bound, the
    /// smallest of those rays' entry distances; returns how many. For a
    /// node that few rays reach, this costs less than the frustum's test
    /// and a [`Soa::meet`] per child it lets through.
    ///
    /// With `PER_OCTANT` (the occlusion walks), a packet of one octant
    /// takes a copy of the loop compiled for that octant, which reads the
    /// rows as constants: no index checks or row addresses made per call
    /// (about 30 instructions a call when read from the frustum). Grid
    /// shadow packets run 7.8 % fewer instructions so, the bunny's 4.7 %
    /// (callgrind). The closest-hit walks keep one copy: a build with the
    /// copies in every walk (and the octant kept in the frustum) ran camera
    /// packets 2–6 % slower, not measured apart (docs/benchmarks.md).
    #[inline(always)]
    fn per_ray<const PER_OCTANT: bool>(
        &self,
        lanes: impl Lanes,
        fr: &Frustum,
        node: &Node,
        want: u64,
        out: &mut Hits,
    ) -> usize {
        // The rows' choice out of the loop over the rays.
        if fr.mixed {
            return self.per_ray_in::<true, FRUSTUM_ROWS>(lanes, fr, node, want, out);
        }
        if !PER_OCTANT {
            return self.per_ray_in::<false, FRUSTUM_ROWS>(lanes, fr, node, want, out);
        }
        match fr.octant() {
            0 => self.per_ray_in::<false, 0>(lanes, fr, node, want, out),
            1 => self.per_ray_in::<false, 1>(lanes, fr, node, want, out),
            2 => self.per_ray_in::<false, 2>(lanes, fr, node, want, out),
            3 => self.per_ray_in::<false, 3>(lanes, fr, node, want, out),
            4 => self.per_ray_in::<false, 4>(lanes, fr, node, want, out),
            5 => self.per_ray_in::<false, 5>(lanes, fr, node, want, out),
            6 => self.per_ray_in::<false, 6>(lanes, fr, node, want, out),
            _ => self.per_ray_in::<false, 7>(lanes, fr, node, want, out),
        }
    }

    /// [`Soa::per_ray`], each ray with its own rows where `MIXED`, else
    /// with octant `OCT`'s rows (the frustum's octant), or the frustum's
    /// rows read at run time where `OCT` is [`FRUSTUM_ROWS`].
    #[inline(always)]
    fn per_ray_in<const MIXED: bool, const OCT: usize>(
        &self,
        lanes: impl Lanes,
        fr: &Frustum,
        node: &Node,
        want: u64,
        out: &mut Hits,
    ) -> usize {
        let mut s = PerRay::new();
        let mut any = 0u32;
        for k in bits(want) {
            if k >= N {
                break;
            }
            let (near_row, far_row) = if MIXED {
                ROWS[usize::from(self.oct[k]) & 7]
            } else if OCT < FRUSTUM_ROWS {
                ROWS[OCT]
            } else {
                (fr.near_row, fr.far_row)
            };
            let r = WideRay {
                origin: [self.origin[0][k], self.origin[1][k], self.origin[2][k]],
                inv: [self.inv[0][k], self.inv[1][k], self.inv[2][k]],
                near_row,
                far_row,
                t_min: self.t_min[k],
            };
            any |= if MIXED {
                lanes.fold_mixed(node, &r, self.reach[k], k, &mut s)
            } else {
                lanes.fold(node, &r, self.reach[k], k, &mut s)
            };
        }
        let mut count = 0;
        while any != 0 {
            let c = any.trailing_zeros() as usize & (WIDTH - 1);
            any &= any - 1;
            let j = count & (WIDTH - 1);
            out.near[j] = s.near[c];
            out.child[j] = node.child[c];
            out.rays[j] = lanes.met(&s, c);
            count += 1;
        }
        count
    }

    /// The farthest reach of the rays in the walk: eight running maxima,
    /// one per lane of an eight-ray group, then combined. A fold over the
    /// rays one by one compiled to a chain of scalar `maxss`, a twentieth
    /// of a grid packet's time (perf); this form compiles to whole-vector
    /// `maxps`. Either way the result is the largest reach: `max_ps` keeps
    /// its second operand when the first is `NaN`, so a `NaN` never enters
    /// a maximum, and the order of the others changes nothing. Every lane
    /// counts: in a packet walked octant by octant, another octant's rays
    /// (walked apart) widen the bound, which costs box tests, never an
    /// answer (such packets are few: camera rays across the middle of the
    /// image, where a direction component changes sign).
    #[inline(always)]
    fn max_reach(&self) -> f32 {
        let mut m = [f32::NEG_INFINITY; 8];
        for group in self.reach[..self.len.min(N)].chunks_exact(8) {
            let Some(x) = group.first_chunk::<8>() else { continue };
            m = std::array::from_fn(|j| max_ps(x[j], m[j]));
        }
        let m: [f32; 4] = std::array::from_fn(|j| max_ps(m[j], m[j + 4]));
        max_ps(max_ps(m[0], m[2]), max_ps(m[1], m[3]))
    }
}

/// The lanes of `live` of eight, the others replaced by `+inf` (first)
/// and by `-inf` (second), for a minimum and a maximum over them. The
/// accumulators of such folds stay in registers only while no lane of
/// them is selected by a bit of `live`: selected, they compiled to masked
/// stores (`vmaskmovps`), which made a packet's set-up several times
/// slower.
#[inline(always)]
fn eight_of(x: &[f32; 8], live: u8) -> ([f32; 8], [f32; 8]) {
    if live == 0xff {
        return (*x, *x);
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
    for i in bits(u64::from(live)) {
        let i = i & 7;
        (lo[i], hi[i]) = (x[i], x[i]);
    }
    (lo, hi)
}

/// The smallest and the largest of `row`'s lanes of `m`, eight lanes at a
/// time (as `min_ps` and `max_ps` fold them).
#[inline(always)]
fn bounds<const N: usize>(row: &[f32; N], m: u64) -> (f32, f32) {
    let (mut lo, mut hi) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
    for c in 0..N / 8 {
        let live = (m >> (8 * c).min(63)) as u8;
        let Some(x) = row.get(8 * c..).and_then(<[f32]>::first_chunk::<8>) else { continue };
        if live == 0 {
            continue;
        }
        let (xl, xh) = eight_of(x, live);
        lo = std::array::from_fn(|i| min_ps(lo[i], xl[i]));
        hi = std::array::from_fn(|i| max_ps(hi[i], xh[i]));
    }
    (
        lo.iter().fold(f32::INFINITY, |m, &x| min_ps(m, x)),
        hi.iter().fold(f32::NEG_INFINITY, |m, &x| max_ps(m, x)),
    )
}

/// A stack entry: a child's reference, the packet's entry bound, and the
/// rays that meet the child's box.
pub(crate) type Entry = (u32, f32, u64);

impl WideBvh {
    /// Walks the packet's rays of `active` (in `soa`, bounded by `fr`)
    /// through the tree: calls `leaf` ([`Leaf`]) for each leaf with the
    /// active rays that meet its box. `N` is the packet's capacity. `ANY` skips the front-to-back ordering. `need` is
    /// [`WideBvh::stack_need`] (kept by the owner: computing it walks the
    /// tree). `lanes` tests a box against eight rays at once.
    #[inline(always)]
    pub(crate) fn walk_packet<const ANY: bool, const N: usize>(
        &self,
        lanes: impl Lanes,
        need: usize,
        fr: &Frustum,
        soa: &mut Soa<N>,
        active: u64,
        leaf: impl Leaf<N>,
    ) {
        if need <= INLINE_STACK {
            self.walk_packet_in::<ANY, N, _>(
                lanes,
                &mut InlineStack::<Entry, INLINE_STACK>::new(),
                fr,
                soa,
                active,
                leaf,
            );
        } else {
            self.walk_packet_in::<ANY, N, _>(lanes, &mut Vec::with_capacity(need), fr, soa, active, leaf);
        }
    }

    #[inline(always)]
    fn walk_packet_in<const ANY: bool, const N: usize, S: Stack<Entry>>(
        &self,
        lanes: impl Lanes,
        stack: &mut S,
        fr: &Frustum,
        soa: &mut Soa<N>,
        mut active: u64,
        mut leaf: impl Leaf<N>,
    ) {
        let nodes = self.nodes();
        if nodes.is_empty() || active == 0 {
            return;
        }
        let mut reach = soa.max_reach();
        // A mixed walk tests every node ray by ray.
        let per_ray = if fr.mixed { u64::BITS } else { PER_RAY };
        // The node or leaf taken next, and the rays that meet its box.
        let (mut cur, mut rays) = (0u32, active);
        loop {
            if cur & LEAF == 0 {
                let Some(node) = nodes.get(cur as usize) else { return };
                let mut out =
                    Hits { near: [0.0; WIDTH], child: [0; WIDTH], lane: [0; WIDTH], rays: [0; WIDTH] };
                let want = rays & active;
                let kept = if want.count_ones() <= per_ray {
                    soa.per_ray::<ANY>(lanes, fr, node, want, &mut out)
                } else {
                    let n = fr.hits(node, reach, &mut out).min(WIDTH);
                    // Of the children the frustum may enter, keep those
                    // that some ray enters on its own test, with those rays.
                    let mut kept = 0;
                    for c in 0..n {
                        let m = soa.meet(lanes, fr, node, usize::from(out.lane[c]), want) & want;
                        if m != 0 {
                            out.near[kept] = out.near[c];
                            out.child[kept] = out.child[c];
                            out.rays[kept] = m;
                            kept += 1;
                        }
                    }
                    kept
                };
                if kept > 0 {
                    if kept > 1 && !ANY {
                        sort(&mut out, kept);
                    }
                    for k in (1..kept).rev() {
                        stack.push((out.child[k], out.near[k], out.rays[k]));
                    }
                    (cur, rays) = (out.child[0], out.rays[0]);
                    continue;
                }
            } else {
                let first = cur & ((1 << FIRST_BITS) - 1);
                let count = ((cur & !LEAF) >> FIRST_BITS) + 1;
                let meet = rays & active;
                if meet != 0 {
                    let done = leaf.visit(first, count, meet, soa, fr);
                    for k in bits(done) {
                        if let Some(x) = soa.reach.get_mut(k) {
                            *x = f32::NEG_INFINITY;
                        }
                    }
                    active &= !done;
                    if active == 0 {
                        return;
                    }
                    if !ANY {
                        reach = soa.max_reach();
                    }
                }
            }
            loop {
                let Some((c, d, m)) = stack.pop() else { return };
                if d <= reach && m & active != 0 {
                    (cur, rays) = (c, m);
                    break;
                }
            }
        }
    }
}

/// Sorts the first `n` hits by entry bound, stable (insertion sort).
#[inline(always)]
fn sort(h: &mut Hits, n: usize) {
    for i in 1..n.min(WIDTH) {
        let (d, c, r) = (h.near[i], h.child[i], h.rays[i]);
        let mut j = i;
        while j > 0 && d < h.near[j - 1] {
            h.near[j] = h.near[j - 1];
            h.child[j] = h.child[j - 1];
            h.rays[j] = h.rays[j - 1];
            j -= 1;
        }
        h.near[j] = d;
        h.child[j] = c;
        h.rays[j] = r;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::Ray;
    use prism_geometry::glam::Vec3;

    #[test]
    fn bits_lists_the_set_bits_in_order() {
        assert_eq!(bits(0).count(), 0);
        assert_eq!(bits(0b1010_0001).collect::<Vec<_>>(), vec![0, 5, 7]);
        assert_eq!(bits(1 << 63).collect::<Vec<_>>(), vec![63]);
    }

    #[test]
    fn octants_split_by_sign_and_set_zero_components_apart() {
        let rays = [
            Ray::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)),
            Ray::new(Vec3::ZERO, Vec3::new(-1.0, 2.0, -3.0)),
            Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 3.0)),
            Ray::new(Vec3::ZERO, Vec3::new(1.0, -0.0, 3.0)),
            Ray::new(Vec3::ZERO, Vec3::new(0.5, 0.5, 0.5)),
        ];
        let br: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
        let g = octants(&br, 0b11111);
        assert_eq!(g[0], 0b10001);
        assert_eq!(g[0b101], 0b00010);
        assert_eq!(g[8], 0b01100);
        assert_eq!(g.iter().fold(0, |a, m| a | m), 0b11111);
        assert!(Frustum::new(&br, g[0]).is_some());
        assert!(Frustum::new(&br, 0b00011).is_none(), "mixed octants fit no frustum");
        assert!(Frustum::new(&br, g[8]).is_none(), "zero components fit no frustum");
    }

    /// The AVX2 eight-ray box test gives the portable one's mask, bit for
    /// bit, on random boxes and rays with the awkward values mixed in:
    /// infinite reciprocals and reaches, `NaN` (as `0 · inf` makes), ±0
    /// and origins on a plane.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_box_test_is_the_portable_one() {
        if !is_x86_feature_detected!("avx2") {
            prism_testkit::skip("this CPU lacks AVX2 (nothing to compare)");
            return;
        }
        // SAFETY: checked just above.
        let avx2 = unsafe { x86::Avx2::new() };
        let mut r = prism_testkit::Rng::new(17);
        let mut rng = move || r.f32();
        let special = [0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1.0, -1.0];
        let mut value = |scale: f32| {
            if rng() < 0.15 { special[(rng() * 7.0) as usize % 7] } else { (rng() - 0.5) * scale }
        };
        let (mut met, mut missed) = (0u32, 0u32);
        for _ in 0..20_000 {
            let near: [f32; 3] = std::array::from_fn(|_| value(4.0));
            let far: [f32; 3] = std::array::from_fn(|a| near[a] + value(4.0).abs());
            let o: [[f32; 8]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| value(8.0)));
            let inv: [[f32; 8]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| value(10.0)));
            let t_min: [f32; 8] = std::array::from_fn(|_| value(1.0).abs());
            let reach: [f32; 8] = std::array::from_fn(|_| value(20.0));
            let (oo, ii) = ([&o[0], &o[1], &o[2]], [&inv[0], &inv[1], &inv[2]]);
            let want = Portable.meet8(near, far, oo, ii, &t_min, &reach);
            let got = avx2.meet8(near, far, oo, ii, &t_min, &reach);
            assert_eq!(
                got, want,
                "near {near:?} far {far:?} o {o:?} inv {inv:?} t_min {t_min:?} reach {reach:?}"
            );
            met |= want;
            missed |= !want & 0xff;
        }
        assert_eq!((met, missed), (0xff, 0xff), "every lane both meets and misses");
    }

    /// The vector maximum of the reaches is the fold over them one by one,
    /// with rays out of the walk (`-inf`), unbounded ones (`inf`) and a
    /// `NaN` among them, at both capacities.
    #[test]
    fn max_reach_is_the_largest_reach() {
        let mut r = prism_testkit::Rng::new(5);
        let mut rng = move || r.f32();
        for _ in 0..2000 {
            let mut soa = Soa::<PACKET> {
                origin: [[0.0; PACKET]; 3],
                inv: [[1.0; PACKET]; 3],
                t_min: [0.0; PACKET],
                reach: std::array::from_fn(|_| match rng() {
                    x if x < 0.3 => f32::NEG_INFINITY,
                    x if x < 0.35 => f32::INFINITY,
                    x if x < 0.37 => f32::NAN,
                    _ => rng() * 100.0 - 10.0,
                }),
                len: (1 + (rng() * 8.0) as usize).min(8) * 8,
                oct: [0; PACKET],
            };
            let fold = |reach: &[f32]| reach.iter().fold(f32::NEG_INFINITY, |r, &x| max_ps(x, r));
            let want = fold(&soa.reach[..soa.len]);
            assert_eq!(soa.max_reach().to_bits(), want.to_bits(), "{:?}", &soa.reach[..soa.len]);
            soa.len = 16;
            let small = Soa::<SMALL_PACKET> {
                origin: [[0.0; SMALL_PACKET]; 3],
                inv: [[1.0; SMALL_PACKET]; 3],
                t_min: [0.0; SMALL_PACKET],
                reach: std::array::from_fn(|k| soa.reach[k]),
                len: 16,
                oct: [0; SMALL_PACKET],
            };
            assert_eq!(small.max_reach().to_bits(), fold(&soa.reach[..16]).to_bits());
            assert_eq!(soa.max_reach().to_bits(), fold(&soa.reach[..16]).to_bits());
        }
    }

    /// A packet's lanes, made eight at a time, are each ray's box ray bit
    /// for bit (origin, reciprocals, `t_min`, reach) and its octant, and
    /// the lanes of rays not asked for meet nothing: random rays with
    /// zero components of either sign, tiny and huge components,
    /// infinite `t_max`, partial masks, and slices ending inside a block
    /// of eight.
    #[test]
    fn lanes_are_each_rays_box_ray() {
        let mut r = prism_testkit::Rng::new(23);
        let mut rng = move || r.f32();
        let component = |x: f32| match (x * 20.0) as u32 {
            0 => 0.0,
            1 => -0.0,
            2 => 1e-30,
            3 => -3e30,
            _ => x - 0.5,
        };
        let (mut uniform, mut mixed, mut zero) = (0, 0, 0);
        for i in 0..3000 {
            let rays: Vec<Ray> = (0..PACKET)
                .map(|_| {
                    let o = Vec3::new(rng(), rng(), rng()) * 8.0 - 4.0;
                    let d = Vec3::new(component(rng()), component(rng()), component(rng()));
                    let t_max = if rng() < 0.3 { f32::INFINITY } else { rng() * 50.0 };
                    Ray { origin: o, t_min: rng() * 0.01, dir: d, t_max }
                })
                .collect();
            let len = if i % 3 == 0 { 1 + (rng() * 63.0) as usize } else { PACKET };
            // Every third packet of one direction's signs.
            let rays: Vec<Ray> = if i % 3 == 1 {
                rays.iter().map(|r| Ray { dir: r.dir.abs().max(Vec3::splat(1e-3)), ..*r }).collect()
            } else {
                rays
            };
            let mask = match i % 4 {
                0 => u64::MAX,
                _ => u64::from(rng().to_bits()) << 32 | u64::from(rng().to_bits()),
            };
            let soa = Soa::<PACKET>::new(&rays[..len], mask);
            for (k, ray) in rays.iter().enumerate() {
                if mask >> k & 1 == 0 || k >= len {
                    assert_eq!(soa.reach[k], f32::NEG_INFINITY, "lane {k} not asked for meets nothing");
                    continue;
                }
                let want = BoxRay::new(ray);
                let got = soa.box_ray(k);
                let parts = |b: &BoxRay| {
                    (
                        b.origin.to_array().map(f32::to_bits),
                        b.inv.to_array().map(f32::to_bits),
                        b.t_min.to_bits(),
                        b.reach().to_bits(),
                    )
                };
                assert_eq!(parts(&got), parts(&want), "ray {k}: {ray:?}");
                assert_eq!(usize::from(soa.oct[k]), octant(&want), "ray {k}: {ray:?}");
                zero += usize::from(soa.oct[k] == 8);
            }
            let live = if len >= 64 { mask } else { mask & ((1 << len) - 1) };
            if live != 0 {
                let first = soa.oct[live.trailing_zeros() as usize];
                let same = bits(live).all(|k| soa.oct[k] == first);
                assert_eq!(soa.all_in(live, first), same);
                if same {
                    uniform += 1;
                } else {
                    mixed += 1;
                }
            }
        }
        assert!(
            zero > 100 && uniform > 100 && mixed > 100,
            "{zero} rays of no octant, {uniform} / {mixed} packets of one / several"
        );
    }

    /// A translated instance's rows ([`Soa::fill_moved`]) are, lane for
    /// lane, the rows [`Soa::fill`] makes of the rays that
    /// `Transform::ray_to_object` gives, with the reaches narrowed so far;
    /// lanes not asked for meet nothing.
    #[test]
    fn moved_lanes_are_the_object_space_rays_lanes() {
        use prism_geometry::Transform;
        let mut r = prism_testkit::Rng::new(31);
        let mut rng = move || r.f32();
        let component = |x: f32| match (x * 20.0) as u32 {
            0 => 0.0,
            1 => -0.0,
            2 => 1e-30,
            _ => x - 0.5,
        };
        let mut compared = 0;
        for i in 0..500 {
            let mut rays: Vec<Ray> = (0..PACKET)
                .map(|_| {
                    let o = Vec3::new(component(rng()), rng(), rng()) * 8.0 - Vec3::new(0.0, 4.0, 4.0);
                    let d = Vec3::new(component(rng()), component(rng()), component(rng()));
                    let t_max = if rng() < 0.3 { f32::INFINITY } else { rng() * 50.0 };
                    Ray { origin: o, t_min: rng() * 0.01, dir: d, t_max }
                })
                .collect();
            let mask = match i % 3 {
                0 => u64::MAX,
                _ => u64::from(rng().to_bits()) << 32 | u64::from(rng().to_bits()),
            };
            let offset = match i % 4 {
                0 => Vec3::new(0.0, -0.0, 3.5),
                _ => Vec3::new(rng(), rng(), rng()) * 20.0 - 10.0,
            };
            let t = Transform::translate(offset).unwrap();
            let Some(moved_by) = t.object_offset() else { panic!("a translation has an offset") };
            let mut world = Soa::<PACKET>::new(&rays, mask);
            // Some rays have found a hit since the rows were made.
            for (k, ray) in rays.iter_mut().enumerate() {
                if rng() < 0.3 {
                    ray.t_max = rng() * 10.0;
                    narrow(&mut world.reach, k, ray.t_max);
                }
            }
            let local: Vec<Ray> = rays.iter().map(|r| t.ray_to_object(r)).collect();
            let want = Soa::<PACKET>::new(&local, mask);
            let mut got = Soa::<PACKET>::empty(mask);
            got.fill_moved(&world, moved_by, mask);
            assert_eq!(got.len, want.len);
            for (k, ray) in rays.iter().enumerate() {
                if mask >> k & 1 == 0 {
                    assert_eq!(got.reach[k], f32::NEG_INFINITY, "lane {k} not asked for meets nothing");
                    continue;
                }
                let parts = |s: &Soa<PACKET>| {
                    (
                        [0, 1, 2].map(|a| (s.origin[a][k].to_bits(), s.inv[a][k].to_bits())),
                        s.t_min[k].to_bits(),
                        s.reach[k].to_bits(),
                        s.oct[k],
                    )
                };
                assert_eq!(parts(&got), parts(&want), "lane {k}: {ray:?} moved by {offset}");
                compared += 1;
            }
        }
        assert!(compared > 10_000, "{compared} lanes compared");
    }

    /// A walk's frustum moved with its rays ([`Frustum::moved`]) is the
    /// frustum of the moved rows over the same rays, and bounds every
    /// subset of them (the rays of one instance).
    #[test]
    fn moved_frustum_is_the_moved_rays_frustum() {
        use prism_geometry::Transform;
        let mut r = prism_testkit::Rng::new(41);
        let mut rng = move || r.f32();
        for i in 0..300 {
            let signs = Vec3::new(1.0, -1.0, if i % 2 == 0 { 1.0 } else { -1.0 });
            let eye = Vec3::new(rng(), rng(), rng()) * 10.0 - 5.0;
            let rays: Vec<Ray> = (0..PACKET)
                .map(|_| {
                    let o = if i % 3 == 0 { eye } else { eye + Vec3::new(rng(), rng(), rng()) };
                    let d = (Vec3::new(rng(), rng(), rng()) + 0.05) * signs;
                    Ray { origin: o, t_min: rng() * 0.01, dir: d, t_max: 100.0 }
                })
                .collect();
            let mask = u64::MAX;
            let offset = Vec3::new(rng(), rng(), rng()) * 40.0 - 20.0;
            let Some(offset) = Transform::translate(offset).unwrap().object_offset() else { continue };
            let world = Soa::<PACKET>::new(&rays, mask);
            let code = u32::from(world.oct[0]);
            let fr = world.frustum(code, mask);
            let mut moved = Soa::<PACKET>::empty(mask);
            moved.fill_moved(&world, offset, mask);
            assert_eq!(fr.moved(offset), moved.frustum(code, mask), "packet {i}");
            let part = u64::from(rng().to_bits()) << 32 | u64::from(rng().to_bits());
            let (all, sub) = (fr.moved(offset), moved.frustum(code, part));
            for a in 0..3 {
                assert!(all.o_lo[a] <= sub.o_lo[a] && all.o_hi[a] >= sub.o_hi[a], "packet {i}, axis {a}");
                assert!(all.inv_lo[a] <= sub.inv_lo[a] && all.inv_hi[a] >= sub.inv_hi[a]);
            }
            assert!(all.t_min <= sub.t_min && all.near_row == sub.near_row && all.far_row == sub.far_row);
            assert!(!all.same_origin || sub.same_origin);
        }
        assert_eq!(Frustum::mixed().moved(Vec3::ONE), Frustum::mixed());
    }

    /// `plan`'s one pass gives the reference's groups and frustums: rays
    /// of mixed octants, zero direction components, partial masks; and
    /// rays of at least [`MIXED_OCTANTS`] octants go together, with the
    /// mixed frustum.
    #[test]
    fn plan_matches_octants_and_frustum_new() {
        let mut r = prism_testkit::Rng::new(11);
        let mut rng = move || r.f32();
        let (mut by_octant, mut mixed) = (0, 0);
        for i in 0..600 {
            // Packets mostly of one octant (as camera and shadow rays),
            // and packets of every octant (as hemisphere rays).
            let one = [1.0, 0.97, 0.8, 0.0][i % 4];
            let rays: Vec<Ray> = (0..PACKET)
                .map(|_| {
                    let o = Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0;
                    let mut d = Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5);
                    if rng() < 0.05 {
                        d.y = if rng() < 0.5 { 0.0 } else { -0.0 };
                    }
                    if rng() < one {
                        d = d.abs();
                    }
                    Ray::with_interval(o, d, rng(), 10.0)
                })
                .collect();
            let br: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
            let mask = (u64::from(rng().to_bits()) << 32 | u64::from(rng().to_bits())) | 1;
            let got = plan(&Soa::<PACKET>::new(&rays, mask), mask);
            let groups = octants(&br, mask);
            if groups[..8].iter().filter(|&&m| m != 0).count() >= MIXED_OCTANTS {
                mixed += 1;
                let all = mask & !groups[8];
                assert_eq!(got[0].0, all, "every finite ray together");
                assert_eq!(got[0].1, (all.count_ones() >= MIN_PACKET).then(Frustum::mixed));
                assert_eq!(got[8], (groups[8], None), "zero components apart");
                assert!(got[1..8].iter().all(|g| *g == (0, None)));
                continue;
            }
            by_octant += 1;
            for o in 0..9 {
                assert_eq!(got[o].0, groups[o], "octant {o}");
                let want = (o < 8 && groups[o].count_ones() >= MIN_PACKET)
                    .then(|| Frustum::new(&br, groups[o]))
                    .flatten();
                assert_eq!(got[o].1, want, "octant {o}");
            }
        }
        assert!(by_octant > 100 && mixed > 100, "{by_octant} by octant, {mixed} mixed");
    }

    /// A node of eight random boxes in `[-5, 5]³`, lane `k`'s child
    /// `first + k`.
    fn random_node(rng: &mut impl FnMut() -> f32, first: u32) -> Node {
        let mut node = Node::EMPTY;
        for k in 0..WIDTH {
            let c = Vec3::new(rng(), rng(), rng()) * 10.0 - 5.0;
            let h = Vec3::new(rng(), rng(), rng()) * 2.0;
            for a in 0..3 {
                node.planes[a][k] = c[a] - h[a];
                node.planes[a + 3][k] = c[a] + h[a];
            }
            node.child[k] = first + k as u32;
        }
        node
    }

    /// The frustum's bounds contain every ray's own entry and exit
    /// distances (random boxes and packets): a box one ray meets, the
    /// packet meets; each ray's own leaf test is the same alone or in the packet.
    #[test]
    fn frustum_bounds_contain_each_rays_distances() {
        let mut r = prism_testkit::Rng::new(7);
        let mut rng = move || r.f32();
        for _ in 0..2000 {
            let base = Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5).normalize_or(Vec3::X);
            let rays: Vec<Ray> = (0..8)
                .map(|_| {
                    let o = Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0;
                    let d = base + 0.2 * Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5);
                    Ray::new(o, d)
                })
                .collect();
            let br: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
            let g = octants(&br, 0xff);
            for &m in &g[..8] {
                if m == 0 {
                    continue;
                }
                let Some(fr) = Frustum::new(&br, m) else { panic!("one octant") };
                let node = random_node(&mut rng, 0);
                let mut out =
                    Hits { near: [0.0; WIDTH], child: [0; WIDTH], lane: [0; WIDTH], rays: [0; WIDTH] };
                let n = fr.hits(&node, f32::INFINITY, &mut out);
                let entered: Vec<u8> = out.lane[..n].to_vec();
                let soa = Soa::<PACKET>::new(&rays, m);
                for lane in 0..WIDTH {
                    let meet = soa.meet(Portable, &fr, &node, lane, u64::MAX);
                    assert_eq!(meet & !m, 0, "only the packet's rays");
                    assert_eq!(soa.meet(Portable, &fr, &node, lane, m), meet, "asking for the packet's rays");
                    assert_eq!(soa.meet(Portable, &fr, &node, lane, 0), 0, "asking for no ray");
                    if meet != 0 {
                        assert!(
                            entered.contains(&(lane as u8)),
                            "rays {meet:b} meet lane {lane}, the packet does not"
                        );
                    }
                    for k in bits(m) {
                        let alone =
                            Soa::<SMALL_PACKET>::new(&rays, 1 << k).meet(Portable, &fr, &node, lane, 1 << k)
                                != 0;
                        assert_eq!(
                            meet >> k & 1 == 1,
                            alone,
                            "ray {k}, lane {lane}: tested alone or together"
                        );
                    }
                }
            }
        }
    }

    /// A node tested ray by ray (`per_ray`, taken when few rays reach it)
    /// keeps the children, and with each the rays, that the frustum and a
    /// [`Soa::meet`] per child keep; its entry bound is the smallest entry
    /// distance of the rays that meet the child, each by the single-ray
    /// node test. Random packets with rays out of the walk (reach `-inf`)
    /// and shortened reaches; the portable and AVX2 lanes.
    #[test]
    fn per_ray_node_test_keeps_what_the_frustum_and_meet_keep() {
        fn check(lanes: impl Lanes, seed: u64) {
            let mut r = prism_testkit::Rng::new(seed);
            let mut rng = move || r.f32();
            let (mut kept_some, mut culled_some) = (false, false);
            let mut octants_seen = 0u32;
            for _ in 0..2000 {
                let base = Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5).normalize_or(Vec3::X);
                let shared = Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0;
                let rays: Vec<Ray> = (0..PACKET)
                    .map(|_| {
                        let o = if rng() < 0.5 { shared } else { Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0 };
                        let d = base + 0.3 * Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5);
                        Ray::with_interval(
                            o,
                            d,
                            rng() * 0.1,
                            if rng() < 0.3 { rng() * 6.0 } else { f32::INFINITY },
                        )
                    })
                    .collect();
                let br: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
                let g = octants(&br, u64::MAX);
                let Some(&m) = g[..8].iter().max_by_key(|m| m.count_ones()) else { continue };
                let Some(fr) = Frustum::new(&br, m) else { panic!("one octant") };
                let node = random_node(&mut rng, 100);
                let mut soa = Soa::<PACKET>::new(&rays, m);
                // Some rays out of the walk, as after an occluded leaf.
                let mut active = m;
                for k in bits(m) {
                    if rng() < 0.2 {
                        soa.reach[k] = f32::NEG_INFINITY;
                        active &= !(1 << k);
                    }
                }
                // A few of the rays, as at a node deep in the walk.
                let mut want = 0;
                for k in bits(active) {
                    if rng() < 0.15 {
                        want |= 1 << k;
                    }
                }
                let empty =
                    || Hits { near: [0.0; WIDTH], child: [0; WIDTH], lane: [0; WIDTH], rays: [0; WIDTH] };
                let mut by_frustum = empty();
                let n = fr.hits(&node, soa.max_reach(), &mut by_frustum);
                let mut want_children = Vec::new();
                for c in 0..n {
                    let met = soa.meet(lanes, &fr, &node, usize::from(by_frustum.lane[c]), want) & want;
                    if met != 0 {
                        want_children.push((by_frustum.child[c], met));
                    }
                }
                want_children.sort_unstable();
                let mut by_ray = empty();
                let kept = soa.per_ray::<false>(lanes, &fr, &node, want, &mut by_ray);
                let got: Vec<(u32, u64)> = (0..kept).map(|c| (by_ray.child[c], by_ray.rays[c])).collect();
                assert_eq!(got, want_children, "want {want:b}");
                // The copy compiled for the frustum's octant: the same
                // children, rays and entry bounds.
                let oct = br[m.trailing_zeros() as usize].inv.cmplt(Vec3A::ZERO).bitmask() as usize;
                assert_eq!(fr.octant(), oct);
                octants_seen |= 1 << oct;
                let mut by_octant = empty();
                assert_eq!(soa.per_ray::<true>(lanes, &fr, &node, want, &mut by_octant), kept);
                for c in 0..kept {
                    let (a, b) = (&by_ray, &by_octant);
                    assert_eq!(
                        (a.child[c], a.rays[c], a.near[c].to_bits()),
                        (b.child[c], b.rays[c], b.near[c].to_bits())
                    );
                }
                for c in 0..kept {
                    let lane = (by_ray.child[c] - 100) as usize;
                    let nearest = bits(by_ray.rays[c])
                        .map(|k| {
                            let b = br[k];
                            let r = WideRay::new(&b);
                            let mut t_near = [0.0; WIDTH];
                            let hit = Portable.node(&node, &r, soa.reach[k], &mut t_near);
                            assert_eq!(hit >> lane & 1, 1, "ray {k} meets lane {lane} alone");
                            t_near[lane]
                        })
                        .fold(f32::INFINITY, f32::min);
                    assert_eq!(by_ray.near[c].to_bits(), nearest.to_bits(), "lane {lane}");
                }
                kept_some |= kept > 0;
                culled_some |= kept < WIDTH && want != 0;
            }
            assert!(kept_some && culled_some, "both kept and culled children");
            assert_eq!(octants_seen, 0xff, "frustums of every octant");
        }
        check(Portable, 3);
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            // SAFETY: checked just above.
            check(unsafe { x86::Avx2::new() }, 4);
        } else {
            prism_testkit::skip("this CPU lacks AVX2 (its lanes not checked)");
        }
    }

    /// In a mixed walk ([`Frustum::mixed`]), the per-ray node test keeps
    /// for each child exactly the rays whose own single-ray node test
    /// (their own octant's planes) meets it, and as its entry bound the
    /// nearest of their entry distances: rays of every octant, some out of
    /// the walk; the portable and AVX2 lanes.
    #[test]
    fn mixed_per_ray_node_test_is_each_rays_own() {
        fn check(lanes: impl Lanes, seed: u64) {
            let mut r = prism_testkit::Rng::new(seed);
            let mut rng = move || r.f32();
            let (mut octants_seen, mut kept_some) = (0u8, false);
            for _ in 0..2000 {
                let shared = Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0;
                let rays: Vec<Ray> = (0..PACKET)
                    .map(|_| {
                        let o = if rng() < 0.5 { shared } else { Vec3::new(rng(), rng(), rng()) * 4.0 - 2.0 };
                        let d = Vec3::new(rng() - 0.5, rng() - 0.5, rng() - 0.5);
                        let d = if d.min_element().abs() < 1e-3 { Vec3::new(0.3, -0.2, 0.1) } else { d };
                        Ray::with_interval(
                            o,
                            d,
                            rng() * 0.1,
                            if rng() < 0.3 { rng() * 6.0 } else { f32::INFINITY },
                        )
                    })
                    .collect();
                let br: Vec<BoxRay> = rays.iter().map(BoxRay::new).collect();
                let node = random_node(&mut rng, 100);
                let mut soa = Soa::<PACKET>::new(&rays, u64::MAX);
                let mut want = 0u64;
                for (k, b) in br.iter().enumerate() {
                    if rng() < 0.2 {
                        soa.reach[k] = f32::NEG_INFINITY;
                    } else if rng() < 0.5 {
                        want |= 1 << k;
                        octants_seen |= 1 << octant(b);
                    }
                }
                let mut expect = [(0u64, f32::INFINITY); WIDTH];
                for k in bits(want) {
                    let mut t_near = [0.0; WIDTH];
                    let hit = Portable.node(&node, &WideRay::new(&br[k]), soa.reach[k], &mut t_near);
                    for (c, e) in expect.iter_mut().enumerate() {
                        if hit >> c & 1 == 1 {
                            *e = (e.0 | 1 << k, e.1.min(t_near[c]));
                        }
                    }
                }
                let expect: Vec<(u32, u64, u32)> = (0..WIDTH)
                    .filter(|&c| expect[c].0 != 0)
                    .map(|c| (100 + c as u32, expect[c].0, expect[c].1.to_bits()))
                    .collect();
                let mut out =
                    Hits { near: [0.0; WIDTH], child: [0; WIDTH], lane: [0; WIDTH], rays: [0; WIDTH] };
                let kept = soa.per_ray::<false>(lanes, &Frustum::mixed(), &node, want, &mut out);
                let got: Vec<(u32, u64, u32)> =
                    (0..kept).map(|c| (out.child[c], out.rays[c], out.near[c].to_bits())).collect();
                assert_eq!(got, expect, "want {want:b}");
                kept_some |= kept > 0;
            }
            assert!(octants_seen == 0xff && kept_some, "octants {octants_seen:b}");
        }
        check(Portable, 5);
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx2") {
            // SAFETY: checked just above.
            check(unsafe { x86::Avx2::new() }, 6);
        } else {
            prism_testkit::skip("this CPU lacks AVX2 (its lanes not checked)");
        }
    }

    /// The AVX2 fold of rays' node tests into a per-ray node test's state,
    /// with the planes picked by rows and by the sign of `inv` (whose
    /// distances agree bit for bit), gives the portable fold's masks,
    /// entry bounds (bit for bit) and rays per child: random nodes with
    /// degenerate and inverted boxes, rays with zero direction components
    /// and origins in face planes, reaches of `-inf` and `inf`, any of the
    /// 64 ray slots. On the same nodes and rays, the single-ray node
    /// tests' folded distances (`distances::<true>`) and the AVX2 and
    /// portable single-ray node tests agree with them, a zero's sign aside.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_fold_matches_the_portable_fold() {
        if !is_x86_feature_detected!("avx2") {
            prism_testkit::skip("this CPU lacks AVX2 (its fold not checked)");
            return;
        }
        // SAFETY: checked just above.
        let avx2 = unsafe { x86::Avx2::new() };
        let mut r = prism_testkit::Rng::new(11);
        let mut rng = move || r.f32();
        let (mut met_many, mut met_hi, mut folded_signs) = (false, false, false);
        for round in 0..3000 {
            let mut node = random_node(&mut rng, 0);
            for k in 0..WIDTH {
                if rng() < 0.1 {
                    // A flat box, whose planes a ray's origin may lie in.
                    node.planes[1][k] = 0.5;
                    node.planes[4][k] = 0.5;
                } else if rng() < 0.05 {
                    for row in 0..3 {
                        node.planes[row][k] = f32::INFINITY;
                        node.planes[row + 3][k] = f32::NEG_INFINITY;
                    }
                }
            }
            let (mut a, mut b, mut m) = (PerRay::new(), PerRay::new(), PerRay::new());
            let (mut any_a, mut any_b) = (0u32, 0u32);
            let mut slots: Vec<usize> = (0..PACKET).filter(|_| rng() < 0.3).collect();
            slots.push(round % PACKET);
            slots.sort_unstable();
            slots.dedup();
            for &k in &slots {
                let pick = |x: f32, v: f32| {
                    if x < 0.1 {
                        0.0
                    } else if x < 0.15 {
                        -0.0
                    } else {
                        v
                    }
                };
                let d = Vec3::new(pick(rng(), rng() - 0.5), pick(rng(), rng() - 0.5), rng() - 0.5);
                let d = if d == Vec3::ZERO { Vec3::X } else { d };
                let mut o = Vec3::new(rng(), rng(), rng()) * 12.0 - 6.0;
                if rng() < 0.2 {
                    o.y = 0.5;
                }
                let ray = Ray::with_interval(
                    o,
                    d,
                    rng() * 0.5,
                    if rng() < 0.5 { rng() * 8.0 } else { f32::INFINITY },
                );
                let wr = WideRay::new(&BoxRay::new(&ray));
                let reach = match (rng() * 10.0) as u32 {
                    0 => f32::NEG_INFINITY,
                    1 => f32::INFINITY,
                    _ => rng() * 10.0,
                };
                let ma = Portable.fold(&node, &wr, reach, k, &mut a);
                let mb = avx2.fold(&node, &wr, reach, k, &mut b);
                let mm = avx2.fold_mixed(&node, &wr, reach, k, &mut m);
                assert_eq!(ma, mb, "round {round}, ray {k}: mask");
                assert_eq!(ma, mm, "round {round}, ray {k}: mask, planes by sign");
                // SAFETY: the CPU has AVX2 (checked above).
                let (by_rows, by_sign, folded) = unsafe {
                    use crate::wide::x86::{distances, distances_by_sign};
                    (
                        distances::<false>(&node, &wr, reach),
                        distances_by_sign(&node, &wr, reach),
                        distances::<true>(&node, &wr, reach),
                    )
                };
                let lanes = |(n, f): (std::arch::x86_64::__m256, std::arch::x86_64::__m256)| {
                    // SAFETY: a `__m256` is eight `f32`s.
                    let [n, f]: [[f32; 8]; 2] = unsafe { std::mem::transmute([n, f]) };
                    (n.map(f32::to_bits), f.map(f32::to_bits))
                };
                assert_eq!(lanes(by_rows), lanes(by_sign), "round {round}, ray {k}: distances");
                // The single-ray node test's form: the same values, a
                // zero's sign aside (`+ 0.0` makes `-0.0` `+0.0`); never
                // `NaN`, as `max`/`min` drop a slab's `NaN`.
                let values = |d| {
                    let (n, f) = lanes(d);
                    let v = |b: u32| (f32::from_bits(b) + 0.0).to_bits();
                    (n.map(v), f.map(v))
                };
                assert_eq!(values(by_rows), values(folded), "round {round}, ray {k}: folded distances");
                folded_signs |= lanes(by_rows) != lanes(folded);
                // The single-ray node tests themselves (AVX2's folded,
                // the portable one's not): the same children, the same
                // entry distances.
                let (mut tp, mut tx) = ([0.0f32; WIDTH], [0.0f32; WIDTH]);
                let mp = crate::wide::NodeTest::test(crate::wide::Portable, &node, &wr, reach, &mut tp);
                // SAFETY: the CPU has AVX2 (checked above).
                let single = unsafe { crate::wide::x86::Avx2::new() };
                let mx = crate::wide::NodeTest::test(single, &node, &wr, reach, &mut tx);
                assert_eq!(mp, mx, "round {round}, ray {k}: single-ray mask");
                let lanes_of = |t: [f32; WIDTH]| t.map(|x| (x + 0.0).to_bits());
                assert_eq!(lanes_of(tp), lanes_of(tx), "round {round}, ray {k}: single-ray entries");
                (any_a, any_b) = (any_a | ma, any_b | mb);
            }
            assert_eq!(a.near.map(f32::to_bits), b.near.map(f32::to_bits), "round {round}: near");
            assert_eq!(a.near.map(f32::to_bits), m.near.map(f32::to_bits), "round {round}: near by sign");
            for c in 0..WIDTH {
                let (ra, rb) = (Portable.met(&a, c), avx2.met(&b, c));
                assert_eq!(ra, rb, "round {round}, child {c}: rays");
                assert_eq!(ra, avx2.met(&m, c), "round {round}, child {c}: rays by sign");
                assert_eq!(ra != 0, any_a >> c & 1 == 1, "round {round}, child {c}");
                met_many |= ra.count_ones() > 4;
                met_hi |= ra >> 32 != 0;
            }
        }
        assert!(met_many && met_hi, "children met by several rays, and by rays above slot 31");
        assert!(folded_signs, "a folded distance was a zero of the other sign");
    }

    /// The AVX2 eight-ray leaf tests give the portable ones' answers
    /// ([`TriangleRays8::occluded`] and `closest`, themselves each ray's
    /// `occludes4` and `intersect4`), the nearest hits and narrowed
    /// intervals bit for bit: groups
    /// of one to eight rays from nearby origins in nearby directions,
    /// against one to four triangles, with integer coordinates (edge
    /// functions exactly zero, the scalar test's lanes), degenerate
    /// triangles, zero direction components and several intervals, at unit
    /// size and scaled by 2⁻⁶² and 2⁴⁵ (edge functions and distances past
    /// the range of `f32` products, also the scalar test's).
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_eight_ray_leaf_test_is_the_portable_one() {
        use prism_geometry::glam::Vec3;
        use prism_geometry::{TriangleRay, TriangleRays8, Triangles4};
        if !is_x86_feature_detected!("avx2") {
            prism_testkit::skip("this CPU lacks AVX2 (nothing to compare)");
            return;
        }
        // SAFETY: checked just above.
        let avx2 = unsafe { x86::Avx2::new() };
        let mut r = prism_testkit::Rng::new(29);
        let mut f = move || r.f32() * 2.0 - 1.0;
        let (mut hits, mut exact_cases, mut nearest, mut scaled_hits) = (0u32, 0u32, 0u32, 0u32);
        for case in 0..30_000usize {
            let integer = case % 4 == 0;
            let scale = [1.0, 2f32.powi(-62), 2f32.powi(45)][(case / 5) % 3];
            let mut p = |s: f32| {
                let v = Vec3::new(f(), f(), f()) * s;
                if integer { v.round() } else { v }
            };
            let tris: Vec<[Vec3; 3]> = (0..1 + case % 4)
                .map(|k| {
                    let t = [p(2.0), p(2.0), p(2.0)].map(|c| c * scale);
                    if (case + k) % 9 == 0 { [t[0], t[1], t[1]] } else { t }
                })
                .collect();
            let tris = Triangles4::new(&tris);
            let (o0, d0) = (p(3.0) * scale, p(1.0) + Vec3::Z * 0.5);
            let mut group: Option<TriangleRays8> = None;
            for i in 0..1 + case % 8 {
                let mut d = d0 + p(0.2);
                if (case + i) % 7 == 0 {
                    d[i % 3] = if i % 2 == 0 { 0.0 } else { -0.0 };
                }
                if d == Vec3::ZERO {
                    d = Vec3::Z;
                }
                let (t_min, t_max) =
                    [(0.0, f32::INFINITY), (0.5, 1.5), (f32::MIN, f32::MAX), (-1.0, 0.25)][(case + i) % 4];
                let tr = TriangleRay::new(&Ray::with_interval(o0 + p(0.1) * scale, d, t_min, t_max));
                group.get_or_insert_with(|| TriangleRays8::like(&tr)).push(&tr);
            }
            let Some(g) = group else { continue };
            let want = Portable.occluded8(&g, &tris);
            assert_eq!(avx2.occluded8(&g, &tris), want, "case {case}: {g:?} {tris:?}");
            // The nearest hits, bit for bit, and the narrowed intervals.
            let (mut a, mut b) = (g, g);
            let (near_a, near_b) = (Portable.closest8(&mut a, &tris), avx2.closest8(&mut b, &tris));
            let bits = |n: &Nearest8| {
                (
                    n.lanes,
                    (0..8)
                        .map(|i| n.get(i).map(|(j, t, b1, b2)| (j, [t, b1, b2].map(f32::to_bits))))
                        .collect::<Vec<_>>(),
                )
            };
            assert_eq!(bits(&near_b), bits(&near_a), "case {case}: closest8");
            assert_eq!(
                b.interval().1.map(f32::to_bits),
                a.interval().1.map(f32::to_bits),
                "case {case}: t_max"
            );
            nearest += near_a.lanes.count_ones();
            hits += want.count_ones();
            exact_cases += u32::from(integer && want != 0);
            scaled_hits += if scale == 1.0 { 0 } else { want.count_ones() };
        }
        assert!(
            hits > 2000 && exact_cases > 300 && nearest == hits && scaled_hits > 500,
            "{hits} hits, {exact_cases} integer cases with hits, {nearest} nearest hits, {scaled_hits} scaled"
        );
    }
}
