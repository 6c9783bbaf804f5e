//! The benchmark's fixed scenes and ray sets (issue 7), shared by
//! `prism-bench` and prism-bvh's measuring examples so that every number in
//! docs/benchmarks.md comes from the same rays.
//!
//! * primary: the bbox-framing camera, one ray per pixel centre;
//! * incoherent: 8 hemisphere rays from each primary hit point;
//! * shadow: one segment from each primary hit point to a light.
//!
//! Hit points come from the caller's closest-hit query (this crate knows no
//! acceleration structure) and are offset along the normal turned toward
//! the primary ray, by `2e-4` of the scene's bounding radius.

use crate::Rng;
use prism_geometry::glam::{DVec3, Vec3};
use prism_geometry::{Aabb, Ray};

/// Vertical field of view of the framing camera.
const VFOV_DEGREES: f32 = 40.0;

/// Seed state of the incoherent rays' generator.
const INCOHERENT_STATE: u64 = 0x5eed_0007;

/// Half the diagonal of `b`: the radius of the sphere the camera frames.
#[must_use]
pub fn bounding_radius(b: Aabb) -> f32 {
    (b.max - b.min).length() / 2.0
}

/// The bbox-framing camera: from the centre of `b`, back along +Z until
/// the bounding sphere fits the 40° vertical field, looking along −Z with
/// +Y up; one unit ray per pixel centre of a `w`×`h` image, row by row from
/// the top.
#[must_use]
pub fn primary_rays(b: Aabb, w: u32, h: u32) -> Vec<Ray> {
    let c = b.center();
    let r = bounding_radius(b);
    let vfov = VFOV_DEGREES.to_radians();
    let eye = c + Vec3::new(0.0, 0.0, r / (vfov / 2.0).sin());
    let forward = (c - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (vfov / 2.0).tan();
    let aspect = w as f32 / h as f32;
    let mut rays = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let sx = (2.0 * (i as f32 + 0.5) / w as f32 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (j as f32 + 0.5) / h as f32) * tan;
            rays.push(Ray::new(eye, (forward + sx * right + sy * up).normalize()));
        }
    }
    rays
}

/// `rays` (one per pixel of a `w`×`h` image, row by row) reordered into
/// `tile`×`tile` pixel blocks, blocks row by row and pixels row by row in
/// each: consecutive rays then belong to neighbouring pixels, as a
/// renderer's packets do.
#[must_use]
pub fn tile_order(rays: &[Ray], w: u32, h: u32, tile: u32) -> Vec<Ray> {
    let tile = tile.max(1);
    let mut out = Vec::with_capacity(rays.len());
    for ty in (0..h).step_by(tile as usize) {
        for tx in (0..w).step_by(tile as usize) {
            for j in ty..(ty + tile).min(h) {
                for i in tx..(tx + tile).min(w) {
                    if let Some(r) = rays.get((j * w + i) as usize) {
                        out.push(*r);
                    }
                }
            }
        }
    }
    out
}

/// For each of `primary` that `closest` hits (it returns the hit point and
/// geometric normal), the point offset off the surface toward the ray's
/// side, and that side's normal: the origins of the secondary sets.
pub fn offset_hit_points(
    primary: &[Ray],
    b: Aabb,
    mut closest: impl FnMut(&Ray) -> Option<(Vec3, Vec3)>,
) -> Vec<(Vec3, Vec3)> {
    let r = bounding_radius(b);
    primary
        .iter()
        .filter_map(|ray| {
            let (p, n) = closest(ray)?;
            let n = if n.dot(ray.dir) > 0.0 { -n } else { n };
            Some((p + n * (2e-4 * r), n))
        })
        .collect()
}

/// `per_point` rays from each point, uniform on the hemisphere of its
/// normal, from a fixed generator state.
#[must_use]
pub fn incoherent_rays(points: &[(Vec3, Vec3)], per_point: usize) -> Vec<Ray> {
    let mut rng = Rng::from_state(INCOHERENT_STATE);
    let mut rays = Vec::with_capacity(points.len() * per_point);
    for &(p, n) in points {
        for _ in 0..per_point {
            rays.push(Ray::new(p, rng.hemisphere(n)));
        }
    }
    rays
}

/// A segment from each point to the light at `centre(b) + r·(1, 2, 1.5)`
/// (unit direction, `t_max` = the distance).
#[must_use]
pub fn shadow_rays(points: &[(Vec3, Vec3)], b: Aabb) -> Vec<Ray> {
    let light = b.center() + bounding_radius(b) * Vec3::new(1.0, 2.0, 1.5);
    points
        .iter()
        .map(|&(p, _)| {
            let to = light - p;
            let dist = to.length();
            Ray::with_interval(p, to / dist, 0.0, dist)
        })
        .collect()
}

