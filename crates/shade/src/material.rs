//! Surface materials.

use crate::{ShadeError, Texture};
use prism_geometry::glam::Vec3;

/// A Whitted material. The outgoing radiance at a surface is
///
/// `w_local · local + reflectivity · L_mirror + transparency · f · L_straight + transmission · (F · L_mirror + (1 − F) · f · L_refracted)`
///
/// where `w_local = 1 − reflectivity − transparency − transmission`,
/// `local` is ambient + Lambert diffuse + Phong specular over all lights
/// with shadows, and `F` is the exact Fresnel reflectance of a
/// dielectric with index `ior`. `L_straight` continues the ray unbent (the
/// report's transparent object); `L_refracted` bends it by Snell's law,
/// with total internal reflection past the critical angle and Beer–Lambert
/// `absorption` inside.
///
/// In detail, with `a` the albedo (the texture's colour at the point), `n`
/// the shading normal turned toward the viewer, `v` the unit direction to
/// the viewer, and for each light `l` its unit direction, `E` its
/// `color · intensity` and `S` its shadow transmittance:
///
/// `local = ambient · a · scene.ambient + Σ S · E · (diffuse · a · max(0, n·l) + specular · specular_color · max(0, r·v)^shininess)`
///
/// with `r = 2 (n·l) n − l`; lights with `n·l <= 0` add nothing (and cost
/// no shadow ray). Let `f` be the see-through filter:
/// [`Material::filter_color`] where set, else the albedo `a`, clamped to
/// `[0, 1]` per channel. `S` is the product over the objects on the
/// segment to the light of `(transparency + transmission) · f_occluder`
/// per channel: opaque objects block, transparent ones cast lighter shadows
/// of their filter's colour (their own, unless `filter_color` is set). A closed solid (sphere, cuboid, cylinder, cone)
/// counts once, where the segment enters it (where it leaves it, for a
/// point inside); open surfaces (planes, disks,
/// triangles, mesh faces) count at every crossing. An absorbing
/// dielectric also darkens them by Beer–Lambert over the segment's length
/// inside it, as it darkens the view through it.
///
/// `L_mirror` reflects the ray about `n`; `L_straight` continues it from
/// the far side of a closed solid (its exit is not shaded); the dielectric
/// enters when the ray meets the outer side (`Hit::front_face`, ratio
/// `n_around / ior`) and leaves otherwise (ratio `ior / n_around`), where
/// `n_around` is the `ior` of the closed dielectric around the object along
/// the ray's path, 1 outside all of them (nested dielectrics: see
/// `media.rs`). Every segment a ray travels inside a closed absorbing
/// dielectric, unbent, refracted or reflected, whatever it ends on, is
/// multiplied by `exp(−absorption · length)` of the innermost one there;
/// open surfaces (planes, disks, triangles, open meshes) have no inside and
/// absorb nothing. `L_straight` and `L_refracted` are multiplied by `f`
/// as a shadow ray's light is, the same both ways: at every crossing of
/// an open surface, and once per closed solid, by the ray that goes through
/// its surface (a shading normal can keep a refracted ray on this side, or
/// send a reflected one through: `L_mirror` then carries `f`), where the
/// ray enters it, or
/// leaves it for a camera inside a dielectric one; a camera inside a
/// closed solid with only `transparency` sees out untinted). `filter_color
/// = [1, 1, 1]` makes clear
/// glass of any colour (POV-Ray's `transmit` rather than `filter`);
/// `absorption` darkens with thickness.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Surface colour (albedo), linear RGB.
    pub texture: Texture,
    /// Ambient coefficient (times the scene's ambient light and the albedo).
    pub ambient: f32,
    /// Lambert diffuse coefficient.
    pub diffuse: f32,
    /// Phong specular coefficient.
    pub specular: f32,
    /// Phong exponent.
    pub shininess: f32,
    /// Colour of highlights (white for plastics, the albedo for metals).
    pub specular_color: Vec3,
    /// Mirror reflection weight in `[0, 1]`.
    pub reflectivity: f32,
    /// Unbent see-through weight in `[0, 1]` (the report's transparency).
    pub transparency: f32,
    /// Refractive (dielectric) weight in `[0, 1]`.
    pub transmission: f32,
    /// Index of refraction of the inside (outside: that of the dielectric
    /// around the object, 1 if none).
    pub ior: f32,
    /// Beer–Lambert absorption coefficient per scene unit inside the
    /// object, per channel (zero: clear).
    pub absorption: Vec3,
    /// The colour what passes through is multiplied by (the view through
    /// the surface and the light of shadow rays through it), linear RGB in
    /// `[0, 1]`; `None`: the surface colour at the point (the albedo). OBJ
    /// `Tf`.
    pub filter_color: Option<Vec3>,
    /// Light the surface gives off itself (OBJ `Ke`), linear RGB, added to
    /// its outgoing radiance: seen by camera rays and in reflections, but it
    /// lights no other surface.
    pub emission: Vec3,
}

