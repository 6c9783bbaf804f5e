//! Triangles, with a watertight intersection test.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{BVec4A, Vec2, Vec3, Vec4};

/// A single triangle `(v0, v1, v2)`; its outward normal follows the
/// counter-clockwise winding, `(v1 − v0) × (v2 − v0)` (right-handed).
///
/// uv: `(b1, 1 − b2)`, from the barycentric coordinates of the hit
/// (`p = (1 − b1 − b2)·v0 + b1·v1 + b2·v2`) read as an OBJ `vt` would be
/// (`v = 0` is an image's top row): an image stands upright with `v0` at
/// its bottom-left corner, `v1` along its bottom edge and `v2` at its
/// top-left corner, as on a quad's lower triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The three corners.
    pub v: [Vec3; 3],
}

impl Triangle {
    /// A triangle with corners `v`.
    ///
    /// # Errors
    /// If a corner is not finite, the triangle has zero area, or its
    /// edges' cross product overflows `f32` (edges past about 1e19).
    pub fn new(v: [Vec3; 3]) -> Result<Self, GeometryError> {
        for p in v {
            check_finite("triangle corner", p)?;
        }
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        // Not the squared length, which underflows to 0 for edges of about
        // 1e-12 (and overflows for 1e10) that a mesh's faces handle.
        if !n.is_finite() {
            return Err(GeometryError::Degenerate(
                "triangle is too large: the product of its edges overflows 32-bit floats (edges up to about 1e19)",
            ));
        }
        if n == Vec3::ZERO {
            return Err(GeometryError::Degenerate("triangle has zero area"));
        }
        Ok(Self { v })
    }

    /// Unit outward normal (counter-clockwise winding). Zero only where
    /// the corners, changed since [`Triangle::new`], no longer span an
    /// area.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        // Not `normalize_or_zero`, whose squared length over- or underflows
        // for edges past about 4e9 or below 1e-10 (a zero normal, or one of
        // length 1.01), as `TriangleMesh`'s faces already do.
        crate::unit_or_extreme((self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])).unwrap_or(Vec3::ZERO)
    }
}

impl Intersect for Triangle {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        TriangleRay::checked(ray)?.intersect(&self.v).map(|(t, _, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t, b1, b2) = TriangleRay::checked(ray)?.intersect(&self.v)?;
        let b0 = 1.0 - b1 - b2;
        let p = b0 * self.v[0] + b1 * self.v[1] + b2 * self.v[2];
        Some(Hit::new(t, p, self.normal(), Vec2::new(b1, 1.0 - b2), ray.dir))
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.v)
    }
}

/// A ray prepared for the watertight ray/triangle test of Woop, Benthin and
/// Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013): prism's one
/// implementation of that test, used by [`Triangle`], [`crate::TriangleMesh`]
/// and the BVH's leaves alike.
///
/// The ray is sheared so that it runs along +Z; each triangle is then
/// tested in 2D with edge functions that are exact in sign on shared edges
/// (falling back to `f64` when an edge function is zero or subnormal), so a
/// ray aimed at a shared edge or vertex of a closed mesh never slips
/// through. A scaled distance past the
/// range of `f32` products (zero, subnormal or infinite) and a subnormal
/// determinant are also decided in `f64`: a ray leaving a triangle of
/// 1e-14 does not meet it again at `t = 0`, and one of 1e13 seen from
/// 3e13 is not missed.
/// Prepare once per ray ([`TriangleRay::new`]), then test many triangles
/// ([`TriangleRay::intersect`]).
///
/// # Layout
///
/// As in the paper, the ray keeps the permuted axes `kx`, `ky`, `kz` of its
/// dominant direction and the shear `(sx, sy, sz)`; a corner `a` (relative
/// to the origin) becomes `(a[kx] − sx·a[kz], a[ky] − sy·a[kz], sz·a[kz])`.
/// The origin is stored permuted too. The scalar test and the four-lane
/// [`TriangleRay::intersect4`] compute these the same way, so they agree
/// bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    /// The origin's coordinates on axes `kx`, `ky`, `kz`.
    origin: [f32; 3],
    /// The axes `kx`, `ky`, `kz` (each below 3).
    k: [usize; 3],
    /// The shear `sx`, `sy`, `sz`.
    shear: [f32; 3],
    /// The ray's `t_min`, raised to `f32::MIN` (so `−∞` never passes).
    t_min: f32,
    /// The ray's `t_max`, lowered to `f32::MAX` (so `+∞` never passes).
    t_max: f32,
}

/// Whether `x` is zero or subnormal: an edge function or a scaled
/// distance that the triangle test decides in `f64` instead (in every
/// kernel, so that they agree bit for bit). `NaN` is not.
#[inline(always)]
fn tiny(x: f32) -> bool {
    x.abs() < f32::MIN_POSITIVE
}

/// Whether the scaled distance `x` (the paper's `T`) is zero, subnormal,
/// infinite or `NaN`: past the range of `f32` products, which the
/// triangle test then sums in `f64` (in every kernel).
#[inline(always)]
fn unsure(x: f32) -> bool {
    !(x.abs() >= f32::MIN_POSITIVE && x.abs() < f32::INFINITY)
}

/// `[t_min, t_max]` narrowed to finite bounds: the interval test then also
/// rejects an infinite or `NaN` `t`, at no cost per triangle.
#[inline(always)]
fn finite_interval(t_min: f32, t_max: f32) -> (f32, f32) {
    (t_min.max(f32::MIN), t_max.min(f32::MAX))
}

/// The axes `[kx, ky, kz]` of a ray whose dominant axis is `kz`, at index
/// `2·kz + 1` where `d[kz] < 0` and `2·kz` otherwise: `kx = (kz + 1) % 3`
/// and `ky = (kx + 1) % 3`, swapped where `d[kz] < 0` (which keeps the
/// winding). One lookup rather than two and a swap.
const AXES: [[usize; 3]; 6] = [[1, 2, 0], [2, 1, 0], [2, 0, 1], [0, 2, 1], [0, 1, 2], [1, 0, 2]];

impl TriangleRay {
    /// [`TriangleRay::new`] for a ray that can meet something: `None` along
    /// a non-finite direction (whose shear would be `0` or `NaN`, meeting
    /// triangles behind the origin at `t = −0`) or within an interval with
    /// a `NaN` end. [`Triangle`] and [`crate::TriangleMesh`] use it.
    #[inline]
    #[must_use]
    pub fn checked(ray: &Ray) -> Option<Self> {
        let usable = ray.dir.is_finite() && !ray.t_min.is_nan() && !ray.t_max.is_nan();
        usable.then(|| Self::new(ray))
    }

