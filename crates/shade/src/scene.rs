//! A renderable scene: geometry, materials, lights, the fog's medium.
//! Per-render choices (camera, fog on/off, sampling) are not here but in
//! [`crate::RenderSettings`].

use crate::{Environment, Light, Material, ShadeError};
use prism_bvh::{Accel, Object, SceneHit};
use prism_geometry::Intersect;
use prism_geometry::glam::{Affine3A, Vec3};

/// A point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Scale on `color` (no distance fall-off, as the report's light).
    pub intensity: f32,
}

/// How fog thickens with the fog distance `d`.
///
/// For every law but [`FogMode::Linear`], `d` is the length of the ray
/// path. For [`FogMode::Linear`] it is **eye-space depth**: a segment along
/// the camera ray's own line (the camera ray and its unbent continuations
/// through transparent surfaces) counts its length times the cosine to the
/// camera's view axis, so that the point it reaches counts by its depth
/// `z`; a segment in any other direction (a reflection, a bent refraction)
/// counts its full length. A surface seen directly is fogged by its depth,
/// one seen in a mirror by the mirror's depth plus the reflected path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FogMode {
    /// The report's fog: weight `(z − start) / (end − start)`, clamped to
    /// `[0, 1]`, on eye-space depth `z` (see above): a wall facing the
    /// camera is evenly fogged.
    Linear {
        /// Depth where fog begins.
        start: f32,
        /// Depth where fog is total.
        end: f32,
    },
    /// [`FogMode::Linear`]'s law on the length of the ray path instead of
    /// depth (`measure = "distance"`): a wall facing the camera gets more
    /// fog toward its corners.
    LinearDistance {
        /// Distance where fog begins.
        start: f32,
        /// Distance where fog is total.
        end: f32,
    },
    /// Weight `1 − exp(−density · d)`.
    Exponential {
        /// Density per scene unit.
        density: f32,
    },
    /// Weight `1 − exp(−(density · d)²)`.
    ExponentialSquared {
        /// Density per scene unit.
        density: f32,
    },
}

impl FogMode {
    /// The fog weight at distance `d` from the eye, in `[0, 1]` (0: clear,
    /// 1: only fog). `d = +∞` (a ray that hits nothing) gives 1 except for
    /// a zero density. A linear law with `end <= start` is a step at `start`.
    #[must_use]
    pub fn weight(&self, d: f32) -> f32 {
        let w = match *self {
            FogMode::Linear { start, end } | FogMode::LinearDistance { start, end } => {
                if end > start {
                    (d - start) / (end - start)
                } else if d >= start {
                    1.0
                } else {
                    0.0
                }
            }
            FogMode::Exponential { density } => {
                if density > 0.0 {
                    1.0 - (-density * d).exp()
                } else {
                    0.0
                }
            }
            FogMode::ExponentialSquared { density } => {
                if density > 0.0 {
                    let x = density * d;
                    1.0 - (-(x * x)).exp()
                } else {
                    0.0
                }
            }
        };
        if w >= 0.0 { w.min(1.0) } else { 0.0 }
    }

    /// The fraction of a path's radiance that survives the fog over the
    /// segment from path length `a` to path length `b` (`a <= b`), so that
    /// the product over the segments of a path is `1 − weight(total
    /// length)`: `(1 − weight(b)) / (1 − weight(a))`, and `1 − weight(b)`
    /// for the first segment (`a <= 0`). For [`FogMode::Exponential`] this
    /// is `exp(−density · (b − a))`, the segment's own law; for the other
    /// laws it makes a reflected or refracted object as foggy as the length
    /// of the path by which it is seen.
    #[must_use]
    pub fn transmittance(&self, a: f32, b: f32) -> f32 {
        let t = match *self {
            FogMode::Exponential { density } if density > 0.0 => (-density * (b - a.max(0.0))).exp(),
            FogMode::ExponentialSquared { density } if density > 0.0 => {
                let (a, b) = (density * a.max(0.0), density * b);
                (-(b * b - a * a)).exp()
            }
            FogMode::Exponential { .. } | FogMode::ExponentialSquared { .. } => 1.0,
            FogMode::Linear { .. } | FogMode::LinearDistance { .. } => {
                if a > 0.0 {
                    let left = 1.0 - self.weight(a);
                    if left > 0.0 { (1.0 - self.weight(b)) / left } else { 0.0 }
                } else {
                    // The first segment: what is left is 1, and `x / 1` is `x`.
                    1.0 - self.weight(b)
                }
            }
        };
        if t >= 0.0 { t.min(1.0) } else { 0.0 }
    }
}

