//! Scene acceleration for prism: closest-hit, occlusion and every-crossing
//! queries over a mix of analytic shapes and instanced triangle meshes,
//! built by [obvhs](https://docs.rs/obvhs) (PLOC with reinsertion) and
//! converted into a CPU-native wide BVH (eight children per 256-byte node,
//! uncompressed SoA `f32` boxes, leaves of four triangles tested at once).
//!
//! # Structure
//!
//! Two levels. Each mesh gets its own hierarchy over its triangles (a
//! *BLAS*), built once however many objects instance it; its triangles are
//! copied in leaf order so that a leaf's triangles are adjacent in memory.
//! Zero-area faces are left out (they can never be hit). A top-level
//! hierarchy (*TLAS*) holds every bounded object by its world-space box:
//! analytic shapes under their transforms, and mesh instances. A ray that
//! reaches a mesh instance is mapped into the mesh's object space (`t` is
//! unchanged by the mapping) and walks that mesh's BLAS; the hit is mapped
//! back, so a 6×6×6 grid of one mesh costs one BLAS plus 216 boxes.
//! Hierarchies are built in parallel (rayon) with the [`BuildQuality`]
//! chosen in [`BuildOptions`].
//!
//! A mesh's hierarchy is the wide layout ([`BlasKind::Wide`]) by default;
//! [`BuildOptions::mesh_layout`] (or the environment variable
//! `PRISM_BVH_BLAS=cwbvh|bvh2|wide` for the default options) selects
//! obvhs's CWBVH or binary BVH instead, each walked by this crate's own
//! walk under the same rules (`t_min`, no `1e-4` clamp, `NaN`-safe slabs,
//! front to back, early exit for occlusion). The wide layout measured
//! 1.3–1.7× the CWBVH's rays per second (docs/benchmarks.md). The top
//! level is always the wide layout.
//!
//! # Infinite planes
//!
//! Infinite planes (and any object without finite bounds) are kept out of
//! the hierarchy: one infinite box would make every node's box infinite
//! (traversal then visits everything, and obvhs's quantised boxes cannot
//! even be built). They are held in a short list that every query tests
//! first, before walking the TLAS; a closest-hit query starts its walk
//! with the plane's `t` as the upper bound. [`Accel::bounds`] excludes
//! them; [`BuildStats::unbounded_objects`] counts them.
//!
//! # Queries and their order
//!
//! * [`Accel::closest_hit`] walks front to back (children ordered by the
//!   ray's octant), shrinking `t_max` at each hit; the geometric hit record
//!   is computed only for the winner.
//! * [`Accel::occluded`] stops at the first hit found, which is *any* hit
//!   in the interval, not the nearest.
//! * [`Accel::for_each_hit`] reports every crossing in the interval in no
//!   particular order (neither by `t` nor by object): callers that need an
//!   order must sort, and callers that combine crossings (the product of
//!   transmittances for coloured shadows) need none. A closed analytic
//!   shape is reported at each of its crossings, each mesh triangle at most
//!   once per instance (also with pre-split builds, where a triangle may sit
//!   in several leaves); the callback may break early (an opaque occluder).
//!   [`Accel::for_each_crossing`] reports the same crossings in the same
//!   order as [`Crossing`]s (object, `t`, side) and leaves the hit record
//!   to [`Accel::crossing_hit`], for callers that need it only for some.
//!
//! * [`Accel::closest_hit_packet`] and [`Accel::occluded_packet`] answer
//!   the first two for up to [`PACKET_SIZE`] coherent rays at a time,
//!   walked together (a frustum per octant prefilters each node, then each
//!   ray's own box test; see `packet.rs`), with the same answers ray for
//!   ray. A scene without mesh instances is traced ray by ray.
//!
//! Every query honours `[t_min, t_max]` inclusively, so rays spawned with
//! [`Ray::spawn`] (origin offset off the surface, `t_min = 0`) find
//! surfaces arbitrarily close; unlike obvhs's own box test, ours does not
//! clamp the near distance to `1e-4`. Rays with a zero or non-finite
//! direction, a non-finite origin, or an empty interval hit nothing. Zero
//! direction components (either sign) are exact.
//!
//! # SIMD
//!
//! The wide layout's node test exists three times ([`Kernel`]): portable
//! Rust over eight-lane arrays (no `unsafe`; the compiler vectorises it),
//! AVX2 intrinsics, and AVX-512 (AVX2's test with a mask-register
//! compare, on 256-bit vectors, in a walk that has AVX-512's 32 vector
//! registers); the walk and its leaf tests are compiled once per kernel,
//! and [`Kernel::detect`] picks the fastest measured that the CPU has
//! (AVX-512, else AVX2, else the portable one) when the structure is
//! built ([`Accel::set_kernel`] or `PRISM_BVH_KERNEL` selects another).
//! All give bit-for-bit the same answers (same operations in the same
//! order, nothing fused; tests compare them). A leaf's four triangles
//! are tested together by [`prism_geometry::TriangleRay::intersect4`],
//! bit-identical to the scalar test; single rays, mostly incoherent, pick
//! the nearest lane without a branch per lane
//! ([`prism_geometry::TriangleRay::intersect4_branchless`], the same hit),
//! packets with the loop. [`Accel::closest_hit`] and the packet
//! queries ([`Accel::closest_hit_packet`], [`Accel::occluded_packet`]) are
//! also compiled for AVX2 as a whole (the CWBVH and BVH2 walks, the
//! analytic shapes and a packet's eight-ray box tests then use 256-bit
//! registers); [`Accel::occluded`] and [`Accel::for_each_hit`] are not, as
//! their AVX2 builds measured slower. Setting the environment variable
//! `PRISM_BVH_NO_SIMD` when the structure is built selects the plain
//! builds, for comparison.
//!
//! [`Accel::closest_hit_brute_force`] and [`Accel::for_each_hit_brute_force`]
//! answer the same questions by testing everything; the tests compare the
//! two.

#![warn(missing_docs)]

mod blas;
mod bvh2;
mod cwbvh;
mod packet;
mod traverse;
mod wide;

use blas::{Blas, MeshPackets};
use obvhs::BvhBuildParams;
use packet::{Frustum, Leaf, MIN_PACKET, Moved, Rows, SMALL_PACKET, Soa, bits};
use prism_geometry::glam::{Vec3, Vec4};
use prism_geometry::{Aabb, Hit, Instance, Intersect, Ray, Shape, Transform, TriangleMesh, TriangleRay};
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::sync::Arc;
use traverse::{BoxRay, Dispatch, Tree, Visit, Walker, visitor, walk_any, walk_any_by};

pub use packet::PACKET as PACKET_SIZE;
pub use wide::Kernel;
use wide::WideBvh;

/// One object of the scene: an analytic shape or an instance of a mesh.
#[derive(Clone, Debug)]
pub enum Object {
    /// An analytic shape placed by a transform.
    Shape(Instance<Shape>),
    /// Mesh number `mesh` (an index into the meshes given to
    /// [`Accel::build`]) placed by `transform`. Many instances may share
    /// one mesh; it is stored once.
    Mesh {
        /// Index into the mesh list.
        mesh: u32,
        /// Object (mesh) space to world.
        transform: Transform,
    },
}

impl Object {
    /// Whether the object is a closed solid, so that a ray leaving it
    /// through a back face was inside: see [`Shape::is_closed`]. A mesh
    /// instance is not known to be closed (that would have to be proven
    /// from its edges) and counts as open.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        match self {
            Self::Shape(s) => s.shape.is_closed(),
            Self::Mesh { .. } => false,
        }
    }
}

/// A hit on the scene: which object (and triangle) and the geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneHit {
    /// Index of the object in the list given to [`Accel::build`].
    pub object: u32,
    /// Triangle index within the mesh, or [`SceneHit::NO_TRIANGLE`] for
    /// analytic shapes.
    pub triangle: u32,
    /// World-space hit (normals outward, see [`Hit`]). For meshes, its uv
    /// is the interpolated vertex uv (or the barycentrics without uvs).
    pub hit: Hit,
}

impl SceneHit {
    /// The `triangle` value of hits on analytic shapes.
    pub const NO_TRIANGLE: u32 = u32::MAX;
}

/// A surface crossing met by [`Accel::for_each_crossing`]: which object,
/// how far and from which side, before its hit record is built
/// ([`Accel::crossing_hit`] builds it, the [`SceneHit`] that
/// [`Accel::for_each_hit`] reports).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Index of the object in the list given to [`Accel::build`].
    pub object: u32,
    /// Triangle index within the mesh, or [`SceneHit::NO_TRIANGLE`].
    pub triangle: u32,
    /// Ray parameter of the crossing.
    pub t: f32,
    /// Whether the ray arrives from the side the outward normal points to
    /// ([`Hit::front_face`] of the full hit).
    pub front_face: bool,
    /// How the full hit is found again.
    found: Found,
}

/// What [`Accel::crossing_hit`] needs to build a [`Crossing`]'s hit.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Found {
    /// An analytic shape, re-solved over `[t_min, t]`: its nearest crossing
    /// there is this one, bit for bit (prism-geometry's
    /// `Intersect::intersect_t` contract).
    Shape { t_min: f32 },
    /// A mesh triangle's hit in the mesh's object space.
    Mesh(Hit),
}

/// Figures about a built structure.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Wall time of the build in seconds.
    pub build_seconds: f64,
    /// Bytes held by the acceleration structures (not the meshes): nodes,
    /// primitive indices and the per-mesh triangle copies in BVH order.
    pub bvh_bytes: usize,
    /// Triangles stored (each mesh counted once).
    pub stored_triangles: usize,
    /// Triangles as seen by rays (each instance counted).
    pub instanced_triangles: usize,
    /// Nodes over all levels (top level plus one tree per mesh).
    pub bvh_nodes: usize,
    /// Objects kept out of the hierarchy and tested by every ray
    /// (infinite planes, and anything without finite bounds).
    pub unbounded_objects: usize,
}

/// Why a scene could not be accelerated.
#[derive(Debug, Clone, PartialEq)]
pub enum BuildError {
    /// An object names a mesh that was not supplied.
    NoSuchMesh {
        /// The object's index.
        object: usize,
        /// The mesh index it named.
        mesh: u32,
    },
    /// More bounded objects than the top level's references can hold
    /// (2²⁷ slots).
    TooManyObjects {
        /// How many there were.
        objects: usize,
    },
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoSuchMesh { object, mesh } => {
                write!(f, "object {object} names mesh {mesh}, which does not exist")
            }
            Self::TooManyObjects { objects } => {
                write!(f, "{objects} objects are more than the top-level hierarchy can hold")
            }
        }
    }
}

impl std::error::Error for BuildError {}

