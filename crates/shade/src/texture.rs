//! Textures: solid colours, the procedural checker, and images.

use crate::ShadeError;
use crate::footprint::{Footprint, smaller};
use crate::mipmap::{Level, build_pyramid, checker_odd_weight, lod, trilinear};
use prism_geometry::glam::{Affine3A, Vec2, Vec3};
use prism_geometry::{azimuth_u, sphere_uv};
use std::path::Path;
use std::sync::Arc;

/// Largest accepted image edge in texels (refused before decoding).
pub const MAX_TEXTURE_EDGE: u32 = 16_384;
/// Largest accepted number of texels (`64 Mi`, 768 MiB of linear RGB).
pub const MAX_TEXTURE_TEXELS: u64 = 64 * 1024 * 1024;

/// How a surface point is turned into texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// The shape's own uv (spherical on spheres, as the report's Jupiter;
    /// cylindrical on cylinder and cone sides; planar on planes; the
    /// mesh's uvs on meshes).
    Uv,
    /// Spherical, from the point `p` relative to the object's centre (the
    /// centre of its object-space bounds, [`crate::Scene::texture_to_object`]):
    /// [`prism_geometry::sphere_uv`] of `d = p / |p|`, `u = 0.5 +
    /// atan2(d.x, d.z) / 2π` (0.5 at +Z, growing toward +X), `v = 0.5 −
    /// asin(d.y) / π` (the report's equation 8).
    Spherical,
    /// Cylindrical about the vertical line through the object's centre: `u` =
    /// [`prism_geometry::azimuth_u`] of `p` (the angle: 0.5 at +Z, growing
    /// toward +X, seam at −Z, as on spheres), `v = 1 − p.y` (the height, so
    /// that the image stands upright). The renderer passes a point whose
    /// `y` is scaled so that the object's own height spans `[0, 1]`
    /// ([`crate::Scene::texture_to_object`]): the image covers the object
    /// from bottom to top.
    Cylindrical,
    /// Planar: `(u, v) = (p.x, p.z)` of the object-space point.
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
        /// Added after the scale: the image is read at `uv * scale +
        /// offset` (an MTL map's `-s` and `-o`; a texture's `scale` and
        /// `offset` in the scene file).
        offset: Vec2,
        /// Tint multiplied in.
        tint: Vec3,
    },
}

impl Mapping {
    /// Texture coordinates of a hit under this mapping: `uv` is the shape's
    /// own uv (used by [`Mapping::Uv`]), `object_point` the hit point in the
    /// object's own space (used by the others).
    #[inline]
    #[must_use]
    pub fn uv(self, uv: Vec2, object_point: Vec3) -> Vec2 {
        let p = object_point;
        match self {
            Mapping::Uv => uv,
            Mapping::Spherical => sphere_uv(p.normalize_or(Vec3::Y)),
            Mapping::Cylindrical => Vec2::new(azimuth_u(p), 1.0 - p.y),
            Mapping::Planar => Vec2::new(p.x, p.z),
        }
    }
}

impl Texture {
    /// The linear colour at a surface point: `point` in world space, `uv`
    /// the shape's own uv, `to_object` the world-to-object map of the
    /// object hit (for the object-space mappings). Never NaN for finite
    /// inputs.
    #[inline]
    #[must_use]
    pub fn color_at(&self, point: Vec3, uv: Vec2, to_object: &Affine3A) -> Vec3 {
        self.color_over(point, uv, to_object, &Footprint::POINT)
    }

    /// The linear colour averaged over the footprint `fp` around a surface
    /// point (arguments as [`Texture::color_at`], which is this with
    /// [`Footprint::POINT`]). The checker is box-filtered exactly over the
    /// footprint's extent along its two axes (world x and z, or u and v);
    /// images are looked up trilinearly in their mip-map at the level of
    /// the footprint's longer axis in texels. Object-space mappings get
    /// their uv footprint by mapping the footprint's axes; [`Mapping::Uv`]
    /// takes `fp.duv`.
    #[must_use]
    pub fn color_over(&self, point: Vec3, uv: Vec2, to_object: &Affine3A, fp: &Footprint) -> Vec3 {
        match self {
            Texture::Solid(c) => *c,
            Texture::Checker { a, b, size, world } => {
                let ([x, y], axes) = if *world {
                    ([point.x, point.z], fp.dp.map(|d| Vec2::new(d.x, d.z)))
                } else {
                    ([uv.x, uv.y], fp.duv)
                };
                let w = axes[0].abs().max(axes[1].abs()) / *size;
                let t = checker_odd_weight(x / size, y / size, w.x, w.y);
                if t <= 0.0 {
                    *a
                } else if t >= 1.0 {
                    *b
                } else {
                    *a * (1.0 - t) + *b * t
                }
            }
            Texture::Image { image, mapping, scale, offset, tint } => {
                let (uv, duv) = match mapping {
                    Mapping::Uv => (uv, fp.duv),
                    _ => {
                        let p = to_object.transform_point3(point);
                        let at = mapping.uv(uv, p);
                        let duv = fp.dp.map(|d| {
                            let e = to_object.transform_vector3(d);
                            if e == Vec3::ZERO {
                                return Vec2::ZERO;
                            }
                            smaller(Some(mapping.uv(uv, p + e) - at), Some(at - mapping.uv(uv, p - e)))
                        });
                        (at, duv)
                    }
                };
                image.sample_over(uv * *scale + *offset, duv.map(|d| d * *scale)) * *tint
            }
        }
    }

