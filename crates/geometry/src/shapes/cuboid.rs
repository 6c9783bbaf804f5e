//! Axis-aligned cuboids (boxes) in object space.

use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// A solid box `[min, max]`, axis-aligned in its object space; rotate or
/// shear it with a [`crate::Transform`].
///
/// uv: on each face, the two in-face coordinates normalised to `[0, 1]`,
/// in axis order (the face normal to X uses `(y, z)`, to Y `(x, z)`, to Z
/// `(x, y)`).
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
        let mut n = Vec3::ZERO;
        n[axis] = if positive { 1.0 } else { -1.0 };
        let rel = (p - self.min) / (self.max - self.min);
        let uv = match axis {
            0 => Vec2::new(rel.y, rel.z),
            1 => Vec2::new(rel.x, rel.z),
            _ => Vec2::new(rel.x, rel.y),
        };
        Hit::new(t, p, n, uv, ray.dir)
    }
}

impl Intersect for Cuboid {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
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
            Some(self.face_hit(ray, t_near, near_face.0, near_face.1))
        } else if ray.contains(t_far) {
            Some(self.face_hit(ray, t_far, far_face.0, far_face.1))
        } else {
            None
        }
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.min, self.max)
    }
}
