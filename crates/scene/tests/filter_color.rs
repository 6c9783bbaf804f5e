//! A material's `filter_color`: the colour that what passes through a see-through
//! surface is multiplied by, in the view through it and in its shadow
//! alike (the surface colour when not set); and MTL's `Tf`, which an OBJ
//! material with `d < 1` takes as its filter (white without one: dissolve
//! fades a surface, `Kd` tints nothing through it).

use prism_geometry::glam::Vec3;
use prism_scene::parse_scene_str;
use prism_shade::{RenderHooks, render};
use std::fs;
use std::path::Path;

/// A see-through sheet (a disk facing +Z at the origin) of colour
/// (0.5, 1, 0.25), `transparency = 0.6`, shown flat (ambient only), with
/// the material keys `extra`, in front of a flat wall (0.9, 0.8, 0.7); the
/// colour at the image centre.
fn through_sheet(extra: &str) -> Result<Vec3, String> {
    let text = format!(
        r#"
[render]
width = 9
height = 9
spp = 1
ambient = [1, 1, 1]
background = [0, 0, 0]

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 20

[materials.sheet]
color = [0.5, 1, 0.25]
transparency = 0.6
ambient = 1
diffuse = 0
specular = 0
{extra}

[materials.wall]
color = [0.9, 0.8, 0.7]
ambient = 1
diffuse = 0
specular = 0

[[objects]]
type = "disk"
center = [0, 0, 0]
normal = [0, 0, 1]
radius = 2
material = "sheet"

[[objects]]
type = "plane"
point = [0, 0, -3]
normal = [0, 0, 1]
material = "wall"
"#
    );
    let loaded =
        parse_scene_str(&text, Path::new("."), Path::new("sheet.toml")).map_err(|e| e.to_string())?;
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    Ok(image.pixels[4 * 9 + 4])
}

fn assert_near(got: Vec3, want: Vec3) {
    assert!((got - want).abs().max_element() < 1e-5, "got {got}, want {want}");
}

#[test]
fn a_sheet_tints_the_view_through_it_by_its_filter() {
    let (own, wall) = (Vec3::new(0.5, 1.0, 0.25), Vec3::new(0.9, 0.8, 0.7));
    // No filter: its own colour.
    assert_near(through_sheet("").unwrap(), 0.4 * own + 0.6 * own * wall);
    // A white filter: clear, whatever its colour.
    assert_near(through_sheet("filter_color = [1, 1, 1]").unwrap(), 0.4 * own + 0.6 * wall);
    // Any other filter.
    let f = Vec3::new(0.2, 0.4, 1.0);
    assert_near(through_sheet("filter_color = [0.2, 0.4, 1]").unwrap(), 0.4 * own + 0.6 * f * wall);
}