    /// Whether [`Texture::color_over`] reads `Footprint::duv` (a checker in
    /// uv, an image under [`Mapping::Uv`]), so that a caller computes it
    /// only then.
    #[must_use]
    pub fn needs_uv_footprint(&self) -> bool {
        match self {
            Texture::Checker { world, .. } => !world,
            Texture::Image { mapping, .. } => *mapping == Mapping::Uv,
            Texture::Solid(_) => false,
        }
    }

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
            Texture::Image { scale, offset, tint, .. } => {
                check_color(*tint)?;
                if !scale.is_finite() {
                    return Err(ShadeError::Material("texture scale must be finite".into()));
                }
                if !offset.is_finite() {
                    return Err(ShadeError::Material("texture offset must be finite".into()));
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

/// A decoded image in linear RGB, row 0 at the top, with its mip-map
/// (built once, when the texture is made).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    base: Level,
    /// Levels 1 onwards, each half the size of the one before.
    mips: Vec<Level>,
    wrap: Wrap,
    /// The file had texels that were not opaque (their alpha is ignored).
    translucent: bool,
    /// Texels of a floating-point file (EXR, HDR) with a negative,
    /// infinite or NaN channel, read as 0 there.
    unusable: u64,
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
        let base = Level { width, height, texels };
        let mips = build_pyramid(&base, wrap);
        Ok(Self { base, mips, wrap, translucent: false, unusable: 0 })
    }

    /// Loads a PNG, JPEG, BMP, EXR or Radiance HDR file (the format is guessed from the
    /// content, not the extension) and converts it to linear RGB: 8- and
    /// 16-bit images are taken to be sRGB-encoded and decoded with the sRGB
    /// EOTF ([`srgb_to_linear`]); floating-point images (EXR, HDR) are taken as
    /// already linear. Alpha is ignored ([`ImageTexture::had_alpha`] says
    /// whether it mattered); grey images become grey RGB. An
    /// Exif orientation (JPEG, PNG) is applied, so that the texture is the
    /// image as a viewer shows it.
    ///
    /// Images wider or taller than [`MAX_TEXTURE_EDGE`] or with more than
    /// [`MAX_TEXTURE_TEXELS`] texels are refused before their pixels are
    /// decoded.
    ///
    /// # Errors
    /// [`ShadeError::Texture`] naming `path` if the file cannot be opened,
    /// is not a supported image, is corrupt, or is too large.
    pub fn load(path: &Path, wrap: Wrap) -> Result<Self, ShadeError> {
        Self::load_checked(path, wrap, |_| Ok(()))
    }

    /// [`ImageTexture::load`], asking `check` first, with the image's size
    /// read from its header and before its pixels are decoded, whether the
    /// memory it takes ([`TextureCost`]) may be spent; its `Err` is the
    /// reason the texture is refused.
    ///
    /// # Errors
    /// As [`ImageTexture::load`], and where `check` refuses.
    pub fn load_checked(
        path: &Path,
        wrap: Wrap,
        check: impl FnOnce(&TextureCost) -> Result<(), String>,
    ) -> Result<Self, ShadeError> {
        let err = |reason: String| ShadeError::Texture { path: path.to_path_buf(), reason };
        let mut reader = image::ImageReader::open(path)
            .map_err(|e| err(e.to_string()))?
            .with_guessed_format()
            .map_err(|e| err(e.to_string()))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_TEXTURE_EDGE);
        limits.max_image_height = Some(MAX_TEXTURE_EDGE);
        limits.max_alloc = Some(1024 * 1024 * 1024);
        reader.limits(limits);
        let Some(format) = reader.format() else {
            return Err(err(
                "not a recognised image format (PNG, JPEG, BMP, EXR or Radiance HDR expected)".into()
            ));
        };
        let decoding = |e: image::ImageError| {
            let name = format.extensions_str().first().map_or("image".to_owned(), |x| x.to_uppercase());
            err(match &e {
                // Plain words first; the decoder's own after them.
                // (Some decoders end their text in a line break.)
                image::ImageError::Decoding(_) => match exr_channels_without_rgb(path, format) {
                    Some(names) => format!(
                        "the EXR image has no R, G and B channels (its channels: {names}); prism reads RGB or RGBA EXR images"
                    ),
                    None => format!("the {name} data is corrupt or cut short ({})", e.to_string().trim_end()),
                },
                image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
                    format!("the {name} data is cut short: the file ends before the image does")
                }
                // The image's size, read from its header alone.
                image::ImageError::Limits(_) => match image::ImageReader::open(path)
                    .and_then(image::ImageReader::with_guessed_format)
                    .map_err(image::ImageError::IoError)
                    .and_then(|mut r| {
                        // Nothing is decoded here; the header's size may be
                        // beyond any limit (2³¹ × 2¹⁴).
                        r.no_limits();
                        r.into_dimensions()
                    }) {
                    Ok((w, h)) if w.max(h) > MAX_TEXTURE_EDGE => {
                        format!("{w}×{h} texels is more than the {MAX_TEXTURE_EDGE} allowed per side")
                    }
                    Ok((w, h)) => format!("{w}×{h} texels need more memory to decode than the 1 GiB allowed"),
                    // PNG allows sides up to 2³¹ − 1.
                    Err(_) => format!(
                        "its size cannot be read from its header ({e}); prism reads textures of up to {MAX_TEXTURE_EDGE} texels per side"
                    ),
                },
                _ => e.to_string(),
            })
        };
        let mut decoder = reader.into_decoder().map_err(decoding)?;
        // The Exif orientation (phone photos are stored sideways with one):
        // the texture is the image as a viewer shows it.
        let orientation = image::ImageDecoder::orientation(&mut decoder).map_err(decoding)?;
        let (width, height) = image::ImageDecoder::dimensions(&decoder);
        if u64::from(width) * u64::from(height) > MAX_TEXTURE_TEXELS {
            return Err(err(format!(
                "{width}×{height} texels is more than the {MAX_TEXTURE_TEXELS} allowed"
            )));
        }
        let cost = TextureCost::new(width, height, image::ImageDecoder::total_bytes(&decoder));
        check(&cost).map_err(err)?;
        let mut decoded = image::DynamicImage::from_decoder(decoder).map_err(decoding)?;
        decoded.apply_orientation(orientation);
        let (width, height) = (decoded.width(), decoded.height());
        let (texels, unusable) = linear_texels(&decoded).map_err(|e| err(e.to_string()))?;
        let translucent = has_translucent_texels(&decoded);
        drop(decoded);
        let t = Self::from_linear(width, height, texels, wrap).map_err(|e| err(e.to_string()))?;
        Ok(Self { translucent, unusable, ..t })
    }

    /// The bilinearly filtered colour at texture coordinates `uv`: `u` runs
    /// left to right over the width, `v` top to bottom over the height (so
    /// `v = 0` is the top row), texel `(i, j)` centred on
    /// `((i + ½) / width, (j + ½) / height)`; outside `[0, 1]` the image is
    /// tiled or clamped by its [`Wrap`]. Non-finite coordinates read as 0.
    #[inline]
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        self.base.bilinear(uv, self.wrap)
    }

    /// The colour averaged over a footprint whose two axes in uv are
    /// `duv`: trilinear in the mip-map, at `log2` of the longer axis in
    /// texels (level 0, plain [`ImageTexture::sample`], for a footprint of
    /// a texel or less).
    #[must_use]
    pub fn sample_over(&self, uv: Vec2, duv: [Vec2; 2]) -> Vec3 {
        trilinear(&self.base, &self.mips, self.wrap, uv, lod(self.base.width, self.base.height, duv))
    }

    /// Whether the file had texels that were not fully opaque: their
    /// alpha is ignored (a texture is a colour; cut-outs need geometry or
    /// a material's `transparency`), which a scene loader warns about.
    #[must_use]
    pub fn had_alpha(&self) -> bool {
        self.translucent
    }

    /// How many texels of a floating-point file (EXR, HDR) had a channel
    /// that was negative, infinite or NaN: such a channel reads as 0 (a
    /// NaN or infinity would poison every pixel that filters it), which a
    /// scene loader warns about.
    #[must_use]
    pub fn unusable_texels(&self) -> u64 {
        self.unusable
    }

    /// Number of mip-map levels, the full-resolution image included.
    #[must_use]
    pub fn levels(&self) -> usize {
        self.mips.len() + 1
    }

    /// Width in texels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.base.width
    }

    /// Height in texels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.base.height
    }

    /// Wrap mode.
    #[must_use]
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The texel at integer coordinates (wrapped or clamped).
    #[must_use]
    pub fn texel(&self, x: i64, y: i64) -> Vec3 {
        self.base.texel(x, y, self.wrap)
    }
}