impl Material {
    /// A plain diffuse material of `color` with a modest highlight.
    #[must_use]
    pub fn diffuse(color: Vec3) -> Self {
        Self {
            texture: Texture::Solid(color),
            ambient: 0.1,
            diffuse: 0.9,
            specular: 0.0,
            shininess: 32.0,
            specular_color: Vec3::ONE,
            reflectivity: 0.0,
            transparency: 0.0,
            transmission: 0.0,
            ior: 1.5,
            absorption: Vec3::ZERO,
            filter_color: None,
            emission: Vec3::ZERO,
        }
    }

    /// Weight of the local (Phong) term.
    #[must_use]
    pub fn local_weight(&self) -> f32 {
        (1.0 - self.reflectivity - self.transparency - self.transmission).max(0.0)
    }

    /// Whether light passes through (transparent or refractive).
    #[must_use]
    pub fn is_see_through(&self) -> bool {
        self.transparency > 0.0 || self.transmission > 0.0
    }

    /// Checks ranges.
    ///
    /// # Errors
    /// [`ShadeError::Material`] naming the offending parameter.
    pub fn validate(&self) -> Result<(), ShadeError> {
        let unit = [
            ("reflectivity", self.reflectivity),
            ("transparency", self.transparency),
            ("transmission", self.transmission),
        ];
        for (name, v) in unit {
            if !(0.0..=1.0).contains(&v) {
                return Err(ShadeError::Material(format!("{name} must be in [0, 1], got {v}")));
            }
        }
        let sum = self.reflectivity + self.transparency + self.transmission;
        if sum > 1.0 + 1e-6 {
            return Err(ShadeError::Material(format!(
                "reflectivity + transparency + transmission must not exceed 1, got {sum}"
            )));
        }
        for (name, v) in [
            ("ambient", self.ambient),
            ("diffuse", self.diffuse),
            ("specular", self.specular),
            ("shininess", self.shininess),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ShadeError::Material(format!("{name} must be a finite number >= 0, got {v}")));
            }
        }
        if !(self.ior.is_finite() && self.ior > 0.0) {
            return Err(ShadeError::Material(format!("ior must be a finite number > 0, got {}", self.ior)));
        }
        if let Some(f) = self.filter_color
            && !(f.is_finite() && f.min_element() >= 0.0 && f.max_element() <= 1.0)
        {
            return Err(ShadeError::Material(format!(
                "filter_color must be in [0, 1] per component, got {f}"
            )));
        }
        if !(self.absorption.is_finite() && self.absorption.min_element() >= 0.0) {
            return Err(ShadeError::Material("absorption must be finite and >= 0".into()));
        }
        if !(self.emission.is_finite() && self.emission.min_element() >= 0.0) {
            return Err(ShadeError::Material("emission must be finite and >= 0".into()));
        }
        if !(self.specular_color.is_finite() && self.specular_color.min_element() >= 0.0) {
            return Err(ShadeError::Material("specular_color must be finite and >= 0".into()));
        }
        self.texture.validate()
    }
}
