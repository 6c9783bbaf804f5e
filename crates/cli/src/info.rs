//! `prism info`: a plain-text description of a loaded scene.

use prism_geometry::glam::Vec3;
use prism_scene::LoadedScene;
use prism_shade::{AreaShape, Falloff, FogMode, LightKind, Projection};
use std::fmt::Write;
use std::path::Path;

fn v(p: Vec3) -> String {
    format!("({}, {}, {})", trim(p.x), trim(p.y), trim(p.z))
}

/// `x` short: three decimals from 0.001 to a million (more below 1, so
/// that four significant digits are kept: 0.0012), trailing zeros
/// dropped; beyond that range in scientific notation (`4e-4`, `1.235e7`),
/// so that a small intensity does not print as 0.
fn trim(x: f32) -> String {
    let zeros = |s: &str| s.trim_end_matches('0').trim_end_matches('.').to_owned();
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return if a == 0.0 { "0".into() } else { x.to_string() };
    }
    if (1e-3..1e6).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(3, 6) as usize;
        return zeros(&format!("{x:.decimals$}"));
    }
    let s = format!("{x:.3e}");
    match s.split_once('e') {
        Some((mantissa, exp)) => format!("{}e{exp}", zeros(mantissa)),
        None => s,
    }
}

/// The description printed by `prism info`.
pub fn describe(loaded: &LoadedScene, path: &Path) -> String {
    let i = &loaded.info;
    let mut s = String::new();
    let _ = writeln!(s, "scene      {}", prism_scene::scene_name(path));
    let aa = &loaded.settings.antialias;
    let adaptive = aa.adaptive.map_or_else(String::new, |t| format!(", adaptive {}", trim(t)));
    let _ = writeln!(
        s,
        "image      {}×{}, {} spp, {} filter{adaptive}, max depth {}, min contribution {}",
        i.width,
        i.height,
        i.spp,
        aa.filter.name(),
        i.max_depth,
        trim(i.min_contribution)
    );
    let c = &i.camera;
    let projection = match c.projection() {
        Projection::Perspective => String::new(),
        Projection::Orthographic => ", orthographic".to_owned(),
    };
    let lens = if c.aperture() > 0.0 {
        format!(", lens aperture {} focused at {}", trim(c.aperture()), trim(c.focus_distance()))
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "camera     at {} looking at {}, up {}, vertical fov {}°{projection}{lens}",
        v(c.position()),
        v(c.look_at()),
        v(c.up()),
        trim(c.vfov_deg())
    );
    let kinds: Vec<String> = i.objects_by_kind.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let _ = writeln!(
        s,
        "objects    {}{}",
        i.objects,
        if kinds.is_empty() { String::new() } else { format!(": {}", kinds.join(", ")) }
    );
    for m in &i.meshes {
        let _ = writeln!(
            s,
            "mesh       {}: {} model{} ({} closed), {} triangles, {} instance{}",
            m.path.display(),
            m.models,
            if m.models == 1 { "" } else { "s" },
            m.closed_models,
            m.triangles,
            m.instances,
            if m.instances == 1 { "" } else { "s" }
        );
    }
    let _ = writeln!(s, "triangles  {} stored, {} instanced", i.stored_triangles, i.instanced_triangles);
    let _ = writeln!(s, "materials  {}: {}", i.materials.len(), i.materials.join(", "));
    let _ = writeln!(s, "lights     {}", i.lights.len());
    for l in &i.lights {
        let place = match l.kind {
            LightKind::Point { position, falloff } => format!("at {}{}", v(position), falloff_text(falloff)),
            LightKind::Spot { position, direction, falloff, .. } => {
                format!("spot at {}, toward {}{}", v(position), v(direction), falloff_text(falloff))
            }
            LightKind::Directional { direction } => format!("directional toward {}", v(direction)),
            LightKind::Area(a) => {
                let shape = match a.shape {
                    AreaShape::Quad { corner, .. } => format!("quad at {}", v(corner)),
                    AreaShape::Disk { center, .. } => format!("disk at {}", v(center)),
                    AreaShape::Sphere { center, .. } => format!("sphere at {}", v(center)),
                };
                format!("{shape}, {} samples", a.samples)
            }
        };
        let _ = writeln!(s, "           {place}, colour {} × {}", v(l.color), trim(l.intensity));
    }
    match &i.fog {
        None => {
            let _ = writeln!(s, "fog        none");
        }
        Some(f) => {
            let mode = match f.mode {
                FogMode::Linear { start, end } => format!("linear from {} to {}", trim(start), trim(end)),
                FogMode::LinearDistance { start, end } => {
                    format!("linear by distance from {} to {}", trim(start), trim(end))
                }
                FogMode::Exponential { density } => format!("exponential, density {}", trim(density)),
                FogMode::ExponentialSquared { density } => {
                    format!("exponential squared, density {}", trim(density))
                }
            };
            let _ = writeln!(
                s,
                "fog        {mode}, colour {}, {}",
                v(f.color),
                if loaded.settings.fog { "on" } else { "off" }
            );
        }
    }
    if i.bounds.is_empty() {
        let _ = writeln!(s, "bounds     empty (no bounded objects)");
    } else {
        let _ = writeln!(s, "bounds     {} to {} (planes excluded)", v(i.bounds.min), v(i.bounds.max));
    }
    if !loaded.aovs.is_empty() {
        let names: Vec<&str> = loaded.aovs.iter().map(|a| a.name()).collect();
        let _ = writeln!(
            s,
            "aov        {}{}",
            names.join(", "),
            if loaded.aov_preview { ", with PNG previews" } else { "" }
        );
    }
    let _ = writeln!(
        s,
        "inputs     {} file{}",
        loaded.inputs.len(),
        if loaded.inputs.len() == 1 { "" } else { "s" }
    );
    s
}

