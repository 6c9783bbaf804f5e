//! What a render looks through: the camera (the file's `[camera]` or a
//! framing camera, with the camera overrides applied) and the `[fog]`
//! table, checked.

use crate::check::{Ctx, Result};
use crate::error::SceneError;
use crate::format::{BackgroundDef, CameraDef, FogDef, FogMeasureDef, FogModeDef, ProjectionDef, SceneFile};
use crate::{CameraName, Overrides};
use prism_geometry::Aabb;
use prism_geometry::glam::Vec3;
use prism_shade::{Camera, Environment, Fog, FogMode, ImageTexture, Projection};
use std::ops::Range;
use std::sync::Arc;
use toml::Spanned;

/// The camera a scene describes, before the overrides.
pub(crate) enum CameraSource<'a> {
    /// A scene file's `[camera]` table, checked here.
    File(&'a Spanned<CameraDef>),
    /// A camera computed by the loader (an OBJ file as a scene): finite,
    /// `eye != look_at`, `up` across the view; not written in any file.
    Framed { eye: Vec3, look_at: Vec3, fov: f32, up: Vec3 },
}

/// The vertical field of view of a camera that does not give one.
const DEFAULT_FOV: f32 = 45.0;

/// The camera of `source` with the overrides of `ov` for an image of
/// `width × height`. Errors in an override name its flag; errors in the
/// file's values point at them.
pub(crate) fn camera(
    ctx: &Ctx,
    source: &CameraSource,
    ov: &Overrides,
    width: u32,
    height: u32,
) -> Result<Camera> {
    let flag_vec3 = |v: Vec3, flag: &'static str| {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SceneError::Option { flag, message: format!("X,Y,Z must be finite numbers, got {v}") })
        }
    };
    let file = match source {
        CameraSource::File(c) => Some(c.get_ref()),
        CameraSource::Framed { .. } => None,
    };
    let (position, look_at) = match source {
        CameraSource::File(c) => {
            let d = c.get_ref();
            let position = match ov.camera_pos {
                Some(p) => flag_vec3(p, "--camera-pos")?,
                None => ctx.vec3(&d.position, "camera position")?,
            };
            let look_at = match ov.look_at {
                Some(p) => flag_vec3(p, "--look-at")?,
                None => ctx.vec3(&d.look_at, "camera look_at")?,
            };
            (position, look_at)
        }
        CameraSource::Framed { eye, look_at, .. } => (
            ov.camera_pos.map_or(Ok(*eye), |p| flag_vec3(p, "--camera-pos"))?,
            ov.look_at.map_or(Ok(*look_at), |p| flag_vec3(p, "--look-at"))?,
        ),
    };
    let up = match (ov.up, file.and_then(|d| d.up.as_ref())) {
        (Some(u), _) => flag_vec3(u, "--up")?,
        (None, Some(u)) => ctx.vec3(u, "camera up")?,
        (None, None) => match source {
            CameraSource::Framed { up, .. } => *up,
            CameraSource::File(_) => Vec3::Y,
        },
    };
    let fov = match (ov.fov, source) {
        (Some(f), _) => {
            if !(f.is_finite() && f > 0.0 && f < 180.0) {
                return Err(SceneError::Option {
                    flag: "--fov",
                    message: format!(
                        "the vertical field of view in degrees must be between 0 and 180 (exclusive), got {f}"
                    ),
                });
            }
            f
        }
        (None, CameraSource::Framed { fov, .. }) => *fov,
        (None, CameraSource::File(c)) => match &c.get_ref().fov {
            Some(n) => {
                let f = ctx.finite(n, "camera fov")?;
                if !(f > 0.0 && f < 180.0) {
                    return Err(ctx.invalid(
                        &n.span(),
                        format!("camera fov is the vertical field of view in degrees and must be between 0 and 180 (exclusive), got {f}"),
                    ));
                }
                f
            }
            None => DEFAULT_FOV,
        },
    };
    // Where a problem of the file's camera is: the table (or a key of it);
    // a framed camera is in no file.
    let table: Option<Range<usize>> = match source {
        CameraSource::File(c) => Some(c.span()),
        CameraSource::Framed { .. } => None,
    };
    // The flag to blame when the direction or up is unusable: the one
    // given, if any.
    let moved = if ov.camera_pos.is_some() {
        Some("--camera-pos")
    } else if ov.look_at.is_some() {
        Some("--look-at")
    } else {
        None
    };
    let Some(f) = prism_geometry::unit_between(position, look_at) else {
        return Err(match moved {
            Some(flag) => SceneError::Option {
                flag,
                message: format!(
                    "the camera position {position} and the look-at point {look_at} must differ"
                ),
            },
            // Told at the camera's table, as it is about two of its keys
            // (a `--set` of either is named there).
            None => SceneError::Invalid {
                location: ctx.place(table.as_ref().or(file.map(|d| d.look_at.span()).as_ref())),
                message: format!("camera look_at {look_at} must differ from the camera position {position}"),
            },
        });
    };
    if prism_geometry::unit(up).is_none_or(|u| f.cross(u).length() < 1e-6) {
        let message = format!(
            "camera up {up} is zero or parallel to the view direction {f}; choose an up vector across it"
        );
        return Err(match (ov.up.map(|_| "--up").or(moved), file.and_then(|d| d.up.as_ref())) {
            (Some(flag), _) => SceneError::Option {
                flag,
                message: if flag == "--up" { message } else { format!("{message} (with --up)") },
            },
            (None, Some(u)) => ctx.invalid(&u.span(), message),
            (None, None) => SceneError::Invalid { location: ctx.place(table.as_ref()), message },
        });
    }
    let camera = Camera::new(position, look_at, up, fov, width, height).map_err(|e| {
        if ov.camera_pos.is_some() || ov.look_at.is_some() || ov.up.is_some() || ov.fov.is_some() {
            SceneError::Option { flag: "--camera-pos/--look-at/--up/--fov", message: e.to_string() }
        } else {
            SceneError::Invalid { location: ctx.place(table.as_ref()), message: e.to_string() }
        }
    })?;
    match file {
        Some(d) => lens(ctx, d, camera),
        None => Ok(camera),
    }
}