/// Build quality of a hierarchy: obvhs's presets, from fastest to build
/// to fastest to trace. The slow presets pre-split large triangles (a
/// triangle may then sit in several leaves; queries account for that).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// `BvhBuildParams::fastest_build`.
    Fastest,
    /// `BvhBuildParams::very_fast_build`.
    VeryFast,
    /// `BvhBuildParams::fast_build`.
    Fast,
    /// `BvhBuildParams::medium_build`.
    #[default]
    Medium,
    /// `BvhBuildParams::slow_build` (pre-splits triangles).
    Slow,
    /// `BvhBuildParams::very_slow_build` (pre-splits triangles).
    VerySlow,
}

impl BuildQuality {
    /// Every preset, fastest build first.
    pub const ALL: [Self; 6] =
        [Self::Fastest, Self::VeryFast, Self::Fast, Self::Medium, Self::Slow, Self::VerySlow];

    fn params(self) -> BvhBuildParams {
        match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::VeryFast => BvhBuildParams::very_fast_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
            Self::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }

    /// A short lower-case name (`"medium"`, `"very-slow"`, …).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Fastest => "fastest",
            Self::VeryFast => "very-fast",
            Self::Fast => "fast",
            Self::Medium => "medium",
            Self::Slow => "slow",
            Self::VerySlow => "very-slow",
        }
    }
}

/// Options for [`Accel::build_with`]; [`Accel::build`] uses the default.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Quality of each mesh's own hierarchy.
    pub mesh_quality: BuildQuality,
    /// Quality of the top-level hierarchy over objects.
    pub top_quality: BuildQuality,
    /// Node layout (and walk) of each mesh's own hierarchy.
    pub mesh_layout: BlasKind,
}

/// Node layout of a mesh's own hierarchy. All are walked by this crate's
/// own traversal (see the crate docs); the top level is always wide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlasKind {
    /// obvhs's compressed wide BVH: eight children per 80-byte node,
    /// quantised boxes, leaves of at most three triangles.
    Cwbvh,
    /// obvhs's binary BVH: two children, 48-byte nodes with full-precision
    /// boxes, leaves of up to the preset's `max_prims_per_leaf` triangles.
    Bvh2,
    /// A CPU-native wide BVH converted from obvhs's binary one: eight
    /// children per 256-byte node with full-precision SoA boxes, leaves of
    /// up to four triangles, node tests by the run-time [`Kernel`].
    Wide,
}

impl BlasKind {
    /// Every layout.
    pub const ALL: [Self; 3] = [Self::Cwbvh, Self::Bvh2, Self::Wide];

    /// A short lower-case name (`"cwbvh"`, `"bvh2"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Cwbvh => "cwbvh",
            Self::Bvh2 => "bvh2",
            Self::Wide => "wide",
        }
    }

    /// The layout named by the environment variable `PRISM_BVH_BLAS`
    /// (`cwbvh` or `bvh2`), if set to one of these: the default
    /// [`BuildOptions`] then use it, for comparisons from any front end.
    #[must_use]
    pub fn from_env() -> Option<Self> {
        let named = std::env::var("PRISM_BVH_BLAS").ok()?;
        Self::ALL.into_iter().find(|k| k.name() == named)
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            mesh_quality: DEFAULT_MESH_QUALITY,
            top_quality: BuildQuality::Medium,
            mesh_layout: BlasKind::from_env().unwrap_or(DEFAULT_MESH_LAYOUT),
        }
    }
}

/// Chosen by measurement (docs/benchmarks.md).
const DEFAULT_MESH_QUALITY: BuildQuality = BuildQuality::Medium;

/// Chosen by measurement (docs/benchmarks.md).
const DEFAULT_MESH_LAYOUT: BlasKind = BlasKind::Wide;

/// Objects whose bounds reach beyond this are tested outside the hierarchy
/// (the compressed node boxes cannot represent them well).
const MAX_BOUNDED_COORD: f32 = 1e18;

/// Rounding slack of a top-level box, in units of `f32::EPSILON` times the
/// box's largest coordinate and the transform's condition number.
const ROUNDING_ULPS: f32 = 32.0;

/// Widens an object's world box (its local box's transformed corners) by
/// the rounding of the ray's trip into object space: the object reports a
/// crossing of the mapped ray, which can lie a few ulps of the world
/// coordinates (scaled by how far the map stretches one axis against
/// another) outside the exact box. Without the slack a box of one object
/// could cull a grazing hit that brute force finds.
fn widen_for_rounding(b: Aabb, t: &Transform) -> Aabb {
    if b.is_empty() || !b.is_finite() {
        return b;
    }
    let norm = |m: prism_geometry::glam::Mat3A| {
        m.x_axis.abs().element_sum().max(m.y_axis.abs().element_sum()).max(m.z_axis.abs().element_sum())
    };
    let cond = norm(t.matrix().matrix3) * norm(t.inverse_matrix().matrix3);
    let scale = b.min.abs().max(b.max.abs()).max_element();
    let pad = Vec3::splat(scale * cond.max(1.0) * ROUNDING_ULPS * f32::EPSILON);
    Aabb::new(b.min - pad, b.max + pad)
}

/// The closest-hit walk over the top level's objects (`BRANCHLESS`: as
/// [`Blas::closest`]; `false` for a packet's rays).
struct ClosestObject<'a, const BRANCHLESS: bool, W: Walker> {
    accel: &'a Accel,
    ray: Ray,
    best: Best,
    /// How the meshes' walks reach their node tests ([`Walker`]).
    walker: W,
}

impl<const BRANCHLESS: bool, W: Walker> Visit for &mut ClosestObject<'_, BRANCHLESS, W> {
    #[inline(always)]
    fn visit(&mut self, slot: u32, br: &mut BoxRay) -> bool {
        let i = self.accel.tlas_objects[slot as usize];
        self.accel.closest_object_walked::<BRANCHLESS>(self.walker, i, &mut self.ray, &mut self.best, br);
        true
    }
}

/// The occlusion walk over the top level's objects.
struct AnyObject<'a, W: Walker> {
    accel: &'a Accel,
    ray: &'a Ray,
    hit: bool,
    /// As [`ClosestObject::walker`].
    walker: W,
}

impl<W: Walker> Visit for &mut AnyObject<'_, W> {
    const ANY: bool = true;

    #[inline(always)]
    fn visit(&mut self, slot: u32, _: &mut BoxRay) -> bool {
        self.hit =
            self.accel.object_occludes_by(self.walker, self.accel.tlas_objects[slot as usize], self.ray);
        !self.hit
    }
}

/// A packet's closest-hit walk over the top level's objects: a mesh
/// instance that several rays meet walks its hierarchy as a packet;
/// anything else is tested ray by ray, as [`ClosestObject`] does. Per ray
/// `k`: its interval so far in `rays[k]` and its best hit in `best[k]`
/// (flat arrays rather than a [`ClosestObject`] each: filling and moving
/// those measured as a fifth of a packet's time).
struct ClosestObjects<'v, 'a, const N: usize, L: MeshPackets> {
    accel: &'a Accel,
    lanes: L,
    rays: &'v mut [Ray; N],
    best: &'v mut [Best; N],
}

impl<const N: usize, L: MeshPackets> ClosestObjects<'_, '_, N, L> {
    /// Walks object `i`'s mesh `blas` with the gathered rays `dense` and
    /// keeps each hit (nearer than the ray's best, as the walk was bounded
    /// by its `t_max`).
    #[inline(always)]
    fn mesh_hits<const M: usize>(
        &mut self,
        i: u32,
        blas: &Blas,
        dense: &Dense<M>,
        fr: Option<&Frustum>,
        reach: &mut [f32],
    ) {
        dense.closest(self.lanes, blas, fr, |k, hit, dir| self.keep(i, k, hit, dir, reach));
    }

    /// Makes ray `k`'s mesh hit `(face, t, b1, b2)` on object `i` (its
    /// object-space direction `dir`) its best, and shortens its reach (in
    /// the top level's walk: `reach` is its row, see [`packet::narrow`]).
    #[inline(always)]
    fn keep(
        &mut self,
        i: u32,
        k: usize,
        (face, t, b1, b2): (u32, f32, f32, f32),
        dir: Vec3,
        reach: &mut [f32],
    ) {
        if let (Some(r), Some(best)) = (self.rays.get_mut(k), self.best.get_mut(k)) {
            r.t_max = t;
            *best = Best::Mesh { object: i, face, t, b1, b2, dir };
            packet::narrow(reach, k, t);
        }
    }

    /// [`Self::keep`] for each hit of a packet walk over object `i`'s
    /// mesh with the packet's own rays (their directions are the
    /// object-space ones: the instance's transform is the identity or a
    /// translation).
    #[inline(always)]
    fn keep_found(&mut self, i: u32, found: blas::Found<N>, reach: &mut [f32]) {
        for (k, hit) in found.into_iter().enumerate() {
            if let (Some(hit), Some(dir)) = (hit, self.rays.get(k).map(|r| r.dir)) {
                self.keep(i, k, hit, dir, reach);
            }
        }
    }

    /// Tests object `i` against the rays of `meet`: a mesh instance met
    /// by several rays as a packet, anything else ray by ray. Each closer
    /// hit becomes its ray's best and shortens the ray and its reach in
    /// `world` (the top level's walk, when there is one: its rows).
    #[inline(always)]
    fn object(&mut self, i: u32, meet: u64, mut world: Option<(&mut Soa<N>, &Frustum)>) {
        let accel = self.accel;
        if let Object::Mesh { mesh, transform } = &accel.objects[i as usize]
            && meet.count_ones() >= MIN_CLOSEST_INSTANCE_PACKET
        {
            let blas = &accel.blas[*mesh as usize];
            if let Some(offset) = transform.object_offset()
                && !fits_small::<N>(meet)
                && let Some((world, fr)) = world.as_mut()
            {
                // Placed by a translation alone: the walk's own rows,
                // moved (no gather; no reciprocals or frustum made again).
                let mut found = [None; N];
                let rows = Rows::Moved(Moved { world, fr, offset });
                self.lanes.closest(blas, self.rays, meet, rows, &mut found);
                self.keep_found(i, found, world.reach_mut());
                return;
            }
            let frame = world.as_ref().and_then(|(_, fr)| in_object_space(fr, transform));
            let reach: &mut [f32] = match world {
                Some((w, _)) => w.reach_mut(),
                None => &mut [],
            };
            if whole::<N>(transform, meet) {
                let mut found = [None; N];
                self.lanes.closest(blas, self.rays, meet, Rows::Made(frame.as_ref()), &mut found);
                self.keep_found(i, found, reach);
                return;
            }
            let rays = &*self.rays;
            let ray = |k: usize| rays.get(k).copied();
            if fits_small::<N>(meet) {
                let dense = Dense::<SMALL_PACKET>::new(transform, meet, ray);
                self.mesh_hits(i, blas, &dense, frame.as_ref(), reach);
            } else {
                let dense = Dense::<N>::new(transform, meet, ray);
                self.mesh_hits(i, blas, &dense, frame.as_ref(), reach);
            }
            return;
        }
        let reach: &mut [f32] = match world {
            Some((w, _)) => w.reach_mut(),
            None => &mut [],
        };
        for k in bits(meet) {
            if let (Some(r), Some(best)) = (self.rays.get_mut(k), self.best.get_mut(k)) {
                let t_max = r.t_max;
                accel.closest_object::<false>(i, r, best);
                if r.t_max != t_max {
                    packet::narrow(reach, k, r.t_max);
                }
            }
        }
    }
}

