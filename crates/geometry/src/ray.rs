//! Rays, and the one place where self-intersection is avoided.

use glam::Vec3;

/// A half-line `origin + t * dir`, valid for `t` in `[t_min, t_max]`.
///
/// `dir` need not be unit length: an affine transform maps a world ray to an
/// object-space ray whose `t` values are the same, so shapes accept any
/// non-zero direction and report `t` in units of `dir`.
///
/// The fields are laid out as two 16-byte halves, `origin, t_min` and
/// `dir, t_max` (`repr(C)`), so that loading `origin` or `dir` from a ray
/// just copied (in 16-byte moves) reads within one half: a load across the
/// halves cannot be forwarded from the copy's stores and stalls the CPU
/// (docs/benchmarks.md, "Issue 11: a ray's halves").
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Smallest accepted parameter (inclusive).
    pub t_min: f32,
    /// Direction of travel; non-zero and finite, not necessarily
    /// normalized (every shape meets nothing along a zero or non-finite
    /// direction, nor within an interval with a `NaN` end).
    pub dir: Vec3,
    /// Largest accepted parameter (inclusive).
    pub t_max: f32,
}

impl Ray {
    /// A ray valid over `[0, +inf)`.
    #[inline]
    #[must_use]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// A ray valid over `[t_min, t_max]`.
    #[inline]
    #[must_use]
    pub fn with_interval(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self { origin, dir, t_min, t_max }
    }

    /// The point at parameter `t`.
    #[inline]
    #[must_use]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }

    /// Whether `t` is finite and lies in this ray's valid interval.
    ///
    /// An infinite `t` (a division that overflowed for a nearly parallel
    /// ray) or NaN is never accepted, even when `t_max` is `+inf`: it names
    /// no point on the ray.
    #[inline]
    #[must_use]
    pub fn contains(&self, t: f32) -> bool {
        t >= self.t_min && t <= self.t_max && t.is_finite()
    }

    /// A ray leaving the surface point `point` (with geometric normal
    /// `geo_normal`) in direction `dir`, started on the correct side of the
    /// surface so that it cannot hit that surface again at `t = 0`.
    ///
    /// This is the spawn rule for every secondary ray (reflection,
    /// refraction, transparency); see [`offset_ray_origin`].
    #[inline]
    #[must_use]
    pub fn spawn(point: Vec3, geo_normal: Vec3, dir: Vec3) -> Self {
        Self::spawn_scaled(point, geo_normal, dir, 1.0)
    }

    /// [`Ray::spawn`] in a scene of `scale` ([`offset_scale`]): the offset
    /// near the origin shrinks with a scene smaller than a unit.
    #[inline]
    #[must_use]
    pub fn spawn_scaled(point: Vec3, geo_normal: Vec3, dir: Vec3, scale: f32) -> Self {
        let n = if geo_normal.dot(dir) < 0.0 { -geo_normal } else { geo_normal };
        Self::new(offset_ray_origin_scaled(point, n, scale), dir)
    }

    /// A shadow ray from the surface point `point` toward `target`: unit
    /// direction, `t_max` the distance to `target` less about the offset
    /// that a ray leaving a surface at `target` would start from (a few
    /// hundred ULPs of its largest coordinate, as [`offset_ray_origin`]
    /// gives), so that a surface through `target` itself (a light set
    /// flush into a ceiling) does not block it, as one through `point`
    /// does not.
    #[inline]
    #[must_use]
    pub fn spawn_to(point: Vec3, geo_normal: Vec3, target: Vec3) -> Self {
        Self::spawn_to_scaled(point, geo_normal, target, 1.0)
    }

    /// [`Ray::spawn_to`] in a scene of `scale` ([`offset_scale`]).
    #[inline]
    #[must_use]
    pub fn spawn_to_scaled(point: Vec3, geo_normal: Vec3, target: Vec3, scale: f32) -> Self {
        let toward = target - point;
        let n = if geo_normal.dot(toward) < 0.0 { -geo_normal } else { geo_normal };
        let origin = offset_ray_origin_scaled(point, n, scale);
        let to = target - origin;
        let dist = to.length();
        let dir = if dist > 0.0 { to / dist } else { n };
        Self { origin, dir, t_min: 0.0, t_max: (dist - end_offset(target, scale)).max(0.0) }
    }
}