/// `camera` with the file's projection, aperture and focus distance.
fn lens(ctx: &Ctx, d: &CameraDef, camera: Camera) -> Result<Camera> {
    let camera = match d.projection.as_ref().map(|p| *p.get_ref()) {
        Some(ProjectionDef::Orthographic) => camera.with_projection(Projection::Orthographic),
        None | Some(ProjectionDef::Perspective) => camera,
    };
    let (aperture, focus) = lens_values(ctx, d)?;
    let focus = focus.unwrap_or(camera.focus_distance());
    let place = d.focus_distance.as_ref().or(d.aperture.as_ref()).map(Spanned::span);
    camera
        .with_lens(aperture, focus)
        .map_err(|e| SceneError::Invalid { location: ctx.place(place.as_ref()), message: e.to_string() })
}

/// A camera's `aperture` (default 0) and `focus_distance`, checked.
fn lens_values(ctx: &Ctx, d: &CameraDef) -> Result<(f32, Option<f32>)> {
    let aperture = ctx.opt_num(d.aperture.as_ref(), 0.0, |n| ctx.non_negative(n, "camera aperture"))?;
    let focus = d.focus_distance.as_ref().map(|n| ctx.positive(n, "camera focus_distance")).transpose()?;
    Ok((aperture, focus))
}