impl<const N: usize, L: MeshPackets> Leaf<N> for ClosestObjects<'_, '_, N, L> {
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, meet: u64, soa: &mut Soa<N>, fr: &Frustum) -> u64 {
        for slot in first..first + count {
            self.object(self.accel.tlas_objects[slot as usize], meet, Some((&mut *soa, fr)));
        }
        0
    }
}

/// A top-level walk's frustum `fr` as it bounds its rays in the object
/// space of an instance under `transform`: as it is under the identity,
/// moved under a translation alone ([`Frustum::moved`]), and `None` under
/// any other map (which turns the directions; the instance's walk then
/// plans its own).
#[inline(always)]
fn in_object_space(fr: &Frustum, transform: &Transform) -> Option<Frustum> {
    if transform.is_identity() { Some(*fr) } else { transform.object_offset().map(|offset| fr.moved(offset)) }
}

/// Fewer rays of a closest-hit packet than this that meet a mesh
/// instance walk it one by one. A packet's incoherent rays (each from
/// its own origin, in unrelated directions) reach most instances in
/// small groups, whose packet set-up cost more than their walks shared:
/// 16 against [`MIN_PACKET`] (4) measured +10 % on the grid's incoherent
/// packets (the Embree peer's rays; +5 % on issue 7's), camera packets
/// level. Occlusion packets keep [`MIN_PACKET`]: their shadow rays lost
/// 1–5 % at 8–24 (docs/benchmarks.md, "Instances met by few rays of a
/// closest-hit packet").
const MIN_CLOSEST_INSTANCE_PACKET: u32 = 16;

/// Whether the rays of `meet` (of a packet of capacity `N`) go to a
/// [`Dense`] packet of [`SMALL_PACKET`] slots rather than of `N`.
#[inline(always)]
fn fits_small<const N: usize>(meet: u64) -> bool {
    N > SMALL_PACKET && meet.count_ones() as usize <= SMALL_PACKET
}

/// Whether a mesh instance met by the rays of `meet` takes the packet's
/// rays as they are: every one of its `N` rays meets it and its transform
/// is the identity, so the rays are already dense and in object space. A
/// gather ([`Dense`]) would copy them unchanged (a scene of one mesh
/// placed as it is: every full camera and shadow packet).
#[inline(always)]
fn whole<const N: usize>(transform: &Transform, meet: u64) -> bool {
    meet.count_ones() as usize == N && transform.is_identity()
}

/// A packet slot's ray where it holds none: no walk reads it (it is
/// not in the packet's mask). Filled in first and then overwritten, not
/// chosen per slot in `std::array::from_fn`: that compiled into copies
/// whose loads straddled earlier stores and stalled (docs/benchmarks.md,
/// "Issue 11: a ray's halves").
const PLACEHOLDER: Ray = Ray { origin: Vec3::ZERO, t_min: 0.0, dir: Vec3::X, t_max: f32::INFINITY };

/// The rays of a packet that meet a mesh instance, gathered to the front
/// of a packet of capacity `M` (a small one when few rays meet it, which
/// is cheaper to set up) in the instance's object space: `ids[j]` is the
/// index in the whole packet of ray `j`. A mesh packet gives each ray the
/// hit it gives alone, whichever rays share the packet (tests/packets.rs),
/// so gathering changes no answer.
struct Dense<const M: usize> {
    local: [Ray; M],
    ids: [u8; M],
    len: usize,
}

impl<const M: usize> Dense<M> {
    /// The rays of `meet` (`ray(k)` gives ray `k`), at most `M` of them.
    #[inline(always)]
    fn new(transform: &Transform, meet: u64, ray: impl Fn(usize) -> Option<Ray>) -> Self {
        let mut ids = [0u8; M];
        let mut len = 0;
        for k in bits(meet) {
            if let Some(id) = ids.get_mut(len) {
                *id = k as u8;
                len += 1;
            }
        }
        let mut local = [PLACEHOLDER; M];
        for (l, &id) in local.iter_mut().zip(&ids[..len.min(M)]) {
            if let Some(r) = ray(usize::from(id)) {
                *l = transform.ray_to_object(&r);
            }
        }
        Self { local, ids, len }
    }

    /// The mask of the gathered rays.
    #[inline(always)]
    fn mask(&self) -> u64 {
        if self.len >= 64 { u64::MAX } else { (1u64 << self.len) - 1 }
    }

    /// The mesh hits: `f(k, hit, dir)` for each hit ray, with its index
    /// `k` in the whole packet, the hit `(face, t, b1, b2)` and its
    /// object-space direction. A callback, not an iterator: an iterator
    /// owning the hits and the rays was built by copying them (`memcpy`,
    /// about 1.4 % of the grid's camera-packet instructions).
    #[inline(always)]
    fn closest(
        &self,
        lanes: impl MeshPackets,
        blas: &Blas,
        fr: Option<&Frustum>,
        mut f: impl FnMut(usize, (u32, f32, f32, f32), Vec3),
    ) {
        let mut found = [None; M];
        lanes.closest(blas, &self.local, self.mask(), Rows::Made(fr), &mut found);
        for ((hit, &id), ray) in found.iter().zip(&self.ids).zip(&self.local).take(self.len) {
            if let Some(hit) = *hit {
                f(usize::from(id), hit, ray.dir);
            }
        }
    }

    /// The occluded rays, as a mask over the whole packet.
    #[inline(always)]
    fn occluded(&self, lanes: impl MeshPackets, blas: &Blas, fr: Option<&Frustum>) -> u64 {
        let hit = lanes.occluded(blas, &self.local, self.mask(), Rows::Made(fr));
        bits(hit).fold(0, |m, j| m | self.ids.get(j).map_or(0, |&k| 1u64 << k))
    }
}

/// A packet's occlusion walk over the top level's objects (a mesh instance
/// met by several rays is walked as a packet); collects the occluded rays.
struct AnyObjects<'a, const N: usize, L: MeshPackets> {
    accel: &'a Accel,
    lanes: L,
    rays: &'a [Ray],
    done: u64,
}

impl<const N: usize, L: MeshPackets> AnyObjects<'_, N, L> {
    /// The rays of `meet` that object `i` occludes: a mesh instance met by
    /// several rays tests them as a packet, anything else ray by ray.
    #[inline(always)]
    fn object(&self, i: u32, meet: u64, world: Option<(&Soa<N>, &Frustum)>) -> u64 {
        let (accel, rays) = (self.accel, self.rays);
        match &accel.objects[i as usize] {
            Object::Mesh { mesh, transform } if meet.count_ones() >= MIN_PACKET => {
                let blas = &accel.blas[*mesh as usize];
                if let (Some(offset), false, Some((world, fr)), Ok(rays)) =
                    (transform.object_offset(), fits_small::<N>(meet), world, <&[Ray; N]>::try_from(rays))
                {
                    // Placed by a translation alone: as `ClosestObjects`.
                    return self.lanes.occluded(blas, rays, meet, Rows::Moved(Moved { world, fr, offset }));
                }
                let frame = world.and_then(|(_, fr)| in_object_space(fr, transform));
                if let (true, Ok(rays)) = (whole::<N>(transform, meet), <&[Ray; N]>::try_from(rays)) {
                    return self.lanes.occluded(blas, rays, meet, Rows::Made(frame.as_ref()));
                }
                let ray = |k: usize| rays.get(k).copied();
                if fits_small::<N>(meet) {
                    Dense::<SMALL_PACKET>::new(transform, meet, ray).occluded(
                        self.lanes,
                        blas,
                        frame.as_ref(),
                    )
                } else {
                    Dense::<N>::new(transform, meet, ray).occluded(self.lanes, blas, frame.as_ref())
                }
            }
            _ => bits(meet)
                .filter(|&k| rays.get(k).is_some_and(|r| accel.object_occludes(i, r)))
                .fold(0, |m, k| m | 1 << k),
        }
    }
}

impl<const N: usize, L: MeshPackets> Leaf<N> for &mut AnyObjects<'_, N, L> {
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, meet: u64, soa: &mut Soa<N>, fr: &Frustum) -> u64 {
        let mut hit = 0u64;
        for slot in first..first + count {
            hit |= self.object(self.accel.tlas_objects[slot as usize], meet & !hit, Some((&*soa, fr)));
        }
        self.done |= hit;
        hit
    }
}

/// The best hit so far during a closest-hit query (world hits are made
/// only once, for the winner).
#[derive(Clone, Copy)]
enum Best {
    None,
    Shape { object: u32, hit: Hit },
    Mesh { object: u32, face: u32, t: f32, b1: f32, b2: f32, dir: Vec3 },
}

/// What a closest-hit query finds before any hit record is built: the
/// object, and for a mesh the triangle, `t` and barycentrics (for an
/// analytic shape, whose test builds its hit anyway, that hit). As
/// Embree's `RTCHit`, it is enough to count hits or read distances;
/// [`Accel::resolve`] builds the full [`SceneHit`] (point, interpolated
/// normal and uv, in world space) that shading needs.
#[derive(Clone, Copy)]
pub struct HitRecord(Best);

impl HitRecord {
    /// The hit object's index (as [`SceneHit::object`]).
    #[must_use]
    pub fn object(&self) -> u32 {
        match self.0 {
            Best::Shape { object, .. } | Best::Mesh { object, .. } => object,
            Best::None => u32::MAX,
        }
    }

    /// The ray parameter of the hit.
    #[must_use]
    pub fn t(&self) -> f32 {
        match self.0 {
            Best::Shape { hit, .. } => hit.t,
            Best::Mesh { t, .. } => t,
            Best::None => f32::INFINITY,
        }
    }

    /// The hit triangle of a mesh (as [`SceneHit::triangle`]), `None` for
    /// an analytic shape.
    #[must_use]
    pub fn triangle(&self) -> Option<u32> {
        match self.0 {
            Best::Mesh { face, .. } => Some(face),
            _ => None,
        }
    }
}

impl std::fmt::Debug for HitRecord {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HitRecord")
            .field("object", &self.object())
            .field("triangle", &self.triangle())
            .field("t", &self.t())
            .finish()
    }
}

