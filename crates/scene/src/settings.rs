//! The `[render]` table with the overrides and limits applied: image size
//! (and [`fit_size`], the one aspect-keeping resize), samples, depth,
//! contribution cut-off, background, ambient light and AOV passes.

use crate::check::{Ctx, Result};
use crate::error::SceneError;
use crate::format::{BackgroundDef, RenderDef};
use crate::{LoadOptions, Overrides};
use prism_geometry::glam::Vec3;
use prism_shade::{Antialias, Aov, PixelFilter};
use std::ops::Range;
use toml::Spanned;

/// Render defaults (also in docs/scene-format.md).
pub(crate) const DEFAULT_SPP: u32 = 4;
pub(crate) const DEFAULT_MAX_DEPTH: u32 = 8;
pub(crate) const DEFAULT_MIN_CONTRIBUTION: f32 = 0.001;

/// What a scene uses where `[render]` does not say: a scene file's
/// defaults ([`Defaults::FILE`]) or an OBJ file's as a scene
/// ([`Defaults::OBJ`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Defaults {
    pub width: u32,
    pub height: u32,
    pub background: Vec3,
}

impl Defaults {
    /// A scene file's (docs/scene-format.md).
    pub const FILE: Self = Self { width: 1280, height: 720, background: Vec3::ZERO };
    /// An OBJ file's as a scene ([`crate::load_obj_scene`]).
    pub const OBJ: Self = Self { width: 640, height: 480, background: Vec3::new(0.05, 0.05, 0.07) };
}

/// The render settings of a scene, checked.
#[derive(Clone, Debug)]
pub(crate) struct Settings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub min_contribution: f32,
    pub background: Vec3,
    pub ambient: Vec3,
    pub aovs: Vec<Aov>,
    pub aov_preview: bool,
    pub antialias: Antialias,
}

/// The image size for a scene of `scene_w × scene_h` pixels when the
/// width and/or height are given (on the command line): both given replace both; one alone sets that side and scales the
/// other to keep the scene's aspect ratio, rounded to the nearest pixel
/// (halves up) and at least 1 (at most `u32::MAX`); neither keeps the
/// scene's size. Where the scene's side to scale from is 0 the aspect
/// ratio is undefined and the scene's other side is kept.
///
/// ```
/// use prism_scene::fit_size;
/// assert_eq!(fit_size(800, 600, Some(400), None), (400, 300));
/// assert_eq!(fit_size(800, 600, None, Some(5)), (7, 5)); // 6.67 → 7
/// assert_eq!(fit_size(800, 600, Some(1), None), (1, 1)); // 0.75 → 1
/// assert_eq!(fit_size(800, 600, Some(10), Some(20)), (10, 20));
/// assert_eq!(fit_size(800, 600, None, None), (800, 600));
/// ```
#[must_use]
pub fn fit_size(scene_w: u32, scene_h: u32, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    // `other × target / this`, rounded: the other side of the resized image.
    let scaled = |other: u32, this: u32, target: u32| {
        if this == 0 {
            return other;
        }
        let (other, this, target) = (u64::from(other), u64::from(this), u64::from(target));
        u32::try_from(((other * target + this / 2) / this).max(1)).unwrap_or(u32::MAX)
    };
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, scaled(scene_h, scene_w, w)),
        (None, Some(h)) => (scaled(scene_w, scene_h, h), h),
        (None, None) => (scene_w, scene_h),
    }
}

