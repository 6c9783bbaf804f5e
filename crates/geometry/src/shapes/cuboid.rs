//! Axis-aligned cuboids (boxes) in object space.

use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A solid box `[min, max]`, axis-aligned in its object space; rotate or
/// shear it with a [`crate::Transform`].
///
/// uv: on each face, the two in-face coordinates normalised to `[0, 1]`
/// (`rel = (p − min) / (max − min)`), oriented so that an image seen from
/// outside reads as in an image viewer: on the four side faces the image's
/// top is at +Y and it is not mirrored (+Z: `(x, 1 − y)`, −Z: `(1 − x, 1 − y)`,
/// +X: `(1 − z, 1 − y)`, −X: `(z, 1 − y)`); the top face (+Y) is `(x, z)`,
/// its image's top toward −Z, and the bottom face (−Y) is `(x, 1 − z)`, its
/// image's top toward +Z, so that both continue the front (+Z) face as in a
/// cross-shaped unfolding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    min: Vec3,
    max: Vec3,
}

impl Cuboid {
    /// The box with corners `min` and `max`.
    ///
    /// # Errors
    /// If a value is not finite or any edge is not strictly positive.
    pub fn new(min: Vec3, max: Vec3) -> Result<Self, GeometryError> {
        if !(min.is_finite() && max.is_finite()) {
            return Err(GeometryError::NonFinite("cuboid corner"));
        }
        let size = max - min;
        let smallest = size.min_element();
        if smallest <= 0.0 {
            return Err(GeometryError::NonPositive { what: "cuboid edge", value: smallest });
        }
        Ok(Self { min, max })
    }

    /// The box centred at `center` with edge lengths `size`.
    ///
    /// # Errors
    /// As [`Cuboid::new`].
    pub fn from_center_size(center: Vec3, size: Vec3) -> Result<Self, GeometryError> {
        Self::new(center - 0.5 * size, center + 0.5 * size)
    }

    /// Lower corner.
    #[must_use]
    pub fn min(&self) -> Vec3 {
        self.min
    }

    /// Upper corner.
    #[must_use]
    pub fn max(&self) -> Vec3 {
        self.max
    }

    fn face_hit(&self, ray: &Ray, t: f32, axis: usize, positive: bool) -> Hit {
        let mut p = ray.at(t);
        p[axis] = if positive { self.max[axis] } else { self.min[axis] };
        p = p.clamp(self.min, self.max);
        let n = face_normal(axis, positive);
        let rel = (p - self.min) / (self.max - self.min);
        let uv = match (axis, positive) {
            (0, true) => Vec2::new(1.0 - rel.z, 1.0 - rel.y),
            (0, false) => Vec2::new(rel.z, 1.0 - rel.y),
            (1, true) => Vec2::new(rel.x, rel.z),
            (1, false) => Vec2::new(rel.x, 1.0 - rel.z),
            (_, true) => Vec2::new(rel.x, 1.0 - rel.y),
            (_, false) => Vec2::new(1.0 - rel.x, 1.0 - rel.y),
        };
        Hit::new(t, p, n, uv, ray.dir)
    }
}

impl Cuboid {
    /// `(t, axis, positive)` of the nearest crossing in the interval: its
    /// `t` and the face it lies on.
    #[inline]
    fn solve(&self, ray: &Ray) -> Option<(f32, usize, bool)> {
        // A direction that is not finite meets nothing (its slabs would
        // start at `t = ±0` wherever the box lies).
        if !ray.dir.is_finite() {
            return None;
        }
        // Slab test remembering which face bounds the interval on each side.
        let mut t_near = f32::NEG_INFINITY;
        let mut t_far = f32::INFINITY;
        let (mut near_face, mut far_face) = ((0, false), (0, false));
        for k in 0..3 {
            let (o, d) = (ray.origin[k], ray.dir[k]);
            if d == 0.0 {
                if o < self.min[k] || o > self.max[k] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d;
            let t_lo = (self.min[k] - o) * inv;
            let t_hi = (self.max[k] - o) * inv;
            // Entering through the min face when d > 0, the max face otherwise.
            let (t_in, t_out, in_pos) = if d > 0.0 { (t_lo, t_hi, false) } else { (t_hi, t_lo, true) };
            if t_in > t_near {
                t_near = t_in;
                near_face = (k, in_pos);
            }
            if t_out < t_far {
                t_far = t_out;
                far_face = (k, !in_pos);
            }
        }
        if t_near > t_far {
            return None;
        }
        if ray.contains(t_near) {
            Some((t_near, near_face.0, near_face.1))
        } else if ray.contains(t_far) {
            Some((t_far, far_face.0, far_face.1))
        } else {
            None
        }
    }
}

/// The outward unit normal of the face across `axis` on its `positive` side.
#[inline]
fn face_normal(axis: usize, positive: bool) -> Vec3 {
    let mut n = Vec3::ZERO;
    n[axis] = if positive { 1.0 } else { -1.0 };
    n
}

impl Intersect for Cuboid {
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.solve(ray).map(|(t, _, _)| t)
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (t, axis, positive) = self.solve(ray)?;
        Some(self.face_hit(ray, t, axis, positive))
    }

