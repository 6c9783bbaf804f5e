//! Parsing a scene from text: what it holds, defaults, and every class of
//! error with its line and column.

use super::*;
use crate::format::SceneFile;
use prism_bvh::Object;
use prism_geometry::glam::Vec3;
use prism_shade::{Aov, FogMode, ImageTexture, Texture, Wrap};
use std::path::Path;
use std::sync::Arc;

#[test]
fn a_full_scene_parses() {
    let extra = r##"
[fog]
mode = "exponential"
density = 0.05
color = "#ffffff"

[materials.floor]
texture = { type = "checker", a = [1, 1, 1], b = [0, 0, 0], size = 2 }

[materials.glass]
color = [1, 1, 1]
transmission = 0.9
ior = 1.5
absorption = [0.1, 0.2, 0.3]

[[objects]]
type = "plane"
material = "floor"

[[objects]]
type = "sphere"
center = [0, 1, 0]
radius = 1
material = "glass"

[[objects]]
type = "cuboid"
size = 1
material = "red"
transform = [{ rotate_y = 45 }, { translate = [2, 0.5, 0] }]

[[objects]]
type = "cuboid"
min = [-1, 0, -1]
max = [1, 1, 1]
transform = [{ shear_angle = { xy = 20 } }, { scale = [1, 2, 1] }, { rotate = { axis = [1, 1, 0], degrees = 10 } }]

[[objects]]
type = "cylinder"
base = [3, 0, 0]
radius = 0.5
height = 2

[[objects]]
type = "cone"
radius = 0.5
height = 1
transform = [{ matrix = [[1, 0, 0, 4], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }]

[[objects]]
type = "disk"
center = [0, 3, 0]
normal = [0, 0, 1]
radius = 1

[[objects]]
type = "triangle"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
name = "a label"
"##;
    let loaded = parse(&format!("{BASE}{extra}")).unwrap();
    let info = &loaded.info;
    assert_eq!((info.width, info.height, info.spp), (320, 180, 2));
    assert_eq!(info.objects, 8);
    assert_eq!(info.objects_by_kind.get("cuboid"), Some(&2));
    assert_eq!(info.objects_by_kind.get("plane"), Some(&1));
    // Sorted names, then the built-in default for objects without a material.
    assert_eq!(info.materials, ["floor", "glass", "red", "(default)"]);
    let scene = &loaded.scene;
    assert_eq!(scene.object_materials.len(), 8);
    assert!(matches!(scene.materials[0].texture, Texture::Checker { size: 2.0, world: true, .. }));
    assert_eq!(scene.materials[1].transmission, 0.9);
    let fog = scene.fog.unwrap();
    assert!(loaded.settings.fog, "a scene's fog is on unless it says `enabled = false`");
    assert!(matches!(fog.mode, FogMode::Exponential { density } if (density - 0.05).abs() < 1e-7));
    assert!((fog.color - Vec3::ONE).abs().max_element() < 1e-6);
    // The box rotated 45° and moved: its transform maps the origin to (2, 0.5, 0).
    let Object::Shape(inst) = &scene.accel.objects()[2] else { panic!("a shape") };
    assert!((inst.transform.point(Vec3::ZERO) - Vec3::new(2.0, 0.5, 0.0)).length() < 1e-6);
    let x = inst.transform.point(Vec3::X);
    assert!((x - Vec3::new(2.0 + 0.5f32.sqrt(), 0.5, -(0.5f32.sqrt()))).length() < 1e-5, "{x}");
    // The matrix is given by rows: the last column is the translation.
    let Object::Shape(cone) = &scene.accel.objects()[5] else { panic!("a shape") };
    assert!((cone.transform.point(Vec3::ZERO) - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-6);
    assert_eq!(loaded.settings.spp, 2);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn large_angles_turn_as_their_remainder_in_a_turn() {
    // 1e9° is 280°; its f32 radians (1.7e7, spaced 2 apart) were not.
    let cam = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let turned = |steps: &str| {
        let text = format!("{cam}[[objects]]\ntype = \"cuboid\"\nsize = 1\ntransform = [{steps}]\n");
        let loaded = parse(&text).unwrap();
        let Object::Shape(inst) = &loaded.scene.accel.objects()[0] else { panic!("a shape") };
        inst.transform.point(Vec3::new(1.0, 0.5, 0.25))
    };
    for (big, small) in [
        ("{ rotate_y = 1e9 }", "{ rotate_y = 280 }"),
        ("{ rotate_x = -3600045 }", "{ rotate_x = -45 }"),
        (
            "{ rotate = { axis = [1, 1, 0], degrees = 7.2e10 } }",
            "{ rotate = { axis = [1, 1, 0], degrees = 0 } }",
        ),
    ] {
        let (a, b) = (turned(big), turned(small));
        assert!((a - b).length() < 1e-6, "{big}: {a}, {small}: {b}");
    }
    let text = format!("{cam}[render]\nbackground = {{ image = \"sky.png\", rotation = 1e9 }}\n");
    let file = SceneFile::parse(&text, Path::new("t.toml")).unwrap();
    let lines = crate::error::Lines::new(&text);
    let ctx = crate::check::Ctx::new(Path::new("t.toml"), &lines);
    let bg = file.render.as_ref().unwrap().get_ref().background.as_ref().unwrap();
    let image = Arc::new(ImageTexture::from_linear(1, 1, vec![Vec3::ONE], Wrap::Repeat).unwrap());
    let env = crate::view::environment(&ctx, bg.get_ref(), &mut |_| Ok(image.clone())).unwrap().unwrap();
    assert_eq!(env.rotation_deg, 280.0);
}

#[test]
fn defaults_apply() {
    let loaded = parse("[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n").unwrap();
    assert_eq!((loaded.info.width, loaded.info.height), (1280, 720));
    assert_eq!(loaded.settings.spp, 4);
    assert_eq!(loaded.settings.max_depth, 8);
    assert!((loaded.info.camera.vfov_deg() - 45.0).abs() < 1e-6);
    assert_eq!(loaded.warnings.len(), 2, "{:?}", loaded.warnings); // no lights, no objects
}

#[test]
fn overrides_replace_the_file_and_keep_the_aspect() {
    let opts = LoadOptions {
        overrides: Overrides { width: Some(160), spp: Some(1), fog: Some(true), ..Overrides::default() },
        ..LoadOptions::default()
    };
    let text = format!("{BASE}[[objects]]\ntype = \"sphere\"\nradius = 1\n");
    let loaded = parse_scene_str_with(&text, Path::new("."), Path::new("t.toml"), &opts).unwrap();
    assert_eq!((loaded.info.width, loaded.info.height), (160, 90));
    assert_eq!(loaded.settings.camera.size().0, 160);
    assert_eq!(loaded.settings.spp, 1);
    // --fog on a scene without fog adds one, with a warning.
    assert!(loaded.scene.fog.is_some() && loaded.settings.fog);
    assert!(loaded.warnings.iter().any(|w| w.contains("no [fog]")));

    let opts = LoadOptions {
        overrides: Overrides { width: Some(100_000), ..Overrides::default() },
        ..LoadOptions::default()
    };
    let err = parse_scene_str_with(&text, Path::new("."), Path::new("t.toml"), &opts).unwrap_err();
    assert!(err.to_string().starts_with("--width: "), "{err}");
}

#[test]
fn syntax_errors_have_line_and_column() {
    let err = expect_err("[[objects]]\ntype = \"sphere\"\nradius = = 1\n", "extra `=`");
    assert_at(&err, "[[objects]]\ntype = \"sphere\"\nradius = = 1\n", "radius = =");
}

#[test]
fn unknown_keys_are_rejected_where_they_are() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\nradios = 2\n",
            "unknown key `radios` in a sphere; did you mean `radius`? (a sphere takes: center, radius, plus",
            Some("radios"),
        ),
        (
            "[materials.x]\ncolour = [1, 0, 0]\n",
            "unknown key `colour`; did you mean `color`?",
            Some("colour"),
        ),
        // A key of another table: where it goes.
        ("[fog]\nspp = 4\n", "unknown key `spp`; it is a key of `[render]`", Some("spp = 4")),
        // On an object or a light, too: a material's key (the commonest
        // slip), a transform step, another table's key.
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ncolor = [1, 0, 0.5]\n",
            "unknown key `color` in a sphere; it is a key of a material: write it under `[materials.NAME]` and give the object `material = \"NAME\"`",
            Some("color = [1, 0, 0.5]"),
        ),
        (
            "[[objects]]\ntype = \"cuboid\"\nsize = 1\nrotate_y = 30\n",
            "unknown key `rotate_y` in a cuboid; it is a step of `transform`: `transform = [{ rotate_y = … }]`",
            Some("rotate_y"),
        ),
        (
            "[[lights]]\nposition = [0, 5, 0]\nspp = 16\n",
            "unknown key `spp` in a point light; it is a key of `[render]`",
            Some("spp = 16"),
        ),
        // The default material's name, which `prism info` would list twice.
        (
            "[materials.\"(default)\"]\ncolor = [1, 0, 0]\n",
            "`(default)` is the name of the material of objects that name none",
            Some("\"(default)\""),
        ),
        // Of two unknown keys, the first in the file (not the first in
        // the alphabet).
        (
            "[[objects]]\ntype = \"sphere\"\nzoom = 2\nbbb = 1\n",
            "unknown key `zoom` in a sphere",
            Some("zoom"),
        ),
    ]);
    // Not `aov`, the nearest spelling among the render table's keys.
    let err = parse(&BASE.replace("spp = 2", "fov = 30")).unwrap_err().to_string();
    assert!(err.contains("unknown key `fov`; it is a key of `[camera]` (expected one of: width,"), "{err}");
    let err = parse(&format!("width = 30\n{BASE}")).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:1:1: unknown key `width`; it is a key of `[render]`"), "{err}");
    let err = parse(&BASE.replace("[camera]", "[camera]\nspp = 4")).unwrap_err().to_string();
    assert!(err.contains("unknown key `spp`; it is a key of `[render]`"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "widht = 3")).unwrap_err().to_string();
    assert!(
        err.starts_with("test.toml:5:1:") && err.contains("unknown key `widht`; did you mean `width`?"),
        "{err}"
    );
}