/// Fog blended toward `color` over every ray segment: a segment from path
/// length `a` to `b` whose far end sends radiance `L` delivers
/// `T · L + (1 − T) · color` with `T = mode.transmittance(a, b)`. For a
/// primary ray this is the report's blend by `weight(d)`; along a path of
/// reflections and refractions the blends compose to `weight` of the whole
/// path length. Rays that hit nothing are at infinite distance (all fog).
///
/// This is the scene's medium; whether a render applies it is the render's
/// choice, [`crate::RenderSettings::fog`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fog {
    /// Linear RGB fog colour.
    pub color: Vec3,
    /// Thickening law.
    pub mode: FogMode,
}

impl Fog {
    /// Whether the fog distance is eye-space depth ([`FogMode::Linear`])
    /// rather than path length.
    #[must_use]
    pub fn by_depth(&self) -> bool {
        matches!(self.mode, FogMode::Linear { .. })
    }

    /// Checks parameters.
    ///
    /// # Errors
    /// [`ShadeError::Scene`] for a non-finite or negative colour, a
    /// negative or non-finite density, or a linear law whose `end` is not
    /// after `start`.
    pub fn validate(&self) -> Result<(), ShadeError> {
        if !(self.color.is_finite() && self.color.min_element() >= 0.0) {
            return Err(ShadeError::Scene(format!("fog colour must be finite and >= 0, got {}", self.color)));
        }
        match self.mode {
            FogMode::Linear { start, end } | FogMode::LinearDistance { start, end } => {
                if !(start.is_finite() && end.is_finite() && end > start) {
                    return Err(ShadeError::Scene(format!(
                        "linear fog needs finite start < end, got start {start}, end {end}"
                    )));
                }
            }
            FogMode::Exponential { density } | FogMode::ExponentialSquared { density } => {
                if !(density.is_finite() && density >= 0.0) {
                    return Err(ShadeError::Scene(format!(
                        "fog density must be a finite number >= 0, got {density}"
                    )));
                }
            }
        }
        Ok(())
    }
}

/// The scene data a render reads: immutable while rendered, shared by
/// every render and view of it (the camera and the other per-render
/// choices are [`crate::RenderSettings`]).
#[derive(Debug)]
pub struct Scene {
    /// The geometry.
    pub accel: Accel,
    /// Material index of each object of `accel`, in the same order.
    pub object_materials: Vec<u32>,
    /// The materials.
    pub materials: Vec<Material>,
    /// The lights (a [`PointLight`] converts with `.into()`).
    pub lights: Vec<Light>,
    /// Ambient light colour (times each material's ambient coefficient).
    pub ambient: Vec3,
    /// Colour of rays that hit nothing (where there is no `environment`).
    pub background: Vec3,
    /// An environment image seen by camera, mirror and glass rays that hit
    /// nothing, in place of `background`; it lights no surface.
    pub environment: Option<Environment>,
    /// The fog's medium, if the scene has one (applied when
    /// [`crate::RenderSettings::fog`] is set).
    pub fog: Option<Fog>,
}

/// Drawn where an object names a material that does not exist (magenta),
/// so that a bad index shows instead of panicking; [`Scene::validate`]
/// reports it.
pub(crate) static MISSING_MATERIAL: Material = Material {
    texture: crate::Texture::Solid(Vec3::new(1.0, 0.0, 1.0)),
    ambient: 0.2,
    diffuse: 0.8,
    specular: 0.0,
    shininess: 1.0,
    specular_color: Vec3::ONE,
    reflectivity: 0.0,
    transparency: 0.0,
    transmission: 0.0,
    ior: 1.0,
    absorption: Vec3::ZERO,
    filter_color: None,
    emission: Vec3::ZERO,
};