impl Best {
    /// The record of a hit, `None` for no hit.
    #[inline(always)]
    fn record(self) -> Option<HitRecord> {
        match self {
            Best::None => None,
            b => Some(HitRecord(b)),
        }
    }
}

/// The acceleration structure over a whole scene.
#[derive(Debug)]
pub struct Accel {
    meshes: Vec<Arc<TriangleMesh>>,
    objects: Vec<Object>,
    bounds: Aabb,
    stats: BuildStats,
    blas: Vec<Blas>,
    /// The top level: a wide BVH over the bounded objects' world boxes.
    tlas: WideBvh,
    tlas_depth: usize,
    /// Object index of each top-level slot.
    tlas_objects: Vec<u32>,
    /// Objects tested outside the hierarchy.
    unbounded: Vec<u32>,
    /// The top level's object when it holds exactly one (a single model,
    /// perhaps over an unbounded floor): single-ray queries (crossings
    /// too) and occlusion packets test it directly, without walking the
    /// top level, whose one box its own hierarchy's root repeats.
    /// Closest-hit packets still walk it: camera packets often miss the
    /// object, and that one box test culls them before they are gathered
    /// into object space (going straight to the object measured 14-21 %
    /// slower on them, docs/benchmarks.md).
    sole: Option<u32>,
    /// Per object: an analytic shape whose transform is the identity (it
    /// is then tested in world space directly, see [`Accel::shape_hit`]).
    identity: Vec<bool>,
    /// Which compiled variant of the queries this CPU runs.
    simd: Simd,
    /// Some top-level slot is a mesh instance: only then do packets pay
    /// (analytic shapes are tested ray by ray either way).
    packets: bool,
}

/// The CPU features the queries may use, detected once per build.
#[derive(Clone, Copy, Debug)]
struct Simd {
    /// AVX2, FMA, BMI1/2, LZCNT and POPCNT: `closest_best_wide` and
    /// `closest_packets_wide`/`occluded_packets_wide` (compiled with these
    /// features) may run.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    wide: bool,
    /// The wide trees' kernel is [`Kernel::Avx512`] (so the CPU has it):
    /// `closest_best_avx512` and `occluded_avx512` run.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx512: bool,
}

impl Simd {
    /// What this CPU has, with `kernel` the structure's node-test kernel
    /// (`avx512` only where the CPU runs that kernel, whoever picked it:
    /// the unsafe calls it gates rely on it).
    fn detect(kernel: Kernel) -> Self {
        #[cfg(target_arch = "x86_64")]
        let wide = std::env::var_os("PRISM_BVH_NO_SIMD").is_none()
            && is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("popcnt");
        #[cfg(not(target_arch = "x86_64"))]
        let wide = false;
        Self { wide, avx512: kernel == Kernel::Avx512 && kernel.supported() }
    }
}

/// Whether a query ray can hit anything at all (finite, non-zero direction).
/// The six components are tested as two vectors without branches. A
/// packet tests all its rays first, and the component-by-component
/// `is_finite` chain had 8 % of a kitchen shadow-packet run's samples
/// (perf); this form cut the packet queries' instructions by 3 %
/// (callgrind). Read as the ray's two 16-byte halves (one load each, the
/// fourth lanes masked off) rather than built from three scalars each, it
/// takes 5 fewer instructions a ray (callgrind, kitchen packets). Much of
/// what perf still charges here is the rays' memory arriving: this is the
/// first pass to read them.
#[inline(always)]
fn usable(ray: &Ray) -> bool {
    let (o, d) = traverse::halves(ray);
    let finite = (o.is_finite_mask() & d.is_finite_mask()).bitmask() & 7 == 7;
    finite & (d.cmpne(Vec4::ZERO).bitmask() & 7 != 0) & (ray.t_min <= ray.t_max)
}

impl Accel {
    /// Builds the structure over `objects`, whose mesh instances index
    /// `meshes`, with the default [`BuildOptions`].
    ///
    /// # Errors
    /// [`BuildError::NoSuchMesh`] if an object names a missing mesh.
    pub fn build(meshes: Vec<Arc<TriangleMesh>>, objects: Vec<Object>) -> Result<Self, BuildError> {
        Self::build_with(meshes, objects, BuildOptions::default())
    }

    /// Builds the structure with explicit options.
    ///
    /// # Errors
    /// [`BuildError::NoSuchMesh`] if an object names a missing mesh.
    pub fn build_with(
        meshes: Vec<Arc<TriangleMesh>>,
        objects: Vec<Object>,
        options: BuildOptions,
    ) -> Result<Self, BuildError> {
        let start = std::time::Instant::now();
        let mut bounds = Aabb::EMPTY;
        let mut instanced = 0;
        let mut used = vec![false; meshes.len()];
        let mut object_bounds = Vec::with_capacity(objects.len());
        let mesh_bounds: Vec<Aabb> = meshes.par_iter().map(|m| m.bounds()).collect();
        for (i, o) in objects.iter().enumerate() {
            let b = match o {
                Object::Shape(s) => {
                    if s.shape.is_bounded() {
                        s.bounds()
                    } else {
                        Aabb::INFINITE
                    }
                }
                Object::Mesh { mesh, transform } => {
                    let m = meshes
                        .get(*mesh as usize)
                        .ok_or(BuildError::NoSuchMesh { object: i, mesh: *mesh })?;
                    used[*mesh as usize] = true;
                    instanced += m.len();
                    transform.aabb(&mesh_bounds[*mesh as usize])
                }
            };
            if b.is_finite() && !b.is_empty() {
                bounds = bounds.union(b);
            }
            object_bounds.push(b);
        }
        // One hierarchy per mesh that some object uses, in parallel.
        let kernel = Kernel::detect();
        let blas: Vec<Blas> = meshes
            .par_iter()
            .zip(used.par_iter())
            .map(|(m, &u)| {
                if u {
                    Blas::build(m, options.mesh_quality, options.mesh_layout, kernel)
                } else {
                    Blas::default()
                }
            })
            .collect();
        let mut unbounded = Vec::new();
        let mut top = Vec::new();
        let mut tlas_boxes = Vec::new();
        for (i, (o, b)) in objects.iter().zip(&object_bounds).enumerate() {
            if let Object::Mesh { mesh, .. } = o
                && blas[*mesh as usize].is_empty()
            {
                continue; // Nothing to hit.
            }
            if b.is_empty() {
                continue;
            }
            let finite = b.is_finite() && b.min.abs().max(b.max.abs()).max_element() <= MAX_BOUNDED_COORD;
            if finite {
                let transform = match o {
                    Object::Shape(s) => &s.transform,
                    Object::Mesh { transform, .. } => transform,
                };
                let b = widen_for_rounding(*b, transform);
                top.push(i as u32);
                tlas_boxes.push(cwbvh::to_obvhs(b.min, b.max));
            } else {
                unbounded.push(i as u32);
            }
        }
        // Leaves of one object: an object test (a transformed shape or a
        // whole instance walk) costs far more than a box test, so each
        // object gets its own box. Leaves of up to four measured 10-20 %
        // slower on the seed scene, mesh.toml and an instance grid
        // (docs/benchmarks.md, "Top-level leaves of one object").
        let (tlas, _) = WideBvh::build(tlas_boxes, None, options.top_quality, 1, kernel)
            .ok_or(BuildError::TooManyObjects { objects: top.len() })?;
        let tlas_objects: Vec<u32> = tlas.order().iter().map(|&k| top[k as usize]).collect();
        let packets = tlas_objects.iter().any(|&i| matches!(objects[i as usize], Object::Mesh { .. }));
        let stats = BuildStats {
            build_seconds: start.elapsed().as_secs_f64(),
            bvh_bytes: tlas.bytes()
                + std::mem::size_of::<u32>() * (top.len() + unbounded.len())
                + blas.iter().map(Blas::bytes).sum::<usize>(),
            stored_triangles: meshes.iter().map(|m| m.len()).sum(),
            instanced_triangles: instanced,
            bvh_nodes: tlas.node_count() + blas.iter().map(Blas::node_count).sum::<usize>(),
            unbounded_objects: unbounded.len(),
        };
        let objects_identity = objects
            .iter()
            .map(|o| matches!(o, Object::Shape(s) if s.transform == Transform::IDENTITY))
            .collect();
        Ok(Self {
            meshes,
            objects,
            bounds,
            stats,
            blas,
            tlas_depth: tlas.stack_need(),
            tlas,
            // `top`, not `tlas_objects`: that repeats an object in padding slots.
            sole: match top[..] {
                [i] => Some(i),
                _ => None,
            },
            tlas_objects,
            unbounded,
            identity: objects_identity,
            simd: Simd::detect(kernel),
            packets,
        })
    }

    /// The objects, in the order given.
    #[must_use]
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The meshes, in the order given.
    #[must_use]
    pub fn meshes(&self) -> &[Arc<TriangleMesh>] {
        &self.meshes
    }

    /// Selects the node-test [`Kernel`] of the wide hierarchies (the
    /// default is [`Kernel::detect`]'s); refused (`false`, nothing changed)
    /// when this CPU cannot run it. All kernels give the same answers; this
    /// is for comparing them.
    pub fn set_kernel(&mut self, kernel: Kernel) -> bool {
        if !kernel.supported() {
            return false;
        }
        let set = self.tlas.set_kernel(kernel) && self.blas.iter_mut().all(|b| b.set_kernel(kernel));
        self.simd.avx512 = set && kernel == Kernel::Avx512;
        set
    }

    /// Bounds of every bounded object (infinite planes excluded).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Build figures.
    #[must_use]
    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    /// The world-space hit of analytic object `i` (`s`): `s.intersect(ray)`,
    /// without mapping the ray and the hit when the transform is the
    /// identity. The normals are still re-normalised as
    /// [`Transform::hit_to_world`] does, so the hit is the same bit for bit
    /// (the identity products are exact; only the sign of a zero
    /// coordinate could differ).
    #[inline(always)]
    fn shape_hit(&self, i: u32, s: &Instance<Shape>, ray: &Ray) -> Option<Hit> {
        if self.identity[i as usize] {
            let h = s.shape.intersect(ray)?;
            let geo_normal = h.geo_normal.normalize_or(h.geo_normal);
            let normal = if h.normal == h.geo_normal { geo_normal } else { h.normal.normalize_or(h.normal) };
            Some(Hit { geo_normal, normal, ..h })
        } else {
            s.intersect(ray)
        }
    }

    /// `t` of the hit of analytic object `i` (`s`); see [`Accel::shape_hit`].
    #[inline(always)]
    fn shape_t(&self, i: u32, s: &Instance<Shape>, ray: &Ray) -> Option<f32> {
        if self.identity[i as usize] { s.shape.intersect_t(ray) } else { s.intersect_t(ray) }
    }