#[test]
fn wrong_types_say_what_was_expected() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = \"big\"\n",
            "expected a number, got the string \"big\"",
            Some("radius"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ncenter = [1, 2]\n",
            "expected an array of 3 numbers, got 2 values",
            Some("center"),
        ),
        ("[[objects]]\ntype = \"blob\"\n", "unknown name `blob`", Some("blob")),
        ("[materials.x]\ncolor = \"red\"\n", "#rrggbb", Some("\"red\"")),
    ]);
}

#[test]
fn missing_required_keys_are_named() {
    let err = parse("[render]\nwidth = 10\n").unwrap_err().to_string();
    assert!(err.contains("missing [camera]"), "{err}");
    let err = parse("[camera]\nposition = [0, 0, 1]\n").unwrap_err().to_string();
    assert!(err.contains("look_at"), "{err}");
    refused(&[
        ("[[objects]]\ntype = \"sphere\"\n", "a sphere needs `radius`", Some("[[objects]]")),
        ("[[objects]]\ntype = \"cuboid\"\n", "a cuboid needs `size`", None),
        (
            "[[objects]]\ntype = \"cuboid\"\nmax = [1, 1, 1]\n",
            "a cuboid with `max` needs `min` too",
            Some("[1"),
        ),
        (
            "[[objects]]\ntype = \"cuboid\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nsize = 2\n",
            "a cuboid takes `min` and `max`, or `size` (and `center`), not both",
            Some("size = 2"),
        ),
        (
            "[[objects]]\ntype = \"disk\"\nradius = 1\nnormal = [0, 0, 0]\n",
            "disk normal is zero",
            Some("[0, 0"),
        ),
        ("[[objects]]\ntype = \"mesh\"\n", "a mesh needs `path`", None),
    ]);
}

