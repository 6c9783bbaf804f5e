//! The record of a ray meeting a surface.

use glam::{Vec2, Vec3};

/// Where and how a ray met a surface.
///
/// Both normals are unit length and point *outward* (away from the solid
/// for closed shapes, along the declared normal for planes and disks, along
/// the counter-clockwise winding normal for triangles); they are never
/// flipped toward the ray. `front_face` says which side the ray came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit, in units of the ray's direction.
    pub t: f32,
    /// The hit point, on the surface.
    pub point: Vec3,
    /// Unit outward normal of the true surface at `point`.
    pub geo_normal: Vec3,
    /// Unit outward shading normal (interpolated for meshes with vertex
    /// normals, equal to `geo_normal` elsewhere), on the same side as
    /// `geo_normal`.
    pub normal: Vec3,
    /// Surface coordinates; each shape documents its parameterisation.
    pub uv: Vec2,
    /// `true` when the ray arrived from the side `geo_normal` points to.
    pub front_face: bool,
}

impl Hit {
    /// A hit whose shading normal equals its geometric normal; `front_face`
    /// is computed from the ray direction `dir`.
    #[inline]
    #[must_use]
    pub fn new(t: f32, point: Vec3, normal: Vec3, uv: Vec2, dir: Vec3) -> Self {
        Self { t, point, geo_normal: normal, normal, uv, front_face: Self::faces(dir, normal) }
    }

    /// Whether a ray along `dir` meets a surface of outward normal `normal`
    /// from the side the normal points to: [`Hit::front_face`]'s rule.
    #[inline]
    #[must_use]
    pub fn faces(dir: Vec3, normal: Vec3) -> bool {
        dir.dot(normal) < 0.0
    }

    /// The shading normal turned to face the incoming ray (for shading).
    #[inline]
    #[must_use]
    pub fn facing_normal(&self) -> Vec3 {
        if self.front_face { self.normal } else { -self.normal }
    }
}
