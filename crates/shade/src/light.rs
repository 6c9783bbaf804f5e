//! Lights: point (optionally with inverse-square fall-off), spot,
//! directional (a sun), and area lights (quad, disk, sphere) sampled with
//! stratified, deterministic shadow rays.
//!
//! Every light is evaluated at a shading point as a short list of
//! *samples*: a direction toward the light, the point (or direction) a
//! shadow ray goes to, and the irradiance the sample delivers to a surface
//! facing it, `e`, so that the Lambert term is `Σ_k S_k · e_k · max(0, n·l_k)`
//! (prism keeps the report's Lambert form without 1/π). A point light has
//! one sample with `e = color · intensity` (divided by `r²` with
//! inverse-square fall-off); an area light of radiance `L` has `N` samples
//! whose `e` estimate `E = ∫ L cos θ_L / r² dA` (times `cos θ` by the
//! integrator).
//!
//! Area-light samples are stratified (a jittered rank-1 lattice of `N`
//! points over the light's parameter square) and jittered by a hash of the
//! shading point and the light's index, so a render is the same bit for bit
//! on any number of threads (the same pixel sample meets the same point).

use crate::ShadeError;
use crate::render::{golden_stride, splitmix64};
use prism_geometry::Ray;
use prism_geometry::glam::Vec3;
use std::f32::consts::{PI, TAU};

/// How a point or spot light dims with distance `r`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Falloff {
    /// No fall-off (the report's light): the same at every distance.
    #[default]
    None,
    /// Physical fall-off: `intensity / r²`.
    InverseSquare,
}

/// The shape of an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// The parallelogram `corner + s · edge_u + t · edge_v`, `s, t ∈ [0, 1]`;
    /// its emitting side is the one `edge_u × edge_v` points to.
    Quad {
        /// One corner.
        corner: Vec3,
        /// First edge from `corner`.
        edge_u: Vec3,
        /// Second edge from `corner`.
        edge_v: Vec3,
    },
    /// A disk; its emitting side is the one `normal` points to.
    Disk {
        /// Centre.
        center: Vec3,
        /// Unit normal.
        normal: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A sphere, emitting outward.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}

/// An area light: a shape that emits `radiance` (the light's
/// `color · intensity`) from its surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The shape.
    pub shape: AreaShape,
    /// Shadow rays per shading point (at least 1).
    pub samples: u32,
    /// Whether a quad or disk emits from both sides (a sphere always emits
    /// outward only).
    pub two_sided: bool,
    /// Whether to trace four probe rays to the light's rim first and, when
    /// they all agree (fully visible or fully hidden), skip the shadow rays
    /// of the samples (POV-Ray's `adaptive` idea; see
    /// docs/scene-format.md for what it can miss).
    pub adaptive: bool,
}

/// What kind of light, and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Light from a point, in every direction.
    Point {
        /// Position.
        position: Vec3,
        /// Fall-off with distance.
        falloff: Falloff,
    },
    /// A point light restricted to a cone: full inside `cos_inner`, none
    /// outside `cos_outer`, a smoothstep between.
    Spot {
        /// Position.
        position: Vec3,
        /// Unit axis of the cone (the way the light points).
        direction: Vec3,
        /// Cosine of the inner half-angle.
        cos_inner: f32,
        /// Cosine of the outer half-angle (`<= cos_inner`).
        cos_outer: f32,
        /// Fall-off with distance.
        falloff: Falloff,
    },
    /// Parallel light travelling along `direction` (unit): a sun. Shadow
    /// rays are parallel and unbounded; no fall-off.
    Directional {
        /// The direction the light travels.
        direction: Vec3,
    },
    /// An area light.
    Area(AreaLight),
}

/// A light: its kind, colour and intensity (for an area light,
/// `color · intensity` is its radiance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Kind and placement.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Scale on `color`.
    pub intensity: f32,
}

impl From<crate::PointLight> for Light {
    /// The report's point light: no fall-off.
    fn from(p: crate::PointLight) -> Self {
        Self {
            kind: LightKind::Point { position: p.position, falloff: Falloff::None },
            color: p.color,
            intensity: p.intensity,
        }
    }
}

/// Where a light sample's shadow ray goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Target {
    /// To this point (exclusive).
    Point(Vec3),
    /// Without end in this unit direction (a directional light).
    Away(Vec3),
}

