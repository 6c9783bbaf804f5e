//! Textures: solid colours, the procedural checker, and images.

use crate::ShadeError;
use prism_geometry::glam::{Vec2, Vec3};
use std::sync::Arc;

/// How a surface point is turned into texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// The shape's own uv (spherical on spheres, as the report's Jupiter;
    /// cylindrical on cylinder and cone sides; planar on planes; the
    /// mesh's uvs on meshes).
    Uv,
    /// Spherical about the object's origin, from the object-space point.
    Spherical,
    /// Cylindrical about the object's Y axis: `u` the angle, `v` the height.
    Cylindrical,
    /// Planar: object-space `(x, z)`.
    Planar,
}

/// What happens outside `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Tile.
    Repeat,
    /// Clamp to the edge.
    Clamp,
}

/// Where a material's colour comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// One linear RGB colour.
    Solid(Vec3),
    /// Two colours in squares of side `size`: in world `(x, z)` when
    /// `world` is true (the chequered floor), else in uv units.
    Checker {
        /// Colour of squares whose index sum is even.
        a: Vec3,
        /// Colour of the other squares.
        b: Vec3,
        /// Edge length of a square.
        size: f32,
        /// World-space (x, z) instead of uv.
        world: bool,
    },
    /// An image.
    Image {
        /// The decoded image.
        image: Arc<ImageTexture>,
        /// How the point becomes uv.
        mapping: Mapping,
        /// uv multiplier (repeat count).
        scale: Vec2,
        /// Tint multiplied in.
        tint: Vec3,
    },
}

impl Texture {
    /// Checks parameters.
    ///
    /// # Errors
    /// [`ShadeError::Material`] for a non-positive checker size or
    /// non-finite colours.
    pub fn validate(&self) -> Result<(), ShadeError> {
        match self {
            Texture::Solid(c) => check_color(*c),
            Texture::Checker { a, b, size, .. } => {
                check_color(*a)?;
                check_color(*b)?;
                if !(size.is_finite() && *size > 0.0) {
                    return Err(ShadeError::Material(format!("checker size must be positive, got {size}")));
                }
                Ok(())
            }
            Texture::Image { scale, tint, .. } => {
                check_color(*tint)?;
                if !scale.is_finite() {
                    return Err(ShadeError::Material("texture scale must be finite".into()));
                }
                Ok(())
            }
        }
    }
}

fn check_color(c: Vec3) -> Result<(), ShadeError> {
    if c.is_finite() && c.min_element() >= 0.0 {
        Ok(())
    } else {
        Err(ShadeError::Material(format!("colours must be finite and >= 0, got {c}")))
    }
}

/// A decoded image in linear RGB, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    wrap: Wrap,
}

impl ImageTexture {
    /// From linear texels, row-major, row 0 at the top.
    ///
    /// # Errors
    /// If the size does not match the data or is zero.
    pub fn from_linear(width: u32, height: u32, texels: Vec<Vec3>, wrap: Wrap) -> Result<Self, ShadeError> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(ShadeError::Material(format!(
                "texture of {width}×{height} needs {} texels, got {}",
                width as usize * height as usize,
                texels.len()
            )));
        }
        Ok(Self { width, height, texels, wrap })
    }

    /// Width in texels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Wrap mode.
    #[must_use]
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The texel at integer coordinates (wrapped or clamped).
    #[must_use]
    pub fn texel(&self, x: i64, y: i64) -> Vec3 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x, y) = match self.wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        self.texels[(y * w + x) as usize]
    }
}
