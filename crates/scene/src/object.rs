//! Objects: the shapes of `[[objects]]` (all but meshes, which are
//! instanced from their files by the build), the keys each kind takes, and
//! the `transform` steps. No I/O.

use crate::check::{Ctx, Result, refuse_foreign, span_of, vec3_of};
use crate::format::{Num, ObjectDef, ObjectKind, Step};
use prism_geometry::glam::{Mat4, Vec3};
use prism_geometry::{Cone, Cuboid, Cylinder, Disk, Plane, Shape, Shear, Sphere, Transform, Triangle};
use std::ops::Range;
use toml::Spanned;

/// The shape of the object `d` of kind `kind` (at `ospan`), checked;
/// `None` for a mesh.
pub(crate) fn shape(
    ctx: &Ctx,
    d: &ObjectDef,
    kind: ObjectKind,
    ospan: &Range<usize>,
) -> Result<Option<Shape>> {
    let shape: Shape = match kind {
        ObjectKind::Sphere => {
            let center = ctx.opt_vec3(d.center.as_ref(), "sphere center", Vec3::ZERO)?;
            let r = required_num(ctx, &d.radius, ospan, "sphere", "radius")?;
            let radius = ctx.positive(r, "sphere radius")?;
            Sphere::new(center, radius).map_err(|e| ctx.geometry(ospan, e))?.into()
        }
        ObjectKind::Plane => {
            let point = ctx.opt_vec3(d.point.as_ref(), "plane point", Vec3::ZERO)?;
            let normal = ctx.opt_vec3(d.normal.as_ref(), "plane normal", Vec3::Y)?;
            let span = d.normal.as_ref().map_or_else(|| ospan.clone(), Spanned::span);
            Plane::new(point, normal).map_err(|e| ctx.geometry(&span, e))?.into()
        }
        ObjectKind::Cuboid => cuboid(ctx, d, ospan)?,
        ObjectKind::Cylinder | ObjectKind::Cone => {
            let name = kind.name();
            let base = ctx.opt_vec3(d.base.as_ref(), &format!("{name} base"), Vec3::ZERO)?;
            let r = required_num(ctx, &d.radius, ospan, name, "radius")?;
            let radius = ctx.positive(r, &format!("{name} radius"))?;
            let h = required_num(ctx, &d.height, ospan, name, "height")?;
            let height = ctx.positive(h, &format!("{name} height"))?;
            if kind == ObjectKind::Cone {
                Cone::new(base, radius, height).map_err(|e| ctx.geometry(ospan, e))?.into()
            } else {
                Cylinder::new(base, radius, height).map_err(|e| ctx.geometry(ospan, e))?.into()
            }
        }
        ObjectKind::Disk => {
            let center = ctx.opt_vec3(d.center.as_ref(), "disk center", Vec3::ZERO)?;
            let normal = ctx.opt_vec3(d.normal.as_ref(), "disk normal", Vec3::Y)?;
            let r = required_num(ctx, &d.radius, ospan, "disk", "radius")?;
            let radius = ctx.positive(r, "disk radius")?;
            let span = d.normal.as_ref().map_or_else(|| ospan.clone(), Spanned::span);
            Disk::new(center, normal, radius).map_err(|e| ctx.geometry(&span, e))?.into()
        }
        ObjectKind::Triangle => {
            let Some(v) = &d.vertices else {
                return Err(
                    ctx.invalid(ospan, "a triangle needs `vertices = [[x, y, z], [x, y, z], [x, y, z]]`")
                );
            };
            let mut pts = [Vec3::ZERO; 3];
            for (p, raw) in pts.iter_mut().zip(v.get_ref().iter()) {
                *p = vec3_of(&raw.0)
                    .ok_or_else(|| ctx.invalid(&v.span(), "triangle vertices must be finite numbers"))?;
            }
            Triangle::new(pts).map_err(|e| ctx.geometry(&v.span(), e))?.into()
        }
        ObjectKind::Mesh => return Ok(None),
    };
    Ok(Some(shape))
}

/// The number `n` that a `kind` requires as `key`.
fn required_num<'n>(
    ctx: &Ctx,
    n: &'n Option<Num>,
    span: &Range<usize>,
    kind: &str,
    key: &str,
) -> Result<&'n Num> {
    n.as_ref().ok_or_else(|| ctx.invalid(span, format!("a {kind} needs `{key}`")))
}

