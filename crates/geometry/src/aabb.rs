//! Axis-aligned bounding boxes.

use crate::Ray;
use glam::Vec3;

/// An axis-aligned box `[min, max]`. An empty box has `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Self = Self { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };
    /// The box containing all of space (the bounds of an infinite plane).
    pub const INFINITE: Self = Self { min: Vec3::NEG_INFINITY, max: Vec3::INFINITY };

    /// The box with the given corners.
    #[inline]
    #[must_use]
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding all `points`.
    #[must_use]
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    /// This box grown to hold `p`.
    #[inline]
    #[must_use]
    pub fn grow(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The smallest box holding both.
    #[inline]
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// Whether the box holds no point.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Whether both corners are finite (a bounded, non-empty box).
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Centre of the box (`NaN` for [`Aabb::EMPTY`] and other empty boxes'
    /// infinite corners: check [`Aabb::is_empty`] first).
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Edge lengths.
    #[inline]
    #[must_use]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The eight corners.
    #[must_use]
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// Whether `p` lies in the box grown by `eps` on every side.
    #[inline]
    #[must_use]
    pub fn contains(&self, p: Vec3, eps: f32) -> bool {
        p.cmpge(self.min - Vec3::splat(eps)).all() && p.cmple(self.max + Vec3::splat(eps)).all()
    }

    /// The parameter interval `(t_enter, t_exit)` over which `ray` is inside
    /// the box, clipped to the ray's own interval; `None` if they miss.
    /// Direction components equal to zero are handled exactly.
    #[must_use]
    pub fn intersect_ray(&self, ray: &Ray) -> Option<(f32, f32)> {
        // An interval with a `NaN` end (or reversed) holds no `t`, and a
        // ray along a non-finite direction meets nothing.
        if !(ray.t_min <= ray.t_max) || !ray.dir.is_finite() {
            return None;
        }
        let mut t0 = ray.t_min;
        let mut t1 = ray.t_max;
        for k in 0..3 {
            let (o, d, lo, hi) = (ray.origin[k], ray.dir[k], self.min[k], self.max[k]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d;
            let (mut a, mut b) = ((lo - o) * inv, (hi - o) * inv);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            t0 = t0.max(a);
            t1 = t1.min(b);
            if t0 > t1 {
                return None;
            }
        }
        Some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::splat(-1.0), Vec3::ONE)
    }

    #[test]
    fn construction_and_queries() {
        let b = Aabb::from_points(&[Vec3::new(1.0, -2.0, 0.5), Vec3::new(-1.0, 3.0, 0.0)]);
        assert_eq!(b, Aabb::new(Vec3::new(-1.0, -2.0, 0.0), Vec3::new(1.0, 3.0, 0.5)));
        assert_eq!(b.center(), Vec3::new(0.0, 0.5, 0.25));
        assert_eq!(b.extent(), Vec3::new(2.0, 5.0, 0.5));
        assert!(Aabb::EMPTY.is_empty() && !b.is_empty());
        assert!(Aabb::from_points(&[]).is_empty());
        assert_eq!(Aabb::EMPTY.union(b), b);
        assert!(!Aabb::INFINITE.is_finite() && b.is_finite());
        assert!(b.contains(Vec3::new(1.0, 3.0, 0.5), 0.0));
        assert!(!b.contains(Vec3::new(1.001, 3.0, 0.5), 0.0));
        assert!(b.contains(Vec3::new(1.001, 3.0, 0.5), 0.01));
        let c = b.corners();
        assert!(c.iter().all(|&p| b.contains(p, 0.0)));
        assert_eq!(Aabb::from_points(&c), b);
    }

    #[test]
    fn slab_interval() {
        let (t0, t1) = unit().intersect_ray(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z)).unwrap();
        assert_eq!((t0, t1), (4.0, 6.0));
        // From inside: clipped to t_min.
        let (t0, t1) = unit().intersect_ray(&Ray::new(Vec3::ZERO, Vec3::X)).unwrap();
        assert_eq!((t0, t1), (0.0, 1.0));
        // Zero components: inside the slab is fine, outside misses.
        assert!(unit().intersect_ray(&Ray::new(Vec3::new(1.0, 1.0, 5.0), Vec3::NEG_Z)).is_some());
        assert!(unit().intersect_ray(&Ray::new(Vec3::new(1.000_001, 0.0, 5.0), Vec3::NEG_Z)).is_none());
        assert!(
            unit()
                .intersect_ray(&Ray::with_interval(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, 0.0, 3.0))
                .is_none()
        );
        assert!(unit().intersect_ray(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z)).is_none());
        assert!(Aabb::EMPTY.intersect_ray(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
        let (t0, t1) = Aabb::INFINITE.intersect_ray(&Ray::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.0))).unwrap();
        assert_eq!((t0, t1), (0.0, f32::INFINITY));
    }

    #[test]
    fn slab_through_an_edge_and_a_corner() {
        let r = Ray::new(Vec3::new(3.0, 3.0, 0.0), Vec3::new(-1.0, -1.0, 0.0));
        assert_eq!(unit().intersect_ray(&r), Some((2.0, 4.0)));
        let r = Ray::new(Vec3::new(2.0, 2.0, 2.0), Vec3::new(-1.0, -1.0, -1.0));
        assert_eq!(unit().intersect_ray(&r), Some((1.0, 3.0)));
    }
}