/// `x` as a JSON number with its shortest decimal form (`0.1`, not
/// `0.10000000149011612`); `null` if not finite.
pub(crate) fn num(x: f32) -> serde_json::Value {
    x.to_string().parse::<f64>().ok().filter(|v| v.is_finite()).map_or(serde_json::Value::Null, Into::into)
}

fn arr(p: Vec3) -> serde_json::Value {
    serde_json::json!([num(p.x), num(p.y), num(p.z)])
}

/// The description as JSON, for scripts (`prism info --json`): the same
/// facts as [`describe`] as numbers and lists, plus the acceleration
/// structure's size and build time. Keys are documented in the README.
pub fn to_json(loaded: &LoadedScene, path: &Path) -> serde_json::Value {
    use serde_json::json;
    let i = &loaded.info;
    let c = &i.camera;
    let bvh = loaded.scene.accel.stats();
    let fog = i.fog.as_ref().map(|f| {
        let (mode, params) = match f.mode {
            FogMode::Linear { start, end } => {
                ("linear", json!({ "start": num(start), "end": num(end), "measure": "depth" }))
            }
            FogMode::LinearDistance { start, end } => {
                ("linear", json!({ "start": num(start), "end": num(end), "measure": "distance" }))
            }
            FogMode::Exponential { density } => ("exponential", json!({ "density": num(density) })),
            FogMode::ExponentialSquared { density } => {
                ("exponential_squared", json!({ "density": num(density) }))
            }
        };
        json!({ "mode": mode, "params": params, "color": arr(f.color), "enabled": loaded.settings.fog })
    });
    json!({
        "scene": prism_scene::scene_name(path),
        "image": {
            "width": i.width,
            "height": i.height,
            "spp": i.spp,
            "filter": loaded.settings.antialias.filter.name(),
            "adaptive": loaded.settings.antialias.adaptive.map(num),
            "max_depth": i.max_depth,
            "min_contribution": num(i.min_contribution),
        },
        "camera": {
            "position": arr(c.position()),
            "look_at": arr(c.look_at()),
            "up": arr(c.up()),
            "vfov_deg": num(c.vfov_deg()),
            "projection": match c.projection() {
                Projection::Perspective => "perspective",
                Projection::Orthographic => "orthographic",
            },
            "aperture": num(c.aperture()),
            "focus_distance": num(c.focus_distance()),
        },
        "objects": i.objects,
        "objects_by_kind": i.objects_by_kind,
        "meshes": i.meshes.iter().map(|m| json!({
            "path": m.path.display().to_string(),
            "models": m.models,
            "triangles": m.triangles,
            "instances": m.instances,
            "closed_models": m.closed_models,
        })).collect::<Vec<_>>(),
        "triangles": { "stored": i.stored_triangles, "instanced": i.instanced_triangles },
        "materials": i.materials,
        "lights": i.lights.iter().map(light_json).collect::<Vec<_>>(),
        "fog": fog,
        "bounds": (!i.bounds.is_empty()).then(|| json!({ "min": arr(i.bounds.min), "max": arr(i.bounds.max) })),
        "bvh": {
            "nodes": bvh.bvh_nodes,
            "bytes": bvh.bvh_bytes,
            "build_seconds": bvh.build_seconds,
            "unbounded_objects": bvh.unbounded_objects,
        },
        "aov": loaded.aovs.iter().map(|a| a.name()).collect::<Vec<_>>(),
        "aov_preview": loaded.aov_preview,
        "inputs": loaded.inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "warnings": loaded.warnings,
    })
}