/// One sample of a light seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub dir: Vec3,
    /// Where the shadow ray goes.
    pub target: Target,
    /// Irradiance on a surface facing `dir`, for this sample's share.
    pub e: Vec3,
}

impl Light {
    /// Checks that every value is finite and usable.
    ///
    /// # Errors
    /// [`ShadeError::Scene`] naming the problem: a non-finite or negative
    /// colour or intensity, a zero direction, a spot whose outer cone is
    /// narrower than its inner one, an area light of zero area or with no
    /// samples.
    pub fn validate(&self) -> Result<(), ShadeError> {
        let bad = |m: &str| Err(ShadeError::Scene(m.to_string()));
        if !(self.color.is_finite()
            && self.color.min_element() >= 0.0
            && self.intensity.is_finite()
            && self.intensity >= 0.0)
        {
            return bad("a light needs a finite, non-negative colour and intensity");
        }
        let unit = |v: Vec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-3;
        match self.kind {
            LightKind::Point { position, .. } if !position.is_finite() => {
                bad("light position must be finite")
            }
            LightKind::Spot { position, direction, cos_inner, cos_outer, .. } => {
                if !(position.is_finite() && unit(direction)) {
                    bad("a spot light needs a finite position and a unit direction")
                } else if !(cos_inner.is_finite() && cos_outer.is_finite() && cos_outer <= cos_inner) {
                    bad("a spot light's outer cone must not be narrower than its inner cone")
                } else {
                    Ok(())
                }
            }
            LightKind::Directional { direction } if !unit(direction) => {
                bad("a directional light needs a unit direction")
            }
            LightKind::Area(a) => {
                if a.samples == 0 {
                    return bad("an area light needs at least one sample");
                }
                if !(a.shape.area() > 0.0 && a.shape.area().is_finite()) {
                    return bad("an area light must have a finite area greater than 0");
                }
                match a.shape {
                    AreaShape::Disk { normal, .. } if !unit(normal) => {
                        bad("a disk light needs a unit normal")
                    }
                    _ => Ok(()),
                }
            }
            _ => Ok(()),
        }
    }

    /// `color · intensity`.
    #[must_use]
    pub fn radiance(&self) -> Vec3 {
        self.color * self.intensity
    }

    /// How many samples the renderer takes of this light at each shading
    /// point (`samples` of an area light, else 1).
    #[must_use]
    pub fn sample_count(&self) -> u32 {
        match self.kind {
            LightKind::Area(a) => a.samples.max(1),
            _ => 1,
        }
    }

    /// Sample `k` of [`Light::sample_count`] seen from `p`, with `seed` the
    /// shading point's hash (see [`sample_seed`]); `None` where the sample
    /// sends no light to `p` (behind a one-sided light, outside a spot's
    /// cone, `p` at the light or inside a sphere light).
    #[must_use]
    pub(crate) fn sample(&self, p: Vec3, k: u32, seed: SampleSeed) -> Option<LightSample> {
        let radiance = self.radiance();
        match self.kind {
            LightKind::Point { position, falloff } => point_sample(p, position, radiance, falloff),
            LightKind::Spot { position, direction, cos_inner, cos_outer, falloff } => {
                let s = point_sample(p, position, radiance, falloff)?;
                let w = spot_weight(-s.dir.dot(direction), cos_inner, cos_outer);
                (w > 0.0).then_some(LightSample { e: s.e * w, ..s })
            }
            LightKind::Directional { direction } => {
                Some(LightSample { dir: -direction, target: Target::Away(-direction), e: radiance })
            }
            LightKind::Area(a) => {
                let n = a.samples.max(1);
                let (u, v) = lattice_point(k, n, seed);
                a.sample_at(p, u, v, radiance / n as f32)
            }
        }
    }

