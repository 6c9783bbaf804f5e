//! Whitted-style shading for prism: the camera, materials, textures,
//! lights, fog, and the parallel, deterministic renderer.
//!
//! A [`Scene`] is plain data over a [`prism_bvh::Accel`]; [`render`] turns
//! it into a linear-radiance [`Image`].

#![warn(missing_docs)]

mod camera;
mod material;
mod render;
mod scene;
mod texture;

pub use camera::Camera;
pub use material::Material;
pub use render::{Image, RenderHooks, RenderSettings, RenderStats, linear_to_srgb8, render, render_samples};
pub use scene::{Fog, FogMode, PointLight, Scene};
pub use texture::{ImageTexture, Mapping, Texture, Wrap};

/// Errors from building shading data.
#[derive(Debug, thiserror::Error)]
pub enum ShadeError {
    /// The camera cannot form a view (e.g. up parallel to the view direction).
    #[error("invalid camera: {0}")]
    Camera(String),
    /// A material parameter is out of range.
    #[error("invalid material: {0}")]
    Material(String),
    /// A texture could not be read or decoded.
    #[error("cannot load texture {path}: {reason}")]
    Texture {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
}