    /// Prepares `ray`. A zero direction hits nothing; a direction that is
    /// not finite, or an interval with a `NaN` end, is the caller's to
    /// refuse (the walks of prism-bvh refuse such rays when a query
    /// starts, once; [`TriangleRay::checked`] does it for one ray).
    #[inline(always)]
    #[must_use]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir.to_array();
        let [ax, ay, az] = ray.dir.abs().to_array();
        // The dominant axis: x where `ax >= ay && ax >= az`, else y where
        // `ay >= az`, else z (`NaN` compares false). Computed without
        // branches: on incoherent rays the choice is random, and its
        // branches were mispredicted about half the time (callgrind's
        // branch simulation, docs/benchmarks.md).
        let x_wins = (ax >= ay) & (ax >= az);
        let y_wins = ay >= az;
        let kz = usize::from(!x_wins) * (1 + usize::from(!y_wins));
        let dz = d[kz];
        let [kx, ky, kz] = AXES[kz * 2 + usize::from(dz < 0.0)];
        // `[d[kx] / dz, d[ky] / dz, 1 / dz]` in one vector division (the
        // same quotients as scalar ones, bit for bit).
        let [sx, sy, sz, _] = (Vec4::new(d[kx], d[ky], 1.0, 1.0) / Vec4::splat(dz)).to_array();
        let o = ray.origin.to_array();
        let origin = [o[kx], o[ky], o[kz]];
        let (t_min, t_max) = finite_interval(ray.t_min, ray.t_max);
        Self { origin, k: [kx, ky, kz], shear: [sx, sy, sz], t_min, t_max }
    }

    /// Corner `p` relative to the origin, sheared and scaled: the paper's
    /// `(a[kx] − sx·a[kz], a[ky] − sy·a[kz], sz·a[kz])` for `a = p − origin`.
    /// [`TriangleRay::intersect4`] computes the same per lane.
    #[inline(always)]
    fn shear(&self, p: Vec3) -> (f32, f32, f32) {
        let p = p.to_array();
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let [ox, oy, oz] = self.origin;
        let (x, y, z) = (p[kx.min(2)] - ox, p[ky.min(2)] - oy, p[kz.min(2)] - oz);
        (x - sx * z, y - sy * z, sz * z)
    }

    /// Narrows the accepted interval's upper end (after a closer hit).
    #[inline(always)]
    pub fn set_t_max(&mut self, t_max: f32) {
        self.t_max = finite_interval(self.t_min, t_max).1;
    }

    /// `(t, b1, b2)` if the ray meets the triangle with corners `v` within
    /// its interval, from either side; `(b1, b2)` are the barycentric
    /// coordinates of `v[1]` and `v[2]` (see [`Triangle`]). Zero-area
    /// triangles are never hit, and neither is an infinite or `NaN` `t`
    /// (a nearly parallel ray whose plane crossing overflows), whatever
    /// the interval.
    #[inline(always)]
    #[must_use]
    pub fn intersect(&self, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let (ax, ay, az) = self.shear(v[0]);
        let (bx, by, bz) = self.shear(v[1]);
        let (cx, cy, cz) = self.shear(v[2]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // The edge functions in `f64`, where the `f32` ones are zero or
        // subnormal (their signs then come from these).
        let mut wide = None;
        if tiny(u) || tiny(v) || tiny(w) {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            let uvw = (cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
            (u, v, w) = (uvw.0 as f32, uvw.1 as f32, uvw.2 as f32);
            wide = Some(uvw);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let t_scaled = u * az + v * bz + w * cz;
        if unsure(t_scaled) || tiny(det) {
            // Past the range of `f32` products. Zero or subnormal by
            // underflow, as a rule: for a triangle of 1e-14 (edge functions
            // of 1e-28) and an origin 1e-18 off its plane (a spawned ray's
            // offset in a scene that small) the products fall below the
            // smallest normal `f32`, and a ray leaving the triangle met it
            // again at `t = −0` or at a small `t` of the wrong sign.
            // Infinite by overflow: a triangle of 1e13 seen from 3e13 (edge
            // functions of 1e26) was missed. A subnormal determinant (a
            // triangle of 1e-20) has no finite `f32` reciprocal. All of it
            // in `f64` (every kernel sends such lanes here: a determinant
            // that small has edge functions as small).
            let (u, v, w) = wide.unwrap_or((f64::from(u), f64::from(v), f64::from(w)));
            // (Edge functions below the smallest subnormal were `±0` in
            // `f32`: their signs are these.)
            if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
                return None;
            }
            let det = u + v + w;
            let t = (u * f64::from(az) + v * f64::from(bz) + w * f64::from(cz)) / det;
            if !(t >= f64::from(self.t_min) && t <= f64::from(self.t_max)) {
                return None;
            }
            return Some((t as f32, (v / det) as f32, (w / det) as f32));
        }
        let rcp = 1.0 / det;
        let t = t_scaled * rcp;
        // The bounds are finite, so this also rejects an infinite or NaN t.
        if !(t >= self.t_min && t <= self.t_max) {
            return None;
        }
        Some((t, v * rcp, w * rcp))
    }
}

/// [`TriangleRay::lanes4`]'s values: per lane `t`, `b1`, `b2`, and as
/// lane masks of the lanes in use, whether the lane passes the edge and
/// determinant tests (`ok`) and whether the scalar test must decide it
/// (`exact`: an edge function zero or subnormal, or, inside the edges, a
/// scaled `t` past the range of `f32` products).
#[derive(Clone, Copy)]
struct Lanes4 {
    t: Vec4,
    b1: Vec4,
    b2: Vec4,
    ok: u32,
    exact: u32,
    /// `ok` as a vector mask, before the lanes in use are picked out: an
    /// unused lane (zero corners, so zero edge functions and determinant)
    /// is never set.
    ok_lanes: BVec4A,
}

/// Up to four triangles in SoA form (`v[corner][axis][lane]`), for
/// [`TriangleRay::intersect4`]: one leaf of a wide BVH, tested at once.
///
/// 160 bytes aligned to 32, so that every block of an array spans three
/// cache lines: at 16-byte alignment, every other block of a heap array
/// spanned four (4.9 % fewer simulated L1 read misses on the bunny's
/// incoherent rays, docs/benchmarks.md).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Triangles4 {
    v: [[[f32; 4]; 3]; 3],
    /// Lanes in use (the others are zero and never reported).
    len: u32,
}

impl Triangles4 {
    /// The first four of `tris` (fewer leave lanes unused).
    #[must_use]
    pub fn new(tris: &[[Vec3; 3]]) -> Self {
        let mut out = Self::default();
        for (lane, t) in tris.iter().take(4).enumerate() {
            for (corner, p) in t.iter().enumerate() {
                for axis in 0..3 {
                    out.v[corner][axis][lane] = p[axis];
                }
            }
            out.len = lane as u32 + 1;
        }
        out
    }

    /// The coordinates as `[corner][axis][lane]`: what a SIMD leaf test
    /// outside this crate reads.
    #[inline(always)]
    #[must_use]
    pub fn rows(&self) -> &[[[f32; 4]; 3]; 3] {
        &self.v
    }

    /// How many lanes hold a triangle (at most 4).
    #[inline(always)]
    #[must_use]
    pub fn len(&self) -> usize {
        (self.len as usize).min(4)
    }

    /// Whether no lane holds a triangle.
    #[inline(always)]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Corners of triangle `lane` (of the first four).
    #[inline(always)]
    #[must_use]
    pub fn corners(&self, lane: usize) -> [Vec3; 3] {
        let v = &self.v;
        let p = |c: usize| Vec3::new(v[c][0][lane & 3], v[c][1][lane & 3], v[c][2][lane & 3]);
        [p(0), p(1), p(2)]
    }
}

impl TriangleRay {
    /// [`TriangleRay::shear`] on the four lanes of corner `c` of a
    /// [`Triangles4`].
    #[inline(always)]
    fn shear4(&self, c: &[[f32; 4]; 3]) -> (Vec4, Vec4, Vec4) {
        let [kx, ky, kz] = self.k.map(|k| k.min(2));
        let [ox, oy, oz] = self.origin.map(Vec4::splat);
        let [sx, sy, sz] = self.shear.map(Vec4::splat);
        let z = Vec4::from_array(c[kz]) - oz;
        let x = (Vec4::from_array(c[kx]) - ox) - sx * z;
        let y = (Vec4::from_array(c[ky]) - oy) - sy * z;
        (x, y, sz * z)
    }