/// The settings of `render` (absent: all defaults) with `options`'
/// overrides and limits. An error in a value from the file points at it;
/// one in an override names its flag.
pub(crate) fn resolve(
    ctx: &Ctx,
    render: Option<&RenderDef>,
    defaults: Defaults,
    options: &LoadOptions,
) -> Result<Settings> {
    let ov = options.overrides;
    let field = |f: Option<&Spanned<u64>>| f.map(|s| (*s.get_ref(), s.span()));
    let width_f = render.and_then(|r| field(r.width.as_ref()));
    let height_f = render.and_then(|r| field(r.height.as_ref()));
    let (width, height) = image_size(ctx, width_f, height_f, defaults, options)?;

    let spp = choose(ctx, ov.spp, "--spp", render.and_then(|r| field(r.spp.as_ref())), DEFAULT_SPP, |s| {
        check_spp(s, options.limits.max_spp)
    })?;
    let depth_f = render.and_then(|r| field(r.max_depth.as_ref()));
    let max_depth = choose(ctx, ov.max_depth, "--max-depth", depth_f, DEFAULT_MAX_DEPTH, |d| {
        check_depth(d, options.limits.max_depth)
    })?;
    let min_contribution = match render.and_then(|r| r.min_contribution.as_ref()) {
        Some(n) => {
            let v = ctx.finite(n, "min_contribution")?;
            if !(0.0..1.0).contains(&v) {
                return Err(ctx.invalid(&n.span(), format!("min_contribution must be in [0, 1), got {v}")));
            }
            v
        }
        None => DEFAULT_MIN_CONTRIBUTION,
    };
    // An environment image (built with the scene) leaves the colour black.
    let background = match render.and_then(|r| r.background.as_ref()) {
        Some(b) => match b.get_ref() {
            BackgroundDef::Color(c) => ctx.color_at(&b.span(), c, "background")?,
            BackgroundDef::Image(_) => Vec3::ZERO,
        },
        None => defaults.background,
    };
    let ambient = ctx.opt_color(render.and_then(|r| r.ambient.as_ref()), "ambient", Vec3::ONE)?;

    // `["none"]` is no pass, as `--aov none`.
    let names = render.and_then(|r| r.aov.as_ref()).map_or(&[][..], |l| l.get_ref().as_slice());
    let aovs = Aov::parse_names(names.iter().map(|n| n.get_ref().as_str()))
        .map_err(|(i, e)| ctx.invalid(&names[i].span(), e.to_string()))?;
    let aov_preview = render.and_then(|r| r.aov_preview).unwrap_or(false);
    let antialias = antialias(ctx, render, ov)?;
    Ok(Settings {
        width,
        height,
        spp,
        max_depth,
        min_contribution,
        background,
        ambient,
        aovs,
        aov_preview,
        antialias,
    })
}

/// `filter` and `adaptive`: the overrides (`--filter`, `--adaptive`), else
/// the file's, else the box and no adaptive sampling.
fn antialias(ctx: &Ctx, render: Option<&RenderDef>, ov: Overrides) -> Result<Antialias> {
    let filter = match (ov.filter, render.and_then(|r| r.filter.as_ref())) {
        (Some(f), _) => f,
        (None, Some(name)) => {
            name.get_ref().parse::<PixelFilter>().map_err(|e| ctx.invalid(&name.span(), e.to_string()))?
        }
        (None, None) => PixelFilter::Box,
    };
    let check = |v: f32| {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(format!("adaptive threshold must be a finite number >= 0, got {v}"))
        }
    };
    let adaptive = match (ov.adaptive, render.and_then(|r| r.adaptive.as_ref())) {
        (Some(v), _) => Some(check(v).map_err(|message| SceneError::Option { flag: "--adaptive", message })?),
        (None, Some(n)) => Some(check(ctx.finite(n, "adaptive")?).map_err(|m| ctx.invalid(&n.span(), m))?),
        (None, None) => None,
    };
    Ok(Antialias { filter, adaptive, point_textures: false })
}

