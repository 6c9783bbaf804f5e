//! `[[lights]]`: point, spot, directional and area lights (quad, disk,
//! sphere), the keys each type takes, checked with their places. No I/O.

use crate::check::{Ctx, Result, refuse_foreign, span_of};
use crate::format::{FalloffDef, LightDef, LightKindDef, Num, V3};
use prism_geometry::glam::Vec3;
use prism_shade::{AreaLight, AreaShape, Falloff, Light, LightKind};
use std::ops::Range;
use toml::Spanned;

/// Shadow rays per shading point of an area light that does not say.
pub(crate) const DEFAULT_AREA_SAMPLES: u32 = 16;
/// The most shadow rays per shading point an area light may ask for.
pub(crate) const MAX_AREA_SAMPLES: u64 = 4096;

impl LightKindDef {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Self::Point => "point",
            Self::Spot => "spot",
            Self::Directional => "directional",
            Self::Quad => "quad",
            Self::Disk => "disk",
            Self::Sphere => "sphere",
        }
    }
}

/// The light of the `[[lights]]` table `l`, checked.
pub(crate) fn light(ctx: &Ctx, l: &Spanned<LightDef>) -> Result<Light> {
    let d = l.get_ref();
    let span = l.span();
    let kind = d.kind.as_ref().map_or(LightKindDef::Point, |k| *k.get_ref());
    check_keys(ctx, d, kind)?;
    let name = kind.name();
    let color = match (&d.color, &d.radiance) {
        (Some(_), Some(r)) => {
            return Err(ctx.invalid(&r.span(), "give `color` or `radiance`, not both (they are the same)"));
        }
        (Some(c), None) | (None, Some(c)) => ctx.light_rgb(c, &format!("{name} light colour"))?,
        (None, None) => Vec3::ONE,
    };
    let intensity = ctx.opt_num(d.intensity.as_ref(), 1.0, |n| ctx.non_negative(n, "light intensity"))?;
    let falloff = match d.falloff.as_ref().map(|f| *f.get_ref()) {
        None | Some(FalloffDef::None) => Falloff::None,
        Some(FalloffDef::InverseSquare) => Falloff::InverseSquare,
    };
    let need = |v: &Option<V3>, key: &str| -> Result<Vec3> {
        match v {
            Some(v) => ctx.vec3(v, &format!("{name} light {key}")),
            None => Err(ctx.invalid(&span, format!("a {name} light needs `{key}`"))),
        }
    };
    let direction = |v: &Option<V3>| -> Result<Vec3> {
        let dir = need(v, "direction")?;
        prism_geometry::unit(dir).ok_or_else(|| {
            ctx.invalid(
                &span_of(v).unwrap_or(span.clone()),
                format!("{name} light direction must not be zero"),
            )
        })
    };
    let kind = match kind {
        LightKindDef::Point => LightKind::Point { position: need(&d.position, "position")?, falloff },
        LightKindDef::Spot => {
            spot(ctx, d, &span, need(&d.position, "position")?, direction(&d.direction)?, falloff)?
        }
        LightKindDef::Directional => LightKind::Directional { direction: direction(&d.direction)? },
        LightKindDef::Quad | LightKindDef::Disk | LightKindDef::Sphere => {
            LightKind::Area(area(ctx, d, kind, &span)?)
        }
    };
    // Each finite alone, the product can still overflow: the light would
    // be infinite, and what it lights black (infinity times zero).
    if !(color * intensity).is_finite() {
        let at = d.intensity.as_ref().map_or(span, Spanned::span);
        return Err(ctx.invalid(
            &at,
            format!(
                "{name} light is too bright (color × intensity overflows: beyond {:.1e}, the largest finite value); \
                 lower the intensity or the colour",
                f32::MAX
            ),
        ));
    }
    Ok(Light { kind, color, intensity })
}

/// A spot light: `outer_angle` required, `inner_angle` (default: the
/// outer one, a hard edge) no wider; both half-angles from the axis in
/// degrees, below 90.
fn spot(
    ctx: &Ctx,
    d: &LightDef,
    span: &Range<usize>,
    position: Vec3,
    direction: Vec3,
    falloff: Falloff,
) -> Result<LightKind> {
    let angle = |n: &Num, key: &str| -> Result<f32> {
        let a = ctx.finite(n, &format!("spot light {key}"))?;
        if (0.0..90.0).contains(&a) {
            Ok(a)
        } else {
            Err(ctx.invalid(
                &n.span(),
                format!("spot light {key} is a half-angle in degrees from the axis and must be in [0, 90), got {a}"),
            ))
        }
    };
    let Some(outer_n) = &d.outer_angle else {
        return Err(ctx.invalid(span, "a spot light needs `outer_angle` (degrees from its axis)"));
    };
    let outer = angle(outer_n, "outer_angle")?;
    if outer == 0.0 {
        // A cone of no width: no point is inside it.
        return Err(ctx.invalid(
            &outer_n.span(),
            "spot light outer_angle 0 lights nothing; give its cone's half-angle in degrees (0 < outer_angle < 90)",
        ));
    }
    let inner = d.inner_angle.as_ref().map_or(Ok(outer), |n| angle(n, "inner_angle"))?;
    if outer < inner {
        return Err(ctx.invalid(
            &outer_n.span(),
            format!("spot light outer_angle ({outer}) must not be smaller than inner_angle ({inner})"),
        ));
    }
    Ok(LightKind::Spot {
        position,
        direction,
        cos_inner: inner.to_radians().cos(),
        cos_outer: outer.to_radians().cos(),
        falloff,
    })
}