/// The secondary ray sets of the Embree peer's benchmark
/// (`../shared/peers/embree/bench.cpp`), made as it makes them, so that
/// `cargo xtask bench --vs-peers` traces the same rays on both sides.
#[derive(Clone, Debug, Default)]
pub struct PeerSets {
    /// Hemisphere rays: `copies` passes over the hit points, one ray per
    /// point per pass, pass after pass.
    pub incoherent: Vec<Ray>,
    /// Segments to the light, in the same order: each point's segment
    /// `copies` times.
    pub shadow: Vec<Ray>,
    /// Passes over the hit points: enough for [`PEER_MIN_SECONDARY`] rays.
    pub copies: usize,
}

/// The peer's default `--min-secondary`: each secondary set holds at
/// least this many rays.
pub const PEER_MIN_SECONDARY: usize = 2_000_000;

/// The Embree peer's secondary rays (its default `--seed 1` and
/// `--min-secondary`), from `primary` in the order the peer traces its
/// single rays (row by row, as [`primary_rays`] gives them): `closest`
/// returns a primary ray's hit distance and geometric normal. As the peer
/// does, in `f64`: each hit point `o + t·d`, moved `2e-4·r` along the
/// normal turned toward the ray; hemisphere directions from normal
/// deviates (Box–Muller over SplitMix64, [`PeerRng`]), flipped into the
/// normal's side; segments to the light at `c + r·(1, 2, 1.5)` ending at
/// `(1 − 1e-4)` of the distance. The peer's camera works in `f64` and
/// prism's in `f32`, so the hit points can differ in their last bits;
/// the directions are the same numbers.
pub fn peer_secondary_rays(
    primary: &[Ray],
    b: Aabb,
    mut closest: impl FnMut(&Ray) -> Option<(f32, Vec3)>,
) -> PeerSets {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let c = (lo + hi) / 2.0;
    let r = peer_norm(hi - lo) / 2.0;
    let eps = 1e-4 * r * 2.0;
    let light = c + DVec3::new(r, r * 2.0, r * 1.5);
    let points: Vec<(DVec3, DVec3)> = primary
        .iter()
        .filter_map(|ray| {
            let (t, n) = closest(ray)?;
            let d = ray.dir.as_dvec3();
            let p = ray.origin.as_dvec3() + f64::from(t) * d;
            let n = peer_normalize(n.as_dvec3());
            let n = if n.dot(d) > 0.0 { -n } else { n };
            Some((p + eps * n, n))
        })
        .collect();
    if points.is_empty() {
        return PeerSets::default();
    }
    let copies = PEER_MIN_SECONDARY.div_ceil(points.len()).max(1);
    let mut rng = PeerRng::new(1);
    let mut sets = PeerSets {
        incoherent: Vec::with_capacity(copies * points.len()),
        shadow: Vec::with_capacity(copies * points.len()),
        copies,
    };
    for _ in 0..copies {
        for &(p, n) in &points {
            let (x, y, z) = (rng.normal(), rng.normal(), rng.normal());
            let v = peer_normalize(DVec3::new(x, y, z));
            let v = if v.dot(n) < 0.0 { -v } else { v };
            sets.incoherent.push(Ray::new(p.as_vec3(), v.as_vec3()));
            let to = light - p;
            let dist = peer_norm(to);
            let dir = DVec3::new(to.x / dist, to.y / dist, to.z / dist);
            sets.shadow.push(Ray::with_interval(
                p.as_vec3(),
                dir.as_vec3(),
                0.0,
                (dist * (1.0 - 1e-4)) as f32,
            ));
        }
    }
    sets
}

/// The peer's vector length, summed in its order.
fn peer_norm(a: DVec3) -> f64 {
    ((a.x * a.x + a.y * a.y) + a.z * a.z).sqrt()
}

/// The peer's normalisation: each component divided by the length.
fn peer_normalize(a: DVec3) -> DVec3 {
    let n = peer_norm(a);
    DVec3::new(a.x / n, a.y / n, a.z / n)
}

/// The Embree peer's random numbers: SplitMix64, uniform deviates in
/// `(0, 1)` from its top 53 bits, and normal deviates by Box–Muller, the
/// cosine of each pair first and its sine kept for the next call.
#[derive(Clone, Debug)]
pub struct PeerRng {
    state: u64,
    cached: Option<f64>,
}

