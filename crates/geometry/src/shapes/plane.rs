//! Infinite planes.

use super::check_finite;
use crate::{Aabb, GeometryError, Hit, Intersect, Ray};
use glam::{Vec2, Vec3};

/// An infinite plane through `point` with unit normal `normal`.
///
/// uv: world-unit coordinates along two tangent axes: `u` along
/// [`Plane::tangent`], `v` along `normal × tangent`, measured from `point`.
/// The tangent is +X projected onto the plane (+Z when the normal is near
/// ±X), so for a floor with `normal = +Y`, `u` runs along +X and `v` along −Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    point: Vec3,
    normal: Vec3,
    tangent: Vec3,
    bitangent: Vec3,
}

impl Plane {
    /// The plane through `point` with normal `normal` (any non-zero length).
    ///
    /// # Errors
    /// If `normal` is zero or a value is not finite.
    pub fn new(point: Vec3, normal: Vec3) -> Result<Self, GeometryError> {
        let point = check_finite("plane point", point)?;
        let normal = check_finite("plane normal", normal)?
            .try_normalize()
            .ok_or(GeometryError::Degenerate("plane normal is zero"))?;
        // Tangent: +X projected onto the plane, or +Z when the normal is ~X.
        let seed = if normal.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
        let tangent = (seed - normal * normal.dot(seed)).normalize();
        let bitangent = normal.cross(tangent);
        Ok(Self { point, normal, tangent, bitangent })
    }

    /// A point on the plane.
    #[must_use]
    pub fn point(&self) -> Vec3 {
        self.point
    }

    /// Unit normal.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// Unit tangent, the direction of increasing `u`.
    #[must_use]
    pub fn tangent(&self) -> Vec3 {
        self.tangent
    }
}

impl Intersect for Plane {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let denom = ray.dir.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.point - ray.origin).dot(self.normal) / denom;
        if !ray.contains(t) {
            return None;
        }
        let rel = ray.at(t) - self.point;
        // Project exactly onto the plane.
        let rel = rel - self.normal * rel.dot(self.normal);
        let uv = Vec2::new(rel.dot(self.tangent), rel.dot(self.bitangent));
        Some(Hit::new(t, self.point + rel, self.normal, uv, ray.dir))
    }

    fn bounds(&self) -> Aabb {
        Aabb::INFINITE
    }
}
