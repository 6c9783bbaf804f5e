//! Whitted-style shading for prism: the camera, materials, textures,
//! lights, fog, and the parallel, deterministic renderer.
//!
//! A [`Scene`] is plain data over a [`prism_bvh::Accel`]; [`render`] turns
//! it into a linear-radiance [`Image`].

#![warn(missing_docs)]

mod camera;
mod integrator;
mod material;
pub mod optics;
mod render;
mod scene;
mod texture;

pub use camera::Camera;
pub use integrator::MAX_DEPTH_LIMIT;
pub use material::Material;
pub use render::{Image, RenderHooks, RenderSettings, RenderStats, linear_to_srgb8, render, render_samples};
pub use scene::{Fog, FogMode, PointLight, Scene};
pub use texture::{
    ImageTexture, MAX_TEXTURE_EDGE, MAX_TEXTURE_TEXELS, Mapping, Texture, Wrap, srgb_to_linear,
    srgb8_to_linear,
};

/// Errors from building shading data.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// The camera cannot form a view (e.g. up parallel to the view direction).
    #[error("invalid camera: {0}")]
    Camera(String),
    /// A material parameter is out of range.
    #[error("invalid material: {0}")]
    Material(String),
    /// The scene is inconsistent (e.g. an object without a material, a
    /// light or fog with invalid values).
    #[error("invalid scene: {0}")]
    Scene(String),
    /// A texture could not be read or decoded.
    #[error("cannot load texture {path}: {reason}")]
    Texture {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
}