    /// Tests object `i` against `ray`; on a hit closer than `ray.t_max`,
    /// records it in `best` and shrinks `ray.t_max`. `BRANCHLESS`: as
    /// [`Blas::closest`] (`true` for single-ray queries, `false` for a
    /// packet's rays).
    #[inline(always)]
    fn closest_object<const BRANCHLESS: bool>(&self, i: u32, ray: &mut Ray, best: &mut Best) {
        self.closest_object_by::<BRANCHLESS>(Dispatch, i, ray, best);
    }

    /// [`Accel::closest_object`], a mesh walked through `walker`
    /// ([`Walker`]).
    #[inline(always)]
    fn closest_object_by<const BRANCHLESS: bool>(
        &self,
        walker: impl Walker,
        i: u32,
        ray: &mut Ray,
        best: &mut Best,
    ) {
        match &self.objects[i as usize] {
            Object::Shape(s) => {
                // The full hit at once, not `intersect_t` and the winner's
                // hit again at the end: in the seed scene a query meets ~1.5
                // analytic candidates, so re-solving the winner costs more
                // than the losers' hit records (measured, docs/benchmarks.md).
                if let Some(hit) = self.shape_hit(i, s, ray) {
                    ray.t_max = hit.t;
                    *best = Best::Shape { object: i, hit };
                }
            }
            Object::Mesh { mesh, transform } => {
                let local = transform.ray_to_object(ray);
                if let Some((face, t, b1, b2)) =
                    self.blas[*mesh as usize].closest_by::<BRANCHLESS>(walker, &local)
                {
                    ray.t_max = t;
                    *best = Best::Mesh { object: i, face, t, b1, b2, dir: local.dir };
                }
            }
        }
    }

    /// [`Accel::closest_object`] inside a walk: a closer hit also narrows
    /// the walk's box ray `br`.
    #[inline(always)]
    fn closest_object_walked<const BRANCHLESS: bool>(
        &self,
        walker: impl Walker,
        i: u32,
        ray: &mut Ray,
        best: &mut Best,
        br: &mut BoxRay,
    ) {
        let t_max = ray.t_max;
        self.closest_object_by::<BRANCHLESS>(walker, i, ray, best);
        if ray.t_max != t_max {
            br.set_t_max(ray.t_max);
        }
    }

    /// The full hit of a record that [`Accel::closest_record`] or
    /// [`Accel::closest_record_packet`] of this structure returned. A
    /// record of another structure gives `None` where its object or
    /// triangle does not exist here (it never panics), and otherwise a
    /// hit that means nothing.
    #[must_use]
    pub fn resolve(&self, record: HitRecord) -> Option<SceneHit> {
        if let Best::Mesh { object, face, .. } = record.0 {
            let Some(Object::Mesh { mesh, .. }) = self.objects.get(object as usize) else { return None };
            if self.meshes.get(*mesh as usize).is_none_or(|m| face as usize >= m.len()) {
                return None;
            }
        }
        self.finish(record.0)
    }

    #[inline(always)]
    fn finish(&self, best: Best) -> Option<SceneHit> {
        match best {
            Best::None => None,
            Best::Shape { object, hit } => Some(SceneHit { object, triangle: SceneHit::NO_TRIANGLE, hit }),
            Best::Mesh { object, face, t, b1, b2, dir } => {
                let Object::Mesh { mesh, transform } = &self.objects[object as usize] else {
                    return None;
                };
                let local = self.meshes[*mesh as usize].hit(face as usize, t, b1, b2, dir);
                Some(SceneHit { object, triangle: face, hit: transform.hit_to_world(&local) })
            }
        }
    }

    /// The nearest hit in `[ray.t_min, ray.t_max]`.
    ///
    /// Rays with a zero or non-finite direction or origin hit nothing.
    #[must_use]
    pub fn closest_hit(&self, ray: &Ray) -> Option<SceneHit> {
        self.finish(self.closest_dispatch(ray))
    }

    /// What [`Accel::closest_hit`] finds, before its [`SceneHit`] is built
    /// ([`Accel::resolve`] builds it): for queries that need only the
    /// object and distance, as Embree's `rtcIntersect1` gives.
    #[must_use]
    pub fn closest_record(&self, ray: &Ray) -> Option<HitRecord> {
        self.closest_dispatch(ray).record()
    }

    /// The closest-hit walk, compiled for AVX2 where the CPU has it, and
    /// for AVX-512 with the walks inline where the structure's kernel is
    /// AVX-512.
    #[inline(always)]
    fn closest_dispatch(&self, ray: &Ray) -> Best {
        #[cfg(target_arch = "x86_64")]
        if self.simd.wide {
            if self.simd.avx512 {
                // SAFETY: `avx512` is set only where the running CPU
                // reports every feature `closest_best_avx512` is compiled
                // for (the AVX-512 kernel's, `Kernel::supported`).
                return unsafe { self.closest_best_avx512(ray) };
            }
            // SAFETY: `wide` is set only when the running CPU reports
            // every feature `closest_best_wide` is compiled for.
            return unsafe { self.closest_best_wide(ray) };
        }
        self.closest_best(Dispatch, ray)
    }

