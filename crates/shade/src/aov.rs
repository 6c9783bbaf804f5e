//! Arbitrary output variables (AOVs): per-pixel geometric measurements of
//! the first surface each camera ray meets, as float images. The
//! definitions are on [`render_aovs`] and in `docs/aov.md`.

use crate::render::{render_pixels, scale_to_mean};
use crate::{Camera, Image, RenderHooks, RenderSettings, RenderStats, Scene};
use prism_geometry::Ray;
use prism_geometry::glam::{DVec3, Vec3};
use std::fmt;
use std::str::FromStr;

/// One kind of AOV pass. Names (for [`FromStr`], [`Aov::name`] and the
/// file names of [`crate::write_aov_files`]): `depth`, `normal`,
/// `geo_normal`, `albedo`, `object_id`. [`render_aovs`] has the exact
/// definitions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// Distance from the camera position to the first hit; `+∞` for a miss.
    Depth,
    /// World-space outward shading normal; 0 for a miss.
    Normal,
    /// World-space outward geometric normal; 0 for a miss.
    GeoNormal,
    /// Linear surface colour after textures; 0 for a miss.
    Albedo,
    /// Scene object index as a float; −1 for a miss. Not averaged: the
    /// pixel-centre ray decides.
    ObjectId,
}

impl Aov {
    /// Every pass, in the canonical order.
    pub const ALL: [Aov; 5] = [Aov::Depth, Aov::Normal, Aov::GeoNormal, Aov::Albedo, Aov::ObjectId];

    /// The pass's name: `depth`, `normal`, `geo_normal`, `albedo` or `object_id`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Normal => "normal",
            Aov::GeoNormal => "geo_normal",
            Aov::Albedo => "albedo",
            Aov::ObjectId => "object_id",
        }
    }

    /// Values per pixel: 1 for depth and object id, 3 for the others.
    #[must_use]
    pub const fn channels(self) -> usize {
        match self {
            Aov::Depth | Aov::ObjectId => 1,
            Aov::Normal | Aov::GeoNormal | Aov::Albedo => 3,
        }
    }

    /// The value of a pixel whose ray hits nothing (per channel).
    #[must_use]
    pub const fn miss_value(self) -> f32 {
        match self {
            Aov::Depth => f32::INFINITY,
            Aov::ObjectId => -1.0,
            Aov::Normal | Aov::GeoNormal | Aov::Albedo => 0.0,
        }
    }

    /// Parses a comma-separated list such as `"depth,normal,object_id"`
    /// (the form of a `--aov` flag). Spaces around names are ignored, and
    /// the names are then read as [`Aov::parse_names`] reads them.
    ///
    /// # Errors
    /// [`AovParseError`]: an empty list, or the first item that is not a
    /// pass name (an empty item included).
    pub fn parse_list(list: &str) -> Result<Vec<Aov>, AovParseError> {
        if list.trim().is_empty() {
            return Err(AovParseError::EmptyList);
        }
        Aov::parse_names(list.split(',').map(str::trim)).map_err(|(_, e)| e)
    }

    /// Reads pass names, one by one (a `--aov` flag's items, or a scene
    /// file's `aov` array): `all` stands for every pass, `none` (alone)
    /// for no pass, repeated names count once, and the passes keep their
    /// first order of appearance. Names are exact: no spaces are trimmed.
    ///
    /// # Errors
    /// The position of the first name that is not a pass name (empty,
    /// unknown, or `none` beside others), and why.
    pub fn parse_names<'a>(
        names: impl IntoIterator<Item = &'a str>,
    ) -> Result<Vec<Aov>, (usize, AovParseError)> {
        let names: Vec<&str> = names.into_iter().collect();
        let mut out = Vec::new();
        if names == ["none"] {
            return Ok(out);
        }
        for (i, &name) in names.iter().enumerate() {
            let found: Vec<Aov> = match name {
                "all" => Aov::ALL.to_vec(),
                "none" => return Err((i, AovParseError::NoneWithOthers)),
                _ => vec![name.parse().map_err(|e| (i, e))?],
            };
            for a in found {
                if !out.contains(&a) {
                    out.push(a);
                }
            }
        }
        Ok(out)
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Aov {
    type Err = AovParseError;

    /// Exact, case-sensitive pass names (see [`Aov`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.is_empty() {
            return Err(AovParseError::EmptyEntry);
        }
        Aov::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| AovParseError::Unknown { name: s.to_owned() })
    }
}