#[test]
fn nan_and_infinity_are_refused() {
    refused(&[
        ("[[objects]]\ntype = \"sphere\"\nradius = nan\n", "must be a finite number", Some("nan")),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1e39\n",
            "sphere radius must lie within ±3.4028235e38 (single precision), got 1e39",
            Some("1e39"),
        ),
        ("[[objects]]\ntype = \"sphere\"\nradius = 1\ncenter = [0, inf, 0]\n", "finite", Some("inf")),
    ]);
    // Too large for f32 is refused too, naming the range.
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1e300\n",
            "within ±3.4028235e38 (single precision), got 1e300",
            None,
        ),
        ("[[lights]]\nposition = [0, 0, 0]\nintensity = -inf\n", "finite", None),
    ]);
}

#[test]
fn zero_and_negative_sizes_are_refused() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 0\n",
            "sphere radius must be greater than 0, got 0",
            Some("radius"),
        ),
        (
            "[[objects]]\ntype = \"cylinder\"\nradius = 1\nheight = -2\n",
            "cylinder height must be greater than 0",
            Some("height = -2"),
        ),
        (
            "[[objects]]\ntype = \"cuboid\"\nsize = [1, 0, 1]\n",
            "cuboid size must be greater than 0",
            Some("size"),
        ),
        (
            "[[objects]]\ntype = \"cuboid\"\nmin = [0, 0, 0]\nmax = [1, 0, 1]\n",
            "must be greater than min",
            None,
        ),
        (
            "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\n",
            "triangle has zero area",
            Some("vertices"),
        ),
        (
            "[materials.m]\ntexture = { type = \"checker\", size = 0 }\n",
            "checker size must be greater than 0",
            None,
        ),
    ]);
}

