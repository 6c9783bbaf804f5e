//! Whitted-style shading for prism: the camera, materials, textures,
//! lights, fog, and the parallel, deterministic renderer.
//!
//! A [`Scene`] is plain, immutable data over a [`prism_bvh::Accel`];
//! [`render()`] turns it into a linear-radiance [`Image`] as the per-render
//! [`RenderSettings`] say (camera, fog on/off, samples, depth, threads). The shading model is documented on
//! [`Material`], fog on [`Fog`], sampling on [`render()`] (a 1-spp
//! render samples pixel centres exactly; more samples are stratified and
//! the same for any number of threads).
//!
//! Geometric passes (depth, normals, albedo, object ids) come from
//! [`render_aovs`] or, with the beauty in the same pass over the pixels,
//! [`render_with_aovs`]; [`write_image_exr`], [`write_aov_files`] and
//! [`write_aov_preview_png`] write them as float OpenEXR files and PNG
//! previews (see `docs/aov.md`).
//!
//! # Example
//!
//! A red Lambert sphere under one light, one pixel, looked at head-on:
//!
//! ```
//! use prism_bvh::{Accel, Object};
//! use prism_geometry::glam::Vec3;
//! use prism_geometry::{Instance, Sphere, Transform};
//! use prism_shade::{Camera, Material, PointLight, RenderHooks, RenderSettings, Scene};
//!
//! let sphere = Instance::new(Sphere::new(Vec3::ZERO, 1.0)?.into(), Transform::IDENTITY);
//! let scene = Scene {
//!     accel: Accel::build(Vec::new(), vec![Object::Shape(sphere)])?,
//!     object_materials: vec![0],
//!     materials: vec![Material { ambient: 0.1, diffuse: 0.9, ..Material::diffuse(Vec3::X) }],
//!     lights: vec![PointLight { position: Vec3::new(0.0, 0.0, 10.0), color: Vec3::ONE, intensity: 1.0 }.into()],
//!     ambient: Vec3::ONE,
//!     background: Vec3::ZERO,
//!     environment: None,
//!     fog: None,
//! };
//! scene.validate()?;
//! let settings = RenderSettings {
//!     camera: Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 10.0, 1, 1)?,
//!     fog: false,
//!     spp: 1,
//!     max_depth: 4,
//!     min_contribution: 1e-3,
//!     threads: None,
//!     antialias: Default::default(),
//! };
//! let (image, stats) = prism_shade::render(&scene, &settings, RenderHooks::default());
//! // The light is straight behind the eye: ambient 0.1 + Lambert 0.9 · cos 0.
//! assert!((image.pixels[0] - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-5);
//! assert_eq!(stats.rays, 2); // the camera ray and one shadow ray
//! assert_eq!((stats.camera_rays, stats.shadow_rays, stats.secondary_rays()), (1, 1, 0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod aov;
mod bounds;
mod camera;
mod environment;
mod exr;
mod filter;
mod footprint;
mod integrator;
mod layers;
mod light;
mod material;
mod media;
mod mipmap;
mod names;
pub mod optics;
mod output;
mod render;
mod scene;
mod texture;
mod tonemap;

pub use aov::{
    AlphaImage, Aov, AovImage, AovImages, AovParseError, render_aovs, render_with_alpha, render_with_aovs,
};
pub use bounds::{BoundsError, PixelBounds};
pub use camera::{Camera, Projection};
pub use environment::Environment;
pub use exr::{
    ExrAttribute, ExrChannel, ExrLayer, ExrSamples, LayeredExr, read_layered_exr, write_layered_exr,
};
pub use filter::{ADAPTIVE_BASE_SAMPLES, Antialias, FilterParseError, FilterSampler, PixelFilter};
pub use footprint::Footprint;
pub use integrator::MAX_DEPTH_LIMIT;
pub use layers::{
    NO_ID, RenderExr, aov_exr_channels, read_render_exr, render_from_exr, render_layers, write_render_exr,
};
pub use light::{AreaLight, AreaShape, Falloff, Light, LightKind, spot_weight};
pub use material::Material;
pub use names::{closest, did_you_mean};
pub use output::{
    OutputError, OutputFormat, OutputTarget, UnfinishedHold, all_or_nothing, aov_path, aov_preview_rgb8,
    names_a_directory, output_target, read_exr_rgb, stop_unfinished_outputs, write_aov_exr, write_aov_files,
    write_aov_preview_png, write_bytes_atomic, write_exr_rgb, write_image, write_image_exr, write_png,
    write_png_rgb8,
};
pub use render::{
    Image, PACKET_MODES, RenderHooks, RenderSettings, RenderStats, in_pool, linear_to_srgb8, render,
    render_region, render_samples, sample_position,
};
pub use scene::{Fog, FogMode, PointLight, Scene};
pub use texture::{
    ImageTexture, MAX_TEXTURE_EDGE, MAX_TEXTURE_TEXELS, Mapping, Texture, TextureCost, Wrap, srgb_to_linear,
    srgb8_to_linear,
};
pub use tonemap::{BitDepth, PngOptions, Tonemap, TonemapParseError, linear_to_srgb};

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