    /// The test's per-lane values on the four lanes of `tris` (before the
    /// interval test); `None` when the edge test already rules out every
    /// lane in use. That skips the division and the interval test for a
    /// ray that passes beside all four triangles, as most of a leaf's do;
    /// the lanes that remain are computed as before.
    #[inline(always)]
    fn lanes4(&self, tris: &Triangles4) -> Option<Lanes4> {
        let v = &tris.v;
        let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) =
            (self.shear4(&v[0]), self.shear4(&v[1]), self.shear4(&v[2]));
        let u = cx * by - cy * bx;
        let vv = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let least = Vec4::splat(f32::MIN_POSITIVE);
        let tiny4 = |x: Vec4| x.abs().cmplt(least);
        let exact = (tiny4(u) | tiny4(vv) | tiny4(w)).bitmask();
        let outside = (u.cmplt(zero) | vv.cmplt(zero) | w.cmplt(zero))
            & (u.cmpgt(zero) | vv.cmpgt(zero) | w.cmpgt(zero));
        let used = (1u32 << tris.len.min(4)) - 1;
        // An exact lane is decided by the scalar test, whatever its `f32`
        // edge functions say.
        if (!outside.bitmask() | exact) & used == 0 {
            return None;
        }
        let det = u + vv + w;
        let t_scaled = u * az + vv * bz + w * cz;
        let rcp = Vec4::ONE / det;
        let ok_lanes = !outside & det.cmpne(zero) & det.is_finite_mask();
        let ok = ok_lanes.bitmask() & used;
        // So is a lane inside its edges whose scaled `t` is past the range
        // of `f32` products (see the scalar test).
        let unsure4 = !(t_scaled.abs().cmpge(least) & t_scaled.abs().cmplt(Vec4::INFINITY));
        let exact = exact | (unsure4 & !outside).bitmask();
        Some(Lanes4 { t: t_scaled * rcp, b1: vv * rcp, b2: w * rcp, ok, exact: exact & used, ok_lanes })
    }

    /// Whether the ray meets any of the (up to) four triangles of `tris`
    /// within its interval: `intersect4(tris).is_some()`, with the interval
    /// tested on all lanes at once and no nearest hit picked (an occlusion
    /// query's leaf test). A lane the scalar test must decide (an edge
    /// function zero or subnormal, a scaled `t` past `f32`'s range) takes
    /// it, as there.
    #[inline(always)]
    #[must_use]
    pub fn occludes4(&self, tris: &Triangles4) -> bool {
        let Some(Lanes4 { t, ok, mut exact, .. }) = self.lanes4(tris) else { return false };
        let inside = (t.cmpge(Vec4::splat(self.t_min)) & t.cmple(Vec4::splat(self.t_max))).bitmask();
        if ok & inside & !exact != 0 {
            return true;
        }
        while exact != 0 {
            let k = exact.trailing_zeros() as usize;
            exact &= exact - 1;
            if self.intersect(&tris.corners(k)).is_some() {
                return true;
            }
        }
        false
    }

    /// [`TriangleRay::intersect`] on the (up to) four triangles of `tris`
    /// at once, in four-lane vectors (glam's `Vec4`). Returns
    /// the hit a loop over the lanes in order would keep, narrowing `t_max`
    /// after each hit: `(lane, t, b1, b2)` of the nearest, the last lane
    /// among equal `t`. Every value is computed by the same operations in
    /// the same order as [`TriangleRay::intersect`], so it is
    /// bit-identical; a lane with an edge function zero or subnormal, or a
    /// scaled `t` past `f32`'s range, takes the scalar test, whose `f64`
    /// fallback decides it.
    #[inline(always)]
    #[must_use]
    pub fn intersect4(&self, tris: &Triangles4) -> Option<(usize, f32, f32, f32)> {
        let lanes = self.lanes4(tris)?;
        self.nearest4(tris, &lanes)
    }

    /// [`TriangleRay::intersect4`]'s hit, with the nearest lane picked
    /// without a branch per lane where no lane needs the scalar test: the
    /// lanes within the interval as one vector compare, their smallest
    /// `t`, and the last lane equal to it (a loop that narrows `t_max`
    /// after each hit keeps exactly that lane: every `t_max` it passes
    /// through is at least the smallest `t`, and after it only an equal
    /// `t` is taken). The same hit bit for bit.
    ///
    /// For incoherent rays, whose lanes hit and miss at random, this
    /// avoids the mispredicted branches of the loop; for coherent rays,
    /// whose branches predict well, the compare, minimum and
    /// variable-index load in front of the narrowed `t_max` measured
    /// slower (docs/benchmarks.md). The BVH's single-ray closest-hit
    /// queries use this one, its packets [`TriangleRay::intersect4`].
    #[inline(always)]
    #[must_use]
    pub fn intersect4_branchless(&self, tris: &Triangles4) -> Option<(usize, f32, f32, f32)> {
        let lanes = self.lanes4(tris)?;
        if lanes.exact != 0 {
            return self.nearest4(tris, &lanes);
        }
        let within =
            lanes.ok_lanes & lanes.t.cmpge(Vec4::splat(self.t_min)) & lanes.t.cmple(Vec4::splat(self.t_max));
        let inside = within.bitmask() & lanes.ok;
        if inside == 0 {
            return None;
        }
        let least = Vec4::select(within, lanes.t, Vec4::INFINITY).min_element();
        let last = lanes.t.cmpeq(Vec4::splat(least)).bitmask() & inside;
        if last == 0 {
            // Not reached: the least `t` is that of a lane of `inside`.
            return self.nearest4(tris, &lanes);
        }
        let k = (31 - last.leading_zeros()) as usize & 3;
        Some((k, lanes.t[k], lanes.b1[k], lanes.b2[k]))
    }

    /// The lane a loop over the lanes in order keeps (narrowing `t_max`
    /// after each hit), the scalar test deciding the exact lanes.
    #[inline(always)]
    fn nearest4(&self, tris: &Triangles4, lanes: &Lanes4) -> Option<(usize, f32, f32, f32)> {
        let Lanes4 { t, b1, b2, ok, exact, .. } = *lanes;
        let (t, b1, b2) = (t.to_array(), b1.to_array(), b2.to_array());
        let mut best: Option<(usize, f32, f32, f32)> = None;
        let mut t_max = self.t_max;
        for k in 0..(tris.len as usize).min(4) {
            let hit = if exact >> k & 1 == 1 {
                let mut r = *self;
                r.t_max = t_max;
                r.intersect(&tris.corners(k))
            } else if ok >> k & 1 == 1 && t[k] >= self.t_min && t[k] <= t_max {
                Some((t[k], b1[k], b2[k]))
            } else {
                None
            };
            if let Some((t, b1, b2)) = hit {
                t_max = t;
                best = Some((k, t, b1, b2));
            }
        }
        best
    }
}

/// Up to eight [`TriangleRay`]s with the same axes `kx`, `ky`, `kz`, in
/// SoA lanes: the rays of a packet that reach one leaf, tested against
/// each of its triangles eight rays at a time (one lane per ray) where
/// [`TriangleRay::occludes4`] tests one ray against four triangles. Every
/// lane computes what [`TriangleRay::intersect`] computes, by the same
/// operations in the same order, so the answers are the same bit for bit;
/// a lane with an edge function zero or subnormal, or a scaled `t` past
/// `f32`'s range, takes the scalar test, as in [`TriangleRay::occludes4`].
///
/// Plain arrays in loops of eight, which the compiler vectorises: in a
/// caller compiled for AVX2, one 256-bit operation a step.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRays8 {
    origin: [[f32; 8]; 3],
    shear: [[f32; 8]; 3],
    /// `+inf` in a lane never used, so that no `t` passes there.
    t_min: [f32; 8],
    t_max: [f32; 8],
    k: [usize; 3],
    len: usize,
}

impl TriangleRays8 {
    /// No rays, and none to be taken: [`TriangleRays8::push`] refuses
    /// every ray (no ray has these axes).
    #[inline(always)]
    #[must_use]
    pub fn empty() -> Self {
        Self {
            origin: [[0.0; 8]; 3],
            shear: [[0.0; 8]; 3],
            t_min: [f32::INFINITY; 8],
            t_max: [f32::NEG_INFINITY; 8],
            k: [usize::MAX; 3],
            len: 0,
        }
    }

    /// No rays yet; [`TriangleRays8::push`] takes rays with the axes of
    /// `first` (which it does not add).
    #[inline(always)]
    #[must_use]
    pub fn like(first: &TriangleRay) -> Self {
        Self {
            origin: [[0.0; 8]; 3],
            shear: [[0.0; 8]; 3],
            t_min: [f32::INFINITY; 8],
            t_max: [f32::NEG_INFINITY; 8],
            k: first.k,
            len: 0,
        }
    }

    /// Adds `ray` in the next lane; `false` (and nothing added) when all
    /// eight are taken or its axes differ from the group's.
    #[inline(always)]
    pub fn push(&mut self, ray: &TriangleRay) -> bool {
        let i = self.len;
        if i >= 8 || ray.k != self.k {
            return false;
        }
        for a in 0..3 {
            self.origin[a][i] = ray.origin[a];
            self.shear[a][i] = ray.shear[a];
        }
        self.t_min[i] = ray.t_min;
        self.t_max[i] = ray.t_max;
        self.len = i + 1;
        true
    }

    /// How many lanes are in use.
    #[inline(always)]
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no lane is in use.
    #[inline(always)]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The origins on the axes `kx`, `ky`, `kz`, as `[axis][lane]`.
    #[inline(always)]
    #[must_use]
    pub fn origin(&self) -> &[[f32; 8]; 3] {
        &self.origin
    }

    /// The shears `sx`, `sy`, `sz`, as `[component][lane]`.
    #[inline(always)]
    #[must_use]
    pub fn shear(&self) -> &[[f32; 8]; 3] {
        &self.shear
    }

    /// The lanes' intervals, narrowed to finite bounds as
    /// [`TriangleRay`]'s are (an unused lane's is empty: `[+inf, -inf]`).
    #[inline(always)]
    #[must_use]
    pub fn interval(&self) -> (&[f32; 8], &[f32; 8]) {
        (&self.t_min, &self.t_max)
    }

    /// The axes `kx`, `ky`, `kz` the group shares, each below 3.
    #[inline(always)]
    #[must_use]
    pub fn axes(&self) -> [usize; 3] {
        self.k.map(|k| k.min(2))
    }

    /// The ray of lane `i` (below [`TriangleRays8::len`]), for the scalar
    /// test of a lane it must decide (see [`TriangleRay::intersect`]).
    #[inline(always)]
    #[must_use]
    pub fn ray(&self, i: usize) -> TriangleRay {
        let i = i & 7;
        TriangleRay {
            origin: [self.origin[0][i], self.origin[1][i], self.origin[2][i]],
            k: self.k,
            shear: [self.shear[0][i], self.shear[1][i], self.shear[2][i]],
            t_min: self.t_min[i],
            t_max: self.t_max[i],
        }
    }

    /// The lanes (bit `i` for the `i`th ray pushed) whose ray meets any of
    /// the (up to) four triangles of `tris` within its interval: bit `i`
    /// is `self`'s `i`th ray's [`TriangleRay::occludes4`].
    #[inline(always)]
    #[must_use]
    pub fn occluded(&self, tris: &Triangles4) -> u32 {
        let used = (1u32 << self.len.min(8)) - 1;
        let mut hit = 0u32;
        for j in 0..tris.len() {
            let Lanes8 { ok, exact, .. } = self.lanes(tris, j);
            hit |= ok;
            hit |= self.scalar_hits(tris, j, exact & used & !hit);
        }
        hit & used
    }