#[test]
fn singular_transforms_are_refused_at_the_step() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [\n  { translate = [1, 0, 0] },\n  { scale = [1, 0, 1] },\n]\n",
            "singular",
            Some("scale"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ shear = { xy = 1, yx = 1 } }]\n",
            "singular",
            None,
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]] }]\n",
            "not affine",
            None,
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotate = { axis = [0, 0, 0], degrees = 3 } }]\n",
            "axis is zero",
            None,
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ spin = 3 }]\n",
            "unknown name `spin`",
            None,
        ),
    ]);
}

#[test]
fn unknown_material_names_list_the_known_ones() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"blue\"\n",
            "unknown material `blue`; the scene defines: red",
            Some("\"blue\""),
        ),
        // A misspelt name gets the closest, whatever its case.
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"Rde\"\n",
            "unknown material `Rde`; did you mean `red`? (the scene defines: red)",
            Some("\"Rde\""),
        ),
    ]);
}

#[test]
fn keys_of_another_shape_are_refused() {
    refused(&[
        ("[[objects]]\ntype = \"plane\"\nradius = 1\n", "`radius` is not a key of a plane", Some("radius")),
        (
            "[materials.m]\ntexture = { type = \"checker\", path = \"x.png\" }\n",
            "`path` is not a key of a checker texture",
            None,
        ),
        ("[materials.m]\ncolor = [1, 1, 1]\ntexture = { type = \"checker\" }\n", "not both", None),
    ]);
}

#[test]
fn render_limits_are_checked_before_allocating() {
    let err = parse(&BASE.replace("width = 320", "width = 1000000")).unwrap_err().to_string();
    assert!(err.contains("over the limit of 16384") && err.contains("--max-side"), "{err}");
    assert!(err.starts_with("test.toml:3:9:"), "{err}");
    let text = BASE.replace("width = 320", "width = 16000").replace("height = 180", "height = 16000");
    let err = parse(&text).unwrap_err().to_string();
    assert!(err.contains("--max-pixels"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "spp = 0")).unwrap_err().to_string();
    assert!(err.contains("at least 1") && err.starts_with("test.toml:5:7:"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "max_depth = 1000000000")).unwrap_err().to_string();
    assert!(err.contains("over the limit of 64"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "width = 1000000000000")).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "spp = -3")).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:5:7:"), "{err}");
    // The limits are configurable.
    let opts =
        LoadOptions { limits: Limits { max_side: 20_000, ..Limits::default() }, ..LoadOptions::default() };
    let text = BASE.replace("width = 320", "width = 20000").replace("height = 180", "height = 10");
    assert!(parse_scene_str_with(&text, Path::new("."), Path::new("t.toml"), &opts).is_ok());
}