/// The camera a render uses: the one `--camera NAME` names, else the
/// first of `[camera]` and `[[cameras]]`. Every `[[cameras]]` entry has a
/// name, and no two cameras share one.
pub(crate) fn choose_camera<'f>(
    ctx: &Ctx,
    file: &'f SceneFile,
    name: Option<&CameraName>,
) -> Result<&'f Spanned<CameraDef>> {
    let all: Vec<&Spanned<CameraDef>> = file.camera.iter().chain(file.cameras.iter()).collect();
    let mut names: Vec<&str> = Vec::with_capacity(all.len());
    for c in &file.cameras {
        if c.get_ref().name.is_none() {
            return Err(ctx.invalid(&c.span(), "a camera in [[cameras]] needs a `name` (for --camera NAME)"));
        }
    }
    for c in &all {
        // Every camera's lens is checked, chosen or not.
        lens_values(ctx, c.get_ref())?;
        if let Some(n) = &c.get_ref().name {
            // A name `--camera` can give.
            CameraName::new(n.get_ref())
                .map_err(|e| ctx.invalid(&n.span(), format!("{e}: `--camera` could not choose it")))?;
            if names.contains(&n.get_ref().as_str()) {
                return Err(
                    ctx.invalid(&n.span(), format!("there is already a camera named `{}`", n.get_ref()))
                );
            }
            names.push(n.get_ref());
        }
    }
    let chosen = match name {
        None => all.first().copied().ok_or_else(|| {
            ctx.invalid_file("missing [camera] table (position and look_at are required), or [[cameras]]")
        })?,
        Some(wanted) => find_camera(&all, &names, wanted)?,
    };
    // Every other camera is checked too, as `--camera` would find it: a
    // scene that loads has no camera that fails when chosen. (The chosen
    // one is checked with the overrides, by [`camera`].)
    for c in all.iter().filter(|c| !std::ptr::eq(**c, chosen)) {
        camera(ctx, &CameraSource::File(c), &Overrides::default(), 1, 1)?;
    }
    Ok(chosen)
}

/// The camera of `all` named `wanted` (`names`: every camera's name).
fn find_camera<'f>(
    all: &[&'f Spanned<CameraDef>],
    names: &[&str],
    wanted: &CameraName,
) -> Result<&'f Spanned<CameraDef>> {
    all.iter()
        .find(|c| c.get_ref().name.as_ref().is_some_and(|n| n.get_ref() == wanted.as_str()))
        .copied()
        .ok_or_else(|| SceneError::Option {
            flag: "--camera",
            message: if names.is_empty() {
                format!("the scene has no camera named `{wanted}`: none of its cameras has a name")
            } else {
                match prism_shade::closest(wanted.as_str(), names) {
                    Some(near) => format!(
                        "the scene has no camera named `{wanted}`; did you mean `{near}`? (its cameras are: {})",
                        names.join(", ")
                    ),
                    None => format!("the scene has no camera named `{wanted}`; its cameras are: {}", names.join(", ")),
                }
            },
        })
}

/// The environment image of `[render] background`, if it names one
/// (`image` gives the image read for its path).
pub(crate) fn environment(
    ctx: &Ctx,
    bg: &BackgroundDef,
    image: &mut dyn FnMut(&Spanned<String>) -> Result<Arc<ImageTexture>>,
) -> Result<Option<Environment>> {
    let BackgroundDef::Image(e) = bg else { return Ok(None) };
    let rotation_deg = ctx.opt_num(e.rotation.as_ref(), 0.0, |n| {
        ctx.finite(n, "background rotation").map(|_| crate::check::within_a_turn(*n.get_ref()) as f32)
    })?;
    let image = image(&e.image)?;
    crate::check::note_unusable_texels(ctx, &e.image.span(), &image);
    Ok(Some(Environment { image, rotation_deg }))
}