/// Refuses a key that belongs to another kind of object.
pub(crate) fn check_keys(ctx: &Ctx, d: &ObjectDef, kind: ObjectKind) -> Result<()> {
    let present = [
        ("center", span_of(&d.center)),
        ("radius", span_of(&d.radius)),
        ("point", span_of(&d.point)),
        ("normal", span_of(&d.normal)),
        ("min", span_of(&d.min)),
        ("max", span_of(&d.max)),
        ("size", span_of(&d.size)),
        ("base", span_of(&d.base)),
        ("height", span_of(&d.height)),
        ("vertices", span_of(&d.vertices)),
        ("path", span_of(&d.path)),
        ("normals", span_of(&d.normals)),
        ("crease_angle", span_of(&d.crease_angle)),
    ];
    let allowed = shape_keys(kind);
    refuse_foreign(ctx, &present, allowed, kind.name(), "material, transform, name")?;
    check_crease(ctx, d)
}

/// The keys of its own that an object of `kind` takes (besides `type`,
/// `material`, `transform` and `name`).
pub(crate) fn shape_keys(kind: ObjectKind) -> &'static [&'static str] {
    match kind {
        ObjectKind::Sphere => &["center", "radius"],
        ObjectKind::Plane => &["point", "normal"],
        ObjectKind::Cuboid => &["center", "size", "min", "max"],
        ObjectKind::Cylinder | ObjectKind::Cone => &["base", "radius", "height"],
        ObjectKind::Disk => &["center", "normal", "radius"],
        ObjectKind::Triangle => &["vertices"],
        ObjectKind::Mesh => &["path", "normals", "crease_angle"],
    }
}

/// `crease_angle`: degrees in `[0, 180]`, with `normals = "auto"` only.
fn check_crease(ctx: &Ctx, d: &ObjectDef) -> Result<()> {
    let Some(n) = &d.crease_angle else { return Ok(()) };
    if d.normals.as_ref().is_some_and(|m| *m.get_ref() != crate::format::NormalsDef::Auto) {
        return Err(
            ctx.invalid(&n.span(), "`crease_angle` applies to `normals = \"auto\"` (computed normals) only")
        );
    }
    let deg = ctx.non_negative(n, "crease_angle")?;
    if deg > 180.0 {
        return Err(ctx.invalid(&n.span(), format!("crease_angle must be at most 180 (degrees), got {deg}")));
    }
    Ok(())
}

/// A cuboid from `min` and `max`, or `size` and `center`.
fn cuboid(ctx: &Ctx, d: &ObjectDef, ospan: &Range<usize>) -> Result<Shape> {
    let cuboid = match (&d.min, &d.max, &d.size) {
        (Some(min), Some(max), None) => {
            if let Some(c) = &d.center {
                return Err(ctx.invalid(
                    &c.span(),
                    "a cuboid takes `min` and `max`, or `size` (and `center`), not both",
                ));
            }
            let (lo, hi) = (ctx.vec3(min, "cuboid min")?, ctx.vec3(max, "cuboid max")?);
            if !(hi - lo).cmpgt(Vec3::ZERO).all() {
                return Err(ctx.invalid(
                    &max.span(),
                    format!("cuboid max {hi} must be greater than min {lo} on every axis"),
                ));
            }
            Cuboid::new(lo, hi).map_err(|e| ctx.geometry(&max.span(), e))?
        }
        (None, None, Some(size)) => {
            let center = ctx.opt_vec3(d.center.as_ref(), "cuboid center", Vec3::ZERO)?;
            let s = vec3_of(&size.get_ref().0)
                .ok_or_else(|| ctx.invalid(&size.span(), "cuboid size must be finite"))?;
            if !(s.min_element() > 0.0) {
                return Err(ctx.invalid(
                    &size.span(),
                    format!("cuboid size must be greater than 0 on every axis, got {s}"),
                ));
            }
            Cuboid::from_center_size(center, s).map_err(|e| ctx.geometry(&size.span(), e))?
        }
        (min, max, Some(size)) if min.is_some() || max.is_some() => {
            return Err(ctx.invalid(
                &size.span(),
                "a cuboid takes `min` and `max`, or `size` (and `center`), not both",
            ));
        }
        (Some(one), None, None) | (None, Some(one), None) => {
            let (given, missing) = if d.min.is_some() { ("min", "max") } else { ("max", "min") };
            return Err(ctx.invalid(&one.span(), format!("a cuboid with `{given}` needs `{missing}` too")));
        }
        _ => {
            return Err(ctx.invalid(
                ospan,
                "a cuboid needs `size` (a number or [x, y, z], with an optional `center`), or both `min` and `max`",
            ));
        }
    };
    Ok(cuboid.into())
}