#[test]
fn bad_cameras_are_refused() {
    let text = BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nup = [0, 1, 10]");
    let err = parse(&text).unwrap_err().to_string();
    assert!(err.contains("parallel to the view direction") && err.starts_with("test.toml:10:6:"), "{err}");
    let text = BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 2, 10]");
    assert!(parse(&text).unwrap_err().to_string().contains("must differ"));
    let text = BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nfov = 180");
    assert!(parse(&text).unwrap_err().to_string().contains("between 0 and 180"));
    // Apart by less than about 1e-19, where the squared distance
    // underflows: a camera like any other (it was refused as "focus
    // distance must be a finite number > 0, got 0", with no place).
    for gap in ["1e-25", "1e-30", "1e-45"] {
        let text = BASE.replace("position = [0, 2, 10]", &format!("position = [0, 0, {gap}]"));
        let scene = parse(&text.replace("look_at = [0, 1, 0]", "look_at = [0, 0, 0]")).unwrap();
        assert!(scene.settings.camera.focus_distance() > 0.0, "{gap}");
    }
}

#[test]
fn bad_fog_and_materials_are_refused() {
    refused(&[
        ("[fog]\nstart = 10\nend = 5\n", "fog end (5) must be greater than fog start (10)", None),
        // Apart as written, equal in single precision: said so.
        (
            "[fog]\nstart = 1\nend = 1.00000001\n",
            "fog end (1.00000001) must be greater than fog start (1) in single precision, which prism computes in: both are 1 there",
            None,
        ),
        (
            "[fog]\nend = 1e-50\n",
            "fog end (1e-50) must be greater than fog start (0) in single precision, which prism computes in: both are 0 there",
            None,
        ),
        ("[fog]\nmode = \"exponential\"\n", "needs `density`", None),
        // A pixel sums up to 65 536 samples of such colours.
        (
            "[fog]\nend = 10\ncolor = [3e38, 3e38, 3e38]\n",
            "fog color [3e38, 3e38, 3e38] must be at most 1e30",
            None,
        ),
        (
            "[materials.m]\ncolor = [1, 2e30, 0]\n",
            "color [1.0, 2e30, 0.0] must be at most 1e30",
            Some("[1, 2e30, 0]"),
        ),
        ("[fog]\nmode = \"exponential\"\ndensity = 0.1\nend = 3\n", "belong to linear fog", None),
        ("[fog]\nmode = \"fuzzy\"\n", "unknown name `fuzzy`", None),
        (
            "[materials.m]\nreflectivity = 0.6\ntransparency = 0.6\n",
            "must not exceed 1",
            Some("[materials.m]"),
        ),
        ("[materials.m]\nreflectivity = 1.5\n", "between 0 and 1", Some("reflectivity")),
        ("[materials.m]\nior = 0\n", "ior must be greater than 0", None),
        ("[materials.m]\ncolor = [1, -1, 0]\n", ">= 0", None),
    ]);
}

// ----- AOV keys --------------------------------------------------------

#[test]
fn aov_keys_list_passes_in_order() {
    let text =
        BASE.replace("spp = 2", "spp = 2\naov = [\"object_id\", \"depth\", \"all\"]\naov_preview = true");
    let loaded = parse(&text).unwrap();
    assert_eq!(
        loaded.aovs,
        [prism_shade::Aov::ObjectId, prism_shade::Aov::Depth, Aov::Normal, Aov::GeoNormal, Aov::Albedo]
    );
    assert!(loaded.aov_preview);
    let loaded = parse(BASE).unwrap();
    assert!(loaded.aovs.is_empty() && !loaded.aov_preview);
}