    /// The lanes of `lanes` whose ray meets triangle `j` of `tris`, each
    /// by the scalar test ([`TriangleRay::intersect`], whose `f64`
    /// fallback decides a zero edge function).
    #[inline(always)]
    #[must_use]
    pub fn scalar_hits(&self, tris: &Triangles4, j: usize, mut lanes: u32) -> u32 {
        let mut hit = 0;
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if self.ray(i).intersect(&tris.corners(j)).is_some() {
                hit |= 1 << i;
            }
        }
        hit
    }

    /// Corner `p` (on the axes `kx`, `ky`, `kz`) sheared per lane as
    /// [`TriangleRay::shear`] does.
    #[inline(always)]
    fn shear8(&self, [px, py, pz]: [f32; 3]) -> [[f32; 8]; 3] {
        let [ox, oy, oz] = &self.origin;
        let [sx, sy, sz] = &self.shear;
        let mut out = [[0.0f32; 8]; 3];
        for i in 0..8 {
            let z = pz - oz[i];
            out[0][i] = (px - ox[i]) - sx[i] * z;
            out[1][i] = (py - oy[i]) - sy[i] * z;
            out[2][i] = sz[i] * z;
        }
        out
    }

    /// Each lane's nearest hit among the (up to) four triangles of `tris`,
    /// the one [`TriangleRay::intersect4`] gives that lane's ray (the last
    /// triangle among equal `t`), bit for bit; each lane hit has its
    /// interval narrowed to its `t`, as the ray's would be.
    #[inline(always)]
    #[must_use]
    pub fn closest(&mut self, tris: &Triangles4) -> Nearest8 {
        let used = (1u32 << self.len.min(8)) - 1;
        let mut out = Nearest8::default();
        for j in 0..tris.len() {
            let Lanes8 { t, b1, b2, ok, exact } = self.lanes(tris, j);
            let mut ok = ok & used;
            while ok != 0 {
                let i = ok.trailing_zeros() as usize & 7;
                ok &= ok - 1;
                self.t_max[i] = t[i];
                out.record(i, j, (t[i], b1[i], b2[i]));
            }
            self.scalar_nearest(tris, j, exact & used, &mut out);
        }
        out
    }

    /// For each lane of `lanes`, the scalar test of triangle `j` of
    /// `tris` within the lane's (narrowed) interval: a hit narrows it and
    /// is recorded in `out`.
    #[inline(always)]
    pub fn scalar_nearest(&mut self, tris: &Triangles4, j: usize, mut lanes: u32, out: &mut Nearest8) {
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize & 7;
            lanes &= lanes - 1;
            if let Some(hit) = self.ray(i).intersect(&tris.corners(j)) {
                self.t_max[i] = hit.0;
                out.record(i, j, hit);
            }
        }
    }

    /// The lanes' upper interval ends, to narrow them.
    #[inline(always)]
    #[must_use]
    pub fn t_max_mut(&mut self) -> &mut [f32; 8] {
        &mut self.t_max
    }

    /// Each lane's test of triangle `j` of `tris`: its `t`, `b1`, `b2`,
    /// the lanes that meet it within their interval that the scalar test
    /// need not decide (`ok`; their values are [`TriangleRay::intersect`]'s,
    /// bit for bit), and those it must (`exact`: an edge function zero or
    /// subnormal, or a scaled `t` past `f32`'s range).
    #[inline(always)]
    fn lanes(&self, tris: &Triangles4, j: usize) -> Lanes8 {
        let [kx, ky, kz] = self.k.map(|k| k.min(2));
        let (v, j) = (&tris.v, j & 3);
        let [a, b, c] = [&v[0], &v[1], &v[2]].map(|p| self.shear8([p[kx][j], p[ky][j], p[kz][j]]));
        let ([ax, ay, az], [bx, by, bz], [cx, cy, cz]) = (a, b, c);
        let mut out = Lanes8 { t: [0.0; 8], b1: [0.0; 8], b2: [0.0; 8], ok: 0, exact: 0 };
        for i in 0..8 {
            let u = cx[i] * by[i] - cy[i] * bx[i];
            let vv = ax[i] * cy[i] - ay[i] * cx[i];
            let w = bx[i] * ay[i] - by[i] * ax[i];
            let zero = tiny(u) | tiny(vv) | tiny(w);
            let outside = ((u < 0.0) | (vv < 0.0) | (w < 0.0)) & ((u > 0.0) | (vv > 0.0) | (w > 0.0));
            let det = u + vv + w;
            let t_scaled = u * az[i] + vv * bz[i] + w * cz[i];
            let rcp = 1.0 / det;
            let t = t_scaled * rcp;
            (out.t[i], out.b1[i], out.b2[i]) = (t, vv * rcp, w * rcp);
            let pass =
                !outside & (det != 0.0) & det.is_finite() & (t >= self.t_min[i]) & (t <= self.t_max[i]);
            // A scaled `t` past the range of `f32` products is the scalar
            // test's too.
            let zero = zero | (!outside & unsure(t_scaled));
            out.ok |= u32::from(pass & !zero) << i;
            out.exact |= u32::from(zero) << i;
        }
        out
    }
}

/// The rays of a packet (`N` of them, a multiple of 8, at most 64), each
/// prepared as [`TriangleRay::new`] prepares it, in SoA lanes: made eight
/// rays at a time where the packet first reaches a leaf
/// ([`PacketRays::prepare`]), by operations the compiler runs eight lanes
/// wide, and read from there into a [`TriangleRays8`] group
/// ([`PacketRays::group`]) or as one [`TriangleRay`] ([`PacketRays::ray`]).
/// Every lane holds what [`TriangleRay::new`] gives its ray, bit for bit.
#[derive(Clone, Debug)]
pub struct PacketRays<const N: usize> {
    /// The origins on each ray's axes `kx`, `ky`, `kz`.
    origin: [[f32; N]; 3],
    /// The shears `sx`, `sy`, `sz`.
    shear: [[f32; N]; 3],
    t_min: [f32; N],
    t_max: [f32; N],
    /// Each ray's axes, as its index into `AXES`.
    code: [u8; N],
    /// The rays made (whole blocks of eight).
    made: u64,
    /// Per index into `AXES`, the rays made with those axes.
    by_code: [u64; 6],
}

impl<const N: usize> Default for PacketRays<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> PacketRays<N> {
    /// Blocks of eight rays.
    const BLOCKS: usize = {
        assert!(N.is_multiple_of(8) && N <= 64, "a packet of 8, 16, …, 64 rays");
        N / 8
    };

    /// No ray made yet.
    #[inline(always)]
    #[must_use]
    pub fn new() -> Self {
        Self {
            origin: [[0.0; N]; 3],
            shear: [[0.0; N]; 3],
            t_min: [0.0; N],
            t_max: [0.0; N],
            code: [0; N],
            made: 0,
            by_code: [0; 6],
        }
    }

    /// Makes the rays of `want` not made yet, with the others of their
    /// blocks of eight: ray `k` from `rays[k]`, whose direction must be
    /// non-zero and finite, as for [`TriangleRay::new`] (another ray's
    /// lanes hold values no answer reads).
    #[inline(always)]
    pub fn prepare(&mut self, rays: &[Ray; N], want: u64) {
        self.prepare_moved(rays, want, None);
    }

    /// [`PacketRays::prepare`] for the rays moved by `offset` where it is
    /// `Some`: each origin `origin + offset`, per component, the rest as
    /// it is (the rays that `Transform::ray_to_object` gives under a
    /// translation alone, see `Transform::object_offset`).
    #[inline(always)]
    pub fn prepare_moved(&mut self, rays: &[Ray; N], want: u64, offset: Option<Vec3>) {
        let todo = want & !self.made;
        if todo == 0 {
            return;
        }
        for b in 0..Self::BLOCKS {
            if todo >> (8 * b) & 0xff != 0 {
                self.prepare8(rays, b, offset);
            }
        }
    }