/// Integer ULP offset per unit of normal (Wächter & Binder use 256).
const INT_SCALE: f32 = 256.0;
/// Below this magnitude a coordinate is offset by a fixed amount instead.
const ORIGIN_BAND: f32 = 1.0 / 32.0;
/// Fixed offset used near the origin.
const FLOAT_SCALE: f32 = 1.0 / 65536.0;

/// How far short of `target` a ray to it stops ([`Ray::spawn_to`]): about
/// the offset [`offset_ray_origin_scaled`] gives a ray leaving a surface
/// there, `INT_SCALE` to twice as many ULPs of its largest coordinate, or
/// the fixed offset near the origin.
#[inline]
fn end_offset(target: Vec3, scale: f32) -> f32 {
    (target.abs().max_element() * (INT_SCALE * f32::EPSILON)).max(FLOAT_SCALE * scale)
}

/// Moves `p` off a surface along `n` (the side the new ray leaves from) by a
/// few hundred ULPs per coordinate, the method of Wächter & Binder, "A Fast
/// and Robust Method for Avoiding Self-Intersection", *Ray Tracing Gems*,
/// ch. 6.
///
/// The offset scales with the magnitude of each coordinate, so it is safe
/// both near the origin and far from it; the spawned ray then uses
/// `t_min = 0`. This is the only self-intersection epsilon in prism. Near
/// the origin (coordinates under 1/32) the offset is a fixed 1/65536,
/// sized for scenes of a unit or more; [`offset_ray_origin_scaled`]
/// shrinks both for a smaller scene.
#[must_use]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    offset_ray_origin_scaled(p, n, 1.0)
}

/// The scale of a scene whose coordinates (surfaces and camera) reach
/// `extent` from the origin, for [`offset_ray_origin_scaled`]: 1 for a
/// scene of a unit or more (so that such scenes keep [`offset_ray_origin`]
/// exactly), else the power of two at or above `extent` (at least
/// 2⁻¹⁰⁰), so that a scene scaled down keeps its offsets in proportion.
#[must_use]
pub fn offset_scale(extent: f32) -> f32 {
    if !(extent < 1.0) {
        return 1.0;
    }
    let floor = 2f32.powi(-100);
    let mut s = 1.0f32;
    while s * 0.5 >= extent && s * 0.5 >= floor {
        s *= 0.5;
    }
    s
}