#[test]
fn unknown_aov_names_are_refused_where_they_are() {
    let text = BASE.replace("spp = 2", "spp = 2\naov = [\"depth\", \"dept\"]");
    let err = parse(&text).unwrap_err().to_string();
    // Line 6, column of the second string.
    assert!(err.starts_with("test.toml:6:17: unknown AOV pass `dept`"), "{err}");
    assert!(err.contains("depth, normal, geo_normal, albedo, object_id"), "{err}");
    let text = BASE.replace("spp = 2", "spp = 2\naov = \"depth\"");
    let err = parse(&text).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:6:7:") && err.contains("expected an array"), "{err}");
    let text = BASE.replace("spp = 2", "spp = 2\naov_preview = 1");
    assert!(parse(&text).unwrap_err().to_string().starts_with("test.toml:6:"));
}

#[test]
fn toml_syntax_errors_say_what_is_wrong_and_where() {
    // (the lines after a sphere's `type`, the text the message points at
    // (its first occurrence there), the whole message after the place).
    // toml 0.9 gives up on an unclosed array or inline table where the next
    // key starts; the message adds where it opened (brackets inside strings
    // and comments not counted). Where toml reads a value it cannot place as
    // an unquoted string, the message says what is missing instead.
    let cases = [
        (
            "center = [0, \"]\", # ]\n  1\nradius = 1",
            "radius",
            "missing comma between array elements, expected `,`; the array opened at line {L}, column 10 is not closed",
        ),
        (
            "transform = [{ scale = 2\nradius = 1",
            "radius",
            "missing comma between key-value pairs, expected `,`; the inline table opened at line {L}, column 14 is not closed",
        ),
        ("center = [0, 1 2]", "1 2", "expected `,` or `]` after `1`"),
        ("transform = [{ scale = 2 2 }]", "2 2", "expected `,` or `}` after `2`"),
        ("radius = 1 2", "1 2", "expected the end of the line after `1`"),
        (
            "radius = ",
            "\n",
            "a value is missing here (a number, a \"string\", true or false, an [array] or a { table })",
        ),
        ("material = red", "red", "`red` is not a value: a string must be quoted (\"red\")"),
        (
            "material = Infinity Blue",
            "Inf",
            "`Infinity Blue` is not a value: a string must be quoted (\"Infinity Blue\")",
        ),
        ("center = [1_000 2]", "1_0", "expected `,` or `]` after `1_000`"),
        ("material = a\\b", "a\\", "`a\\b` is not a value: a string must be quoted ('a\\b')"),
        ("radius = 1\nradius = 2", "radius = 2", "duplicate key `radius`: it is already defined above"),
        ("radius = 1e999999999999999999999", "1e9", "floating-point number overflowed"),
        ("center = [0, , 1]", ", 1]", "extra comma in array, expected value"),
        ("center = [, 0, 1]", ", 0", "extra comma in array, expected value"),
        ("transform = [{ , scale = 2 }]", ", scale", "extra comma in inline table, expected key"),
        ("radius = = 1", "= 1", "extra `=`"),
        (
            "transform = [{ translate = [1, 0, 0], scale = 2 }]",
            "{ translate",
            "a transform step takes one key; give each step its own table, in order: `transform = [{ scale = 2 }, { translate = [0, 1, 0] }]`",
        ),
        (
            "transform = [{ scale = 2 }, {}]",
            "{}",
            "a transform step needs one key: translate, rotate_x, rotate_y, rotate_z, rotate, scale, shear, shear_angle or matrix",
        ),
        ("radius = 1979-05-27", "1979", "expected a number, got the date 1979-05-27"),
        ("radius = 07:32:00", "07", "expected a number, got the date 07:32:00"),
        (
            "radius = 99999999999999999999",
            "999",
            "expected a number, got the whole number 99999999999999999999, beyond the 64-bit range",
        ),
    ];
    for (lines, at, message) in cases {
        let text = format!("{BASE}[[objects]]\ntype = \"sphere\"\n{lines}\n");
        let err = parse(&text).unwrap_err().to_string();
        let start = BASE.len() + "[[objects]]\ntype = \"sphere\"\n".len();
        let offset = start + text[start..].find(at).unwrap_or_else(|| panic!("{at:?} in {lines:?}"));
        let (line, column) = crate::error::line_col(&text, offset);
        // {L}: the line of the sphere's first line below `type`.
        let message = message.replace("{L}", &crate::error::line_col(&text, start).0.to_string());
        assert_eq!(err, format!("test.toml:{line}:{column}: {message}"), "{lines:?}");
        assert!(!err.contains('\n'), "one line: {err}");
    }
    // A trailing comma is valid in an array, and in an inline table under
    // TOML 1.1, which toml 0.9 reads.
    let sphere = "[[objects]]\ntype = \"sphere\"\nradius = 1\ncenter = [0, 1, 2, ]\n";
    parse(&format!("{BASE}{sphere}transform = [{{ scale = 2, }}]\n")).unwrap();
}