/// One light for `info --json`: `type`, its placement keys as in the
/// scene file, `color` and `intensity`.
fn light_json(l: &prism_shade::Light) -> serde_json::Value {
    use serde_json::json;
    let falloff = |f: Falloff| match f {
        Falloff::None => "none",
        Falloff::InverseSquare => "inverse_square",
    };
    let mut v = match l.kind {
        LightKind::Point { position, falloff: f } => {
            json!({ "type": "point", "position": arr(position), "falloff": falloff(f) })
        }
        LightKind::Spot { position, direction, cos_inner, cos_outer, falloff: f } => json!({
            "type": "spot",
            "position": arr(position),
            "direction": arr(direction),
            "inner_angle": num(cos_inner.clamp(-1.0, 1.0).acos().to_degrees()),
            "outer_angle": num(cos_outer.clamp(-1.0, 1.0).acos().to_degrees()),
            "falloff": falloff(f),
        }),
        LightKind::Directional { direction } => json!({ "type": "directional", "direction": arr(direction) }),
        LightKind::Area(a) => {
            let mut v = match a.shape {
                AreaShape::Quad { corner, edge_u, edge_v } => json!({
                    "type": "quad", "corner": arr(corner), "edge_u": arr(edge_u), "edge_v": arr(edge_v),
                }),
                AreaShape::Disk { center, normal, radius } => json!({
                    "type": "disk", "center": arr(center), "normal": arr(normal), "radius": num(radius),
                }),
                AreaShape::Sphere { center, radius } => {
                    json!({ "type": "sphere", "center": arr(center), "radius": num(radius) })
                }
            };
            v["samples"] = a.samples.into();
            v["two_sided"] = a.two_sided.into();
            v
        }
    };
    v["color"] = arr(l.color);
    v["intensity"] = num(l.intensity);
    v
}

/// ", inverse-square" for a light that dims with distance.
fn falloff_text(f: Falloff) -> &'static str {
    match f {
        Falloff::None => "",
        Falloff::InverseSquare => ", inverse-square",
    }
}

#[cfg(test)]
mod tests {
    use super::trim;

    #[test]
    fn numbers_keep_their_significant_digits() {
        for (x, want) in [
            (0.0, "0"),
            (-0.0, "0"),
            (1.0, "1"),
            (-2.5, "-2.5"),
            (12.345, "12.345"),
            (0.0012, "0.0012"),
            (0.5, "0.5"),
            (1234.5, "1234.5"),
            // A dim light's intensity printed as "× 0".
            (0.0004, "4e-4"),
            (1e-30, "1e-30"),
            (-3.25e-5, "-3.25e-5"),
            (12_345_678.0, "1.235e7"),
            (f32::INFINITY, "inf"),
        ] {
            assert_eq!(trim(x), want, "{x}");
        }
    }
}