/// The sRGB electro-optical transfer function: an sRGB-encoded value in
/// `[0, 1]` to linear (inputs are clamped to `[0, 1]`; NaN reads as 0).
#[must_use]
pub fn srgb_to_linear(s: f32) -> f32 {
    let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
    if s <= 0.040_45 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) }
}

/// An 8-bit sRGB value to linear: [`srgb_to_linear`] of `b / 255`.
#[must_use]
pub fn srgb8_to_linear(b: u8) -> f32 {
    srgb_to_linear(f32::from(b) / 255.0)
}

fn srgb8_lut() -> [f32; 256] {
    std::array::from_fn(|i| srgb8_to_linear(i as u8))
}

/// The memory loading an image takes ([`ImageTexture::load_checked`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureCost {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Bytes held at once while it loads: the decoded file and the linear
    /// texels made from it, or the texels and their mip-map.
    pub peak: u64,
    /// Bytes the texture keeps: its linear texels and mip-map.
    pub kept: u64,
}

impl TextureCost {
    /// The cost of an image of `width × height` texels whose decoded pixels
    /// take `decoded` bytes.
    #[must_use]
    pub fn new(width: u32, height: u32, decoded: u64) -> Self {
        let texels = u64::from(width) * u64::from(height) * std::mem::size_of::<Vec3>() as u64;
        // The levels after the first: a third of it at most.
        let mips = texels / 3 + 64;
        Self { width, height, peak: texels + decoded.max(mips), kept: texels + mips }
    }
}