/// The image size: the overrides first (named by flag), else the file's
/// `width`/`height` (with their spans), else `defaults`; checked against
/// the limits.
fn image_size(
    ctx: &Ctx,
    width_f: Option<(u64, Range<usize>)>,
    height_f: Option<(u64, Range<usize>)>,
    defaults: Defaults,
    options: &LoadOptions,
) -> Result<(u32, u32)> {
    let (ov, limits): (Overrides, _) = (options.overrides, options.limits);
    let fw = width_f.as_ref().map_or(u64::from(defaults.width), |w| w.0);
    let fh = height_f.as_ref().map_or(u64::from(defaults.height), |h| h.0);
    let (width, height) = if ov.width.is_none() && ov.height.is_none() {
        (fw, fh)
    } else {
        // A file's side over u32::MAX is over every limit; scaled from it saturates.
        let side = |s: u64| u32::try_from(s).unwrap_or(u32::MAX);
        let (w, h) = fit_size(side(fw), side(fh), ov.width, ov.height);
        (u64::from(w), u64::from(h))
    };
    // A side the file gives points at the file; one a flag gives, or one
    // the other side's flag derives (keeping the aspect), names that flag.
    let derived = |other: Option<u32>, flag: &str| {
        other.map_or_else(String::new, |v| format!(" (from {flag} {v}, keeping the scene's aspect)"))
    };
    let no_flags = ov.width.is_none() && ov.height.is_none();
    for (value, flag, spanned, name, from) in [
        (
            width,
            if ov.width.is_some() || ov.height.is_none() { "--width" } else { "--height" },
            if no_flags { width_f.as_ref() } else { None },
            "width",
            if ov.width.is_none() { derived(ov.height, "--height") } else { String::new() },
        ),
        (
            height,
            if ov.height.is_some() || ov.width.is_none() { "--height" } else { "--width" },
            if no_flags { height_f.as_ref() } else { None },
            "height",
            if ov.height.is_none() { derived(ov.width, "--width") } else { String::new() },
        ),
    ] {
        let problem = if value == 0 {
            Some(format!("image {name}{from} must be at least 1 pixel"))
        } else if value > u64::from(limits.max_side) {
            Some(format!(
                "image {name} {value}{from} is over the limit of {} pixels per side (raise it with --max-side)",
                limits.max_side
            ))
        } else {
            None
        };
        if let Some(message) = problem {
            return Err(match spanned {
                Some((_, span)) => ctx.invalid(span, message),
                None if ov.width.is_some() || ov.height.is_some() => SceneError::Option { flag, message },
                None => ctx.invalid_file(message),
            });
        }
    }
    if width * height > limits.max_pixels {
        let message = format!(
            "image of {width}×{height} = {} pixels is over the limit of {} pixels (raise it with --max-pixels)",
            width * height,
            limits.max_pixels
        );
        return Err(match (ov.width.or(ov.height), width_f.as_ref().or(height_f.as_ref())) {
            (Some(_), _) => SceneError::Option { flag: "--width/--height", message },
            (None, Some((_, span))) => ctx.invalid(span, message),
            (None, None) => ctx.invalid_file(message),
        });
    }
    Ok((width as u32, height as u32))
}

/// The override (checked, its error naming `flag`), else the file's value
/// (checked, its error at its span), else `default` (checked, its error naming
/// the file).
fn choose(
    ctx: &Ctx,
    over: Option<u32>,
    flag: &'static str,
    file: Option<(u64, Range<usize>)>,
    default: u32,
    check: impl Fn(u64) -> std::result::Result<u32, String>,
) -> Result<u32> {
    match (over, file) {
        (Some(v), _) => check(u64::from(v)).map_err(|message| SceneError::Option { flag, message }),
        (None, Some((v, span))) => check(v).map_err(|m| ctx.invalid(&span, m)),
        // The default meets the limits too (`--max-spp 1` with a scene
        // that sets no `spp`).
        (None, None) => check(u64::from(default))
            .map_err(|m| ctx.invalid_file(format!("{m}; it is the default, as the scene sets none"))),
    }
}

fn check_spp(spp: u64, max: u32) -> std::result::Result<u32, String> {
    if spp == 0 {
        Err("spp (samples per pixel) must be at least 1".into())
    } else if spp > u64::from(max) {
        Err(format!("spp {spp} is over the limit of {max} samples per pixel (raise it with --max-spp)"))
    } else {
        Ok(spp as u32)
    }
}

fn check_depth(depth: u64, max: u32) -> std::result::Result<u32, String> {
    if depth > u64::from(max) {
        Err(format!(
            "max_depth {depth} is over the limit of {max} bounces (the renderer never goes deeper than {})",
            prism_shade::MAX_DEPTH_LIMIT
        ))
    } else {
        Ok(depth as u32)
    }
}
