//! Affine transforms that place shapes in the world.

use crate::{Aabb, GeometryError, Hit, Ray};
use glam::{Affine3A, Mat3, Mat3A, Mat4, Vec3, Vec3A};

/// Smallest |determinant| of the linear part accepted as invertible.
const MIN_ABS_DET: f32 = 1e-12;

/// An invertible affine transform from object space to world space, with
/// its inverse and normal matrix (inverse transpose) cached.
///
/// Construct with the named constructors and chain with [`Transform::then`];
/// a transform that would be singular or non-finite is rejected with
/// [`GeometryError::SingularTransform`] or [`GeometryError::NonFinite`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    to_world: Affine3A,
    to_object: Affine3A,
    normal: Mat3A,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self =
        Self { to_world: Affine3A::IDENTITY, to_object: Affine3A::IDENTITY, normal: Mat3A::IDENTITY };

    /// Checks and wraps an affine map.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] if any entry is NaN or infinite,
    /// [`GeometryError::SingularTransform`] if the linear part is not
    /// invertible.
    pub fn try_from_affine(m: Affine3A) -> Result<Self, GeometryError> {
        if !m.is_finite() {
            return Err(GeometryError::NonFinite("transform"));
        }
        let det = m.matrix3.determinant();
        if !(det.abs() > MIN_ABS_DET) {
            return Err(GeometryError::SingularTransform { det });
        }
        let inv = m.inverse();
        if !inv.is_finite() {
            return Err(GeometryError::SingularTransform { det });
        }
        Ok(Self { to_world: m, to_object: inv, normal: inv.matrix3.transpose() })
    }

    /// From a 4×4 matrix whose last row is `(0, 0, 0, 1)` (column vectors:
    /// `p' = M p`).
    ///
    /// # Errors
    /// As [`Transform::try_from_affine`], plus
    /// [`GeometryError::NotAffine`] if the last row is not `(0, 0, 0, 1)`.
    pub fn try_from_mat4(m: Mat4) -> Result<Self, GeometryError> {
        if m.row(3) != glam::Vec4::W {
            return Err(GeometryError::NotAffine);
        }
        Self::try_from_affine(Affine3A::from_mat4(m))
    }

    /// Translation by `v`.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] if `v` is not finite.
    pub fn translate(v: Vec3) -> Result<Self, GeometryError> {
        Self::try_from_affine(Affine3A::from_translation(v))
    }

    /// Rotation by `angle` radians about the X axis (right-handed).
    #[must_use]
    pub fn rotate_x(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_x(angle))
    }

    /// Rotation by `angle` radians about the Y axis (right-handed):
    /// `(x, y, z) -> (x cos a + z sin a, y, -x sin a + z cos a)`, the
    /// report's equation 6.
    #[must_use]
    pub fn rotate_y(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_y(angle))
    }

    /// Rotation by `angle` radians about the Z axis (right-handed).
    #[must_use]
    pub fn rotate_z(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_z(angle))
    }

    /// Rotation by `angle` radians about `axis` (any non-zero length).
    ///
    /// # Errors
    /// [`GeometryError::Degenerate`] if `axis` is zero or not finite.
    pub fn rotate_axis(axis: Vec3, angle: f32) -> Result<Self, GeometryError> {
        let axis = axis.try_normalize().ok_or(GeometryError::Degenerate("rotation axis is zero"))?;
        Ok(Self::rotation(Mat3::from_axis_angle(axis, angle)))
    }

    fn rotation(m: Mat3) -> Self {
        let m = Mat3A::from(m);
        // A rotation's inverse is its transpose, and its normal matrix is itself.
        Self {
            to_world: Affine3A::from_mat3(m.into()),
            to_object: Affine3A::from_mat3(m.transpose().into()),
            normal: m,
        }
    }

    /// Non-uniform scale by `s`.
    ///
    /// # Errors
    /// [`GeometryError::SingularTransform`] if a component is zero.
    pub fn scale(s: Vec3) -> Result<Self, GeometryError> {
        Self::try_from_affine(Affine3A::from_scale(s))
    }

    /// General shear: `x' = x + xy·y + xz·z`, `y' = y + yx·x + yz·z`,
    /// `z' = z + zx·x + zy·y`. The report's sheared box is
    /// `shear(Shear { xy: tan φ, ..Shear::NONE })`.
    ///
    /// # Errors
    /// [`GeometryError::SingularTransform`] if the factors make the map
    /// singular (e.g. `xy = yx = 1`).
    pub fn shear(s: Shear) -> Result<Self, GeometryError> {
        let m = Mat3::from_cols(
            Vec3::new(1.0, s.yx, s.zx),
            Vec3::new(s.xy, 1.0, s.zy),
            Vec3::new(s.xz, s.yz, 1.0),
        );
        Self::try_from_affine(Affine3A::from_mat3(m))
    }

    /// `self` followed by `next` (world = next(self(object))).
    #[must_use]
    pub fn then(&self, next: &Self) -> Self {
        let to_object = self.to_object * next.to_object;
        Self { to_world: next.to_world * self.to_world, to_object, normal: to_object.matrix3.transpose() }
    }

    /// The inverse transform.
    #[must_use]
    pub fn inverse(&self) -> Self {
        Self { to_world: self.to_object, to_object: self.to_world, normal: self.to_world.matrix3.transpose() }
    }

    /// The object-to-world affine map.
    #[inline]
    #[must_use]
    pub fn matrix(&self) -> Affine3A {
        self.to_world
    }

    /// The world-to-object affine map.
    #[inline]
    #[must_use]
    pub fn inverse_matrix(&self) -> Affine3A {
        self.to_object
    }

    /// Maps an object-space point to world space.
    #[inline]
    #[must_use]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p)
    }

    /// Maps an object-space direction (no translation) to world space.
    #[inline]
    #[must_use]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.to_world.transform_vector3(v)
    }

    /// Maps an object-space normal to a unit world-space normal with the
    /// inverse transpose; outward stays outward, also under reflections.
    #[inline]
    #[must_use]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        Vec3::from(self.normal * Vec3A::from(n)).normalize_or(n)
    }

    /// Maps a world-space ray into object space; `t` values are preserved.
    #[inline]
    #[must_use]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.to_object.transform_point3(ray.origin),
            dir: self.to_object.transform_vector3(ray.dir),
            t_min: ray.t_min,
            t_max: ray.t_max,
        }
    }

    /// Maps a hit found on an object-space ray back to world space.
    #[inline]
    #[must_use]
    pub fn hit_to_world(&self, hit: &Hit) -> Hit {
        let geo_normal = self.normal(hit.geo_normal);
        let normal = if hit.normal == hit.geo_normal { geo_normal } else { self.normal(hit.normal) };
        Hit {
            t: hit.t,
            point: self.point(hit.point),
            geo_normal,
            normal,
            uv: hit.uv,
            front_face: hit.front_face,
        }
    }

    /// World-space bounds of an object-space box (exact for the box's
    /// corners; infinite boxes stay infinite).
    #[must_use]
    pub fn aabb(&self, b: &Aabb) -> Aabb {
        if b.is_empty() {
            return *b;
        }
        if !b.is_finite() {
            return Aabb::INFINITE;
        }
        Aabb::from_points(&b.corners().map(|c| self.point(c)))
    }
}

/// Shear factors for [`Transform::shear`]; `xy` is "x by y".
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shear {
    /// x gains `xy·y`.
    pub xy: f32,
    /// x gains `xz·z`.
    pub xz: f32,
    /// y gains `yx·x`.
    pub yx: f32,
    /// y gains `yz·z`.
    pub yz: f32,
    /// z gains `zx·x`.
    pub zx: f32,
    /// z gains `zy·y`.
    pub zy: f32,
}

impl Shear {
    /// No shear.
    pub const NONE: Self = Self { xy: 0.0, xz: 0.0, yx: 0.0, yz: 0.0, zx: 0.0, zy: 0.0 };
}