/// The channel names of an EXR file none of whose layers has R, G and B
/// channels (a luminance `Y` image, a depth pass), which the decoder
/// refuses with "does not contain non-deep rgb channels": the file is not
/// corrupt, and its channels say what it is. `None` for other formats and
/// for EXR files with RGB layers or unreadable headers.
fn exr_channels_without_rgb(path: &Path, format: image::ImageFormat) -> Option<String> {
    if format != image::ImageFormat::OpenExr {
        return None;
    }
    let meta = ::exr::meta::MetaData::read_from_file(path, false).ok()?;
    let mut names = Vec::new();
    for header in &meta.headers {
        let layer: Vec<String> = header.channels.list.iter().map(|c| c.name.to_string()).collect();
        if ["R", "G", "B"].iter().all(|rgb| layer.iter().any(|n| n == rgb)) {
            return None;
        }
        names.extend(layer);
    }
    Some(if names.is_empty() { "none".to_owned() } else { names.join(", ") })
}

/// The decoded image's texels in linear RGB, converted straight from its
/// own pixels (no full-size copy in between): 8- and 16-bit channels
/// through the sRGB EOTF, floats taken as linear (non-finite or negative
/// ones as 0). The buffer is reserved fallibly, so a texture too large for
/// the memory left is an error, not an abort.
/// The texels in linear RGB, and how many float texels had a channel that
/// was negative, infinite or NaN (read as 0).
fn linear_texels(
    decoded: &image::DynamicImage,
) -> Result<(Vec<Vec3>, u64), std::collections::TryReserveError> {
    use image::DynamicImage as D;
    let mut texels = Vec::new();
    texels.try_reserve_exact(decoded.width() as usize * decoded.height() as usize)?;
    let lut8 = srgb8_lut();
    let s8 = |c: &[u8]| Vec3::new(lut8[c[0] as usize], lut8[c[1] as usize], lut8[c[2] as usize]);
    let s16 = |c: [u16; 3]| Vec3::from_array(c.map(|v| srgb_to_linear(f32::from(v) / 65535.0)));
    // Non-finite or negative texels would poison every pixel that sees them.
    let mut unusable = 0u64;
    let mut float = |c: Vec3| {
        if c.cmpge(Vec3::ZERO).all() && c.is_finite() {
            c
        } else {
            unusable += 1;
            Vec3::select(c.cmpge(Vec3::ZERO) & c.is_finite_mask(), c, Vec3::ZERO)
        }
    };
    match decoded {
        D::ImageLuma8(b) => texels.extend(b.pixels().map(|p| s8(&[p.0[0]; 3]))),
        D::ImageLumaA8(b) => texels.extend(b.pixels().map(|p| s8(&[p.0[0]; 3]))),
        D::ImageRgb8(b) => texels.extend(b.pixels().map(|p| s8(&p.0))),
        D::ImageRgba8(b) => texels.extend(b.pixels().map(|p| s8(&p.0))),
        D::ImageLuma16(b) => texels.extend(b.pixels().map(|p| s16([p.0[0]; 3]))),
        D::ImageLumaA16(b) => texels.extend(b.pixels().map(|p| s16([p.0[0]; 3]))),
        D::ImageRgb16(b) => texels.extend(b.pixels().map(|p| s16(p.0))),
        D::ImageRgba16(b) => texels.extend(b.pixels().map(|p| s16([p.0[0], p.0[1], p.0[2]]))),
        D::ImageRgb32F(b) => texels.extend(b.pixels().map(|p| float(Vec3::from_array(p.0)))),
        D::ImageRgba32F(b) => texels.extend(b.pixels().map(|p| float(Vec3::new(p.0[0], p.0[1], p.0[2])))),
        // Any other layout a later `image` adds: through its own conversion.
        other => texels.extend(other.to_rgb32f().pixels().map(|p| Vec3::from_array(p.0.map(srgb_to_linear)))),
    }
    Ok((texels, unusable))
}