impl Scene {
    /// Checks that every object has a material, every material, light and
    /// the fog are valid, and the ambient and background colours are
    /// finite and non-negative. [`crate::render()`] does not need this to
    /// be safe (a missing material is drawn magenta), but a loader should
    /// call it.
    ///
    /// # Errors
    /// [`ShadeError::Material`] for an invalid material, else
    /// [`ShadeError::Scene`] naming the problem.
    pub fn validate(&self) -> Result<(), ShadeError> {
        let n = self.accel.objects().len();
        if self.object_materials.len() != n {
            return Err(ShadeError::Scene(format!(
                "{} objects but {} object material indices",
                n,
                self.object_materials.len()
            )));
        }
        if let Some((i, m)) =
            self.object_materials.iter().enumerate().find(|(_, m)| **m as usize >= self.materials.len())
        {
            return Err(ShadeError::Scene(format!(
                "object {i} uses material {m}, but there are {} materials",
                self.materials.len()
            )));
        }
        for (i, m) in self.materials.iter().enumerate() {
            m.validate().map_err(|e| match e {
                ShadeError::Material(msg) => ShadeError::Material(format!("material {i}: {msg}")),
                other => other,
            })?;
        }
        for (i, l) in self.lights.iter().enumerate() {
            l.validate().map_err(|e| match e {
                ShadeError::Scene(m) => ShadeError::Scene(format!("light {i}: {m}")),
                other => other,
            })?;
        }
        for (name, c) in [("ambient", self.ambient), ("background", self.background)] {
            if !(c.is_finite() && c.min_element() >= 0.0) {
                return Err(ShadeError::Scene(format!("{name} colour must be finite and >= 0, got {c}")));
            }
        }
        if let Some(f) = &self.fog {
            f.validate()?;
        }
        Ok(())
    }

    /// The material of object `object` (magenta if it names none).
    #[inline]
    #[must_use]
    pub fn material_of(&self, object: u32) -> &Material {
        self.object_materials
            .get(object as usize)
            .and_then(|&m| self.materials.get(m as usize))
            .unwrap_or(&MISSING_MATERIAL)
    }

    /// Whether object `object` is a closed solid, so that a ray leaving it
    /// through a back face was inside it: an analytic solid
    /// ([`Object::is_closed`]) or an instance of a mesh found closed
    /// (watertight and consistently oriented) when it was built,
    /// [`prism_geometry::TriangleMesh::is_closed`]. Closed objects are
    /// shaded once where a ray passes through them and dim a shadow once.
    #[inline]
    #[must_use]
    pub fn is_closed(&self, object: u32) -> bool {
        match self.accel.objects().get(object as usize) {
            Some(Object::Mesh { mesh, .. }) => {
                self.accel.meshes().get(*mesh as usize).is_some_and(|m| m.is_closed())
            }
            Some(o) => o.is_closed(),
            None => false,
        }
    }

    /// The world-to-object map of object `object` (identity if none).
    #[inline]
    #[must_use]
    pub fn to_object(&self, object: u32) -> Affine3A {
        match self.accel.objects().get(object as usize) {
            Some(Object::Shape(inst)) => inst.transform.inverse_matrix(),
            Some(Object::Mesh { transform, .. }) => transform.inverse_matrix(),
            None => Affine3A::IDENTITY,
        }
    }

    /// The world-to-texture map of object `object` for `texture`:
    /// [`Scene::to_object`], except under the mappings about a centre.
    /// [`crate::Mapping::Spherical`] measures its direction from the centre
    /// of the object's own bounds (object space), and
    /// [`crate::Mapping::Cylindrical`] its angle about the vertical line
    /// through that centre, with the object's own height (`y` from `min`
    /// to `max`) scaled to `[0, 1]` so that the image covers the object
    /// from bottom to top. So a sphere made with `center = [3, 0, 0]` maps
    /// as one moved there by `translate`: the shape's own centre, not the
    /// world's origin. Unbounded objects (planes) keep their object space.
    #[must_use]
    pub fn texture_to_object(&self, object: u32, texture: &crate::Texture) -> Affine3A {
        let to_object = self.to_object(object);
        let crate::Texture::Image { mapping, .. } = texture else { return to_object };
        if !matches!(mapping, crate::Mapping::Spherical | crate::Mapping::Cylindrical) {
            return to_object;
        }
        let bounds = match self.accel.objects().get(object as usize) {
            Some(Object::Shape(inst)) => inst.shape.bounds(),
            Some(Object::Mesh { mesh, .. }) => match self.accel.meshes().get(*mesh as usize) {
                Some(m) => m.bounds(),
                None => return to_object,
            },
            None => return to_object,
        };
        let centre = (bounds.min + bounds.max) * 0.5;
        if !centre.is_finite() {
            return to_object;
        }
        if *mapping == crate::Mapping::Spherical {
            return Affine3A::from_translation(-centre) * to_object;
        }
        let (lo, height) = (bounds.min.y, bounds.max.y - bounds.min.y);
        if !(lo.is_finite() && height.is_finite() && height > 0.0) {
            return to_object;
        }
        let scale = Affine3A::from_scale(Vec3::new(1.0, 1.0 / height, 1.0))
            * Affine3A::from_translation(Vec3::new(-centre.x, -lo, -centre.z));
        scale * to_object
    }