    /// Where the ray `ray` meets this light, if it does before or at
    /// `t_max`, and the radiance it sees there: `color · intensity` on an
    /// emitting side, black on the back of a one-sided light. Only area
    /// lights have a surface to meet. A light at the same distance as a
    /// surface (`t_max` its hit: a light flush with a ceiling) is seen.
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let LightKind::Area(a) = self.kind else { return None };
        let (t, facing) = a.shape.intersect(ray)?;
        if !(t > ray.t_min && t <= t_max) {
            return None;
        }
        Some((t, if facing || a.two_sided { self.radiance() } else { Vec3::ZERO }))
    }

    /// Four points on an area light's rim as seen from `p` (the quad's
    /// corners, four points on a disk's rim or on a sphere's silhouette),
    /// probed first by adaptive sampling; `None` for other lights.
    #[must_use]
    pub(crate) fn probes(&self, p: Vec3) -> Option<[Vec3; 4]> {
        let LightKind::Area(a) = self.kind else { return None };
        if !a.adaptive || a.samples < 8 {
            return None;
        }
        Some(match a.shape {
            AreaShape::Quad { corner, edge_u, edge_v } => {
                [corner, corner + edge_u, corner + edge_v, corner + edge_u + edge_v]
            }
            AreaShape::Disk { center, normal, radius } => {
                let (t, b) = normal.any_orthonormal_pair();
                [center + radius * t, center - radius * t, center + radius * b, center - radius * b]
            }
            AreaShape::Sphere { center, radius } => {
                let to = center - p;
                let d = to.length();
                if !(d > radius) {
                    return None;
                }
                // The silhouette circle: centre and radius seen from p.
                let w = to / d;
                let (t, b) = w.any_orthonormal_pair();
                let sin = radius / d;
                let cos = (1.0 - sin * sin).max(0.0).sqrt();
                let c = p + w * (d * cos * cos);
                let r = d * cos * sin;
                [c + r * t, c - r * t, c + r * b, c - r * b]
            }
        })
    }
}

/// The one point-light sample: toward `position`, irradiance `radiance`
/// (over `r²` with inverse-square fall-off).
fn point_sample(p: Vec3, position: Vec3, radiance: Vec3, falloff: Falloff) -> Option<LightSample> {
    let to = position - p;
    let r2 = to.length_squared();
    if !(r2 > 0.0) {
        return None;
    }
    let e = match falloff {
        Falloff::None => radiance,
        Falloff::InverseSquare => radiance / r2,
    };
    Some(LightSample { dir: to / r2.sqrt(), target: Target::Point(position), e })
}

/// A spot light's weight at `cos_angle` from its axis: 1 inside the inner
/// cone, 0 outside the outer one, a smoothstep of the cosine between.
#[must_use]
pub fn spot_weight(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_angle >= cos_inner {
        1.0
    } else if cos_angle <= cos_outer {
        0.0
    } else {
        let x = (cos_angle - cos_outer) / (cos_inner - cos_outer);
        x * x * (3.0 - 2.0 * x)
    }
}

impl AreaShape {
    /// Surface area (the emitting side of a quad or disk).
    #[must_use]
    pub fn area(&self) -> f32 {
        match *self {
            // Edges of 1e10 (a normal area of 1e20) or 1e-12: the cross
            // product's squared length is out of range, its length is not.
            Self::Quad { edge_u, edge_v, .. } => prism_geometry::length(edge_u.cross(edge_v)),
            Self::Disk { radius, .. } => PI * radius * radius,
            Self::Sphere { radius, .. } => 4.0 * PI * radius * radius,
        }
    }

    /// The nearest crossing of `ray` with the shape (`t` in the ray's
    /// parameter, `t > 0`) and whether the ray meets the emitting side.
    fn intersect(&self, ray: &Ray) -> Option<(f32, bool)> {
        let (o, d) = (ray.origin, ray.dir);
        match *self {
            Self::Quad { corner, edge_u, edge_v } => {
                // The unit normal and the area apart: |n|² is the quad's
                // size to the fourth, which left f32's range for a quad
                // 1e10 across (or 1e-12), and the light went unseen.
                let n = edge_u.cross(edge_v);
                let area = prism_geometry::length(n);
                let n = n / area;
                let denom = n.dot(d);
                if denom == 0.0 || !n.is_finite() {
                    return None;
                }
                let t = n.dot(corner - o) / denom;
                let q = o + t * d - corner;
                // Coordinates of q in the (edge_u, edge_v) basis.
                let s = q.cross(edge_v).dot(n) / area;
                let r = edge_u.cross(q).dot(n) / area;
                ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r) && t > 0.0).then_some((t, denom < 0.0))
            }
            Self::Disk { center, normal, radius } => {
                let denom = normal.dot(d);
                if denom == 0.0 {
                    return None;
                }
                let t = normal.dot(center - o) / denom;
                let inside = (o + t * d - center).length_squared() <= radius * radius;
                (inside && t > 0.0).then_some((t, denom < 0.0))
            }
            Self::Sphere { center, radius } => {
                let oc = o - center;
                let a = d.length_squared();
                let half_b = oc.dot(d);
                let c = oc.length_squared() - radius * radius;
                let disc = half_b * half_b - a * c;
                if !(disc >= 0.0) || a == 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                let t0 = (-half_b - sq) / a;
                let t1 = (-half_b + sq) / a;
                if t0 > 0.0 {
                    Some((t0, true))
                } else if t1 > 0.0 {
                    Some((t1, false))
                } else {
                    None
                }
            }
        }
    }
}