#[test]
fn dotted_keys_are_read_as_tables() {
    // TOML's dotted keys, at the top level and in tables, read as the
    // tables they name (toml 0.8 refused these where the value is spanned).
    let dotted = BASE
        .replace("[render]\n", "")
        .replace("width = ", "render.width = ")
        .replace("height = ", "render.height = ")
        .replace("spp = ", "render.spp = ");
    assert_ne!(dotted, BASE);
    let (a, b) = (parse(BASE).unwrap(), parse(&dotted).unwrap());
    assert_eq!((a.settings.camera.size(), a.settings.spp), (b.settings.camera.size(), b.settings.spp));
    let text = format!("{BASE}[materials]\ndotted.color = [1, 0, 0]\nchecks.texture.type = \"checker\"\n");
    parse(&text).unwrap();
    // A dotted key under a key that wants a value: the value's type is named.
    let err = expect_err(
        "[[objects]]\ntype = \"sphere\"\ncenter.x = 1\n",
        "expected an array of 3 numbers, got a table",
    );
    assert_at(&err, "[[objects]]\ntype = \"sphere\"\ncenter.x = 1\n", "center.x");
}

#[test]
fn large_finite_values_are_not_mistaken_for_zero() {
    // Squared lengths past f32's range (about 1.8e19 and up) once made these
    // "zero", "parallel" or "singular".
    let far = BASE.replace("position = [0, 2, 10]", "position = [1e20, 2, 10]");
    assert_ne!(far, BASE);
    let loaded = parse(&far).unwrap();
    assert!(loaded.settings.camera.focus_distance().is_finite());
    // Past f32's range apart: a direction all the same, not "the same point".
    let farther = BASE
        .replace("position = [0, 2, 10]", "position = [3e38, 2, 10]")
        .replace("look_at = [0, 1, 0]", "look_at = [-3e38, 1, 0]");
    let camera = parse(&farther).unwrap().settings.camera;
    assert_eq!(camera.focus_distance(), f32::MAX);
    let sideways = camera.ray(0.5 * camera.size().0 as f32, 0.5 * camera.size().1 as f32).dir;
    assert!((sideways.normalize() - Vec3::NEG_X).length() < 1e-3, "{sideways}");
    parse(&BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nup = [0, 1e30, 0]")).unwrap();
    parse(&format!("{BASE}[[lights]]\ntype = \"directional\"\ndirection = [0, -1e30, -1e30]\n")).unwrap();
    for scale in ["1e20", "1e-20"] {
        parse(&format!(
            "{BASE}[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{{ scale = {scale} }}]\n"
        ))
        .unwrap();
    }
    let quad =
        "[[lights]]\ntype = \"quad\"\ncorner = [0, 5, 0]\nedge_u = [1e20, 0, 0]\nedge_v = [0, 0, 1e20]\n";
    let err = expect_err(quad, "a quad light's area overflows 32-bit floats");
    assert_at(&err, quad, "edge_v");
}

#[test]
fn arrays_longer_than_expected_are_refused_where_they_are() {
    let three = "expected an array of 3 numbers, got 4 values";
    refused(&[
        ("[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0, 7]\nradius = 1\n", three, Some("center")),
        ("[[lights]]\nposition = [1, 2, 3, 4]\n", three, Some("position = [1, 2, 3, 4]")),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ translate = [1, 2, 3, 4] }]\n",
            three,
            Some("translate"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotate = { axis = [0, 1, 0, 5], degrees = 30 } }]\n",
            three,
            Some("rotate"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n\
             transform = [{ matrix = [[1, 0, 0, 0, 7], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] }]\n",
            "expected an array of 4 numbers, got 5 values",
            Some("matrix"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n\
             transform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 1]] }]\n",
            "expected an array of 4 rows [a, b, c, d], got 5 values",
            Some("matrix"),
        ),
        (
            "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\n",
            "expected an array of 3 points [x, y, z], got 4 values",
            Some("vertices"),
        ),
        // Too short, in the same words: points and rows, not numbers.
        (
            "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0]]\n",
            "expected an array of 3 points [x, y, z], got 2 values",
            Some("vertices"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n\
             transform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]] }]\n",
            "expected an array of 4 rows [a, b, c, d], got 3 values",
            Some("matrix"),
        ),
        // Every value past the last is counted, whatever it is.
        (
            "[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0, 7, \"x\"]\nradius = 1\n",
            "got 5 values",
            Some("center"),
        ),
    ]);
    // The camera's vectors, at their own column.
    for (from, to, column) in [
        ("position = [0, 2, 10]", "position = [0, 2, 10, 99]", 12),
        ("look_at = [0, 1, 0]", "look_at = [0, 1, 0, \"x\"]", 11),
    ] {
        let text = BASE.replace(from, to);
        let err = parse(&text).unwrap_err().to_string();
        let line = text.lines().position(|l| l == to).unwrap() + 1;
        assert_eq!(err, format!("test.toml:{line}:{column}: {three}"));
    }
}