impl PeerRng {
    /// The generator the peer seeds with `seed`.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self { state: seed, cached: None }
    }

    /// The next 64 bits (SplitMix64).
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in the open interval `(0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal deviate.
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.cached.take() {
            return v;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let rr = (-2.0 * u1.ln()).sqrt();
        let ph = 2.0 * std::f64::consts::PI * u2;
        self.cached = Some(rr * ph.sin());
        rr * ph.cos()
    }
}

/// Offsets of an `n`×`n`×`n` grid of copies of a model of size `extent`,
/// spaced 1.25 of its size apart (the benchmark's `bunny-grid6` for `n = 6`).
#[must_use]
pub fn grid_offsets(extent: Vec3, n: u32) -> Vec<Vec3> {
    let n = n.max(1);
    let mut v = Vec::with_capacity((n * n * n) as usize);
    for ix in 0..n {
        for iy in 0..n {
            for iz in 0..n {
                v.push(1.25 * Vec3::new(ix as f32, iy as f32, iz as f32) * extent);
            }
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::{Intersect, Sphere};

    #[test]
    fn tile_order_is_a_permutation_into_blocks() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let rays = primary_rays(b, 20, 11);
        let tiled = tile_order(&rays, 20, 11, 8);
        assert_eq!(tiled.len(), rays.len());
        // The first block's second row starts with pixel (0, 1).
        assert_eq!(tiled[8].dir, rays[20].dir);
        // Every ray appears once.
        let mut a: Vec<_> = rays.iter().map(|r| r.dir.to_array().map(f32::to_bits)).collect();
        let mut t: Vec<_> = tiled.iter().map(|r| r.dir.to_array().map(f32::to_bits)).collect();
        a.sort_unstable();
        t.sort_unstable();
        assert_eq!(a, t);
    }

    #[test]
    fn the_camera_frames_the_box_and_secondary_rays_leave_the_surface() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let primary = primary_rays(b, 64, 36);
        assert_eq!(primary.len(), 64 * 36);
        // Every corner of the box projects inside the image: the middle rays
        // point at the centre, and all start at one eye on +Z.
        let eye = primary[0].origin;
        assert!(eye.z > 1.0 && eye.x == 0.0 && eye.y == 0.0);
        let mid = primary[18 * 64 + 32].dir;
        assert!(mid.dot(Vec3::NEG_Z) > 0.99, "{mid}");
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let points = offset_hit_points(&primary, b, |r| sphere.intersect(r).map(|h| (h.point, h.geo_normal)));
        assert!(points.len() > primary.len() / 10, "{}", points.len());
        for &(p, n) in &points {
            assert!(p.length() > 1.0 && n.dot(p) > 0.0, "offset outward: {p} {n}");
        }
        let inc = incoherent_rays(&points, 8);
        assert_eq!(inc.len(), points.len() * 8);
        assert!(inc.iter().zip(points.iter().flat_map(|p| [p; 8])).all(|(r, &(_, n))| r.dir.dot(n) >= 0.0));
        for r in shadow_rays(&points, b) {
            assert!(r.t_max.is_finite() && (r.dir.length() - 1.0).abs() < 1e-5);
        }
        assert_eq!(grid_offsets(Vec3::ONE, 2).len(), 8);
        assert_eq!(grid_offsets(Vec3::ONE, 2)[7], Vec3::splat(1.25));
    }

    #[test]
    fn peer_rng_gives_the_peers_numbers() {
        // Reference values from a Python transcription of the peer's `Rng`
        // (SplitMix64; Box–Muller with the platform's log, sin and cos).
        let mut r = PeerRng::new(1);
        assert_eq!(r.next_u64(), 0x910a_2dec_8902_5cc1);
        assert_eq!(r.next_u64(), 0xbeeb_8da1_658e_ec67);
        let mut r = PeerRng::new(1);
        let (a, b) = (r.normal(), r.normal());
        assert!((a - -0.028_249_746_095_854_695).abs() < 1e-15, "{a}");
        assert!((b - -1.065_617_648_414_326).abs() < 1e-15, "{b}");
        // Normal deviates: mean 0 and variance 1, within sampling error.
        let n = 100_000;
        let xs: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let mean = xs.iter().sum::<f64>() / f64::from(n);
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / f64::from(n);
        assert!(mean.abs() < 0.02 && (var - 1.0).abs() < 0.02, "{mean} {var}");
    }

    #[test]
    fn peer_sets_repeat_the_hit_points_pass_after_pass() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let primary = primary_rays(b, 64, 36);
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let sets = peer_secondary_rays(&primary, b, |r| sphere.intersect(r).map(|h| (h.t, h.geo_normal)));
        let hits = primary.iter().filter(|r| sphere.intersect(r).is_some()).count();
        assert_eq!(sets.copies, PEER_MIN_SECONDARY.div_ceil(hits));
        assert_eq!(sets.incoherent.len(), sets.copies * hits);
        assert_eq!(sets.shadow.len(), sets.incoherent.len());
        let light = Vec3::new(1.0, 2.0, 1.5) * 3f32.sqrt();
        for (i, (inc, sh)) in sets.incoherent.iter().zip(&sets.shadow).enumerate() {
            // Pass after pass over the same points, in the primary order.
            let first = &sets.incoherent[i % hits];
            assert_eq!(inc.origin, first.origin);
            assert_eq!(sh.origin, inc.origin);
            // Off the sphere, toward the camera's side, by 2e-4 of r.
            let out = inc.origin.length() - 1.0;
            assert!((out - 2e-4 * 3f32.sqrt()).abs() < 1e-5, "{out}");
            // Into the outer hemisphere; unit directions.
            assert!(inc.dir.dot(inc.origin) >= 0.0 && (inc.dir.length() - 1.0).abs() < 1e-6);
            // To the light, stopping just short of it.
            let to = light - sh.origin;
            assert!(sh.dir.dot(to.normalize()) > 0.999_999 && sh.t_max < to.length());
            assert!(sh.t_max > to.length() * (1.0 - 2e-4));
        }
        // The passes draw new directions.
        assert_ne!(sets.incoherent[0].dir, sets.incoherent[hits].dir);
    }
}