    /// No point and no uv.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        let (t, axis, positive) = self.solve(ray)?;
        Some((t, Hit::faces(ray.dir, face_normal(axis, positive))))
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.min, self.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{check_hit, close, close3};

    fn cube() -> Cuboid {
        Cuboid::new(Vec3::splat(-1.0), Vec3::splat(1.0)).unwrap()
    }

    #[test]
    fn hit_from_outside_on_each_axis() {
        let c = cube();
        let h = c.intersect(&Ray::new(Vec3::new(0.5, -0.5, 5.0), Vec3::NEG_Z)).unwrap();
        check_hit(&h, 4.0, Vec3::new(0.5, -0.5, 1.0), Vec3::Z, Vec2::new(0.75, 0.75), true);
        let h = c.intersect(&Ray::new(Vec3::new(-3.0, 0.5, 0.0), Vec3::new(2.0, 0.0, 0.0))).unwrap();
        check_hit(&h, 1.0, Vec3::new(-1.0, 0.5, 0.0), Vec3::NEG_X, Vec2::new(0.5, 0.25), true);
        let h = c.intersect(&Ray::new(Vec3::new(0.0, 4.0, -0.5), Vec3::NEG_Y)).unwrap();
        check_hit(&h, 3.0, Vec3::new(0.0, 1.0, -0.5), Vec3::Y, Vec2::new(0.5, 0.25), true);
    }

    #[test]
    fn hit_from_inside_is_the_exit_face() {
        let h = cube().intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::X)).unwrap();
        check_hit(&h, 1.0, Vec3::new(1.0, 0.5, 0.0), Vec3::X, Vec2::new(0.5, 0.25), false);
        let h = cube().intersect(&Ray::new(Vec3::ZERO, Vec3::new(0.0, -1.0, -1.0))).unwrap();
        close(h.t, 1.0, 1e-6);
        close3(h.point, Vec3::new(0.0, -1.0, -1.0), 1e-6);
        assert!(!h.front_face);
    }

    #[test]
    fn oblique_hit() {
        // From (3, 2, 0) along (−1, −0.5, 0): reaches x = 1 at t = 2, y = 1 (an edge).
        let h = cube().intersect(&Ray::new(Vec3::new(3.0, 1.5, 0.25), Vec3::new(-1.0, -0.25, 0.0))).unwrap();
        check_hit(&h, 2.0, Vec3::new(1.0, 1.0, 0.25), Vec3::X, Vec2::new(0.375, 0.0), true);
    }

    #[test]
    fn grazing_along_a_face_and_corner() {
        // In the plane of the top face (zero y component): enters at the x = −1 face.
        let h = cube().intersect(&Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X)).unwrap();
        check_hit(&h, 4.0, Vec3::new(-1.0, 1.0, 0.0), Vec3::NEG_X, Vec2::new(0.5, 0.0), true);
        // Straight at a corner.
        let h = cube().intersect(&Ray::new(Vec3::splat(5.0), Vec3::splat(-1.0))).unwrap();
        close(h.t, 4.0, 1e-6);
        close3(h.point, Vec3::ONE, 1e-6);
        assert_eq!(h.geo_normal.abs().max_element(), 1.0);
        assert!(h.geo_normal.min_element() >= 0.0, "one of the corner's outward faces");
    }

    #[test]
    fn misses_just_outside_the_silhouette() {
        let c = cube();
        assert!(c.intersect(&Ray::new(Vec3::new(-5.0, 1.000_001, 0.0), Vec3::X)).is_none());
        assert!(c.intersect(&Ray::new(Vec3::new(1.000_001, 0.0, 5.0), Vec3::NEG_Z)).is_none());
        assert!(c.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z)).is_none(), "behind");
        assert!(c.intersect(&Ray::with_interval(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, 0.0, 3.99)).is_none());
    }

    #[test]
    fn zero_direction_never_hits() {
        assert!(cube().intersect(&Ray::new(Vec3::ZERO, Vec3::ZERO)).is_none());
        // A direction so small that 1/d overflows.
        let tiny = Ray::new(Vec3::ZERO, Vec3::new(1.0e-40, 0.0, 0.0));
        if let Some(h) = cube().intersect(&tiny) {
            assert!(h.t.is_finite() && h.point.is_finite(), "{h:?}");
        }
    }

    #[test]
    fn construction_and_bounds() {
        assert!(Cuboid::new(Vec3::ONE, Vec3::ONE).is_err());
        assert!(Cuboid::new(Vec3::ONE, Vec3::ZERO).is_err());
        assert!(Cuboid::new(Vec3::ZERO, Vec3::new(1.0, f32::NAN, 1.0)).is_err());
        let c = Cuboid::from_center_size(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 4.0, 6.0)).unwrap();
        assert_eq!(c.bounds(), Aabb::new(Vec3::ZERO, Vec3::new(2.0, 4.0, 6.0)));
    }
}