    /// The surface colour (albedo, linear) at a hit: the material's texture
    /// evaluated there. Also what an albedo AOV shows.
    #[must_use]
    pub fn albedo_at(&self, hit: &SceneHit) -> Vec3 {
        let m = self.material_of(hit.object);
        match &m.texture {
            crate::Texture::Solid(c) => *c,
            t => t.color_at(hit.hit.point, hit.hit.uv, &self.texture_to_object(hit.object, t)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fog_weights_follow_their_laws() {
        let lin = FogMode::Linear { start: 2.0, end: 6.0 };
        assert_eq!(lin.weight(1.0), 0.0);
        assert_eq!(lin.weight(2.0), 0.0);
        assert_eq!(lin.weight(3.0), 0.25);
        assert_eq!(lin.weight(6.0), 1.0);
        assert_eq!(lin.weight(f32::INFINITY), 1.0);
        let e = FogMode::Exponential { density: 0.3 };
        assert!((e.weight(2.0) - (1.0 - (-0.6f32).exp())).abs() < 1e-7);
        assert_eq!(e.weight(f32::INFINITY), 1.0);
        let e2 = FogMode::ExponentialSquared { density: 0.3 };
        assert!((e2.weight(2.0) - (1.0 - (-0.36f32).exp())).abs() < 1e-7);
        assert_eq!(FogMode::Exponential { density: 0.0 }.weight(f32::INFINITY), 0.0);
        assert_eq!(FogMode::Linear { start: 1.0, end: 1.0 }.weight(1.0), 1.0);
        assert!(lin.weight(f32::NAN).is_finite());
    }

    #[test]
    fn segment_transmittances_compose_to_the_whole_path() {
        for mode in [
            FogMode::Linear { start: 2.0, end: 20.0 },
            FogMode::Linear { start: -3.0, end: 20.0 },
            FogMode::Exponential { density: 0.1 },
            FogMode::ExponentialSquared { density: 0.07 },
        ] {
            let cuts = [0.0f32, 1.5, 4.0, 9.0, 13.0];
            let product: f32 = cuts.windows(2).map(|w| mode.transmittance(w[0], w[1])).product();
            assert!((product - (1.0 - mode.weight(13.0))).abs() < 1e-5, "{mode:?}");
            assert_eq!(mode.transmittance(0.0, f32::INFINITY), 0.0);
            assert_eq!(mode.transmittance(5.0, 5.0), 1.0);
        }
        // The distance law is the depth law's formula.
        let (lin, dist) =
            (FogMode::Linear { start: 2.0, end: 6.0 }, FogMode::LinearDistance { start: 2.0, end: 6.0 });
        for d in [0.0, 2.5, 4.0, 7.0] {
            assert_eq!(lin.weight(d), dist.weight(d));
            assert_eq!(lin.transmittance(1.0, d), dist.transmittance(1.0, d));
        }
        // Past the end of linear fog nothing gets through, without 0/0.
        let lin = FogMode::Linear { start: 0.0, end: 1.0 };
        assert_eq!(lin.transmittance(2.0, 3.0), 0.0);
    }

    #[test]
    fn fog_validation() {
        let ok = Fog { color: Vec3::ONE, mode: FogMode::Linear { start: 1.0, end: 2.0 } };
        assert!(ok.validate().is_ok());
        for mode in [
            FogMode::Linear { start: 2.0, end: 2.0 },
            FogMode::Linear { start: f32::NAN, end: 2.0 },
            FogMode::Exponential { density: -1.0 },
            FogMode::ExponentialSquared { density: f32::INFINITY },
        ] {
            assert!(matches!(Fog { mode, ..ok }.validate(), Err(ShadeError::Scene(_))), "{mode:?}");
        }
        assert!(Fog { color: Vec3::NAN, ..ok }.validate().is_err());
    }
}