    /// [`Accel::closest_best`] compiled for AVX2 (8-wide node tests).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_best_wide(&self, ray: &Ray) -> Best {
        self.closest_best(Dispatch, ray)
    }

    /// [`Accel::closest_best`] compiled for AVX-512, with the wide trees'
    /// walks compiled into it ([`wide::x86::InAvx512`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl")]
    fn closest_best_avx512(&self, ray: &Ray) -> Best {
        // SAFETY: this function runs only where the CPU has AVX-512 F and
        // VL and AVX2 (its callers' contract, by its features).
        self.closest_best(unsafe { wide::x86::InAvx512::new() }, ray)
    }

    #[inline(always)]
    fn closest_best(&self, walker: impl Walker, ray: &Ray) -> Best {
        if !usable(ray) {
            return Best::None;
        }
        let mut v = ClosestObject::<true, _> { accel: self, ray: *ray, best: Best::None, walker };
        for &i in &self.unbounded {
            self.closest_object_by::<true>(walker, i, &mut v.ray, &mut v.best);
        }
        if let Some(i) = self.sole {
            self.closest_object_by::<true>(walker, i, &mut v.ray, &mut v.best);
            return v.best;
        }
        let mut br = BoxRay::new(&v.ray);
        walk_any_by(walker, &self.tlas, self.tlas_depth, &mut br, &mut v);
        v.best
    }

    #[inline(always)]
    fn object_occludes(&self, i: u32, ray: &Ray) -> bool {
        self.object_occludes_by(Dispatch, i, ray)
    }

    /// [`Accel::object_occludes`], a mesh walked through `walker`
    /// ([`Walker`]).
    #[inline(always)]
    fn object_occludes_by(&self, walker: impl Walker, i: u32, ray: &Ray) -> bool {
        match &self.objects[i as usize] {
            // `t` only: no hit record (prism-geometry's `intersect_t`).
            Object::Shape(s) => self.shape_t(i, s, ray).is_some(),
            Object::Mesh { mesh, transform } => {
                self.blas[*mesh as usize].occluded_by(walker, &transform.ray_to_object(ray))
            }
        }
    }

    /// Whether anything lies in `[ray.t_min, ray.t_max]` (early exit).
    ///
    /// Compiled for the baseline target where the kernel is AVX2 or
    /// portable: an AVX2 build of it, as [`Accel::closest_hit`] has,
    /// measured 5-13 % slower on shadow rays (docs/benchmarks.md, "AVX2
    /// builds of the queries"). Where the structure's kernel is AVX-512, a
    /// build compiled for AVX-512 with the walks inline runs instead, as
    /// for `closest_hit` (kitchen shadow rays +9.5 %, the bunny's and the
    /// grid's level).
    #[must_use]
    pub fn occluded(&self, ray: &Ray) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.simd.wide && self.simd.avx512 {
            // SAFETY: `avx512` is set only where the running CPU reports
            // every feature `occluded_avx512` is compiled for.
            return unsafe { self.occluded_avx512(ray) };
        }
        self.occluded_impl(Dispatch, ray)
    }

    /// [`Accel::occluded_impl`] compiled for AVX-512, the wide trees'
    /// walks compiled into it ([`wide::x86::InAvx512`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl")]
    fn occluded_avx512(&self, ray: &Ray) -> bool {
        // SAFETY: this function runs only where the CPU has AVX-512 F and
        // VL and AVX2 (its callers' contract, by its features).
        self.occluded_impl(unsafe { wide::x86::InAvx512::new() }, ray)
    }

    #[inline(always)]
    fn occluded_impl(&self, walker: impl Walker, ray: &Ray) -> bool {
        if !usable(ray) {
            return false;
        }
        if self.unbounded.iter().any(|&i| self.object_occludes_by(walker, i, ray)) {
            return true;
        }
        if let Some(i) = self.sole {
            return self.object_occludes_by(walker, i, ray);
        }
        let mut br = BoxRay::new(ray);
        let mut v = AnyObject { accel: self, ray, hit: false, walker };
        walk_any_by(walker, &self.tlas, self.tlas_depth, &mut br, &mut v);
        v.hit
    }

    /// Whether the packet queries walk packets here (the scene has mesh
    /// instances); otherwise they trace ray by ray, and a caller may as
    /// well not gather its rays.
    #[must_use]
    pub fn packets_pay(&self) -> bool {
        self.packets
    }

    /// [`Accel::closest_hit`] for each of `rays`, into the same index of
    /// `out` (as many as the shorter of the two holds), tracing up to
    /// [`PACKET_SIZE`] rays at a time together: for coherent rays such as
    /// the camera rays of neighbouring pixels. The hits are the ones
    /// `closest_hit` gives ray by ray (the tests compare them), whatever
    /// the rays. Batches of incoherent rays from neighbouring points pay
    /// too: eight hemisphere rays from each of eight neighbouring hit
    /// points measured 35 % faster this way than ray by ray on the bunny,
    /// 19 % on the kitchen and 12 % over a grid of instances
    /// (docs/benchmarks.md, "Incoherent packets walked whole"), as a
    /// node's memory serves every ray that reaches it while each ray's
    /// own node test runs. A scene without
    /// mesh instances is traced ray by ray: its analytic shapes are tested
    /// per ray anyway, and the packet's bookkeeping measured slower there.
    pub fn closest_hit_packet(&self, rays: &[Ray], out: &mut [Option<SceneHit>]) {
        self.closest_packets(rays, out, |best| self.finish(best));
    }

    /// [`Accel::closest_record`] for each of `rays`, traced together as
    /// [`Accel::closest_hit_packet`] traces them.
    pub fn closest_record_packet(&self, rays: &[Ray], out: &mut [Option<HitRecord>]) {
        self.closest_packets(rays, out, Best::record);
    }

    /// The packet queries' common part: `done` makes each ray's answer.
    #[inline(always)]
    fn closest_packets<T>(&self, rays: &[Ray], out: &mut [Option<T>], done: impl Fn(Best) -> Option<T>) {
        if !self.packets {
            for (r, o) in rays.iter().zip(out) {
                *o = done(self.closest_dispatch(r));
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if self.simd.wide {
            // SAFETY: `wide` is set only when the running CPU reports
            // every feature `closest_packets_wide` is compiled for.
            return unsafe { self.closest_packets_wide(rays, out, &done) };
        }
        self.closest_packet_chunks(rays, out, &done);
    }

    /// [`Accel::closest_packet_chunks`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_packets_wide<T>(
        &self,
        rays: &[Ray],
        out: &mut [Option<T>],
        done: &impl Fn(Best) -> Option<T>,
    ) {
        // SAFETY: this function is compiled for AVX2 and, by its callers'
        // contract, runs only where the CPU has it.
        let lanes = unsafe { packet::x86::Avx2::new() };
        self.closest_packet_chunks_in(lanes, rays, out, done);
    }

    /// The packet queries' plain build.
    #[inline(always)]
    fn closest_packet_chunks<T>(
        &self,
        rays: &[Ray],
        out: &mut [Option<T>],
        done: &impl Fn(Best) -> Option<T>,
    ) {
        self.closest_packet_chunks_in(packet::Portable, rays, out, done);
    }

    #[inline(always)]
    fn closest_packet_chunks_in<T>(
        &self,
        lanes: impl MeshPackets,
        rays: &[Ray],
        out: &mut [Option<T>],
        done: &impl Fn(Best) -> Option<T>,
    ) {
        for (rays, out) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
            if rays.len() <= SMALL_PACKET {
                self.closest_packet_impl::<SMALL_PACKET, T>(lanes, rays, out, done);
            } else {
                self.closest_packet_impl::<PACKET_SIZE, T>(lanes, rays, out, done);
            }
        }
    }

    /// One packet of at most `N` rays (see [`crate::packet`]).
    #[inline(always)]
    fn closest_packet_impl<const N: usize, T>(
        &self,
        lanes: impl MeshPackets,
        rays: &[Ray],
        out: &mut [Option<T>],
        done: &impl Fn(Best) -> Option<T>,
    ) {
        let mut mask = 0u64;
        for (k, r) in rays.iter().enumerate().take(N) {
            mask |= u64::from(usable(r)) << k;
        }
        if self.unbounded.is_empty()
            && let Some(i) = self.sole
            && let Object::Mesh { mesh, transform } = &self.objects[i as usize]
            && whole::<N>(transform, mask)
            && let Ok(rays) = <&[Ray; N]>::try_from(rays)
        {
            // One mesh placed as it is, met by the whole packet, and
            // nothing before it: its packet walk takes the rays as they
            // are, and its hits are the answers (a scene of one model,
            // such as `prism render model.obj`).
            let mut found = [None; N];
            lanes.closest(&self.blas[*mesh as usize], rays, mask, Rows::Made(None), &mut found);
            for ((o, f), r) in out.iter_mut().zip(found).zip(rays) {
                *o = f.and_then(|(face, t, b1, b2)| {
                    done(Best::Mesh { object: i, face, t, b1, b2, dir: r.dir })
                });
            }
            return;
        }
        let mut best = [Best::None; N];
        let mut live = [PLACEHOLDER; N];
        for (l, r) in live.iter_mut().zip(rays) {
            // Copied whether usable or not: only the rays of `mask` are read.
            *l = *r;
        }
        if !self.unbounded.is_empty() {
            for k in bits(mask) {
                for &i in &self.unbounded {
                    self.closest_object::<false>(i, &mut live[k], &mut best[k]);
                }
            }
        }
        if let Some(i) = self.sole {
            // One object on the top level: its walk would reach only it
            // (as `occluded_packet_impl` and the single-ray queries).
            ClosestObjects { accel: self, lanes, rays: &mut live, best: &mut best }.object(i, mask, None);
        } else {
            self.closest_packet_walk(lanes, &mut live, &mut best, mask);
        }
        for (k, o) in out.iter_mut().enumerate().take(rays.len().min(N)) {
            *o = if mask >> k & 1 == 1 { done(best[k]) } else { None };
        }
    }

    /// The top-level walk of [`Accel::closest_packet_impl`]'s rays of
    /// `mask`: each closer hit goes to the ray's `best`.
    #[inline(always)]
    fn closest_packet_walk<const N: usize>(
        &self,
        lanes: impl MeshPackets,
        live: &mut [Ray; N],
        best: &mut [Best; N],
        mask: u64,
    ) {
        let mut soa = Soa::<N>::empty(mask);
        soa.fill(&live[..], mask);
        for &(m, fr) in &packet::plan(&soa, mask) {
            match fr {
                Some(fr) => self.tlas.walk_packet::<false, N>(
                    lanes,
                    self.tlas_depth,
                    &fr,
                    &mut soa,
                    m,
                    ClosestObjects { accel: self, lanes, rays: live, best },
                ),
                None => {
                    for k in bits(m) {
                        let mut c = ClosestObject::<false, _> {
                            accel: self,
                            ray: live[k],
                            best: best[k],
                            walker: Dispatch,
                        };
                        walk_any(&self.tlas, self.tlas_depth, &mut soa.box_ray(k), &mut c);
                        (live[k], best[k]) = (c.ray, c.best);
                    }
                }
            }
        }
    }

    /// [`Accel::occluded`] for each of `rays`, into the same index of
    /// `out` (as many as the shorter holds), up to [`PACKET_SIZE`] rays at
    /// a time together: for coherent rays such as the shadow rays from one
    /// point toward an area light's samples. The answers are `occluded`'s.
    /// As for [`Accel::closest_hit_packet`], a scene without mesh instances
    /// is traced ray by ray.
    pub fn occluded_packet(&self, rays: &[Ray], out: &mut [bool]) {
        if !self.packets {
            for (r, o) in rays.iter().zip(out) {
                *o = self.occluded(r);
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if self.simd.wide {
            // SAFETY: `wide` is set only when the running CPU reports
            // every feature `occluded_packets_wide` is compiled for.
            return unsafe { self.occluded_packets_wide(rays, out) };
        }
        self.occluded_packet_chunks(rays, out);
    }

    /// [`Accel::occluded_packet_chunks`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn occluded_packets_wide(&self, rays: &[Ray], out: &mut [bool]) {
        // SAFETY: this function is compiled for AVX2 and, by its callers'
        // contract, runs only where the CPU has it.
        let lanes = unsafe { packet::x86::Avx2::new() };
        self.occluded_packet_chunks_in(lanes, rays, out);
    }

    /// The occlusion packets' plain build.
    #[inline(always)]
    fn occluded_packet_chunks(&self, rays: &[Ray], out: &mut [bool]) {
        self.occluded_packet_chunks_in(packet::Portable, rays, out);
    }

    #[inline(always)]
    fn occluded_packet_chunks_in(&self, lanes: impl MeshPackets, rays: &[Ray], out: &mut [bool]) {
        for (rays, out) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
            // One packet, with per-ray arrays of the size it needs.
            if rays.len() <= SMALL_PACKET {
                self.occluded_packet_impl::<SMALL_PACKET>(lanes, rays, out);
            } else {
                self.occluded_packet_impl::<PACKET_SIZE>(lanes, rays, out);
            }
        }
    }

    /// One packet of at most `N` rays.
    #[inline(always)]
    fn occluded_packet_impl<const N: usize>(&self, lanes: impl MeshPackets, rays: &[Ray], out: &mut [bool]) {
        let mut live = 0u64;
        let mut done = 0u64;
        for (k, ray) in rays.iter().enumerate().take(N) {
            if usable(ray) {
                if self.unbounded.iter().any(|&i| self.object_occludes(i, ray)) {
                    done |= 1 << k;
                } else {
                    live |= 1 << k;
                }
            }
        }
        if let Some(i) = self.sole {
            done |= AnyObjects::<N, _> { accel: self, lanes, rays, done: 0 }.object(i, live, None);
        } else {
            done |= self.occluded_packet_walk::<N>(lanes, rays, live);
        }
        for (k, o) in out.iter_mut().enumerate().take(rays.len()) {
            *o = done >> k & 1 == 1;
        }
    }

    /// The top-level walk of [`Accel::occluded_packet_impl`]'s rays of
    /// `live`: returns those occluded.
    #[inline(always)]
    fn occluded_packet_walk<const N: usize>(&self, lanes: impl MeshPackets, rays: &[Ray], live: u64) -> u64 {
        let mut done = 0u64;
        let mut soa = Soa::<N>::empty(live);
        soa.fill(rays, live);
        for &(m, fr) in &packet::plan(&soa, live) {
            match fr {
                Some(fr) => {
                    let mut leaf = AnyObjects::<N, _> { accel: self, lanes, rays, done: 0 };
                    self.tlas.walk_packet::<true, N>(lanes, self.tlas_depth, &fr, &mut soa, m, &mut leaf);
                    done |= leaf.done;
                }
                None => {
                    for k in bits(m) {
                        let mut v = AnyObject { accel: self, ray: &rays[k], hit: false, walker: Dispatch };
                        walk_any(&self.tlas, self.tlas_depth, &mut soa.box_ray(k), &mut v);
                        done |= u64::from(v.hit) << k;
                    }
                }
            }
        }
        done
    }

    /// Every crossing of analytic object `i` (`s`) in the ray's interval,
    /// each with its hit record: brute force's reference for
    /// [`Accel::object_crossings`].
    fn shape_crossings_brute_force(
        &self,
        i: u32,
        s: &Instance<Shape>,
        ray: &Ray,
        f: &mut impl FnMut(&SceneHit) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        step_crossings(
            ray,
            |r| self.shape_hit(i, s, r).map(|hit| (hit.t, hit)),
            |_, _, hit| f(&SceneHit { object: i, triangle: SceneHit::NO_TRIANGLE, hit }),
        )
    }

    /// Every crossing of object `i` in the ray's interval, without its hit
    /// record: object, `t` and side (prism-geometry's
    /// `Intersect::intersect_side` for shapes; a mesh's object-space hit,
    /// not yet placed in the world).
    fn object_crossings(
        &self,
        i: u32,
        ray: &Ray,
        f: &mut impl FnMut(&Crossing) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        match &self.objects[i as usize] {
            Object::Shape(s) => step_crossings(
                ray,
                |r| if self.identity[i as usize] { s.shape.intersect_side(r) } else { s.intersect_side(r) },
                |t_min, t, front_face| {
                    let found = Found::Shape { t_min };
                    f(&Crossing { object: i, triangle: SceneHit::NO_TRIANGLE, t, front_face, found })
                },
            ),
            Object::Mesh { mesh, transform } => {
                let m = &self.meshes[*mesh as usize];
                let local = transform.ray_to_object(ray);
                self.blas[*mesh as usize].crossings(&local, |face, t, b1, b2| {
                    let hit = m.hit(face as usize, t, b1, b2, local.dir);
                    let front_face = hit.front_face;
                    f(&Crossing { object: i, triangle: face, t, front_face, found: Found::Mesh(hit) })
                })
            }
        }
    }

    /// Calls `f` for every surface crossing along the ray's interval, in no
    /// particular order, until `f` breaks. A closed shape crossed twice
    /// (entering and leaving) is reported at each crossing; `SceneHit::hit`
    /// says which by `front_face`. Each mesh triangle is reported at most
    /// once per instance. Used for coloured shadows behind transparent
    /// objects.
    ///
    /// [`Accel::for_each_crossing`] gives the same crossings in the same
    /// order without building each one's hit record.
    pub fn for_each_hit(&self, ray: &Ray, mut f: impl FnMut(&SceneHit) -> ControlFlow<()>) {
        self.for_each_crossing(ray, |c| match self.crossing_hit(ray, c) {
            Some(h) => f(&h),
            None => ControlFlow::Continue(()),
        });
    }

    /// [`Accel::for_each_hit`]'s crossings, each as a [`Crossing`] (object,
    /// `t`, side) whose hit record [`Accel::crossing_hit`] builds on demand:
    /// a shadow ray needs only the side of an opaque occluder, and the hit
    /// (point, normal, uv) only of a textured see-through one.
    pub fn for_each_crossing(&self, ray: &Ray, mut f: impl FnMut(&Crossing) -> ControlFlow<()>) {
        if !usable(ray) {
            return;
        }
        for &i in &self.unbounded {
            if self.object_crossings(i, ray, &mut f).is_break() {
                return;
            }
        }
        if let Some(i) = self.sole {
            let _ = self.object_crossings(i, ray, &mut f);
            return;
        }
        let mut br = BoxRay::new(ray);
        walk_any(
            &self.tlas,
            self.tlas_depth,
            &mut br,
            visitor(|slot, _| {
                self.object_crossings(self.tlas_objects[slot as usize], ray, &mut f).is_continue()
            }),
        );
    }

    /// The nearest of object `object`'s crossings in the ray's interval,
    /// without a walk of the hierarchy and without the other objects:
    /// the nearest that [`Accel::for_each_crossing`] reports for it (for a
    /// mesh, where two triangles meet at the same `t`, either). For
    /// questions about a few known objects, such as which solids hold a
    /// point (a closed solid whose nearest crossing from the point is a
    /// back face holds it). `None` for an object that does not exist.
    #[must_use]
    pub fn first_crossing_of(&self, object: u32, ray: &Ray) -> Option<Crossing> {
        if !usable(ray) {
            return None;
        }
        let i = object as usize;
        match self.objects.get(i)? {
            Object::Shape(s) => {
                let (t, front_face) =
                    if self.identity[i] { s.shape.intersect_side(ray) } else { s.intersect_side(ray) }?;
                let found = Found::Shape { t_min: ray.t_min };
                Some(Crossing { object, triangle: SceneHit::NO_TRIANGLE, t, front_face, found })
            }
            Object::Mesh { mesh, transform } => {
                let local = transform.ray_to_object(ray);
                let (face, t, b1, b2) = self.blas[*mesh as usize].closest_by::<true>(Dispatch, &local)?;
                let hit = self.meshes[*mesh as usize].hit(face as usize, t, b1, b2, local.dir);
                let front_face = hit.front_face;
                Some(Crossing { object, triangle: face, t, front_face, found: Found::Mesh(hit) })
            }
        }
    }

    /// The full hit of a crossing that [`Accel::for_each_crossing`] of this
    /// structure reported for `ray` (the same ray): the [`SceneHit`] that
    /// [`Accel::for_each_hit`] reports for it, bit for bit. `None` for a
    /// crossing of another structure whose object is not of the same kind
    /// here (it never panics).
    #[must_use]
    pub fn crossing_hit(&self, ray: &Ray, c: &Crossing) -> Option<SceneHit> {
        let hit = match (c.found, self.objects.get(c.object as usize)?) {
            (Found::Shape { t_min }, Object::Shape(s)) => {
                self.shape_hit(c.object, s, &Ray { t_min, t_max: c.t, ..*ray })?
            }
            (Found::Mesh(local), Object::Mesh { transform, .. }) => transform.hit_to_world(&local),
            _ => return None,
        };
        Some(SceneHit { object: c.object, triangle: c.triangle, hit })
    }

    fn hit_object_brute_force(&self, i: usize, ray: &Ray) -> Option<SceneHit> {
        match &self.objects[i] {
            Object::Shape(s) => self.shape_hit(i as u32, s, ray).map(|hit| SceneHit {
                object: i as u32,
                triangle: SceneHit::NO_TRIANGLE,
                hit,
            }),
            Object::Mesh { mesh, transform } => {
                let m = &self.meshes[*mesh as usize];
                let local = transform.ray_to_object(ray);
                let (f, t, b1, b2) = m.intersect_brute_force(&local)?;
                let hit = transform.hit_to_world(&m.hit(f, t, b1, b2, local.dir));
                Some(SceneHit { object: i as u32, triangle: f as u32, hit })
            }
        }
    }

    /// [`Accel::closest_hit`] by testing every object and every triangle:
    /// the reference the hierarchy is tested against. Slow.
    #[must_use]
    pub fn closest_hit_brute_force(&self, ray: &Ray) -> Option<SceneHit> {
        if !usable(ray) {
            return None;
        }
        let mut ray = *ray;
        let mut best = None;
        for i in 0..self.objects.len() {
            if let Some(h) = self.hit_object_brute_force(i, &ray) {
                ray.t_max = h.hit.t;
                best = Some(h);
            }
        }
        best
    }

    /// [`Accel::for_each_hit`] by testing every object and every triangle:
    /// the reference the hierarchy is tested against. Slow.
    pub fn for_each_hit_brute_force(&self, ray: &Ray, mut f: impl FnMut(&SceneHit) -> ControlFlow<()>) {
        if !usable(ray) {
            return;
        }
        for i in 0..self.objects.len() {
            let flow = match &self.objects[i] {
                Object::Shape(s) => self.shape_crossings_brute_force(i as u32, s, ray, &mut f),
                Object::Mesh { mesh, transform } => {
                    let m = &self.meshes[*mesh as usize];
                    let local = transform.ray_to_object(ray);
                    let tr = TriangleRay::new(&local);
                    let mut flow = ControlFlow::Continue(());
                    for face in 0..m.len() {
                        if let Some((t, b1, b2)) = tr.intersect(&m.triangle(face)) {
                            let hit = transform.hit_to_world(&m.hit(face, t, b1, b2, local.dir));
                            flow = f(&SceneHit { object: i as u32, triangle: face as u32, hit });
                            if flow.is_break() {
                                break;
                            }
                        }
                    }
                    flow
                }
            };
            if flow.is_break() {
                return;
            }
        }
    }
}