/// Glass or a sheet given no colour is clear: the default grey colour
/// does not filter.
#[test]
fn a_see_through_material_without_a_colour_is_clear() {
    let text = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
                [materials.glass]\ntransmission = 1\nior = 1.5\n\
                [materials.grey]\ntransmission = 1\ncolor = [0.8, 0.8, 0.8]\n\
                [[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"glass\"\n\
                [[objects]]\ntype = \"sphere\"\ncenter = [3, 0, 0]\nradius = 1\nmaterial = \"grey\"\n";
    let loaded = parse_scene_str(text, Path::new("."), Path::new("g.toml")).expect("loads");
    assert_eq!(loaded.scene.material_of(0).filter_color, Some(Vec3::ONE));
    assert_eq!(loaded.scene.material_of(1).filter_color, None, "a colour given filters");
}

#[test]
fn a_filter_on_an_opaque_material_is_warned_about() {
    let text = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
                [materials.paint]\ncolor = [1, 0, 0]\nfilter_color = [0, 1, 0]\n\
                [[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"paint\"\n";
    let loaded = parse_scene_str(text, Path::new("."), Path::new("p.toml")).expect("loads");
    assert!(
        loaded.warnings.iter().any(|w| w.contains("p.toml:6:") && w.contains("filter_color does nothing")),
        "{:?}",
        loaded.warnings
    );
    // Where something passes through, no warning.
    let clear = text.replace("filter_color", "transparency = 0.5\nfilter_color");
    let loaded = parse_scene_str(&clear, Path::new("."), Path::new("p.toml")).expect("loads");
    assert!(loaded.warnings.iter().all(|w| !w.contains("filter_color")), "{:?}", loaded.warnings);
}

#[test]
fn a_filter_over_one_is_refused_naming_it() {
    let e = through_sheet("filter_color = [1.5, 0, 0]").unwrap_err();
    assert!(e.contains("filter_color") && e.contains("between 0 and 1"), "{e}");
    assert!(e.contains("sheet.toml:"), "the place is named: {e}");
}

/// The material of `sheet.obj` (one quad, material `m` of `sheet.mtl`
/// written from `mtl`), as loaded through a scene.
fn mtl_material(mtl: &str) -> Result<prism_shade::Material, String> {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let obj = "mtllib sheet.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl m\nf 1 2 3 4\n";
    fs::write(d.join("sheet.obj"), obj).expect("sheet.obj");
    fs::write(d.join("sheet.mtl"), format!("newmtl m\n{mtl}")).expect("sheet.mtl");
    let text = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = \"sheet.obj\"\n";
    let loaded = parse_scene_str(text, d, Path::new("s.toml")).map_err(|e| e.to_string())?;
    let m = loaded.scene.material_of(0);
    Ok(m.clone())
}

#[test]
fn an_mtl_material_filters_by_its_tf_not_its_kd() {
    let m = mtl_material("Kd 1 0 0\nd 0.4\nTf 0 1 0.5\n").unwrap();
    assert!((m.transparency - 0.6).abs() < 1e-6);
    assert_eq!(m.filter_color, Some(Vec3::new(0.0, 1.0, 0.5)));
    // One number for all three.
    assert_eq!(mtl_material("Kd 1 0 0\nd 0.4\nTf 0.25\n").unwrap().filter_color, Some(Vec3::splat(0.25)));
    // Without `Tf`, clear: dissolve fades the surface and does not tint.
    assert_eq!(mtl_material("Kd 1 0 0\nd 0.4\n").unwrap().filter_color, Some(Vec3::ONE));
    // Opaque: no filter to ask for.
    assert_eq!(mtl_material("Kd 1 0 0\nTf 0 1 0\n").unwrap().filter_color, None);
    // The XYZ and spectral forms are not read.
    for other in ["Tf xyz 0.2 0.3 0.4", "Tf spectral glass.rfl 1.0"] {
        assert_eq!(
            mtl_material(&format!("Kd 1 0 0\nd 0.4\n{other}\n")).unwrap().filter_color,
            Some(Vec3::ONE)
        );
    }
    for bad in ["Tf 2 0 0", "Tf 0 1", "Tf x y z"] {
        let e = mtl_material(&format!("Kd 1 0 0\nd 0.4\n{bad}\n")).unwrap_err();
        assert!(e.contains("Tf") && e.contains("sheet.obj") && e.contains("MTL"), "{bad}: {e}");
    }
}

#[test]
fn absorption_without_transmission_is_warned_about() {
    // A sheet (transparency) or an opaque paint has no inside to absorb
    // along: the colour a user asked for would silently not appear.
    for (extra, warned) in [
        ("", true),
        ("transparency = 0.9\n", true),
        ("transmission = 0.9\n", false),
        ("absorption_zero", false),
    ] {
        let absorption = if extra == "absorption_zero" {
            "absorption = [0, 0, 0]\n"
        } else {
            "absorption = [2, 0.1, 2]\n"
        };
        let extra = if extra == "absorption_zero" { "" } else { extra };
        let text = format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
             [materials.g]\n{extra}{absorption}\
             [[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"g\"\n"
        );
        let loaded = parse_scene_str(&text, Path::new("."), Path::new("a.toml")).expect("loads");
        let line = if extra.is_empty() { "a.toml:5:" } else { "a.toml:6:" };
        let found =
            loaded.warnings.iter().any(|w| w.contains(line) && w.contains("absorption does nothing here"));
        assert_eq!(found, warned, "{extra:?} {absorption:?}: {:?}", loaded.warnings);
    }
}
