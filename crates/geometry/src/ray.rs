//! Rays, and the one place where self-intersection is avoided.

use glam::Vec3;

/// A half-line `origin + t * dir`, valid for `t` in `[t_min, t_max]`.
///
/// `dir` need not be unit length: an affine transform maps a world ray to an
/// object-space ray whose `t` values are the same, so shapes accept any
/// non-zero direction and report `t` in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Direction of travel; non-zero, not necessarily normalized.
    pub dir: Vec3,
    /// Smallest accepted parameter (inclusive).
    pub t_min: f32,
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

    /// Whether `t` lies in this ray's valid interval.
    #[inline]
    #[must_use]
    pub fn contains(&self, t: f32) -> bool {
        t >= self.t_min && t <= self.t_max
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
        let n = if geo_normal.dot(dir) < 0.0 { -geo_normal } else { geo_normal };
        Self::new(offset_ray_origin(point, n), dir)
    }

    /// A shadow ray from the surface point `point` toward `target`: unit
    /// direction, `t_max` is the distance to `target`.
    #[inline]
    #[must_use]
    pub fn spawn_to(point: Vec3, geo_normal: Vec3, target: Vec3) -> Self {
        let toward = target - point;
        let n = if geo_normal.dot(toward) < 0.0 { -geo_normal } else { geo_normal };
        let origin = offset_ray_origin(point, n);
        let to = target - origin;
        let dist = to.length();
        let dir = if dist > 0.0 { to / dist } else { n };
        Self { origin, dir, t_min: 0.0, t_max: dist }
    }
}

/// Integer ULP offset per unit of normal (Wächter & Binder use 256).
const INT_SCALE: f32 = 256.0;
/// Below this magnitude a coordinate is offset by a fixed amount instead.
const ORIGIN_BAND: f32 = 1.0 / 32.0;
/// Fixed offset used near the origin.
const FLOAT_SCALE: f32 = 1.0 / 65536.0;

/// Moves `p` off a surface along `n` (the side the new ray leaves from) by a
/// few hundred ULPs per coordinate, the method of Wächter & Binder, "A Fast
/// and Robust Method for Avoiding Self-Intersection", *Ray Tracing Gems*,
/// ch. 6.
///
/// The offset scales with the magnitude of each coordinate, so it is safe
/// both near the origin and far from it; the spawned ray then uses
/// `t_min = 0`. This is the only self-intersection epsilon in prism.
#[must_use]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let of = [(INT_SCALE * n.x) as i32, (INT_SCALE * n.y) as i32, (INT_SCALE * n.z) as i32];
    let pa = p.to_array();
    let na = n.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        let bits = pa[k].to_bits() as i32;
        let moved = f32::from_bits(bits.wrapping_add(if pa[k] < 0.0 { -of[k] } else { of[k] }) as u32);
        out[k] =
            if pa[k].abs() < ORIGIN_BAND || !moved.is_finite() { pa[k] + FLOAT_SCALE * na[k] } else { moved };
    }
    Vec3::from_array(out)
}
