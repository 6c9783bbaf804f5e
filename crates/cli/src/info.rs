//! `prism info`: a plain-text description of a loaded scene.

use prism_geometry::glam::Vec3;
use prism_scene::LoadedScene;
use prism_shade::{AreaShape, Falloff, FogMode, LightKind};
use std::fmt::Write;
use std::path::Path;

fn v(p: Vec3) -> String {
    format!("({}, {}, {})", trim(p.x), trim(p.y), trim(p.z))
}

fn trim(x: f32) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// The description printed by `prism info`.
pub fn describe(loaded: &LoadedScene, path: &Path) -> String {
    let i = &loaded.info;
    let mut s = String::new();
    let _ = writeln!(s, "scene      {}", path.display());
    let _ = writeln!(
        s,
        "image      {}×{}, {} spp, max depth {}, min contribution {}",
        i.width,
        i.height,
        i.spp,
        i.max_depth,
        trim(i.min_contribution)
    );
    let c = &i.camera;
    let _ = writeln!(
        s,
        "camera     at {} looking at {}, up {}, vertical fov {}°",
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
            "mesh       {}: {} model{}, {} triangles, {} instance{}",
            m.path.display(),
            m.models,
            if m.models == 1 { "" } else { "s" },
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

/// ", inverse-square" for a light that dims with distance.
fn falloff_text(f: Falloff) -> &'static str {
    match f {
        Falloff::None => "",
        Falloff::InverseSquare => ", inverse-square",
    }
}