impl AreaLight {
    /// The sample at parameter `(u, v) ∈ [0, 1)²` seen from `p`, for a
    /// light of radiance `share` per sample (`radiance / N`).
    fn sample_at(&self, p: Vec3, u: f32, v: f32, share: Vec3) -> Option<LightSample> {
        let (x, normal, area) = match self.shape {
            AreaShape::Quad { corner, edge_u, edge_v } => {
                let n = edge_u.cross(edge_v);
                let area = prism_geometry::length(n);
                (corner + u * edge_u + v * edge_v, n / area, area)
            }
            AreaShape::Disk { center, normal, radius } => {
                let (dx, dy) = concentric_disk(u, v);
                let (t, b) = normal.any_orthonormal_pair();
                (center + radius * (dx * t + dy * b), normal, PI * radius * radius)
            }
            AreaShape::Sphere { center, radius } => return sphere_sample(p, center, radius, u, v, share),
        };
        let to = x - p;
        let r2 = to.length_squared();
        if !(r2 > 0.0) {
            return None;
        }
        let dir = to / r2.sqrt();
        let cos_l = -normal.dot(dir);
        let cos_l = if self.two_sided { cos_l.abs() } else { cos_l };
        if !(cos_l > 0.0) {
            return None;
        }
        Some(LightSample { dir, target: Target::Point(x), e: share * (area * cos_l / r2) })
    }
}

/// A sample of a sphere light of centre `c`, radius `r` seen from `p`:
/// uniform over the cone it subtends (pbrt's method), so each sample
/// carries `L · Ω / N` with `Ω = 2π (1 − cos θ_max)`.
fn sphere_sample(p: Vec3, c: Vec3, r: f32, u: f32, v: f32, share: Vec3) -> Option<LightSample> {
    let to = c - p;
    let d2 = to.length_squared();
    if !(d2 > r * r) {
        return None;
    }
    let d = d2.sqrt();
    let w = to / d;
    let cos_max = (1.0 - r * r / d2).max(0.0).sqrt();
    let cos_t = 1.0 - u * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = TAU * v;
    let (t, b) = w.any_orthonormal_pair();
    let dir = (w * cos_t + (t * phi.cos() + b * phi.sin()) * sin_t).normalize();
    // The point on the sphere along dir (the near crossing; a grazing
    // direction that rounds off the sphere takes the tangent point).
    let half_b = dir.dot(to);
    let disc = (half_b * half_b - (d2 - r * r)).max(0.0);
    let dist = half_b - disc.sqrt();
    let solid_angle = TAU * (1.0 - cos_max);
    Some(LightSample { dir, target: Target::Point(p + dir * dist), e: share * solid_angle })
}

/// Shirley–Chiu concentric map of `[0, 1)²` to the unit disk.
#[must_use]
pub(crate) fn concentric_disk(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, theta) =
        if a.abs() > b.abs() { (a, PI / 4.0 * (b / a)) } else { (b, PI / 2.0 - PI / 4.0 * (a / b)) };
    (r * theta.cos(), r * theta.sin())
}