/// An area light's shape and sampling keys.
fn area(ctx: &Ctx, d: &LightDef, kind: LightKindDef, span: &Range<usize>) -> Result<AreaLight> {
    let name = kind.name();
    let need_vec = |v: &Option<V3>, key: &str| -> Result<(Vec3, Range<usize>)> {
        match v {
            Some(v) => Ok((ctx.vec3(v, &format!("{name} light {key}"))?, v.span())),
            None => Err(ctx.invalid(span, format!("a {name} light needs `{key}`"))),
        }
    };
    let radius = || -> Result<f32> {
        let Some(r) = &d.radius else {
            return Err(ctx.invalid(span, format!("a {name} light needs `radius`")));
        };
        ctx.positive(r, &format!("{name} light radius (a light of zero area is refused)"))
    };
    let shape = match kind {
        LightKindDef::Quad => {
            let (corner, _) = need_vec(&d.corner, "corner")?;
            let (edge_u, _) = need_vec(&d.edge_u, "edge_u")?;
            let (edge_v, v_span) = need_vec(&d.edge_v, "edge_v")?;
            let area = prism_geometry::length(edge_u.cross(edge_v));
            if area.is_infinite() {
                return Err(ctx.invalid(
                    &v_span,
                    format!("a quad light's area overflows 32-bit floats (edges {edge_u} and {edge_v}); use shorter edges"),
                ));
            }
            if !(area > 0.0) {
                return Err(ctx.invalid(
                    &v_span,
                    "a quad light has zero area: edge_u and edge_v must be non-zero and not parallel",
                ));
            }
            AreaShape::Quad { corner, edge_u, edge_v }
        }
        LightKindDef::Disk => {
            let center = ctx.opt_vec3(d.center.as_ref(), "disk light center", Vec3::ZERO)?;
            let (normal, n_span) = need_vec(&d.normal, "normal")?;
            let normal = prism_geometry::unit(normal)
                .ok_or_else(|| ctx.invalid(&n_span, "disk light normal must not be zero"))?;
            AreaShape::Disk { center, normal, radius: radius()? }
        }
        _ => {
            let center = ctx.opt_vec3(d.center.as_ref(), "sphere light center", Vec3::ZERO)?;
            AreaShape::Sphere { center, radius: radius()? }
        }
    };
    let samples = match &d.samples {
        Some(n) if (1..=MAX_AREA_SAMPLES).contains(n.get_ref()) => *n.get_ref() as u32,
        Some(n) => {
            return Err(ctx.invalid(
                &n.span(),
                format!("light samples must be between 1 and {MAX_AREA_SAMPLES}, got {}", n.get_ref()),
            ));
        }
        None => DEFAULT_AREA_SAMPLES,
    };
    Ok(AreaLight {
        shape,
        samples,
        two_sided: d.two_sided.as_ref().is_some_and(|b| *b.get_ref()),
        adaptive: d.adaptive.as_ref().is_none_or(|b| *b.get_ref()),
    })
}

/// Refuses a key that belongs to another type of light.
fn check_keys(ctx: &Ctx, d: &LightDef, kind: LightKindDef) -> Result<()> {
    let present = [
        ("position", span_of(&d.position)),
        ("falloff", span_of(&d.falloff)),
        ("direction", span_of(&d.direction)),
        ("inner_angle", span_of(&d.inner_angle)),
        ("outer_angle", span_of(&d.outer_angle)),
        ("corner", span_of(&d.corner)),
        ("edge_u", span_of(&d.edge_u)),
        ("edge_v", span_of(&d.edge_v)),
        ("center", span_of(&d.center)),
        ("normal", span_of(&d.normal)),
        ("radius", span_of(&d.radius)),
        ("samples", span_of(&d.samples)),
        ("two_sided", span_of(&d.two_sided)),
        ("adaptive", span_of(&d.adaptive)),
    ];
    let allowed = light_keys(kind);
    refuse_foreign(ctx, &present, allowed, &format!("{} light", kind.name()), "color or radiance, intensity")
}

/// The keys of its own that a light of `kind` takes (besides `type`,
/// `color`/`radiance` and `intensity`).
pub(crate) fn light_keys(kind: LightKindDef) -> &'static [&'static str] {
    match kind {
        LightKindDef::Point => &["position", "falloff"],
        LightKindDef::Spot => &["position", "direction", "inner_angle", "outer_angle", "falloff"],
        LightKindDef::Directional => &["direction"],
        LightKindDef::Quad => &["corner", "edge_u", "edge_v", "samples", "two_sided", "adaptive"],
        LightKindDef::Disk => &["center", "normal", "radius", "samples", "two_sided", "adaptive"],
        LightKindDef::Sphere => &["center", "radius", "samples", "adaptive"],
    }
}