#[test]
fn a_transform_step_written_as_a_table_is_refused_at_its_value() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n[[objects.transform]]\nscale = 0\n",
            "scale [0, 0, 0] has a zero factor",
            Some("scale = 0"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n[[objects.transform]]\ntranslate = [1, 0, 0]\n\
             [[objects.transform]]\nrotate = { axis = [0, 0, 0], degrees = 3 }\n",
            "axis is zero",
            Some("rotate ="),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n[[objects.transform]]\n\
             matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]\n",
            "not affine",
            Some("matrix ="),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1\n[[objects.transform]]\nrotate_y = 1e39\n",
            "transform step: a rotation angle must be finite numbers",
            Some("rotate_y"),
        ),
    ]);
}

#[test]
fn nesting_past_the_readers_limit_is_refused_at_its_line() {
    // serde's recursion limit comes without a place; the deepest line is it.
    let header = format!("[{}]\nx = 1\n", vec!["a"; 1000].join("."));
    refused(&[(&header, "tables nested too deep for the reader (recursion limit)", Some("[a.a.a"))]);
}

#[test]
fn a_list_written_as_one_table_and_a_table_as_a_list_say_how_to_write_them() {
    let cam = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let err = parse(&format!("{cam}[objects]\ntype = \"sphere\"\nradius = 1\n")).unwrap_err().to_string();
    assert!(
        err.starts_with(
            "test.toml:4:1: `objects` is a list: write each entry under its own `[[objects]]` header"
        ),
        "{err}"
    );
    let err = parse(&format!("{cam}[lights]\nposition = [0, 5, 0]\n")).unwrap_err().to_string();
    assert!(err.contains("`lights` is a list: write each entry under its own `[[lights]]`"), "{err}");
    let err = parse("[[camera]]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n").unwrap_err().to_string();
    assert!(
        err.contains("`camera` is one table: write `[camera]` (single brackets), not `[[camera]]`"),
        "{err}"
    );
    let err = parse(&format!("{cam}[[render]]\nspp = 4\n")).unwrap_err().to_string();
    assert!(err.contains("`render` is one table: write `[render]`"), "{err}");
}

#[test]
fn a_number_with_a_unit_is_told_that_numbers_take_none() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = 1m\n",
            "`1m` is not a value: a number takes no unit (`m`); write `1`",
            Some("1m"),
        ),
        ("[fog]\nend = 30deg\n", "`30deg` is not a value: a number takes no unit (`deg`); write `30`", None),
        ("[fog]\nend = 30°\n", "`30°` is not a value: a number takes no unit (`°`); write `30`", Some("30°")),
        // Not a number at all: still "a string must be quoted".
        ("[fog]\nend = big\n", "`big` is not a value: a string must be quoted", Some("big")),
    ]);
}