    /// Makes block `b` (rays `8b..8b + 8`), moved by `offset`.
    #[inline(always)]
    fn prepare8(&mut self, rays: &[Ray; N], b: usize, offset: Option<Vec3>) {
        let base = 8 * b;
        let Some(block) = rays.get(base..base + 8) else { return };
        let mut o = [[0.0f32; 8]; 3];
        let mut d = [[0.0f32; 8]; 3];
        let (mut t0, mut t1) = ([0.0f32; 8], [0.0f32; 8]);
        for (i, r) in block.iter().enumerate() {
            let (ro, rd) = (r.origin.to_array(), r.dir.to_array());
            for a in 0..3 {
                o[a][i] = ro[a];
                d[a][i] = rd[a];
            }
            (t0[i], t1[i]) = finite_interval(r.t_min, r.t_max);
        }
        if let Some(offset) = offset {
            let offset = offset.to_array();
            for (row, off) in o.iter_mut().zip(offset) {
                for x in row {
                    *x += off;
                }
            }
        }
        let mut code = [0u8; 8];
        let mut out = [[0.0f32; 8]; 6];
        for i in 0..8 {
            let (dx, dy, dz) = (d[0][i], d[1][i], d[2][i]);
            let (ox, oy, oz) = (o[0][i], o[1][i], o[2][i]);
            let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
            // As `TriangleRay::new`: the dominant axis `kz`, then
            // `kx = (kz + 1) % 3`, `ky = (kx + 1) % 3`, swapped where
            // `d[kz] < 0`; by selects, which run eight lanes wide.
            let x_wins = (ax >= ay) & (ax >= az);
            let y_wins = ay >= az;
            let (pz, pa, pb, qz, qa, qb) = if x_wins {
                (dx, dy, dz, ox, oy, oz)
            } else if y_wins {
                (dy, dz, dx, oy, oz, ox)
            } else {
                (dz, dx, dy, oz, ox, oy)
            };
            let neg = pz < 0.0;
            let (px, py, qx, qy) = if neg { (pb, pa, qb, qa) } else { (pa, pb, qa, qb) };
            let kz = u8::from(!x_wins) * (1 + u8::from(!y_wins));
            code[i] = kz * 2 + u8::from(neg);
            // `[d[kx], d[ky], 1] / dz`, the quotients of `TriangleRay::new`.
            out[0][i] = px / pz;
            out[1][i] = py / pz;
            out[2][i] = 1.0 / pz;
            out[3][i] = qx;
            out[4][i] = qy;
            out[5][i] = qz;
        }
        for a in 0..3 {
            self.shear[a][base..base + 8].copy_from_slice(&out[a]);
            self.origin[a][base..base + 8].copy_from_slice(&out[3 + a]);
        }
        self.t_min[base..base + 8].copy_from_slice(&t0);
        self.t_max[base..base + 8].copy_from_slice(&t1);
        self.code[base..base + 8].copy_from_slice(&code);
        for (c, m) in self.by_code.iter_mut().enumerate() {
            let lanes =
                code.iter().enumerate().fold(0u64, |m, (i, &k)| m | u64::from(usize::from(k) == c) << i);
            *m |= lanes << base;
        }
        self.made |= 0xff << base;
    }

    /// Whether ray `k` is made.
    #[inline(always)]
    #[must_use]
    pub fn is_made(&self, k: usize) -> bool {
        k < N && self.made >> k & 1 == 1
    }

    /// Ray `k` (made), as [`TriangleRay::new`] gives it, with its interval
    /// as narrowed since.
    #[inline(always)]
    #[must_use]
    pub fn ray(&self, k: usize) -> TriangleRay {
        let k = k % N;
        TriangleRay {
            origin: [self.origin[0][k], self.origin[1][k], self.origin[2][k]],
            k: AXES[usize::from(self.code[k]) % 6],
            shear: [self.shear[0][k], self.shear[1][k], self.shear[2][k]],
            t_min: self.t_min[k],
            t_max: self.t_max[k],
        }
    }

    /// Narrows ray `k`'s interval to end at `t_max` (after a closer hit),
    /// as [`TriangleRay::set_t_max`].
    #[inline(always)]
    pub fn set_t_max(&mut self, k: usize, t_max: f32) {
        let k = k % N;
        self.t_max[k] = finite_interval(self.t_min[k], t_max).1;
    }

    /// Fills `g` with up to eight rays of `rest` (all made, by
    /// [`PacketRays::prepare`]) that share axes: the lowest and those after
    /// it with its axes, in order (the rays [`TriangleRays8::push`] takes
    /// from them), with each lane's ray in `lane`; returns the rays taken.
    #[inline(always)]
    pub fn group(&self, rest: u64, g: &mut TriangleRays8, lane: &mut [u8; 8]) -> u64 {
        debug_assert!(rest & !self.made == 0, "every ray of `rest` made ({rest:#x}, {:#x})", self.made);
        let lowest = rest.trailing_zeros() as usize;
        if lowest >= N || self.made >> lowest & 1 == 0 {
            // Not reached: the caller made the rays of `rest`.
            *g = TriangleRays8::empty();
            return rest;
        }
        let c = usize::from(self.code[lowest]) % 6;
        let mut taken = rest & self.by_code[c];
        // Keep the first eight: `after` ends as the bits past the eighth.
        let mut after = taken;
        for _ in 0..8 {
            after &= after.wrapping_sub(1);
        }
        taken ^= after;
        g.k = AXES[c];
        g.len = taken.count_ones() as usize;
        let run = taken >> lowest;
        if run & (run + 1) == 0 && lowest + 8 <= N {
            // Consecutive rays: eight lanes copied at once (those past
            // `len` hold other rays, which no answer reads).
            for (i, l) in lane.iter_mut().enumerate() {
                *l = (lowest + i) as u8;
            }
            let from = |x: &[f32; N]| -> [f32; 8] {
                let mut v = [0.0; 8];
                v.copy_from_slice(&x[lowest..lowest + 8]);
                v
            };
            g.origin = [from(&self.origin[0]), from(&self.origin[1]), from(&self.origin[2])];
            g.shear = [from(&self.shear[0]), from(&self.shear[1]), from(&self.shear[2])];
            g.t_min = from(&self.t_min);
            g.t_max = from(&self.t_max);
        } else {
            // Each lane's ray (the lanes past `len` repeat the lowest),
            // then each row built whole from its eight values: written
            // lane by lane into the group, as `push` writes, the kitchen's
            // shadow packets measured 6 % slower (docs/benchmarks.md).
            let mut m = taken;
            let mut ks = [lowest; 8];
            for (k, l) in ks.iter_mut().zip(lane.iter_mut()) {
                if m != 0 {
                    *k = m.trailing_zeros() as usize % N;
                    m &= m - 1;
                }
                *l = *k as u8;
            }
            let row = |x: &[f32; N]| ks.map(|k| x[k % N]);
            g.origin = [row(&self.origin[0]), row(&self.origin[1]), row(&self.origin[2])];
            g.shear = [row(&self.shear[0]), row(&self.shear[1]), row(&self.shear[2])];
            g.t_min = row(&self.t_min);
            g.t_max = row(&self.t_max);
        }
        taken
    }
}

/// [`TriangleRays8::lanes`]'s values for one triangle.
struct Lanes8 {
    t: [f32; 8],
    b1: [f32; 8],
    b2: [f32; 8],
    ok: u32,
    exact: u32,
}

/// Each lane's nearest hit ([`TriangleRays8::closest`]): bit `i` of
/// `lanes` set when lane `i` hit, then its triangle (lane of the block),
/// `t` and barycentrics `b1`, `b2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Nearest8 {
    /// The lanes with a hit.
    pub lanes: u32,
    /// Per lane, the triangle hit (0–3).
    pub triangle: [u32; 8],
    /// Per lane, the hit's `t`.
    pub t: [f32; 8],
    /// Per lane, the barycentric coordinate of the triangle's second corner.
    pub b1: [f32; 8],
    /// Per lane, the barycentric coordinate of the triangle's third corner.
    pub b2: [f32; 8],
}

impl Nearest8 {
    /// Records hit `(t, b1, b2)` on triangle `j` for lane `i`.
    #[inline(always)]
    pub fn record(&mut self, i: usize, j: usize, (t, b1, b2): (f32, f32, f32)) {
        let i = i & 7;
        self.lanes |= 1 << i;
        self.triangle[i] = j as u32;
        (self.t[i], self.b1[i], self.b2[i]) = (t, b1, b2);
    }