/// Whether `decoded` has an alpha channel with any texel below opaque.
fn has_translucent_texels(decoded: &image::DynamicImage) -> bool {
    use image::DynamicImage as D;
    match decoded {
        D::ImageLumaA8(b) => b.pixels().any(|p| p.0[1] < u8::MAX),
        D::ImageRgba8(b) => b.pixels().any(|p| p.0[3] < u8::MAX),
        D::ImageLumaA16(b) => b.pixels().any(|p| p.0[1] < u16::MAX),
        D::ImageRgba16(b) => b.pixels().any(|p| p.0[3] < u16::MAX),
        D::ImageRgba32F(b) => b.pixels().any(|p| p.0[3] < 1.0),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pixel_layout_converts_as_images_own_conversion_does() {
        // The direct conversion against `image`'s conversion to float RGB
        // and the sRGB EOTF (linear floats kept): each of the ten layouts.
        use image::DynamicImage as D;
        let rgba8 =
            image::RgbaImage::from_fn(7, 5, |x, y| image::Rgba([(x * 37) as u8, (y * 51) as u8, 200, 9]));
        let base = D::ImageRgba8(rgba8);
        let layouts = [
            base.to_luma8().into(),
            base.to_luma_alpha8().into(),
            base.to_rgb8().into(),
            base.clone(),
            base.to_luma16().into(),
            base.to_luma_alpha16().into(),
            base.to_rgb16().into(),
            base.to_rgba16().into(),
            base.to_rgb32f().into(),
            base.to_rgba32f().into(),
        ];
        for d in layouts {
            let float = matches!(d, D::ImageRgb32F(_) | D::ImageRgba32F(_));
            let want: Vec<Vec3> = d
                .to_rgb32f()
                .pixels()
                .map(|p| Vec3::from_array(if float { p.0 } else { p.0.map(srgb_to_linear) }))
                .collect();
            let (got, unusable) = linear_texels(&d).unwrap();
            assert_eq!(unusable, 0);
            assert_eq!(got.len(), want.len());
            for (g, w) in got.iter().zip(&want) {
                assert!((*g - *w).abs().max_element() <= 1e-6, "{:?}: {g} against {w}", d.color());
            }
        }
    }

    /// An Exif block (big-endian TIFF) holding the orientation tag alone.
    fn exif_orientation(value: u16) -> Vec<u8> {
        let mut e = b"MM\0\x2a\0\0\0\x08\0\x01".to_vec();
        e.extend_from_slice(&[0x01, 0x12, 0, 3, 0, 0, 0, 1]); // tag 0x0112, SHORT, one
        e.extend_from_slice(&value.to_be_bytes());
        e.extend_from_slice(&[0, 0, 0, 0, 0, 0]); // padding; no next IFD
        e
    }

    #[test]
    fn an_exif_orientation_is_applied_as_a_viewer_does() {
        // Stored 16×8, red left and blue right, with "turn 90° clockwise to
        // show" (6): shown 8×16, red on top. Also "mirror left to right" (2).
        use image::ImageEncoder as _;
        let stored = image::RgbImage::from_fn(16, 8, |x, _| {
            if x < 8 { image::Rgb([255, 0, 0]) } else { image::Rgb([0, 0, 255]) }
        });
        let red = Vec3::new(1.0, 0.0, 0.0);
        let blue = Vec3::new(0.0, 0.0, 1.0);
        for (name, tag, size, top_left, bottom_right) in [
            ("o6.png", 6, (8, 16), red, blue),
            ("o6.jpg", 6, (8, 16), red, blue),
            ("o2.png", 2, (16, 8), blue, red),
            ("o1.png", 1, (16, 8), red, blue),
        ] {
            let path = temp(name);
            let mut bytes = Vec::new();
            if name.ends_with(".png") {
                let mut enc = image::codecs::png::PngEncoder::new(&mut bytes);
                enc.set_exif_metadata(exif_orientation(tag)).unwrap();
                enc.write_image(&stored, 16, 8, image::ExtendedColorType::Rgb8).unwrap();
            } else {
                let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100);
                enc.set_exif_metadata(exif_orientation(tag)).unwrap();
                enc.write_image(&stored, 16, 8, image::ExtendedColorType::Rgb8).unwrap();
            }
            std::fs::write(&path, bytes).unwrap();
            let t = ImageTexture::load(&path, Wrap::Clamp).unwrap();
            assert_eq!((t.width(), t.height()), size, "{name}");
            // Texel centres a quarter in from the corners (v = 0 is the top).
            let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 0.05;
            let (tl, br) = (t.sample(Vec2::splat(0.25)), t.sample(Vec2::splat(0.75)));
            assert!(near(tl, top_left) && near(br, bottom_right), "{name}: {tl} {br}");
        }
    }

    #[test]
    fn a_textures_cost_counts_the_decode_texels_and_mip_map() {
        // 1024 × 512 RGBA 16-bit: 4 MiB decoded, 6 MiB of texels, 2 MiB of
        // mip-map at most.
        let c = TextureCost::new(1024, 512, 1024 * 512 * 8);
        assert_eq!(c.kept, 6 * (1 << 20) + 2 * (1 << 20) + 64);
        assert_eq!(c.peak, 6 * (1 << 20) + 4 * (1 << 20));
        // A refusal stops the load before the pixels are decoded, naming
        // the file, with the size read from the header.
        let path = temp("cost.png");
        image::RgbImage::new(40, 30).save(&path).unwrap();
        let mut seen = None;
        let e = ImageTexture::load_checked(&path, Wrap::Repeat, |c| {
            seen = Some((c.width, c.height));
            Err("too big".into())
        })
        .unwrap_err();
        assert_eq!(seen, Some((40, 30)));
        assert!(matches!(&e, ShadeError::Texture { reason, .. } if reason == "too big"), "{e}");
        assert_eq!(ImageTexture::load_checked(&path, Wrap::Repeat, |_| Ok(())).unwrap().width(), 40);
        let _ = std::fs::remove_file(path);
    }

    fn temp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("prism-shade-test-{}-{name}", std::process::id()))
    }

    #[test]
    fn srgb_round_trip() {
        for b in 0..=255u8 {
            assert_eq!(crate::linear_to_srgb8(srgb8_to_linear(b)), b);
        }
        assert_eq!(srgb8_to_linear(0), 0.0);
        assert_eq!(srgb8_to_linear(255), 1.0);
        assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
        assert_eq!(srgb_to_linear(f32::NAN), 0.0);
    }

    #[test]
    fn bilinear_interpolates_between_texel_centres() {
        let t = ImageTexture::from_linear(
            2,
            2,
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 1.0)],
            Wrap::Clamp,
        )
        .expect("valid");
        // Texel centres are exact.
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.25)), Vec3::X);
        assert_eq!(t.sample(Vec2::new(0.25, 0.75)), Vec3::Y);
        // Halfway between all four: their mean.
        assert!((t.sample(Vec2::new(0.5, 0.5)) - Vec3::new(0.5, 0.5, 0.25)).length() < 1e-6);
        // A quarter of the way from texel 0 to texel 1 along u.
        assert!((t.sample(Vec2::new(0.375, 0.25)) - Vec3::new(0.25, 0.0, 0.0)).length() < 1e-6);
        // Clamp holds the edge; repeat wraps to the opposite texel.
        assert_eq!(t.sample(Vec2::new(-3.0, 0.25)), Vec3::ZERO);
        let r = ImageTexture::from_linear(2, 1, vec![Vec3::ZERO, Vec3::ONE], Wrap::Repeat).expect("valid");
        assert!((r.sample(Vec2::new(0.0, 0.5)) - Vec3::splat(0.5)).length() < 1e-6);
        assert!((r.sample(Vec2::new(1.25, 0.5)) - Vec3::ZERO).length() < 1e-6);
        assert!((r.sample(Vec2::new(-0.25, 0.5)) - Vec3::ONE).length() < 1e-6);
        // Non-finite or huge coordinates do not panic.
        for uv in [Vec2::NAN, Vec2::INFINITY, Vec2::splat(1e30), Vec2::splat(-1e30)] {
            assert!(t.sample(uv).is_finite());
            assert!(r.sample(uv).is_finite());
        }
    }

    #[test]
    fn mappings() {
        let uv = Vec2::new(0.3, 0.7);
        assert_eq!(Mapping::Uv.uv(uv, Vec3::ONE), uv);
        assert_eq!(Mapping::Planar.uv(uv, Vec3::new(2.0, 5.0, -3.0)), Vec2::new(2.0, -3.0));
        let c = Mapping::Cylindrical.uv(uv, Vec3::new(0.0, 0.25, 2.0));
        assert!((c - Vec2::new(0.5, 0.75)).length() < 1e-6);
        let s = Mapping::Spherical.uv(uv, Vec3::new(0.0, 3.0, 0.0));
        assert!((s - Vec2::new(0.5, 0.0)).length() < 1e-6);
        let s = Mapping::Spherical.uv(uv, Vec3::new(-2.0, 0.0, 0.0));
        assert!((s.y - 0.5).abs() < 1e-6 && (s.x - 0.25).abs() < 1e-6);
        // The centre itself maps somewhere finite.
        assert!(Mapping::Spherical.uv(uv, Vec3::ZERO).is_finite());
    }

    #[test]
    fn checker_in_uv_space() {
        let t = Texture::Checker { a: Vec3::ONE, b: Vec3::ZERO, size: 0.5, world: false };
        let at = |u, v| t.color_at(Vec3::ZERO, Vec2::new(u, v), &Affine3A::IDENTITY);
        assert_eq!(at(0.1, 0.1), Vec3::ONE);
        assert_eq!(at(0.6, 0.1), Vec3::ZERO);
        assert_eq!(at(0.6, 0.6), Vec3::ONE);
        assert_eq!(at(-0.1, 0.1), Vec3::ZERO);
        assert!(at(f32::NAN, 1e30).is_finite());
    }

    #[test]
    fn image_texture_uses_its_mapping_in_object_space() {
        let img =
            Arc::new(ImageTexture::from_linear(2, 1, vec![Vec3::ZERO, Vec3::ONE], Wrap::Clamp).expect("ok"));
        let t = Texture::Image {
            image: img,
            mapping: Mapping::Planar,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
            tint: Vec3::new(1.0, 0.5, 0.0),
        };
        // The object sits at x = 10: world x = 10.75 is object x = 0.75.
        let to_object = Affine3A::from_translation(Vec3::new(-10.0, 0.0, 0.0));
        let c = t.color_at(Vec3::new(10.75, 0.0, 0.5), Vec2::ZERO, &to_object);
        assert!((c - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-6);
    }

    #[test]
    fn load_decodes_srgb_png_to_linear() {
        let path = temp("ok.png");
        let bytes = [0u8, 128, 255, 255, 64, 0];
        image::save_buffer(&path, &bytes, 2, 1, image::ExtendedColorType::Rgb8).expect("can write temp png");
        let t = ImageTexture::load(&path, Wrap::Clamp);
        let _ = std::fs::remove_file(&path);
        let t = t.expect("loads");
        assert_eq!((t.width(), t.height(), t.wrap()), (2, 1, Wrap::Clamp));
        let want0 = Vec3::new(0.0, srgb8_to_linear(128), 1.0);
        assert_eq!(t.texel(0, 0), want0);
        assert_eq!(t.texel(1, 0), Vec3::new(1.0, srgb8_to_linear(64), 0.0));
        // The file's name, not its extension, is trusted for nothing.
        let path = temp("png-named.bmp");
        image::save_buffer_with_format(
            &path,
            &bytes,
            2,
            1,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .expect("can write");
        let t = ImageTexture::load(&path, Wrap::Repeat);
        let _ = std::fs::remove_file(&path);
        assert_eq!(t.expect("loads by content").texel(0, 0), want0);
    }

    #[test]
    fn load_keeps_float_images_linear() {
        let path = temp("lin.exr");
        let img = image::Rgb32FImage::from_raw(1, 1, vec![0.5, 2.0, 0.25]).expect("sized");
        img.save(&path).expect("can write exr");
        let t = ImageTexture::load(&path, Wrap::Clamp);
        let _ = std::fs::remove_file(&path);
        assert_eq!(t.expect("loads").texel(0, 0), Vec3::new(0.5, 2.0, 0.25));
    }

    fn crc32(data: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in data {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }

    #[test]
    fn an_exr_without_rgb_is_told_by_its_channels_not_called_corrupt() {
        use crate::exr::{ExrChannel, ExrLayer, LayeredExr, write_layered_exr};
        let grey = temp("grey.exr");
        let layer = |channels: Vec<ExrChannel>| LayeredExr {
            width: 4,
            height: 2,
            data_window: crate::PixelBounds::new(0, 4, 0, 2).expect("bounds"),
            layers: vec![ExrLayer { name: String::new(), channels }],
            attributes: Default::default(),
        };
        write_layered_exr(&grey, &layer(vec![ExrChannel::f32("Y", vec![0.5; 8])])).expect("can write");
        match ImageTexture::load(&grey, Wrap::Repeat) {
            Err(ShadeError::Texture { reason, .. }) => assert_eq!(
                reason,
                "the EXR image has no R, G and B channels (its channels: Y); prism reads RGB or RGBA EXR images"
            ),
            other => panic!("{other:?}"),
        }
        // R, G and B load (the same writer, so the test's file is sound).
        let rgb = ["R", "G", "B"].map(|c| ExrChannel::f32(c, vec![0.25; 8])).to_vec();
        write_layered_exr(&grey, &layer(rgb)).expect("can write");
        assert_eq!(ImageTexture::load(&grey, Wrap::Repeat).expect("loads").texel(1, 1), Vec3::splat(0.25));
        let _ = std::fs::remove_file(&grey);
    }

    #[test]
    fn load_refuses_bad_files_without_panicking() {
        let missing = temp("missing.png");
        assert!(matches!(ImageTexture::load(&missing, Wrap::Clamp), Err(ShadeError::Texture { .. })));
        let garbage = temp("garbage.png");
        std::fs::write(&garbage, b"this is not an image at all").expect("can write");
        let e = ImageTexture::load(&garbage, Wrap::Clamp);
        // A truncated PNG: a real header, then nothing.
        let truncated = temp("truncated.png");
        let mut ok = Vec::new();
        {
            use image::ImageEncoder;
            image::codecs::png::PngEncoder::new(&mut ok)
                .write_image(&[1u8; 48], 4, 4, image::ExtendedColorType::Rgb8)
                .expect("encodes");
        }
        std::fs::write(&truncated, &ok[..ok.len() / 2]).expect("can write");
        let t = ImageTexture::load(&truncated, Wrap::Clamp);
        // PNG headers claiming 100000 × 100000 texels, 2³¹ − 1 × 2¹⁴ (the
        // widest PNG allows: beyond the image library's own limit on a
        // header), and 2³² − 1 squared (beyond PNG's rules).
        let huge = |w: u32, h: u32| {
            let path = temp(&format!("huge-{w}-{h}.dat")); // named as no format: read by its content
            let mut f = b"\x89PNG\r\n\x1a\n".to_vec();
            let mut ihdr = b"IHDR".to_vec();
            ihdr.extend_from_slice(&w.to_be_bytes());
            ihdr.extend_from_slice(&h.to_be_bytes());
            ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
            f.extend_from_slice(&13u32.to_be_bytes());
            f.extend_from_slice(&ihdr);
            f.extend_from_slice(&crc32(&ihdr).to_be_bytes());
            // Then a small (wrong) IDAT and the end: decoding must stop at the size.
            let mut idat = b"IDAT".to_vec();
            idat.extend_from_slice(&[0x78, 0x9c, 0x63, 0, 0, 0, 1, 0, 1]);
            f.extend_from_slice(&9u32.to_be_bytes());
            f.extend_from_slice(&idat);
            f.extend_from_slice(&crc32(&idat).to_be_bytes());
            f.extend_from_slice(&0u32.to_be_bytes());
            f.extend_from_slice(b"IEND");
            f.extend_from_slice(&crc32(b"IEND").to_be_bytes());
            std::fs::write(&path, &f).expect("can write");
            let r = ImageTexture::load(&path, Wrap::Clamp);
            let _ = std::fs::remove_file(&path);
            r
        };
        // A JPEG cut in half: the decoder's own text ends in a line break,
        // which the message must not carry.
        let half_jpeg = temp("half.jpg");
        let mut jpg = Vec::new();
        image::codecs::jpeg::JpegEncoder::new(&mut jpg)
            .encode(&[90u8; 16 * 16 * 3], 16, 16, image::ExtendedColorType::Rgb8)
            .expect("encodes");
        std::fs::write(&half_jpeg, &jpg[..jpg.len() / 2]).expect("can write");
        match ImageTexture::load(&half_jpeg, Wrap::Clamp) {
            Err(ShadeError::Texture { reason, .. }) => {
                assert!(reason.starts_with("the JPG data is") && !reason.contains('\n'), "{reason:?}");
            }
            other => panic!("{other:?}"),
        }
        let _ = std::fs::remove_file(&half_jpeg);
        let h = huge(100_000, 100_000);
        let widest = huge(i32::MAX as u32, 16_384);
        let beyond = huge(u32::MAX, u32::MAX);
        for p in [&garbage, &truncated] {
            let _ = std::fs::remove_file(p);
        }
        for (what, r) in
            [("garbage", e), ("truncated", t), ("huge", h), ("widest", widest), ("beyond", beyond)]
        {
            match r {
                Err(ShadeError::Texture { path, reason }) => {
                    assert!(path.to_string_lossy().contains("prism-shade-test"), "{what}: {path:?}");
                    assert!(!reason.is_empty());
                    // Its size, from the header, against the limit.
                    match what {
                        "huge" => {
                            assert_eq!(reason, "100000×100000 texels is more than the 16384 allowed per side")
                        }
                        "widest" => {
                            assert_eq!(
                                reason,
                                "2147483647×16384 texels is more than the 16384 allowed per side"
                            );
                        }
                        "beyond" => assert!(
                            reason.starts_with("its size cannot be read from its header (")
                                && reason.ends_with("prism reads textures of up to 16384 texels per side"),
                            "{reason}"
                        ),
                        _ => {}
                    }
                }
                other => panic!("{what}: expected a texture error, got {other:?}"),
            }
        }
    }
}