/// A list of AOV pass names that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AovParseError {
    /// A name that is not a pass.
    #[error(
        "unknown AOV pass `{name}`{}: expected one of depth, normal, geo_normal, albedo, object_id (or all; or none alone)",
        crate::names::did_you_mean(.name, &Aov::ALL.map(Aov::name))
    )]
    Unknown {
        /// The name given.
        name: String,
    },
    /// An empty name (`depth,,normal`, `""` in a file).
    #[error(
        "the list of AOV passes has an empty entry: expected names among depth, normal, geo_normal, albedo, \
         object_id (or all), separated by single commas"
    )]
    EmptyEntry,
    /// No name at all (`--aov ''`).
    #[error(
        "the list of AOV passes is empty: give pass names (depth, normal, geo_normal, albedo, object_id, or all), \
         or none for no pass"
    )]
    EmptyList,
    /// `none` beside other names (`depth,none`).
    #[error("`none` means no pass and stands alone; leave it out to write the other passes")]
    NoneWithOthers,
}

/// One AOV pass: `aov.channels()` floats per pixel, interleaved, rows in
/// order from the top (row 0 at the top, as [`Image`]).
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Which pass.
    pub aov: Aov,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height · aov.channels()` values, row-major.
    pub data: Vec<f32>,
}

impl AovImage {
    /// Values per pixel (`aov.channels()`).
    #[must_use]
    pub fn channels(&self) -> usize {
        self.aov.channels()
    }

    /// The values of pixel `(i, j)`, or `None` outside the image.
    #[must_use]
    pub fn pixel(&self, i: u32, j: u32) -> Option<&[f32]> {
        if i >= self.width || j >= self.height {
            return None;
        }
        let c = self.channels();
        let at = (j as usize * self.width as usize + i as usize) * c;
        self.data.get(at..at + c)
    }

    /// The first value of pixel `(i, j)` (depth or object id for the
    /// one-channel passes), or `None` outside the image.
    #[must_use]
    pub fn scalar(&self, i: u32, j: u32) -> Option<f32> {
        self.pixel(i, j).and_then(|p| p.first().copied())
    }

    /// Pixel `(i, j)` as a vector (a one-channel value repeated in all
    /// three), or `None` outside the image.
    #[must_use]
    pub fn vec3(&self, i: u32, j: u32) -> Option<Vec3> {
        match self.pixel(i, j)? {
            [x] => Some(Vec3::splat(*x)),
            [x, y, z] => Some(Vec3::new(*x, *y, *z)),
            _ => None,
        }
    }

    /// Interleaved RGB floats, one-channel values repeated in R, G and B:
    /// what [`crate::write_aov_exr`] stores.
    #[must_use]
    pub fn to_rgb(&self) -> Vec<f32> {
        if self.channels() == 3 {
            self.data.clone()
        } else {
            self.data.iter().flat_map(|&v| [v, v, v]).collect()
        }
    }
}

/// The passes of one render, in the order they were asked for (repeats
/// dropped).
#[derive(Clone, Debug, PartialEq)]
pub struct AovImages {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The passes.
    pub passes: Vec<AovImage>,
}

impl AovImages {
    /// The pass `aov`, if it was rendered.
    #[must_use]
    pub fn get(&self, aov: Aov) -> Option<&AovImage> {
        self.passes.iter().find(|p| p.aov == aov)
    }
}

/// Renders the AOV passes `aovs` (no shading: one primary ray per sample,
/// plus the pixel-centre ray for [`Aov::ObjectId`] when `spp > 1`).
///
/// Definitions, exactly:
/// - rays: the render's pinhole camera, `settings.camera` ([`crate::Camera::ray`]), through the
///   sample positions of the beauty render, [`crate::sample_position`]
///   (with `settings.spp = 1`, the pixel centre `(i + 0.5, j + 0.5)` and no
///   jitter, so that a pass is an exact geometric measurement);
/// - `depth`: the Euclidean distance from the camera position to the first
///   hit along the ray, in scene units; `+∞` where nothing is hit;
/// - `normal`: the world-space unit shading normal at the first hit,
///   outward as the surface defines it (not flipped toward the camera);
///   `geo_normal` the world-space unit geometric normal; both 0 where
///   nothing is hit;
/// - `albedo`: the linear surface colour after textures
///   ([`Scene::albedo_at`]); 0 (not the background) where nothing is hit;
/// - `object_id`: the index of the object hit in the scene's
///   [`prism_bvh::Accel`], as a float; −1 where nothing is hit.
///
/// With `spp > 1` each pass is the mean of the samples (summed in sample
/// order, times `1 / spp`), except `object_id`, which takes the ray through
/// the pixel centre. A pixel with any missed sample thus has depth `+∞`,
/// and averaged normals at edges are shorter than 1. No value is NaN;
/// `+∞` appears only in depth. Results are the same for any number of
/// threads. Rows run in parallel (`settings.threads`); `hooks` report
/// progress and cancel (rows not rendered hold the miss values).
/// `settings.max_depth` and `min_contribution` do not matter here.
/// `stats.rays` counts the rays traced.
pub fn render_aovs(
    scene: &Scene,
    settings: &RenderSettings,
    aovs: &[Aov],
    hooks: RenderHooks<'_>,
) -> (AovImages, RenderStats) {
    let (_, images, _, stats) = render_passes(scene, settings, aovs, None, false, false, hooks);
    (images, stats)
}

/// The beauty image and the AOV passes `aovs` in one pass over the pixels.
///
/// The image is the same, bit for bit, as [`crate::render()`]'s with the same
/// settings (it is the same sample loop; adaptive supersampling, which
/// needs a pixel's samples to stop early, is off here), and the passes as
/// [`render_aovs`]'s; `stats.rays` counts the rays of both (the passes
/// trace their own primary rays).
pub fn render_with_aovs(
    scene: &Scene,
    settings: &RenderSettings,
    aovs: &[Aov],
    hooks: RenderHooks<'_>,
) -> (Image, AovImages, RenderStats) {
    let (image, passes, _, stats) = render_passes(scene, settings, aovs, None, true, false, hooks);
    (image, passes, stats)
}

/// A render over a transparent background: the colour *premultiplied* by
/// coverage, and the coverage (alpha) of each pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaImage {
    /// Linear RGB premultiplied by alpha: the mean over the pixel's samples
    /// of the sample's radiance where its camera ray hit a surface, and 0
    /// where it hit nothing (the background contributes nothing directly;
    /// seen in mirrors and through glass it still does).
    pub color: Image,
    /// Per pixel, row-major: the fraction of its samples whose camera ray
    /// hit a surface, in `[0, 1]` (0 where only background is seen).
    pub alpha: Vec<f32>,
}

/// The beauty over a transparent background ([`AlphaImage`]) and the AOV
/// passes `aovs` (possibly none), in one pass over the pixels (POV-Ray's
/// `+UA`; Blender's "transparent film").
///
/// Where every sample of a pixel hits a surface, its colour is bit for bit
/// that of [`crate::render()`] (without adaptive supersampling, which is off
/// here) and its alpha 1. An area light seen directly covers its samples as
/// a surface does. Each camera ray is tested
/// once more for a hit by the pass sink (counted in `stats.aov_rays`).
pub fn render_with_alpha(
    scene: &Scene,
    settings: &RenderSettings,
    aovs: &[Aov],
    hooks: RenderHooks<'_>,
) -> (AlphaImage, AovImages, RenderStats) {
    let (image, passes, alpha, stats) = render_passes(scene, settings, aovs, None, true, true, hooks);
    let (color, alpha) = alpha.unwrap_or_else(|| (image.clone(), vec![1.0; image.pixels.len()]));
    (AlphaImage { color, alpha }, passes, stats)
}

/// The beauty (if `beauty`) and the passes `aovs` of `region` (`None`: the
/// whole image), one pass over its pixels.
pub(crate) fn render_passes(
    scene: &Scene,
    settings: &RenderSettings,
    aovs: &[Aov],
    region: Option<crate::PixelBounds>,
    beauty: bool,
    alpha: bool,
    hooks: RenderHooks<'_>,
) -> (Image, AovImages, Option<(Image, Vec<f32>)>, RenderStats) {
    let mut wanted: Vec<Aov> = Vec::with_capacity(aovs.len());
    for &a in aovs {
        if !wanted.contains(&a) {
            wanted.push(a);
        }
    }
    let spp = settings.spp.max(1);
    let (mut image, rows, stats) =
        render_pixels(scene, settings, 0..spp, region, beauty, &wanted, alpha, hooks);
    scale_to_mean(&mut image, spp);
    let (w, h) = (image.width, image.height);
    let n = w as usize * h as usize;
    let mut data: Vec<Vec<f32>> = wanted.iter().map(|a| Vec::with_capacity(n * a.channels())).collect();
    let mut coverage = alpha.then(|| (Vec::with_capacity(n), Vec::with_capacity(n)));
    for row in rows {
        for (d, p) in data.iter_mut().zip(&row.passes) {
            d.extend_from_slice(p);
        }
        if let (Some((rgb, a)), Some(row)) = (&mut coverage, &row.alpha) {
            rgb.extend_from_slice(&row.rgb);
            a.extend_from_slice(&row.alpha);
        }
    }
    let passes =
        wanted.iter().zip(data).map(|(&aov, data)| AovImage { aov, width: w, height: h, data }).collect();
    let coverage = coverage.map(|(pixels, a)| (Image { width: w, height: h, pixels }, a));
    (image, AovImages { width: w, height: h, passes }, coverage, stats)
}

/// The coverage sink of one row: per pixel, the samples whose camera ray
/// hit a surface and the sum of their radiance.
struct AlphaRow {
    hits: u32,
    /// In f64, as the beauty sums a pixel's samples: a fully covered
    /// pixel is the plain render's bit for bit.
    covered: DVec3,
    /// Premultiplied colour per pixel of the row.
    rgb: Vec<Vec3>,
    /// Alpha per pixel of the row.
    alpha: Vec<f32>,
}

/// Per-pixel sums of the averaged passes.
#[derive(Clone, Copy)]
struct Sums {
    depth: f32,
    normal: Vec3,
    geo: Vec3,
    albedo: Vec3,
}

impl Sums {
    const ZERO: Sums = Sums { depth: 0.0, normal: Vec3::ZERO, geo: Vec3::ZERO, albedo: Vec3::ZERO };
}

/// The AOV sink of one image row in the sample loop
/// ([`crate::render::render_pixels`]): it sees every camera ray of a pixel
/// ([`AovRow::sample`]), then stores the pixel's values
/// ([`AovRow::end_pixel`]). Its passes start at the miss values, so a row
/// skipped by a cancel reads as "nothing hit".
pub(crate) struct AovRow<'a> {
    wanted: &'a [Aov],
    spp: u32,
    want_averaged: bool,
    want_id: bool,
    /// One buffer per wanted pass, `width · channels` values.
    passes: Vec<Vec<f32>>,
    sums: Sums,
    centre_id: Option<f32>,
    /// Coverage and the premultiplied beauty, when alpha is wanted.
    alpha: Option<AlphaRow>,
    /// The image column of the row's first value (a partial render's `x0`).
    x0: u32,
    /// Rays traced for the passes.
    pub(crate) rays: u64,
}

fn finite_or_zero(v: Vec3) -> Vec3 {
    if v.is_finite() { v } else { Vec3::ZERO }
}

impl<'a> AovRow<'a> {
    /// A row of `width` pixels of the passes `wanted` (no repeats), for a
    /// render of `spp` samples per pixel, with coverage if `alpha`.
    pub(crate) fn new(wanted: &'a [Aov], width: u32, spp: u32, alpha: bool) -> Self {
        let n = width as usize;
        Self {
            wanted,
            spp: spp.max(1),
            want_averaged: wanted.iter().any(|&a| a != Aov::ObjectId),
            want_id: wanted.contains(&Aov::ObjectId),
            passes: wanted.iter().map(|a| vec![a.miss_value(); width as usize * a.channels()]).collect(),
            sums: Sums::ZERO,
            centre_id: None,
            alpha: alpha.then(|| AlphaRow {
                hits: 0,
                covered: DVec3::ZERO,
                rgb: vec![Vec3::ZERO; n],
                alpha: vec![0.0; n],
            }),
            x0: 0,
            rays: 0,
        }
    }

    /// The same row, its first value being image column `x0`.
    pub(crate) fn starting_at(self, x0: u32) -> Self {
        Self { x0, ..self }
    }

    /// One sample's camera ray of the current pixel, and the radiance the
    /// beauty got from it (finite; 0 without a beauty).
    #[inline]
    pub(crate) fn sample(&mut self, scene: &Scene, ray: &Ray, radiance: Vec3) {
        if !(self.want_averaged || (self.want_id && self.spp == 1) || self.alpha.is_some()) {
            return;
        }
        self.rays += 1;
        let hit = scene.accel.closest_hit(ray);
        if let Some(a) = &mut self.alpha {
            // A surface, or an area light seen against the background, covers the sample.
            let seen = hit.is_some() || scene.lights.iter().any(|l| l.intersect(ray, ray.t_max).is_some());
            if seen {
                a.hits += 1;
                a.covered += radiance.as_dvec3();
            }
        }
        let sums = &mut self.sums;
        match &hit {
            Some(_) if !self.want_averaged => {}
            Some(hit) => {
                let d = hit.hit.t * ray.dir.length();
                sums.depth += if d.is_nan() { f32::INFINITY } else { d };
                sums.normal += finite_or_zero(hit.hit.normal);
                sums.geo += finite_or_zero(hit.hit.geo_normal);
                sums.albedo += finite_or_zero(scene.albedo_at(hit));
            }
            None => sums.depth = f32::INFINITY,
        }
        if self.spp == 1 {
            self.centre_id = Some(hit.map_or(-1.0, |h| h.object as f32));
        }
    }

    /// Stores pixel `(i, j)` (after all its samples) and starts the next.
    pub(crate) fn end_pixel(&mut self, scene: &Scene, camera: &Camera, i: u32, j: u32) {
        if self.want_id && self.centre_id.is_none() {
            self.rays += 1;
            let ray = camera.ray(i as f32 + 0.5, j as f32 + 0.5);
            self.centre_id = Some(scene.accel.closest_hit(&ray).map_or(-1.0, |h| h.object as f32));
        }
        let inv = 1.0 / self.spp as f32;
        let (sums, id) = (self.sums, self.centre_id.unwrap_or(-1.0));
        let i = (i - self.x0) as usize;
        for (a, buf) in self.wanted.iter().zip(&mut self.passes) {
            match a {
                Aov::Depth => buf[i] = sums.depth * inv,
                Aov::ObjectId => buf[i] = id,
                Aov::Normal | Aov::GeoNormal | Aov::Albedo => {
                    let v = match a {
                        Aov::Normal => sums.normal,
                        Aov::GeoNormal => sums.geo,
                        _ => sums.albedo,
                    } * inv;
                    buf[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
                }
            }
        }
        if let Some(a) = &mut self.alpha {
            a.rgb[i] = a.covered.as_vec3() * inv;
            a.alpha[i] = a.hits as f32 * inv;
            a.hits = 0;
            a.covered = DVec3::ZERO;
        }
        self.sums = Sums::ZERO;
        self.centre_id = None;
    }
}