    /// Lane `i`'s hit as `(triangle, t, b1, b2)`.
    #[must_use]
    pub fn get(&self, i: usize) -> Option<(usize, f32, f32, f32)> {
        let i = i & 7;
        (self.lanes >> i & 1 == 1).then(|| (self.triangle[i] as usize, self.t[i], self.b1[i], self.b2[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close, uniform};

    fn tri() -> Triangle {
        Triangle::new([Vec3::ZERO, Vec3::X, Vec3::Y]).unwrap()
    }

    #[test]
    fn axes_follow_the_papers_rule_on_ties_signs_and_nan() {
        // Woop et al.'s choice, written with branches: the largest |d|
        // (the first of equals, x before y before z), then the next two
        // axes in cyclic order, swapped where d[kz] < 0.
        fn reference(d: Vec3) -> [usize; 3] {
            let [ax, ay, az] = d.abs().to_array();
            let kz = if ax >= ay && ax >= az {
                0
            } else if ay >= az {
                1
            } else {
                2
            };
            let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
            if d[kz] < 0.0 { [ky, kx, kz] } else { [kx, ky, kz] }
        }
        let values = [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 2.0, -2.0, f32::NAN, f32::INFINITY];
        for x in values {
            for y in values {
                for z in values {
                    let d = Vec3::new(x, y, z);
                    let tr = TriangleRay::new(&Ray::new(Vec3::ZERO, d));
                    assert_eq!(tr.k, reference(d), "direction {d}");
                }
            }
        }
    }

    #[test]
    fn hits_from_both_sides_with_upright_uv() {
        // uv = (b1, 1 − b2): on (0,0,0), (1,0,0), (0,1,0) seen from +Z, u
        // runs along +X and v = 0 (an image's top row) lies at y = 1.
        let h = tri().intersect(&Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.25, 0.5, 0.0), Vec3::Z, Vec2::new(0.25, 0.5), true);
        let h = tri().intersect(&Ray::new(Vec3::new(0.5, 0.25, -1.0), Vec3::new(0.0, 0.0, 0.5))).unwrap();
        check_hit(&h, 2.0, Vec3::new(0.5, 0.25, 0.0), Vec3::Z, Vec2::new(0.5, 0.75), false);
        // Oblique.
        let h = tri().intersect(&Ray::new(Vec3::new(1.25, 0.25, 1.0), Vec3::new(-1.0, 0.0, -1.0))).unwrap();
        check_hit(&h, 1.0, Vec3::new(0.25, 0.25, 0.0), Vec3::Z, Vec2::new(0.25, 0.75), true);
        let h = tri().intersect(&Ray::new(Vec3::new(0.0, 1.0, 1.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 1.0, Vec3::Y, Vec3::Z, Vec2::ZERO, true);
    }

    #[test]
    fn edges_and_vertices_are_hit_and_just_outside_is_not() {
        let t = tri();
        for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.5, 0.5, 0.0)] {
            let h = t.intersect(&Ray::new(p + Vec3::Z, Vec3::NEG_Z)).unwrap_or_else(|| panic!("{p}"));
            close(h.t, 1.0, 1e-6);
        }
        for p in [Vec3::new(0.5, -1e-6, 1.0), Vec3::new(-1e-6, 0.5, 1.0), Vec3::new(0.5, 0.500_001, 1.0)] {
            assert!(t.intersect(&Ray::new(p, Vec3::NEG_Z)).is_none(), "{p}");
        }
    }

    #[test]
    fn parallel_rays_and_intervals() {
        let t = tri();
        assert!(t.intersect(&Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X)).is_none(), "in its plane");
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::X)).is_none());
        assert!(t.intersect(&Ray::with_interval(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z, 0.0, 0.5)).is_none());
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::Z)).is_none(), "behind");
        assert!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO)).is_none());
    }

    #[test]
    fn nearly_parallel_ray_never_returns_infinity() {
        // The plane is reached at t = 1e48, beyond f32: no hit, not t = ∞.
        let far = Triangle::new([
            Vec3::new(-1e15, -1e15, 0.0),
            Vec3::new(1e15, -1e15, 0.0),
            Vec3::new(0.0, 1e15, 0.0),
        ]);
        let r = Ray::new(Vec3::new(0.0, 0.0, 1e10), Vec3::new(1e-38, 0.0, -1e-38));
        if let Some(h) = far.unwrap().intersect(&r) {
            assert!(h.t.is_finite() && h.point.is_finite(), "{h:?}");
        }
    }

    #[test]
    fn degenerate_triangles_are_rejected() {
        assert!(Triangle::new([Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)]).is_err());
        assert!(Triangle::new([Vec3::ZERO, Vec3::X, Vec3::NAN]).is_err());
        assert_eq!(tri().bounds(), Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(tri().normal(), Vec3::Z);
    }

    #[test]
    fn huge_and_tiny_triangles_have_unit_normals() {
        // Edges of 5e9: the normal's squared length overflows (it was 0,
        // and the hit was taken for the back face).
        let big = Triangle::new([Vec3::ZERO, Vec3::new(0.0, 5e9, 0.0), Vec3::new(0.0, 0.0, 5e9)]).unwrap();
        let h = big.intersect(&Ray::new(Vec3::new(1.0, 1.25e9, 1.25e9), Vec3::NEG_X)).unwrap();
        assert_eq!((h.geo_normal, h.front_face), (Vec3::X, true));
        // Edges of 1e-12: refused as of zero area before; 1e-10 gave a
        // normal of length 1.0000027.
        for e in [1e-12f32, 1e-11, 1e-10] {
            let small = Triangle::new([Vec3::ZERO, Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, e, 0.0)]).unwrap();
            assert_eq!(small.normal(), Vec3::Z, "edge {e}");
        }
        // A triangle with no area stays refused at any size; one whose
        // edges' product overflows is refused as too large, not as flat.
        assert!(Triangle::new([Vec3::ZERO, Vec3::splat(1e-30), Vec3::splat(2e-30)]).is_err());
        let e =
            Triangle::new([Vec3::ZERO, Vec3::new(3e38, 0.0, 0.0), Vec3::new(0.0, 3e38, 0.0)]).unwrap_err();
        assert!(e.to_string().starts_with("triangle is too large"), "{e}");
    }

    /// A tilted triangle and the rays around it, scaled by 2ᵉ for e from
    /// −66 to 60, meet and leave as at unit size: camera rays (their
    /// directions scaled too) hit at the same `t` (to a few ulps; to 1e-5
    /// below 2⁻⁶³, where edge functions are subnormal), and rays spawned from
    /// the hits (the offset of a scene that size) leave it without meeting
    /// it again. Before the test summed its scaled distance in `f64` where
    /// `f32` products under- or overflow, a ray leaving a triangle of
    /// 1e-14 met it again at `t = 0` or a small wrong `t` (the scene was
    /// unlit), and a triangle of 1e13 seen from 3e13 was missed.
    #[test]
    fn triangles_of_any_size_are_met_and_left_as_at_unit_size() {
        let unit = [Vec3::ZERO, Vec3::new(1.0, 0.0, 0.5), Vec3::new(0.0, 1.0, 0.5)];
        let eye = Vec3::new(0.3, 0.3, 3.0);
        for e in (-66..=60).step_by(3) {
            let s = 2f32.powi(e);
            let tri = Triangle::new(unit.map(|c| c * s)).unwrap();
            let offset = crate::offset_scale(3.0 * s);
            let mut met = 0;
            for i in 0..24 {
                for j in 0..24 - i {
                    let aim = Vec3::new((i as f32 + 0.3) / 24.0, (j as f32 + 0.3) / 24.0, 0.0);
                    let at_one = Triangle::new(unit).unwrap().intersect(&Ray::new(eye, aim - eye));
                    let ray = Ray::new(eye * s, (aim - eye) * s);
                    let hit = tri.intersect(&ray);
                    assert_eq!(hit.is_some(), at_one.is_some(), "2^{e}: aimed at {aim}");
                    let (Some(h), Some(one)) = (hit, at_one) else { continue };
                    met += 1;
                    // Below 2⁻⁶³ the edge functions (2⁻¹²⁶ and less) are
                    // subnormal, and `t` keeps fewer bits.
                    let tol = if e < -63 { 1e-5 } else { 4.0 * f32::EPSILON };
                    assert!((h.t - one.t).abs() <= tol * one.t, "2^{e}: t {} against {}", h.t, one.t);
                    for d in [Vec3::Z, h.geo_normal, Vec3::new(0.3, -0.2, 1.0), Vec3::new(1.0, 1.0, 0.1)] {
                        let d = if d.dot(h.geo_normal) < 0.0 { -d } else { d };
                        let again = tri.intersect(&Ray::spawn_scaled(h.point, h.geo_normal, d, offset));
                        assert!(again.is_none(), "2^{e}: left {h:?} along {d} and met {again:?}");
                    }
                }
            }
            assert!(met > 200, "2^{e}: {met} met");
        }
    }

    /// `intersect4` and `intersect4_branchless` keep exactly what a loop of
    /// `intersect` over the lanes (narrowing `t_max` after each hit) keeps:
    /// the same lane, `t`, `b1`, `b2` bit for bit, on random and degenerate
    /// triangles, exact ties, rays through shared edges and vertices,
    /// axis-parallel rays with `±0.0` components, and every interval kind.
    #[test]
    fn intersect4_is_the_scalar_loop_bit_for_bit() {
        let mut f = uniform(0x2545_f491_u64);
        let mut hits = 0;
        let mut exact_lanes = 0;
        let mut scaled_hits = 0;
        for case in 0..60_000 {
            // Every third case scaled by 2⁻⁶² or 2⁴⁵: edge functions and
            // distances past the range of `f32` products, the scalar
            // test's lanes.
            let scale = [1.0, 2f32.powi(-62), 2f32.powi(45)][(case / 7) % 3];
            let tris: Vec<[Vec3; 3]> =
                random_leaf(&mut f, case).into_iter().map(|t| t.map(|c| c * scale)).collect();
            let mut o = Vec3::new(f(), f(), f()) * 2.0;
            let mut d = Vec3::new(f(), f(), f());
            if case % 3 == 0 {
                o = o.round();
                d = d.round();
            }
            if case % 5 == 0 {
                d[case % 3] = if case % 2 == 0 { 0.0 } else { -0.0 };
            }
            if d == Vec3::ZERO {
                d = Vec3::Z;
            }
            let (t_min, t_max) = match case % 4 {
                0 => (0.0, f32::INFINITY),
                1 => (0.5, 1.5),
                2 => (f32::MIN, f32::MAX),
                _ => (-1.0, 0.25),
            };
            let tr = TriangleRay::new(&Ray::with_interval(o * scale, d, t_min * scale, t_max * scale));
            let mut scalar = tr;
            let mut want = None;
            for (k, t) in tris.iter().enumerate() {
                if let Some((t, b1, b2)) = scalar.intersect(t) {
                    scalar.set_t_max(t);
                    want = Some((k, t.to_bits(), b1.to_bits(), b2.to_bits()));
                }
            }
            let got = tr
                .intersect4(&Triangles4::new(&tris))
                .map(|(k, t, b1, b2)| (k, t.to_bits(), b1.to_bits(), b2.to_bits()));
            assert_eq!(got, want, "case {case}: {tris:?} {o} {d}");
            let branchless = tr
                .intersect4_branchless(&Triangles4::new(&tris))
                .map(|(k, t, b1, b2)| (k, t.to_bits(), b1.to_bits(), b2.to_bits()));
            assert_eq!(branchless, want, "case {case}: intersect4_branchless");
            assert_eq!(tr.occludes4(&Triangles4::new(&tris)), want.is_some(), "case {case}: occludes4");
            hits += usize::from(want.is_some());
            exact_lanes += usize::from(case % 3 == 0 && want.is_some());
            scaled_hits += usize::from(scale != 1.0 && want.is_some());
        }
        assert!(hits > 1500 && exact_lanes > 500 && scaled_hits > 500, "{hits} {exact_lanes} {scaled_hits}");
    }

    /// One to four random triangles for test case `case`, with degenerate
    /// ones, small-integer corners (exact hits on shared edges and
    /// vertices) and exact copies among them.
    fn random_leaf(f: &mut impl FnMut() -> f32, case: usize) -> Vec<[Vec3; 3]> {
        let n = 1 + case % 4;
        let mut tris = Vec::new();
        for k in 0..n {
            let mut t = [Vec3::new(f(), f(), f()), Vec3::new(f(), f(), f()), Vec3::new(f(), f(), f())];
            match (case / 4 + k) % 7 {
                // Degenerate: a repeated corner, or collinear corners.
                0 => t[2] = t[1],
                1 => t[2] = t[0] + (t[1] - t[0]) * 0.5,
                // Small integers: rays hit shared edges and vertices exactly.
                2 | 3 => t = t.map(|p| (p * 2.0).round()),
                // A copy of the previous triangle (an exact tie).
                4 if k > 0 => t = tris[k - 1],
                _ => {}
            }
            tris.push(t);
        }
        tris
    }

    /// Eight rays at a time give each ray's own `occludes4`, bit for bit
    /// the same answers: rays from nearby origins in nearby directions (a
    /// packet), some with integer coordinates (exact edge hits), some
    /// with a zero direction component, under several intervals; a ray
    /// whose axes differ from the group's is refused.
    #[test]
    fn eight_rays_occluded_is_each_rays_occludes4() {
        let mut f = uniform(0x9e37_79b9_u64);
        let (mut hits, mut exact, mut refused) = (0, 0, 0);
        for case in 0..20_000 {
            let tris = Triangles4::new(&random_leaf(&mut f, case));
            let (o0, d0) = (Vec3::new(f(), f(), f()) * 2.0, Vec3::new(f(), f(), f()));
            let spread = [0.0, 0.05, 0.5][case % 3];
            let mut group: Option<TriangleRays8> = None;
            let mut rays = Vec::new();
            for i in 0..(1 + case % 11) {
                let mut o = o0 + Vec3::new(f(), f(), f()) * spread;
                let mut d = d0 + Vec3::new(f(), f(), f()) * spread;
                if case % 4 == 0 {
                    (o, d) = (o.round(), d.round());
                }
                if (case + i) % 9 == 0 {
                    d[i % 3] = if i % 2 == 0 { 0.0 } else { -0.0 };
                }
                if d == Vec3::ZERO {
                    d = Vec3::Z;
                }
                let (t_min, t_max) =
                    [(0.0, f32::INFINITY), (0.5, 1.5), (f32::MIN, f32::MAX), (-1.0, 0.25)][(case + i) % 4];
                let tr = TriangleRay::new(&Ray::with_interval(o, d, t_min, t_max));
                let g = group.get_or_insert_with(|| TriangleRays8::like(&tr));
                let full = g.len() == 8;
                if g.push(&tr) {
                    rays.push(tr);
                } else {
                    assert!(full || tr.k != g.k, "case {case}: ray {i} refused");
                    refused += 1;
                }
            }
            let Some(g) = group else { continue };
            // Each lane's `t`, triangle by triangle, is the scalar test's.
            for j in 0..tris.len as usize {
                let l = g.lanes(&tris, j);
                for (i, r) in rays.iter().enumerate().filter(|(i, _)| l.exact >> i & 1 == 0) {
                    let scalar = r.intersect(&tris.corners(j)).map(|h| [h.0, h.1, h.2].map(f32::to_bits));
                    let lane = (l.ok >> i & 1 == 1).then(|| [l.t[i], l.b1[i], l.b2[i]].map(f32::to_bits));
                    assert_eq!(lane, scalar, "case {case}: triangle {j}, ray {i}");
                }
            }
            // Each lane's nearest hit is its ray's `intersect4`, and its
            // interval is narrowed to it.
            let mut near = g;
            let nearest = near.closest(&tris);
            for (i, r) in rays.iter().enumerate() {
                let want = r.intersect4(&tris);
                let bits = |h: Option<(usize, f32, f32, f32)>| {
                    h.map(|(j, t, b1, b2)| (j, [t, b1, b2].map(f32::to_bits)))
                };
                assert_eq!(bits(nearest.get(i)), bits(want), "case {case}: ray {i}");
                let t_max = want.map_or(g.interval().1[i], |h| h.1);
                assert_eq!(near.interval().1[i].to_bits(), t_max.to_bits(), "case {case}: ray {i}'s t_max");
            }
            let want = rays.iter().enumerate().fold(0u32, |m, (i, r)| m | u32::from(r.occludes4(&tris)) << i);
            assert_eq!(g.occluded(&tris), want, "case {case}: {tris:?} {rays:?}");
            hits += want.count_ones();
            exact += u32::from(case % 4 == 0 && want != 0);
        }
        assert!(hits > 2500 && exact > 200 && refused > 1000, "{hits} {exact} {refused}");
    }

    /// A [`TriangleRay`]'s fields as bits, to compare two bit for bit.
    fn ray_bits(r: &TriangleRay) -> ([u32; 3], [usize; 3], [u32; 3], [u32; 2]) {
        (r.origin.map(f32::to_bits), r.k, r.shear.map(f32::to_bits), [r.t_min.to_bits(), r.t_max.to_bits()])
    }

    /// `N` rays for [`PacketRays`]: near one direction (or, in every
    /// fourth case, any), with zero and `-0.0` components, components of
    /// equal size (ties for the dominant axis), lattice values and the
    /// interval kinds of the eight-ray test.
    fn packet_of<const N: usize>(f: &mut impl FnMut() -> f32, case: usize) -> [Ray; N] {
        let d0 = Vec3::new(f(), f(), f());
        std::array::from_fn(|i| {
            let mut d = if case.is_multiple_of(4) {
                Vec3::new(f(), f(), f())
            } else {
                d0 + Vec3::new(f(), f(), f()) * 0.1
            };
            match (case + i) % 13 {
                0 => d[i % 3] = 0.0,
                1 => d[i % 3] = -0.0,
                2 => d = Vec3::new(d.x, d.x, -d.x),
                3 => d = Vec3::new(-d.y, d.y, d.z.abs().min(d.y.abs())),
                4 => d = Vec3::new(0.0, -0.0, d.z),
                6 => d = Vec3::new(d.x * 0.5, d.y, -d.y),
                5 => d = d.round(),
                _ => {}
            }
            if d == Vec3::ZERO {
                d = Vec3::NEG_Y;
            }
            let o = Vec3::new(f(), f(), f()) * 3.0;
            let (t_min, t_max) =
                [(0.0, f32::INFINITY), (0.5, 1.5), (f32::MIN, f32::MAX), (-1.0, 0.25)][(case + i) % 4];
            Ray::with_interval(o, d, t_min, t_max)
        })
    }

    /// A random mask of `N` bits: dense, sparse, one run, or all.
    fn mask_of<const N: usize>(f: &mut impl FnMut() -> f32, case: usize) -> u64 {
        let all = if N == 64 { u64::MAX } else { (1 << N) - 1 };
        let bits = (0..N).fold(0u64, |m, k| m | u64::from(f() > [-0.8, 0.0, 0.7][case % 3]) << k);
        let run = (all >> (case % N)) << (case / 3 % N) & all;
        [bits, bits, run, all][case / 2 % 4] & all
    }

    /// Each made ray of a [`PacketRays`] is [`TriangleRay::new`]'s ray,
    /// bit for bit, in packets of 16 and 64, made whole blocks of eight at
    /// a time; and narrowing its interval is [`TriangleRay::set_t_max`].
    #[test]
    fn packet_rays_are_triangle_ray_new_bit_for_bit() {
        fn check<const N: usize>(f: &mut impl FnMut() -> f32, case: usize) -> usize {
            let rays = packet_of::<N>(f, case);
            let want = mask_of::<N>(f, case);
            let mut pr = PacketRays::<N>::new();
            pr.prepare(&rays, want);
            // A second call makes nothing more and changes nothing.
            pr.prepare(&rays, want);
            let mut seen = 0;
            for (k, ray) in rays.iter().enumerate() {
                let block_wanted = want >> (k / 8 * 8) & 0xff != 0;
                assert_eq!(pr.is_made(k), block_wanted, "case {case}: ray {k}");
                if !block_wanted {
                    continue;
                }
                let mut tr = TriangleRay::new(ray);
                assert_eq!(ray_bits(&pr.ray(k)), ray_bits(&tr), "case {case}: ray {k} {ray:?}");
                let t = f().abs() * 2.0;
                tr.set_t_max(t);
                let mut narrowed = pr.clone();
                narrowed.set_t_max(k, t);
                assert_eq!(ray_bits(&narrowed.ray(k)), ray_bits(&tr), "case {case}: ray {k} narrowed to {t}");
                seen += 1;
            }
            seen
        }
        let mut f = uniform(0x2545_f491_u64);
        let mut made = 0;
        for case in 0..3000 {
            made += check::<64>(&mut f, case) + check::<16>(&mut f, case);
        }
        assert!(made > 100_000, "{made}");
    }

    /// [`PacketRays::group`] takes the rays [`TriangleRays8::push`] takes
    /// (the lowest of `rest` and those after it with its axes, up to
    /// eight) in the same lanes, and the group answers as the pushed one
    /// does, whether its rays lie in one run or apart.
    #[test]
    fn packet_groups_are_the_pushed_groups() {
        fn check<const N: usize>(f: &mut impl FnMut() -> f32, case: usize, runs: &mut [usize; 2]) {
            let rays = packet_of::<N>(f, case);
            let meet = mask_of::<N>(f, case);
            let tris = Triangles4::new(&random_leaf(f, case));
            let mut pr = PacketRays::<N>::new();
            pr.prepare(&rays, meet);
            let prepared: Vec<TriangleRay> = rays.iter().map(TriangleRay::new).collect();
            let (mut g, mut lane) = (TriangleRays8::empty(), [0u8; 8]);
            let mut rest = meet;
            while rest != 0 {
                let lowest = rest.trailing_zeros() as usize;
                let mut want = TriangleRays8::like(&prepared[lowest]);
                let mut want_lanes = Vec::new();
                for k in (lowest..N).filter(|&k| rest >> k & 1 == 1) {
                    if want.push(&prepared[k]) {
                        want_lanes.push(k as u8);
                    }
                }
                let taken = pr.group(rest, &mut g, &mut lane);
                let want_taken = want_lanes.iter().fold(0u64, |m, &k| m | 1 << k);
                assert_eq!(taken, want_taken, "case {case}: rest {rest:#x}");
                assert_eq!((g.len(), g.k), (want.len(), want.k), "case {case}");
                assert_eq!(&lane[..g.len()], &want_lanes[..], "case {case}");
                for i in 0..g.len() {
                    assert_eq!(ray_bits(&g.ray(i)), ray_bits(&want.ray(i)), "case {case}: lane {i}");
                }
                assert_eq!(g.occluded(&tris), want.occluded(&tris), "case {case}");
                let (mut a, mut b) = (g, want);
                assert_eq!(a.closest(&tris), b.closest(&tris), "case {case}");
                let run = taken >> lowest;
                runs[usize::from(run & (run + 1) == 0 && lowest + 8 <= N)] += 1;
                rest &= !taken;
            }
        }
        let mut f = uniform(0x6c07_8965_u64);
        let mut runs = [0; 2];
        for case in 0..3000 {
            check::<64>(&mut f, case, &mut runs);
            check::<16>(&mut f, case, &mut runs);
        }
        // Both ways of filling a group ran, many times.
        assert!(runs[0] > 2000 && runs[1] > 2000, "{runs:?}");
    }

    /// The prepared ray runs along +z in its sheared frame, whichever axis
    /// dominates its direction and whatever the signs: its origin maps to
    /// exactly `(0, 0, 0)`, and a point `t` along it to `(≈0, ≈0, ≈t)`.
    #[test]
    fn prepared_ray_runs_along_z() {
        let mut f = uniform(0x5851_f42d_u64);
        let mut seen = [[false; 2]; 3];
        for case in 0..3000 {
            let mut d = Vec3::new(f(), f(), f());
            if case % 7 == 0 {
                d[case % 3] = 0.0;
            }
            if d == Vec3::ZERO {
                continue;
            }
            let o = Vec3::new(f(), f(), f()) * 10.0;
            let tr = TriangleRay::new(&Ray::new(o, d));
            let [kx, ky, kz] = tr.k;
            let mut axes = [kx, ky, kz];
            axes.sort_unstable();
            assert_eq!(axes, [0, 1, 2], "{d}");
            assert!(d.abs().max_element() == d.abs()[kz], "{d}: kz {kz}");
            seen[kz][usize::from(d[kz] < 0.0)] = true;
            // (kx, ky, kz) is right-handed for +z, swapped for -z.
            assert_eq!((kx + 1) % 3 == ky, d[kz] >= 0.0, "{d}");
            assert_eq!(tr.shear(o), (0.0, 0.0, 0.0));
            for t in [0.5f32, 2.0, 7.0] {
                let (x, y, z) = tr.shear(o + t * d);
                let tol = 1e-4 * (1.0 + o.abs().max_element());
                assert!(x.abs() < tol && y.abs() < tol && (z - t).abs() < tol * t, "{d} {t}: {x} {y} {z}");
            }
        }
        assert_eq!(seen, [[true; 2]; 3]);
    }

    /// The plain statement of the set-up (the paper's, with scalar
    /// divisions), which `TriangleRay::new` computes more cheaply: same
    /// axes (ties broken toward x, then y), same bits.
    fn reference(ray: &Ray) -> ([usize; 3], [f32; 3], [f32; 3]) {
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = ray.dir[kz];
        let shear = [ray.dir[kx] / dz, ray.dir[ky] / dz, 1.0 / dz];
        ([kx, ky, kz], shear, [ray.origin[kx], ray.origin[ky], ray.origin[kz]])
    }

    /// Every block of an array of them lies in three 64-byte cache lines.
    #[test]
    fn a_block_of_four_spans_three_cache_lines() {
        let (size, align) = (std::mem::size_of::<Triangles4>(), std::mem::align_of::<Triangles4>());
        assert_eq!((size, align), (160, 32));
        let blocks = vec![Triangles4::default(); 8];
        for b in &blocks {
            let start = std::ptr::from_ref(b) as usize;
            let lines = (start + size - 1) / 64 - start / 64 + 1;
            assert_eq!(lines, 3, "block at {start:#x}");
        }
    }

    #[test]
    fn set_up_matches_the_scalar_statement_bit_for_bit() {
        let mut f = uniform(0x2545_f491);
        let special = [
            Vec3::ONE,
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(0.0, -0.0, 1.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(-0.0, 2.0, -2.0),
            Vec3::NEG_X,
            Vec3::NEG_Y,
            Vec3::NEG_Z,
            Vec3::new(3.0, -1e-30, 1e30),
            Vec3::new(f32::MIN_POSITIVE, -f32::MIN_POSITIVE, 1e-45),
        ];
        let random: Vec<Vec3> = (0..2000).map(|_| Vec3::new(f(), f(), f()) * 10f32.powf(4.0 * f())).collect();
        for d in special.into_iter().chain(random) {
            let ray = Ray::with_interval(Vec3::new(f(), f(), f()) * 5.0, d, 0.25, 8.0);
            let tr = TriangleRay::new(&ray);
            let (k, shear, origin) = reference(&ray);
            assert_eq!(tr.k, k, "{d}");
            assert_eq!(tr.shear.map(f32::to_bits), shear.map(f32::to_bits), "{d}");
            assert_eq!(tr.origin.map(f32::to_bits), origin.map(f32::to_bits), "{d}");
            assert_eq!((tr.t_min, tr.t_max), (0.25, 8.0));
        }
    }
}