/// Most crossings reported for one analytic shape along one ray.
const MAX_SHAPE_CROSSINGS: usize = 8;

/// Steps through an analytic shape's crossings in the ray's interval,
/// nearest first: `probe` finds the nearest crossing in what is left of
/// the interval (its `t` and what else it gives), `report` takes it with
/// the start of that interval. Analytic shapes are convex: at most two
/// crossings (a few more steps only guard against a shape reporting a
/// tangent twice).
#[inline(always)]
fn step_crossings<T>(
    ray: &Ray,
    mut probe: impl FnMut(&Ray) -> Option<(f32, T)>,
    mut report: impl FnMut(f32, f32, T) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let mut r = *ray;
    for _ in 0..MAX_SHAPE_CROSSINGS {
        let Some((t, x)) = probe(&r) else { break };
        report(r.t_min, t, x)?;
        let next = t.next_up();
        if !(next <= r.t_max) {
            break;
        }
        r.t_min = next;
    }
    ControlFlow::Continue(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slack grows with the box's coordinates and with how unevenly the
    /// transform stretches space, and leaves empty and infinite boxes alone.
    #[test]
    fn top_level_boxes_are_widened_by_rounding_slack() {
        let b = Aabb::new(Vec3::new(1.0, -2.0, 3.0), Vec3::new(2.0, 4.0, 5.0));
        let pad = |w: Aabb| (b.min - w.min).max_element().max((w.max - b.max).max_element());
        let plain = widen_for_rounding(b, &Transform::IDENTITY);
        assert!(plain.min.cmplt(b.min).all() && plain.max.cmpgt(b.max).all());
        // 32 ULPs of the largest coordinate (5), to within the rounding of
        // the widened planes.
        let want = 5.0 * ROUNDING_ULPS * f32::EPSILON;
        assert!((pad(plain) / want - 1.0).abs() < 0.02, "{} vs {want}", pad(plain));
        let squash = Transform::scale(Vec3::new(100.0, 1.0, 0.01)).unwrap();
        let cond = 100.0 * 100.0; // ‖M‖ · ‖M⁻¹‖
        let squashed = widen_for_rounding(b, &squash);
        let ratio = pad(squashed) / pad(plain);
        assert!((ratio / cond - 1.0).abs() < 0.02, "{ratio}");
        assert_eq!(widen_for_rounding(Aabb::EMPTY, &squash), Aabb::EMPTY);
        assert_eq!(widen_for_rounding(Aabb::INFINITE, &squash), Aabb::INFINITE);
    }

    /// An `n`×`n` grid over the unit square in x/z, two triangles a cell,
    /// raised to `y = sin(fx·u)·cos(fz·v)·amp` for `[fx, fz, amp]`.
    pub(crate) fn wavy_grid(n: u32, [fx, fz, amp]: [f32; 3]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                positions.push(Vec3::new(u, (u * fx).sin() * (v * fz).cos() * amp, v));
            }
        }
        let w = n + 1;
        let mut indices = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = j * w + i;
                indices.push([a, a + 1, a + w + 1]);
                indices.push([a, a + w + 1, a + w]);
            }
        }
        (positions, indices)
    }

    /// Whether this CPU has what kernel `k` needs, asked independently of
    /// [`Kernel::supported`].
    fn host_has(k: Kernel) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
            match k {
                Kernel::Portable => true,
                Kernel::Avx2 => avx2,
                Kernel::Avx512 => {
                    avx2 && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            k == Kernel::Portable
        }
    }

    /// Every kernel this CPU has is selectable and actually walks (so the
    /// kernel comparisons in `tests/blas_kinds.rs` ran it): this FAILS,
    /// rather than skipping, where the host has AVX2 or AVX-512 and that
    /// path did not run; and detection picks AVX-512 where the CPU has it
    /// (measured fastest), else AVX2, else the portable one.
    #[test]
    fn every_kernel_the_host_has_is_exercised() {
        let (positions, indices) = wavy_grid(20, [9.0, 7.0, 0.3]);
        let mesh = Arc::new(TriangleMesh::new(positions, None, None, indices).unwrap());
        let objects = vec![Object::Mesh { mesh: 0, transform: Transform::IDENTITY }];
        let options = BuildOptions { mesh_layout: BlasKind::Wide, ..BuildOptions::default() };
        let mut accel = Accel::build_with(vec![mesh], objects, options).unwrap();
        let ray = Ray::new(Vec3::new(0.5, 1.0, 0.5), Vec3::new(0.01, -1.0, 0.02));
        let mut reference = None;
        for k in Kernel::ALL {
            assert_eq!(k.supported(), host_has(k), "{}", k.name());
            if !host_has(k) {
                assert!(!accel.set_kernel(k), "{} accepted without the CPU features", k.name());
                continue;
            }
            assert!(accel.set_kernel(k), "{}", k.name());
            let before = wide::WALKS[k as usize].load(std::sync::atomic::Ordering::Relaxed);
            let hit = accel.closest_hit(&ray).map(|h| (h.triangle, h.hit.t.to_bits()));
            assert!(hit.is_some());
            assert!(accel.occluded(&ray));
            let after = wide::WALKS[k as usize].load(std::sync::atomic::Ordering::Relaxed);
            assert!(after >= before + 2, "the {} kernel did not run", k.name());
            assert_eq!(*reference.get_or_insert(hit), hit, "{}", k.name());
        }
        if std::env::var_os("PRISM_BVH_KERNEL").is_none() {
            // The measured fastest (docs/benchmarks.md) that the CPU has.
            let expected = match std::env::var_os("PRISM_BVH_NO_SIMD") {
                None if host_has(Kernel::Avx512) => Kernel::Avx512,
                None if host_has(Kernel::Avx2) => Kernel::Avx2,
                _ => Kernel::Portable,
            };
            assert_eq!(Kernel::detect(), expected);
        }
    }

    /// A record resolves to its hit here, and to `None` (no panic) in a
    /// structure without its object or triangle.
    #[test]
    fn records_of_another_structure_resolve_to_none() {
        let (positions, indices) = wavy_grid(20, [4.0, 4.0, 0.2]);
        let big = Arc::new(TriangleMesh::new(positions, None, None, indices).unwrap());
        let small = Arc::new(
            TriangleMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], None, None, vec![[0, 1, 2]]).unwrap(),
        );
        let mesh = |m| Object::Mesh { mesh: 0, transform: Transform::translate(m).unwrap() };
        let two = Accel::build(vec![big], vec![mesh(Vec3::new(0.0, -5.0, 0.0)), mesh(Vec3::ZERO)]).unwrap();
        let one = Accel::build(vec![small], vec![mesh(Vec3::ZERO)]).unwrap();
        // The grids lie near y = 0 and y = -5, across x, z in [0, 1].
        let ray = Ray::new(Vec3::new(0.37, 5.0, 0.41), Vec3::NEG_Y);
        let record = two.closest_record(&ray).expect("the upper grid");
        assert_eq!(record.object(), 1);
        assert!(record.triangle().is_some_and(|f| f > 0), "{record:?}");
        let hit = two.resolve(record).expect("its own record");
        assert_eq!((hit.object, hit.hit.t.to_bits()), (1, record.t().to_bits()));
        assert!(one.resolve(record).is_none(), "object 1 does not exist in `one`");
        let front = two.closest_record(&Ray::new(Vec3::new(0.37, -1.0, 0.41), Vec3::NEG_Y)).unwrap();
        assert_eq!(front.object(), 0);
        assert!(one.resolve(front).is_none(), "no such triangle in `one`'s mesh");
    }

    /// The AVX2-compiled queries, single and packed, give bit-for-bit the
    /// answers of the plain ones, and records, occlusion and packets agree
    /// with `closest_hit`. On a CPU without the wide variant's features
    /// only the comparison with the AVX2 builds is left out; on one that
    /// has them with the variant turned off (`PRISM_BVH_NO_SIMD`), the
    /// test skips (and fails under CI). (x86-64 only: the AVX2 and AVX-512
    /// builds it compares exist there.)
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn wide_queries_match_plain_ones() {
        let (positions, indices) = wavy_grid(40, [9.0, 7.0, 0.3]);
        let mesh = Arc::new(TriangleMesh::new(positions, None, None, indices).unwrap());
        let mut objects = Vec::new();
        for k in 0..4 {
            let t = Transform::translate(Vec3::new(k as f32 * 0.7, 0.0, (k % 2) as f32 * 0.5)).unwrap();
            objects.push(Object::Mesh { mesh: 0, transform: t });
        }
        objects.push(Object::Mesh { mesh: 0, transform: Transform::rotate_y(0.6) });
        let sphere = prism_geometry::Sphere::new(Vec3::new(1.0, 0.2, 0.5), 0.3).unwrap();
        objects.push(Object::Shape(Instance::new(Shape::from(sphere), Transform::IDENTITY)));
        let accel = Accel::build(vec![mesh], objects).unwrap();
        // The top level's tree (leaves of one object): each leaf's box
        // holds its object's world box.
        let world_box = |i: u32| {
            let b = match &accel.objects[i as usize] {
                Object::Shape(s) => s.bounds(),
                Object::Mesh { mesh, transform } => transform.aabb(&accel.meshes[*mesh as usize].bounds()),
            };
            Some((b.min.to_array(), b.max.to_array()))
        };
        accel.tlas.validate(|s| world_box(*accel.tlas_objects.get(s)?));
        let wide_on = accel.simd.wide;
        if !wide_on && host_has(Kernel::Avx2) {
            prism_testkit::skip("the CPU has AVX2 but the wide variant is off (PRISM_BVH_NO_SIMD is set?)");
        }
        let mut rng = prism_testkit::Rng::new(0x9e37_79b9);
        let mut f = move || rng.range(-1.0, 1.0);
        let mut hits = 0;
        let mut rays = Vec::new();
        for k in 0..20_000 {
            let o = Vec3::new(f() * 3.0 + 1.0, f() * 2.0, f() * 3.0 + 0.5);
            let mut d = Vec3::new(f(), f(), f());
            if k % 5 == 0 {
                d[k % 3] = if k % 2 == 0 { 0.0 } else { -0.0 };
            }
            if d == Vec3::ZERO {
                continue;
            }
            let ray = Ray::with_interval(o, d, 0.0, if k % 3 == 0 { 1.5 } else { f32::INFINITY });
            // SAFETY: `accel.simd.wide` says this CPU has the features.
            let wide = wide_on.then(|| accel.finish(unsafe { accel.closest_best_wide(&ray) }));
            let plain = accel.finish(accel.closest_best(Dispatch, &ray));
            if accel.simd.avx512 {
                // SAFETY: `avx512` says this CPU has the features.
                let inline = accel.finish(unsafe { accel.closest_best_avx512(&ray) });
                assert_eq!(
                    inline.map(|h| (h.object, h.triangle, h.hit.t.to_bits())),
                    plain.map(|h| (h.object, h.triangle, h.hit.t.to_bits())),
                    "{ray:?}"
                );
            }
            let record = accel.closest_record(&ray);
            assert_eq!(
                record.map(|r| (r.object(), r.triangle().unwrap_or(SceneHit::NO_TRIANGLE), r.t().to_bits())),
                plain.map(|h| (h.object, h.triangle, h.hit.t.to_bits())),
                "the record is the hit's: {ray:?}"
            );
            assert_eq!(
                record.and_then(|r| accel.resolve(r)).map(|h| h.hit.point),
                plain.map(|h| h.hit.point)
            );
            let bits = |h: Option<SceneHit>| h.map(|h| (h.object, h.triangle, h.hit.t.to_bits()));
            if let Some(wide) = wide {
                assert_eq!(bits(wide), bits(plain), "{ray:?}");
            }
            assert_eq!(accel.occluded(&ray), plain.is_some(), "{ray:?}");
            hits += usize::from(plain.is_some());
            rays.push(ray);
        }
        assert!(hits > 500, "{hits}");
        // The packet queries' AVX2 build against their plain one: on a
        // pinhole camera's rows of rays (coherent packets, looking down on
        // the instances, most of them hitting) and on the random rays
        // above, in full packets and in small ones.
        let camera = rays.len();
        for row in 0..48 {
            for col in 0..64 {
                let d = Vec3::new(col as f32 / 32.0 - 1.0, -1.5, row as f32 / 48.0 - 0.5);
                rays.push(Ray::new(Vec3::new(1.6, 2.5, 0.7), d));
            }
        }
        let camera_hits = rays[camera..].iter().filter(|r| accel.closest_hit(r).is_some()).count();
        assert!(camera_hits > 2_000, "the camera rows should mostly hit: {camera_hits}");
        let finish = |best| accel.finish(best);
        let key = |h: Option<SceneHit>| h.map(|h| (h.object, h.triangle, h.hit.t.to_bits()));
        let mut packets_hit = 0;
        for size in [PACKET_SIZE, 13] {
            for chunk in rays.chunks(size) {
                let (mut wide, mut plain) = (vec![None; chunk.len()], vec![None; chunk.len()]);
                accel.closest_packet_chunks(chunk, &mut plain, &finish);
                if wide_on {
                    // SAFETY: `accel.simd.wide` says this CPU has the features.
                    unsafe { accel.closest_packets_wide(chunk, &mut wide, &finish) };
                } else {
                    wide.clone_from(&plain);
                }
                for (k, ray) in chunk.iter().enumerate() {
                    assert_eq!(key(wide[k]), key(plain[k]), "packet of {size}: {ray:?}");
                    assert_eq!(key(plain[k]), key(accel.closest_hit(ray)), "packet of {size}: {ray:?}");
                    packets_hit += usize::from(plain[k].is_some());
                }
                let (mut wide, mut plain) = (vec![false; chunk.len()], vec![false; chunk.len()]);
                accel.occluded_packet_chunks(chunk, &mut plain);
                if wide_on {
                    // SAFETY: as above.
                    unsafe { accel.occluded_packets_wide(chunk, &mut wide) };
                } else {
                    wide.clone_from(&plain);
                }
                assert_eq!(wide, plain, "occlusion packets of {size}");
                for (k, ray) in chunk.iter().enumerate() {
                    assert_eq!(plain[k], accel.occluded(ray), "occlusion packet of {size}: {ray:?}");
                }
            }
        }
        assert_eq!(packets_hit, 2 * (hits + camera_hits));
    }
}