/// The product of the object's `transform` steps, checked step by step.
pub(crate) fn transform(ctx: &Ctx, d: &ObjectDef) -> Result<Transform> {
    let Some(steps) = &d.transform else { return Ok(Transform::IDENTITY) };
    let mut acc = Transform::IDENTITY;
    for step in steps.get_ref() {
        let span = step.get_ref().value_span();
        let bad = |what: &str| ctx.invalid(&span, format!("transform step: {what} must be finite numbers"));
        let f = |v: f64| v as f32;
        let t = match step.get_ref() {
            Step::Translate(v) => Transform::translate(vec3_of(v.get_ref()).ok_or_else(|| bad("translate"))?)
                .map_err(|e| ctx.geometry(&span, e))?,
            Step::RotateX(a) | Step::RotateY(a) | Step::RotateZ(a) => {
                let a = *a.get_ref();
                if !f(a).is_finite() {
                    return Err(bad("a rotation angle"));
                }
                let a = f(crate::check::within_a_turn(a));
                match step.get_ref() {
                    Step::RotateX(_) => Transform::rotate_x(a.to_radians()),
                    Step::RotateY(_) => Transform::rotate_y(a.to_radians()),
                    _ => Transform::rotate_z(a.to_radians()),
                }
            }
            Step::Rotate(r) => {
                let axis = vec3_of(&r.get_ref().axis).ok_or_else(|| bad("a rotation axis"))?;
                let deg = r.get_ref().degrees;
                if !f(deg).is_finite() {
                    return Err(bad("a rotation angle"));
                }
                let deg = f(crate::check::within_a_turn(deg));
                Transform::rotate_axis(axis, deg.to_radians()).map_err(|e| ctx.geometry(&span, e))?
            }
            Step::Scale(s) => {
                let s = vec3_of(&s.get_ref().0).ok_or_else(|| bad("scale"))?;
                if s.cmpeq(Vec3::ZERO).any() {
                    return Err(ctx.invalid(
                        &span,
                        format!(
                            "scale {s} has a zero factor; it would flatten the object (singular transform)"
                        ),
                    ));
                }
                Transform::scale(s).map_err(|e| ctx.geometry(&span, e))?
            }
            Step::Shear(s) | Step::ShearAngle(s) => {
                let angle = matches!(step.get_ref(), Step::ShearAngle(_));
                let s = s.get_ref();
                let raw = [s.xy, s.xz, s.yx, s.yz, s.zx, s.zy];
                let mut k = [0f32; 6];
                for (o, v) in k.iter_mut().zip(raw) {
                    let v = f(v);
                    if !v.is_finite() {
                        return Err(bad("shear factors"));
                    }
                    if angle && !(v.abs() < 90.0) {
                        return Err(ctx.invalid(
                            &span,
                            format!("shear angles must be between -90 and 90 degrees, got {v}"),
                        ));
                    }
                    *o = if angle { v.to_radians().tan() } else { v };
                }
                let [xy, xz, yx, yz, zx, zy] = k;
                Transform::shear(Shear { xy, xz, yx, yz, zx, zy }).map_err(|e| ctx.geometry(&span, e))?
            }
            Step::Matrix(rows) => {
                let mut cols = [[0f32; 4]; 4];
                for (r, row) in rows.get_ref().iter().enumerate() {
                    for (c, v) in row.0.iter().enumerate() {
                        let v = f(*v);
                        if !v.is_finite() {
                            return Err(bad("matrix entries"));
                        }
                        cols[c][r] = v;
                    }
                }
                Transform::try_from_mat4(Mat4::from_cols_array_2d(&cols))
                    .map_err(|e| ctx.geometry(&span, e))?
            }
        };
        acc = acc.then(&t);
    }
    // The product of invertible steps can still be numerically singular.
    Transform::try_from_affine(acc.matrix()).map_err(|e| ctx.geometry(&steps.span(), e))
}
