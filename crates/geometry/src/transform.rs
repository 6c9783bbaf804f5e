//! Affine transforms that place shapes in the world.

use crate::{Aabb, GeometryError, Hit, Ray};
use glam::{Affine3A, DMat3, Mat3, Mat3A, Mat4, Vec3, Vec3A};

/// Smallest |determinant| of the linear part, relative to the product of
/// its column lengths, accepted as invertible.
pub(crate) const MIN_FLATNESS: f32 = 1e-6;

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
    /// `to_object` is exactly the identity: [`Transform::ray_to_object`]
    /// returns the ray as it is. For a finite ray its products would only
    /// turn a `-0.0` component into `+0.0`; for a non-finite one they
    /// could turn an infinity into `NaN` (`0 · ∞`), which the copy keeps.
    /// A scene of one mesh placed as it is (the common case) then prepares
    /// its rays without a matrix product each.
    identity: bool,
    /// `to_object` moves points and nothing else (its linear part is
    /// exactly the identity) and is not the identity: `Some` of the offset
    /// it adds (see [`Transform::object_offset`]).
    offset: Option<Vec3>,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        to_world: Affine3A::IDENTITY,
        to_object: Affine3A::IDENTITY,
        normal: Mat3A::IDENTITY,
        identity: true,
        offset: None,
    };

    /// Checks and wraps an affine map.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] if any entry is NaN or infinite,
    /// [`GeometryError::SingularTransform`] if the linear part is not
    /// safely invertible: `|det| <= 1e-6 · |c0|·|c1|·|c2|` for its columns
    /// `c0, c1, c2` (it flattens space by a factor of a million or more
    /// relative to its own scale; a uniform scale of any size passes),
    /// [`GeometryError::Degenerate`] if its inverse is past the range of
    /// `f32` (a scale below about `1e-38`).
    pub fn try_from_affine(m: Affine3A) -> Result<Self, GeometryError> {
        if !m.is_finite() {
            return Err(GeometryError::NonFinite("transform"));
        }
        // In f64: the determinant of a scale of 1e13 (or 1e-13) is past
        // f32's range, and the inverse would be lost with it.
        let d = DMat3::from_cols(
            m.matrix3.x_axis.as_dvec3(),
            m.matrix3.y_axis.as_dvec3(),
            m.matrix3.z_axis.as_dvec3(),
        );
        let det = d.determinant();
        // Relative test: |det| against the volume the columns could span at
        // most (Hadamard's bound), so that a small uniform scale (a model in
        // millimetres) is accepted while a flattening map is not.
        let hadamard = d.x_axis.length() * d.y_axis.length() * d.z_axis.length();
        if !(det.abs() > f64::from(MIN_FLATNESS) * hadamard) {
            return Err(GeometryError::SingularTransform { det, flatness: det.abs() / hadamard });
        }
        let d_inv = d.inverse();
        let inv =
            Affine3A::from_mat3_translation(d_inv.as_mat3(), (-(d_inv * m.translation.as_dvec3())).as_vec3());
        if !inv.is_finite() {
            return Err(GeometryError::Degenerate(
                "transform's inverse is past the range of 32-bit floats (a scale too far from 1)",
            ));
        }
        Ok(Self::from_parts(m, inv, inv.matrix3.transpose()))
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
    /// Unchecked: `angle` must be finite (a `NaN` or infinite angle gives
    /// a map of `NaN`s; [`Transform::rotate_axis`] refuses one).
    #[must_use]
    pub fn rotate_x(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_x(angle))
    }

    /// Rotation by `angle` radians about the Y axis (right-handed):
    /// `(x, y, z) -> (x cos a + z sin a, y, -x sin a + z cos a)`, the
    /// report's equation 6. Unchecked, as [`Transform::rotate_x`].
    #[must_use]
    pub fn rotate_y(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_y(angle))
    }

    /// Rotation by `angle` radians about the Z axis (right-handed).
    /// Unchecked, as [`Transform::rotate_x`].
    #[must_use]
    pub fn rotate_z(angle: f32) -> Self {
        Self::rotation(Mat3::from_rotation_z(angle))
    }

    /// Rotation by `angle` radians about `axis` (any non-zero length).
    ///
    /// # Errors
    /// [`GeometryError::Degenerate`] if `axis` is zero or not finite,
    /// [`GeometryError::NonFinite`] if `angle` is not.
    pub fn rotate_axis(axis: Vec3, angle: f32) -> Result<Self, GeometryError> {
        if !angle.is_finite() {
            return Err(GeometryError::NonFinite("rotation angle"));
        }
        let axis =
            crate::unit(axis).ok_or(GeometryError::Degenerate("rotation axis is zero or not finite"))?;
        Ok(Self::rotation(Mat3::from_axis_angle(axis, angle)))
    }

    fn rotation(m: Mat3) -> Self {
        let m = Mat3A::from(m);
        // A rotation's inverse is its transpose, and its normal matrix is itself.
        Self::from_parts(Affine3A::from_mat3(m.into()), Affine3A::from_mat3(m.transpose().into()), m)
    }

    /// From the map, its inverse and its normal matrix.
    fn from_parts(to_world: Affine3A, to_object: Affine3A, normal: Mat3A) -> Self {
        let identity = to_object == Affine3A::IDENTITY;
        let offset =
            (!identity && to_object.matrix3 == Mat3A::IDENTITY).then(|| Vec3::from(to_object.translation));
        Self { to_world, to_object, normal, identity, offset }
    }

    /// Non-uniform scale by `s`.
    ///
    /// # Errors
    /// As [`Transform::try_from_affine`]: [`GeometryError::NonFinite`] if a
    /// component is not finite, [`GeometryError::SingularTransform`] if one
    /// is zero (or the components differ by a factor of a million or
    /// more), [`GeometryError::Degenerate`] if they are below about `1e-38`.
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
    /// Unchecked: the product of two valid maps can leave `f32`'s range
    /// (a scale of `1e20` twice) or its inverse can (`1e-25` twice);
    /// [`Transform::try_then`] checks it.
    #[must_use]
    pub fn then(&self, next: &Self) -> Self {
        let to_object = self.to_object * next.to_object;
        Self::from_parts(next.to_world * self.to_world, to_object, to_object.matrix3.transpose())
    }

    /// [`Transform::then`], the product checked as
    /// [`Transform::try_from_affine`] checks a map.
    ///
    /// # Errors
    /// As [`Transform::try_from_affine`], for the product.
    pub fn try_then(&self, next: &Self) -> Result<Self, GeometryError> {
        Self::try_from_affine(next.to_world * self.to_world)
    }

    /// The inverse transform.
    #[must_use]
    pub fn inverse(&self) -> Self {
        Self::from_parts(self.to_object, self.to_world, self.to_world.matrix3.transpose())
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
        let m = Vec3::from(self.normal * Vec3A::from(n));
        // `unit` where `m`'s squared length under- or overflows (a scale
        // of 1e-20 makes the inverse transpose 1e20).
        crate::unit_or_extreme(m).unwrap_or(n)
    }

    /// Whether the map to object space is exactly the identity, so that
    /// [`Transform::ray_to_object`] returns a ray as it is.
    #[inline]
    #[must_use]
    pub fn is_identity(&self) -> bool {
        self.identity
    }

    /// Where the map to object space is a translation and nothing else
    /// (a model placed by `translate` alone): the offset it adds to a
    /// point. [`Transform::ray_to_object`] then moves a ray's origin by it
    /// and keeps its direction as it is, so that a ray's values that
    /// depend on its direction alone (reciprocals, octant, a triangle
    /// test's shear) hold in object space too. `None` for the identity and
    /// for every map that turns, scales or shears.
    #[inline]
    #[must_use]
    pub fn object_offset(&self) -> Option<Vec3> {
        self.offset
    }

    /// Maps a world-space ray into object space; `t` values are preserved.
    /// Under a translation alone ([`Transform::object_offset`]) the origin
    /// is `origin + offset`, per component, and the direction is kept: the
    /// matrix product would give the same values but for the sign of a
    /// zero component.
    #[inline]
    #[must_use]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        if self.identity {
            return *ray;
        }
        if let Some(offset) = self.offset {
            return Ray { origin: ray.origin + offset, ..*ray };
        }
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

    /// World-space bounds of the object-space ball of `radius` about
    /// `centre` (an ellipsoid in the world): exact, unlike the bounds of
    /// its box, which a rotation widens by up to √3. See
    /// [`Transform::tightest`] for the rounding.
    #[must_use]
    pub fn ball_aabb(&self, centre: Vec3, radius: f32) -> Aabb {
        let rows = self.to_world.matrix3.transpose();
        let half = radius * Vec3::new(rows.x_axis.length(), rows.y_axis.length(), rows.z_axis.length());
        self.centred(centre, half)
    }

    /// World-space bounds of the object-space disk of `radius` about
    /// `centre` across the unit `normal`: exact (an ellipse in the world;
    /// along world axis `i`, `radius · |row_i × normal|`, which is
    /// `radius · √(|row_i|² − (row_i · normal)²)` without its cancellation
    /// when a row is nearly along the normal: a disk or cylinder turned by
    /// a hundredth of a degree lost its thin extent there).
    #[must_use]
    pub fn disk_aabb(&self, centre: Vec3, normal: Vec3, radius: f32) -> Aabb {
        let rows = self.to_world.matrix3.transpose();
        let n = Vec3A::from(normal);
        let across = |r: Vec3A| r.cross(n).length();
        let half = radius * Vec3::new(across(rows.x_axis), across(rows.y_axis), across(rows.z_axis));
        self.centred(centre, half)
    }

    /// The box of half-extents `half` about the image of `centre`, widened
    /// by a few units in the last place of its values (the products and
    /// roots round), or the empty box if anything overflowed.
    fn centred(&self, centre: Vec3, half: Vec3) -> Aabb {
        let c = self.point(centre);
        let pad = 4.0 * f32::EPSILON * (half + c.abs());
        let b = Aabb::new(c - half - pad, c + half + pad);
        if b.is_finite() { b } else { Aabb::EMPTY }
    }

    /// The tighter of `exact` (from [`Transform::ball_aabb`] or
    /// [`Transform::disk_aabb`], empty where they overflowed) and the
    /// bounds of `object_box` (the shape's own box): the first is exact
    /// up to a few units in the last place, the second exact at the box's
    /// corners, so their overlap holds the shape and is never looser than
    /// the box's bounds.
    #[must_use]
    pub fn tightest(&self, exact: Aabb, object_box: &Aabb) -> Aabb {
        let corners = self.aabb(object_box);
        if exact.is_empty() || !corners.is_finite() {
            return corners;
        }
        Aabb::new(exact.min.max(corners.min), exact.max.min(corners.max))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `try_then` refuses the products `then` makes without a check, and
    /// gives `then`'s map where the product is fine; `rotate_axis` refuses
    /// an angle that is not finite.
    #[test]
    fn checked_composition_and_rotation() {
        let big = Transform::scale(Vec3::splat(1e20)).unwrap();
        assert!(matches!(big.try_then(&big), Err(GeometryError::NonFinite(_))));
        let small = Transform::scale(Vec3::splat(1e-25)).unwrap();
        assert!(small.try_then(&small).is_err());
        let a = Transform::rotate_axis(Vec3::Y, 0.5).unwrap();
        let b = Transform::translate(Vec3::new(1.0, 2.0, 3.0)).unwrap();
        let p = Vec3::new(0.3, -0.7, 2.0);
        assert_eq!(a.try_then(&b).unwrap().point(p), a.then(&b).point(p));
        for angle in [f32::NAN, f32::INFINITY] {
            assert!(matches!(Transform::rotate_axis(Vec3::Y, angle), Err(GeometryError::NonFinite(_))));
        }
    }
    use crate::testutil::{close, close3, uniform};
    use crate::{Cuboid, Instance, Intersect, Sphere};
    use std::f32::consts::FRAC_PI_2;

    fn t(v: Vec3) -> Transform {
        Transform::translate(v).unwrap()
    }

    #[test]
    fn normals_and_axes_of_extreme_scale_stay_unit() {
        // A uniform scale of 1e-20: the inverse transpose is 1e20, whose
        // product's squared length overflows; the normal is still the
        // object's turned, not left in object space.
        let m = Transform::rotate_y(FRAC_PI_2).then(&Transform::scale(Vec3::splat(1e-20)).unwrap());
        close3(m.normal(Vec3::X), Vec3::new(0.0, 0.0, -1.0), 1e-6);
        let m = Transform::rotate_y(FRAC_PI_2).then(&Transform::scale(Vec3::splat(1e20)).unwrap());
        close3(m.normal(Vec3::X), Vec3::new(0.0, 0.0, -1.0), 1e-6);
        // Any finite, non-zero axis is a direction.
        for axis in [Vec3::new(1e20, 0.0, 0.0), Vec3::new(1e-30, 0.0, 0.0), Vec3::new(3e38, 3e38, 0.0)] {
            let r = Transform::rotate_axis(axis, FRAC_PI_2).unwrap();
            // The axis itself stays put; a direction across it turns.
            let d = crate::unit(axis).unwrap();
            close3(r.vector(d), d, 1e-6);
            close3(r.vector(Vec3::Z), d.cross(Vec3::Z), 1e-6);
        }
        for axis in [Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::NAN] {
            assert!(Transform::rotate_axis(axis, 1.0).is_err(), "{axis}");
        }
    }

    #[test]
    fn composition_order_is_self_then_next() {
        // Rotate a quarter turn about Y, then translate: (1,0,0) -> (0,0,-1) -> (5,0,-1).
        let m = Transform::rotate_y(FRAC_PI_2).then(&t(Vec3::new(5.0, 0.0, 0.0)));
        close3(m.point(Vec3::X), Vec3::new(5.0, 0.0, -1.0), 1e-6);
        // The other order: (1,0,0) -> (6,0,0) -> (0,0,-6).
        let m = t(Vec3::new(5.0, 0.0, 0.0)).then(&Transform::rotate_y(FRAC_PI_2));
        close3(m.point(Vec3::X), Vec3::new(0.0, 0.0, -6.0), 1e-5);
        // Directions ignore translation.
        close3(m.vector(Vec3::X), Vec3::new(0.0, 0.0, -1.0), 1e-6);
    }

    /// A translation alone has an offset, and maps rays as the matrix
    /// product does (up to the sign of a zero); every other map, and the
    /// identity, has none.
    #[test]
    fn translations_move_rays_by_their_offset() {
        let m = t(Vec3::new(1.5, -2.0, 0.25)).then(&t(Vec3::new(0.5, 0.0, -3.0)));
        assert_eq!(m.object_offset(), Some(Vec3::new(-2.0, 2.0, 2.75)));
        let mut u = uniform(7);
        for _ in 0..1000 {
            let o = Vec3::new(u() * 50.0, u() * 50.0, u());
            let d = Vec3::new(u(), 0.0, u());
            let ray = Ray { origin: o, dir: d, t_min: 0.5, t_max: 9.0 };
            let local = m.ray_to_object(&ray);
            let product = Ray {
                origin: m.inverse_matrix().transform_point3(o),
                dir: m.inverse_matrix().transform_vector3(d),
                ..ray
            };
            // Equal as numbers (a zero of either sign), bit for bit otherwise.
            assert_eq!(local, product);
            assert_eq!(local.dir.to_array().map(f32::to_bits), d.to_array().map(f32::to_bits));
            assert_eq!(local.origin, o + Vec3::new(-2.0, 2.0, 2.75));
        }
        for other in [
            Transform::IDENTITY,
            t(Vec3::ZERO),
            Transform::rotate_y(0.3).then(&t(Vec3::X)),
            Transform::scale(Vec3::splat(2.0)).unwrap(),
            Transform::shear(Shear { xy: 0.5, ..Shear::NONE }).unwrap(),
            t(Vec3::X).then(&t(-Vec3::X)),
        ] {
            assert_eq!(other.object_offset(), None, "{other:?}");
        }
    }

    #[test]
    fn rotations_are_right_handed() {
        close3(Transform::rotate_x(FRAC_PI_2).point(Vec3::Y), Vec3::Z, 1e-6);
        close3(Transform::rotate_y(FRAC_PI_2).point(Vec3::Z), Vec3::X, 1e-6);
        close3(Transform::rotate_z(FRAC_PI_2).point(Vec3::X), Vec3::Y, 1e-6);
        let about = Transform::rotate_axis(Vec3::new(0.0, 0.0, 3.0), FRAC_PI_2).unwrap();
        close3(about.point(Vec3::X), Vec3::Y, 1e-6);
        assert!(Transform::rotate_axis(Vec3::ZERO, 1.0).is_err());
    }

    #[test]
    fn inverse_round_trips() {
        let m = Transform::scale(Vec3::new(2.0, 0.5, 3.0))
            .unwrap()
            .then(&Transform::shear(Shear { xy: 0.7, zx: -0.3, ..Shear::NONE }).unwrap())
            .then(&Transform::rotate_axis(Vec3::new(1.0, 2.0, 3.0), 0.8).unwrap())
            .then(&t(Vec3::new(-4.0, 1.0, 9.0)));
        let inv = m.inverse();
        for p in [Vec3::ZERO, Vec3::new(1.0, -2.0, 3.5), Vec3::splat(10.0)] {
            close3(inv.point(m.point(p)), p, 1e-4);
            close3(m.point(inv.point(p)), p, 1e-4);
        }
        close3(m.inverse().inverse().point(Vec3::ONE), m.point(Vec3::ONE), 1e-5);
        let id = m.then(&inv);
        close3(id.point(Vec3::new(3.0, 2.0, 1.0)), Vec3::new(3.0, 2.0, 1.0), 1e-4);
    }

    #[test]
    fn normals_under_non_uniform_scale_use_the_inverse_transpose() {
        // The sphere x² + y² + z² = 1 scaled by (2, 1, 1): at the object point
        // (1,1,0)/√2 the normal is ∝ (1/2, 1, 0), not the scaled (2, 1, 0).
        let m = Transform::scale(Vec3::new(2.0, 1.0, 1.0)).unwrap();
        let n = m.normal(Vec3::new(1.0, 1.0, 0.0).normalize());
        close3(n, Vec3::new(0.5, 1.0, 0.0).normalize(), 1e-6);
        // Perpendicular to the transformed tangent.
        let tangent = m.vector(Vec3::new(-1.0, 1.0, 0.0));
        close(n.dot(tangent), 0.0, 1e-6);
    }

    #[test]
    fn normals_under_shear() {
        // The report's shear x' = x + y·tan φ: the top face (normal +Y) keeps
        // its normal, the side x = 1 (normal +X) tilts to (1, −tan φ, 0)/len.
        let tan = 30f32.to_radians().tan();
        let m = Transform::shear(Shear { xy: tan, ..Shear::NONE }).unwrap();
        close3(m.point(Vec3::new(1.0, 2.0, 0.0)), Vec3::new(1.0 + 2.0 * tan, 2.0, 0.0), 1e-6);
        close3(m.normal(Vec3::Y), Vec3::Y, 1e-6);
        close3(m.normal(Vec3::X), Vec3::new(1.0, -tan, 0.0).normalize(), 1e-6);
        // Still perpendicular to the sheared side's tangent (0, 1, 0) -> (tan, 1, 0).
        close(m.normal(Vec3::X).dot(m.vector(Vec3::Y)), 0.0, 1e-6);
    }

    #[test]
    fn reflection_keeps_outward_normals_outward() {
        let mirror = Transform::scale(Vec3::new(-1.0, 1.0, 1.0)).unwrap().then(&t(Vec3::new(0.0, 0.0, -5.0)));
        let s = Instance::new(Sphere::new(Vec3::new(1.0, 0.0, 0.0), 1.0).unwrap(), mirror);
        // The mirrored sphere is centred at (−1, 0, −5).
        let h = s.intersect(&Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::NEG_Z)).unwrap();
        close(h.t, 4.0, 1e-5);
        close3(h.geo_normal, Vec3::Z, 1e-6);
        assert!(h.front_face);
        let b = Instance::new(Cuboid::new(Vec3::splat(-1.0), Vec3::ONE).unwrap(), mirror);
        let h = b.intersect(&Ray::new(Vec3::new(3.0, 0.0, -5.0), Vec3::NEG_X)).unwrap();
        close3(h.geo_normal, Vec3::X, 1e-6);
        assert!(h.front_face);
    }

    #[test]
    fn uniform_scales_far_from_one_are_invertible() {
        // Their determinants (1e60, 1e-60) are past f32's range; the check
        // and the inverse are made in f64.
        for s in [1e20f32, 1e13, 1e-13, 1e-20] {
            let m = Transform::scale(Vec3::splat(s)).unwrap_or_else(|e| panic!("scale {s}: {e}"));
            let m = m.then(&t(Vec3::new(1.0, 2.0, 3.0) * s));
            let p = Vec3::new(0.5, -0.25, 2.0);
            let back = m.ray_to_object(&Ray::new(m.point(p), Vec3::X)).origin;
            close3(back, p, 1e-5 * p.length());
        }
        // A scale whose inverse is past f32's range is refused as such.
        let tiny = Transform::scale(Vec3::new(1e-39, 1.0, 1.0));
        assert!(matches!(tiny, Err(GeometryError::SingularTransform { .. } | GeometryError::Degenerate(_))));
    }

    #[test]
    fn singular_and_non_finite_matrices_are_rejected() {
        assert!(matches!(
            Transform::scale(Vec3::new(1.0, 0.0, 1.0)),
            Err(GeometryError::SingularTransform { .. })
        ));
        let flat = Transform::shear(Shear { xy: 1.0, yx: 1.0, ..Shear::NONE });
        assert!(matches!(flat, Err(GeometryError::SingularTransform { .. })));
        assert!(matches!(
            Transform::translate(Vec3::new(f32::NAN, 0.0, 0.0)),
            Err(GeometryError::NonFinite(_))
        ));
        let squash = Mat4::from_cols_array(&[
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ]);
        assert!(Transform::try_from_mat4(squash).is_err());
        let projective = Mat4::from_cols_array(&[
            1.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ]);
        assert_eq!(Transform::try_from_mat4(projective), Err(GeometryError::NotAffine));
        // Nearly flat relative to its own scale: two columns almost parallel.
        let nearly = Transform::shear(Shear { xy: 1.0, yx: 0.999_999_9, ..Shear::NONE });
        assert!(matches!(nearly, Err(GeometryError::SingularTransform { .. })));
        // A long shear keeps its determinant of 1; the message says what
        // is wrong with it instead.
        let long = Transform::shear(Shear { xy: 1e8, ..Shear::NONE }).unwrap_err();
        assert_eq!(
            long.to_string(),
            "transform is numerically singular: its axes span 1.00e-8 of the volume their lengths could \
             (more than 1e-6 is needed; determinant 1); it would all but flatten the object"
        );
        assert!(Transform::shear(Shear { xy: 1e5, ..Shear::NONE }).is_ok());
        let zero = Transform::scale(Vec3::new(1.0, 0.0, 1.0)).unwrap_err().to_string();
        assert_eq!(zero, "transform is singular (determinant 0); it would flatten the object");
        // A diagonal scale is exactly invertible, however anisotropic.
        assert!(Transform::scale(Vec3::new(1.0, 1.0, 1e-7)).is_ok());
    }

    #[test]
    fn small_and_large_uniform_scales_are_accepted() {
        for s in [1e-5, 1e-3, 1.0, 1e4] {
            let m = Transform::scale(Vec3::splat(s)).unwrap();
            close3(m.inverse().point(m.point(Vec3::ONE)), Vec3::ONE, 1e-5);
        }
    }

    #[test]
    fn full_matrix_matches_named_constructors() {
        let named = Transform::rotate_z(0.3).then(&t(Vec3::new(1.0, 2.0, 3.0)));
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_rotation_z(0.3);
        let full = Transform::try_from_mat4(m).unwrap();
        close3(full.point(Vec3::new(0.5, -1.0, 2.0)), named.point(Vec3::new(0.5, -1.0, 2.0)), 1e-5);
        close3(full.normal(Vec3::X), named.normal(Vec3::X), 1e-6);
        assert_eq!(Transform::default(), Transform::IDENTITY);
    }

    #[test]
    fn bounds_of_a_rotated_box() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let r = Transform::rotate_y(45f32.to_radians()).aabb(&b);
        let s = 2f32.sqrt();
        close3(r.max, Vec3::new(s, 1.0, s), 1e-5);
        close3(r.min, -Vec3::new(s, 1.0, s), 1e-5);
        assert_eq!(Transform::IDENTITY.aabb(&Aabb::INFINITE), Aabb::INFINITE);
        assert!(Transform::IDENTITY.aabb(&Aabb::EMPTY).is_empty());
    }

    /// Every way of making the identity maps a ray to itself, as the matrix
    /// product would (equal values: the product may only turn `-0.0` into
    /// `+0.0`), and a transform that is not the identity still moves it.
    #[test]
    fn identity_transforms_keep_rays_as_they_are() {
        let mut rand = uniform(0x9e37_79b9_u64);
        let mut f = move || rand() * 100.0;
        let shifted = t(Vec3::new(1.0, -2.0, 3.0));
        let identities = [
            Transform::IDENTITY,
            Transform::default(),
            t(Vec3::ZERO),
            Transform::rotate_x(0.0),
            Transform::scale(Vec3::ONE).unwrap(),
            Transform::shear(Shear::NONE).unwrap(),
            t(Vec3::ZERO).then(&Transform::IDENTITY).inverse(),
        ];
        for m in identities {
            assert!(m.identity, "{m:?}");
            assert!(m.is_identity());
            for k in 0..100 {
                let mut dir = Vec3::new(f(), f(), f());
                dir[k % 3] = if k % 2 == 0 { 0.0 } else { -0.0 };
                let ray = Ray::with_interval(Vec3::new(f(), f(), f()), dir, 0.5, 1e3);
                let got = m.ray_to_object(&ray);
                assert_eq!(got.origin.to_array().map(f32::to_bits), ray.origin.to_array().map(f32::to_bits));
                assert_eq!(got.dir.to_array().map(f32::to_bits), ray.dir.to_array().map(f32::to_bits));
                assert_eq!((got.t_min, got.t_max), (ray.t_min, ray.t_max));
                assert_eq!(got.origin, m.to_object.transform_point3(ray.origin));
                assert_eq!(got.dir, m.to_object.transform_vector3(ray.dir));
            }
        }
        assert!(!shifted.identity && !shifted.inverse().identity);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(shifted.ray_to_object(&ray).origin, Vec3::new(-1.0, 2.0, -3.0));
        assert!(!Transform::rotate_x(1e-3).identity);
        assert!(!Transform::rotate_x(1e-3).is_identity());
    }
}