/// The fog of a `[fog]` table, checked: the fog's medium, and whether the
/// file turns it on (`enabled`, default on). A table of `enabled` alone
/// gives no medium (the build then adds the default one, as `--fog` does
/// without `[fog]`).
pub(crate) fn fog(ctx: &Ctx, f: &Spanned<FogDef>) -> Result<(Option<Fog>, bool)> {
    let d = f.get_ref();
    let on = d.enabled.unwrap_or(true);
    let FogDef { mode, measure, start, end, density, color, enabled } = d;
    // `enabled` alone; an empty table is still linear fog missing its `end`.
    if enabled.is_some()
        && mode.is_none()
        && measure.is_none()
        && start.is_none()
        && end.is_none()
        && density.is_none()
        && color.is_none()
    {
        return Ok((None, on));
    }
    let mode = d.mode.as_ref().map_or(FogModeDef::Linear, |m| *m.get_ref());
    let color = ctx.opt_color(d.color.as_ref(), "fog color", Vec3::ONE)?;
    let mode = match mode {
        FogModeDef::Linear => {
            if let Some(n) = &d.density {
                return Err(ctx.invalid(
                    &n.span(),
                    "`density` belongs to exponential fog; linear fog takes `start` and `end`",
                ));
            }
            let start = ctx.opt_num(d.start.as_ref(), 0.0, |n| ctx.non_negative(n, "fog start"))?;
            let Some(end_n) = &d.end else {
                return Err(
                    ctx.invalid(&f.span(), "linear fog needs `end`, the distance where the fog is total")
                );
            };
            let end = ctx.finite(end_n, "fog end")?;
            if !(end > start) {
                let written = (*end_n.get_ref(), d.start.as_ref().map_or(0.0, |n| *n.get_ref()));
                return Err(ctx.invalid(
                    &end_n.span(),
                    if written.0 > written.1 {
                        // Apart as written, equal once rounded.
                        let text = |v: f64| {
                            if v == 0.0 || (1e-4..1e16).contains(&v.abs()) { v.to_string() } else { format!("{v:e}") }
                        };
                        format!(
                            "fog end ({}) must be greater than fog start ({}) in single precision, which prism computes in: both are {end} there",
                            text(written.0),
                            text(written.1)
                        )
                    } else {
                        format!("fog end ({end}) must be greater than fog start ({start})")
                    },
                ));
            }
            match d.measure.as_ref().map(|m| *m.get_ref()) {
                Some(FogMeasureDef::Distance) => FogMode::LinearDistance { start, end },
                Some(FogMeasureDef::Depth) | None => FogMode::Linear { start, end },
            }
        }
        FogModeDef::Exponential | FogModeDef::ExponentialSquared => {
            if let Some(m) = &d.measure {
                return Err(ctx.invalid(
                    &m.span(),
                    "`measure` belongs to linear fog; exponential fog is measured along the ray",
                ));
            }
            if let Some(n) = d.start.as_ref().or(d.end.as_ref()) {
                return Err(ctx.invalid(
                    &n.span(),
                    "`start` and `end` belong to linear fog; exponential fog takes `density`",
                ));
            }
            let Some(n) = &d.density else {
                return Err(ctx.invalid(&f.span(), "exponential fog needs `density` (per scene unit)"));
            };
            let density = ctx.positive(n, "fog density")?;
            if mode == FogModeDef::Exponential {
                FogMode::Exponential { density }
            } else {
                FogMode::ExponentialSquared { density }
            }
        }
    };
    Ok((Some(Fog { color, mode }), on))
}

/// The end of the fog `--fog` adds to a scene without `[fog]`: 1.5 times
/// the distance from `eye` to the farthest corner of `bounds`; where the
/// bounds are empty or infinite (a scene of planes alone), 3 times the
/// distance from `eye` to `look_at`, so that the fog scales with the scene
/// as the rest of the picture does (it was a fixed 100).
pub(crate) fn default_fog_end(eye: Vec3, look_at: Vec3, bounds: Aabb) -> f32 {
    let far = if bounds.is_empty() || !bounds.is_finite() {
        // Along the unit direction: the squared length under- or
        // overflows for points under 1e-19 or over 1.8e19 apart.
        let d = look_at - eye;
        2.0 * prism_geometry::unit(d).map_or(0.0, |u| u.dot(d))
    } else {
        bounds.corners().iter().map(|c| c.distance(eye)).fold(0.0_f32, f32::max)
    };
    if far.is_finite() && far > 0.0 { (1.5 * far).min(f32::MAX) } else { f32::MAX }
}