/// Point `k` of `n` of a jittered rank-1 lattice over `[0, 1)²`: stratum
/// `k` of `n` in `u`, stratum `k · g mod n` in `v` (`g` coprime with `n`,
/// about 0.618 n), each jittered inside its stratum by a hash of `seed`
/// and `k`. Every row and column of the `n × n` grid holds one point, so
/// the estimate is stratified in both directions and unbiased. One sample
/// is the centre.
#[must_use]
pub(crate) fn lattice_point(k: u32, n: u32, seed: SampleSeed) -> (f32, f32) {
    if n <= 1 {
        return (0.5, 0.5);
    }
    let kv = ((u64::from(k) * u64::from(seed.stride)) % u64::from(n)) as u32;
    let z = splitmix64(seed.hash ^ (u64::from(k).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
    let (ju, jv) = unit_pair(z);
    let below_one = 1.0 - f32::EPSILON / 2.0;
    let inv = 1.0 / n as f32;
    (((k as f32 + ju) * inv).min(below_one), ((kv as f32 + jv) * inv).min(below_one))
}

/// Two numbers in `[0, 1)` from the bits of `z`.
#[inline]
pub(crate) fn unit_pair(z: u64) -> (f32, f32) {
    ((z >> 40) as f32 * (1.0 / 16_777_216.0), ((z >> 16) & 0xFF_FFFF) as f32 * (1.0 / 16_777_216.0))
}

/// What a shading point's samples of one light share: the jitter's seed
/// and the lattice's stride.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleSeed {
    hash: u64,
    stride: u32,
}

/// The seed of the light samples at shading point `p` for light number
/// `light` of `n` samples: a hash of the point's bits, so the same camera
/// sample always meets the same light samples, whatever the thread.
#[inline]
#[must_use]
pub(crate) fn sample_seed(p: Vec3, light: usize, n: u32) -> SampleSeed {
    let [x, y, z] = p.to_array().map(f32::to_bits);
    let stride = if n > 1 { golden_stride(n) } else { 1 };
    let hash = splitmix64(
        u64::from(x)
            ^ (u64::from(y) << 21)
            ^ (u64::from(z) << 42)
            ^ ((light as u64) << 56)
            ^ 0xA076_1D64_78BD_642F,
    );
    SampleSeed { hash, stride }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_points_fill_every_row_and_column_once() {
        for n in [2u32, 3, 9, 16, 17, 64] {
            let seed = sample_seed(Vec3::new(0.25, -1.5, 3.0), 2, n);
            let (mut rows, mut cols) = (vec![false; n as usize], vec![false; n as usize]);
            for k in 0..n {
                let (u, v) = lattice_point(k, n, seed);
                assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
                let (i, j) = ((u * n as f32) as usize, (v * n as f32) as usize);
                assert!(!cols[i] && !rows[j], "n {n}: sample {k} shares a row or column");
                (cols[i], rows[j]) = (true, true);
                assert_eq!(lattice_point(k, n, seed), (u, v), "deterministic");
            }
        }
        assert_eq!(lattice_point(0, 1, sample_seed(Vec3::ZERO, 0, 1)), (0.5, 0.5));
        // Another shading point jitters differently.
        let a = lattice_point(3, 16, sample_seed(Vec3::ZERO, 0, 16));
        let b = lattice_point(3, 16, sample_seed(Vec3::X, 0, 16));
        assert_ne!(a, b);
    }

    #[test]
    fn a_quad_is_met_at_every_scale() {
        // The scene of the format's scale promise (2⁻⁴⁶ to 2⁴³): a quad
        // 2 wide, 4 above the eye, scaled as a whole. Its squared area
        // (the scale⁴) left f32's range at 1e10 and 1e-12: no hit at all.
        for e in -14..=14 {
            let s = 10f32.powi(e);
            let quad = AreaShape::Quad {
                corner: Vec3::new(-1.0, 4.0, -2.0) * s,
                edge_u: Vec3::new(2.0, 0.0, 0.0) * s,
                edge_v: Vec3::new(0.0, 0.0, 2.0) * s,
            };
            let centre = Ray::new(Vec3::ZERO, Vec3::new(0.0, 4.0, -1.0) * s);
            let (t, facing) = quad.intersect(&centre).unwrap_or_else(|| panic!("scale {s}: missed"));
            assert!((t - 1.0).abs() < 1e-5 && facing, "scale {s}: t {t}");
            let beside = Ray::new(Vec3::ZERO, Vec3::new(1.1, 4.0, -1.0) * s);
            assert_eq!(quad.intersect(&beside), None, "scale {s}");
        }
    }

    #[test]
    fn concentric_disk_stays_in_the_disk() {
        for (u, v) in [(0.0, 0.0), (0.5, 0.5), (0.999, 0.1), (0.3, 0.999)] {
            let (x, y) = concentric_disk(u, v);
            assert!(x * x + y * y <= 1.0 + 1e-6);
        }
        assert_eq!(concentric_disk(0.5, 0.5), (0.0, 0.0));
    }
}