/// [`offset_ray_origin`] in a scene of `scale` ([`offset_scale`]): the
/// band near the origin and its fixed offset scaled by it.
#[must_use]
pub fn offset_ray_origin_scaled(p: Vec3, n: Vec3, scale: f32) -> Vec3 {
    let (band, fixed) = (ORIGIN_BAND * scale, FLOAT_SCALE * scale);
    let of = [(INT_SCALE * n.x) as i32, (INT_SCALE * n.y) as i32, (INT_SCALE * n.z) as i32];
    let pa = p.to_array();
    let na = n.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        let bits = pa[k].to_bits() as i32;
        let moved = f32::from_bits(bits.wrapping_add(if pa[k] < 0.0 { -of[k] } else { of[k] }) as u32);
        out[k] = if pa[k].abs() < band || !moved.is_finite() { pa[k] + fixed * na[k] } else { moved };
    }
    Vec3::from_array(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_and_contains() {
        let r = Ray::with_interval(Vec3::ONE, Vec3::new(0.0, 2.0, 0.0), 1.0, 3.0);
        assert_eq!(r.at(1.5), Vec3::new(1.0, 4.0, 1.0));
        assert!(r.contains(1.0) && r.contains(3.0) && !r.contains(0.5) && !r.contains(3.5));
        let open = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(open.contains(1e30) && !open.contains(f32::INFINITY) && !open.contains(f32::NAN));
    }

    #[test]
    fn offset_moves_to_the_normal_side_at_every_scale() {
        for &s in &[0.0f32, 1e-3, 0.03, 0.5, 1.0, 7.0, 1e3, 1e6, -1e-3, -0.5, -1e6] {
            let p = Vec3::new(s, -s, 0.5 * s);
            for n in [Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 1.0, 1.0).normalize(), Vec3::new(-0.6, 0.0, 0.8)] {
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "p = {p}, n = {n}, q = {q}");
                assert!(q.is_finite());
                // Small: a few hundred ULPs, or 1/65536 near the origin.
                assert!((q - p).length() <= 1e-4 * p.abs().max_element().max(1.0), "{p} -> {q}");
            }
        }
        let far = offset_ray_origin(Vec3::splat(f32::MAX), Vec3::ONE.normalize());
        assert!(far.is_finite());
    }

    #[test]
    fn a_small_scene_scales_its_offsets() {
        assert_eq!((offset_scale(5.0), offset_scale(1.0), offset_scale(f32::NAN)), (1.0, 1.0, 1.0));
        assert_eq!(offset_scale(0.3), 0.5);
        assert_eq!(offset_scale(6e-6), 2f32.powi(-17));
        assert_eq!(offset_scale(0.0), 2f32.powi(-100));
        // The same point and normal, scaled down by a power of two, move by
        // the same fraction of the scene.
        for k in [0, 10, 20, 40] {
            let s = 2f32.powi(-k);
            for p in [Vec3::new(0.3, 0.0, -0.7), Vec3::new(1e-3, 0.02, 0.5)] {
                let n = Vec3::new(0.0, 1.0, 0.0);
                let q = offset_ray_origin_scaled(p * s, n, offset_scale(s));
                let one = offset_ray_origin(p, n);
                assert!(
                    ((q - p * s) / s - (one - p)).length() <= 1e-6 * (one - p).length(),
                    "{k}: {q} {one}"
                );
            }
        }
        // At scale 1, the same as the unscaled rule.
        let (p, n) = (Vec3::new(0.01, 2.0, -3.0), Vec3::new(0.6, 0.8, 0.0));
        assert_eq!(offset_ray_origin_scaled(p, n, 1.0), offset_ray_origin(p, n));
    }

    #[test]
    fn spawn_picks_the_side_of_the_direction() {
        let p = Vec3::new(1.0, 0.0, 0.0);
        let out = Ray::spawn(p, Vec3::X, Vec3::new(1.0, 1.0, 0.0));
        assert!(out.origin.x > 1.0 && out.t_min == 0.0);
        let inward = Ray::spawn(p, Vec3::X, Vec3::new(-1.0, 1.0, 0.0));
        assert!(inward.origin.x < 1.0);
        let shadow = Ray::spawn_to(p, Vec3::X, Vec3::new(5.0, 3.0, 0.0));
        assert!((shadow.dir.length() - 1.0).abs() < 1e-6);
        // It stops short of the target by the far end's offset: a surface
        // through the target (a light in a ceiling) lies past `t_max`.
        let target = Vec3::new(5.0, 3.0, 0.0);
        let gap = (shadow.at(shadow.t_max) - target).length();
        assert!(gap > 1e-5 && gap < 1e-3, "{gap}");
        assert!(shadow.t_max < (target - shadow.origin).length());
        let far = Vec3::new(5.0, 3.0, 0.0) * 1e6;
        let to_far = Ray::spawn_to(p, Vec3::X, far);
        let gap = (to_far.at(to_far.t_max) - far).length();
        assert!(gap > 1e-5 * 1e6 && gap < 1e-3 * 1e6, "{gap}");
        // A target at the point itself: an empty interval.
        assert_eq!(Ray::spawn_to(p, Vec3::X, p).t_max, 0.0);
        assert!(shadow.origin.x > 1.0);
        let behind = Ray::spawn_to(p, Vec3::X, Vec3::new(-5.0, 0.0, 0.0));
        assert!(behind.origin.x < 1.0);
    }
}
