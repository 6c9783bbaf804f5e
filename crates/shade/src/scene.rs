//! A renderable scene: geometry, materials, lights, camera, fog.

use crate::{Camera, Material};
use prism_bvh::Accel;
use prism_geometry::glam::Vec3;

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

/// How fog thickens with distance `d` along each ray segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FogMode {
    /// The report's fog: weight `(d − start) / (end − start)`, clamped to `[0, 1]`.
    Linear {
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

/// Fog blended toward `color` over every ray segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fog {
    /// Linear RGB fog colour.
    pub color: Vec3,
    /// Thickening law.
    pub mode: FogMode,
    /// Whether the fog is applied (toggled by `--fog`/`--no-fog` and keys).
    pub enabled: bool,
}

/// Everything the renderer needs.
#[derive(Debug)]
pub struct Scene {
    /// The geometry.
    pub accel: Accel,
    /// Material index of each object of `accel`, in the same order.
    pub object_materials: Vec<u32>,
    /// The materials.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<PointLight>,
    /// Ambient light colour (times each material's ambient coefficient).
    pub ambient: Vec3,
    /// Colour of rays that hit nothing.
    pub background: Vec3,
    /// Fog, if the scene has one.
    pub fog: Option<Fog>,
    /// The camera.
    pub camera: Camera,
}
