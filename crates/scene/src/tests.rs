//! Unit tests of the loader: parsing, every class of error with its
//! place, path resolution, mesh caching and MTL mapping.

use super::*;
use prism_bvh::Object;
use prism_geometry::glam::Vec3;
use prism_shade::{FogMode, Mapping, Texture};
use std::fs;

const BASE: &str = r#"
[render]
width = 320
height = 180
spp = 2

[camera]
position = [0, 2, 10]
look_at = [0, 1, 0]

[[lights]]
position = [5, 8, 5]

[materials.red]
color = [0.8, 0.1, 0.1]
specular = 0.5
"#;

fn parse(text: &str) -> Result<LoadedScene, SceneError> {
    parse_scene_str(text, Path::new("."), Path::new("test.toml"))
}

/// Parses `BASE + extra`, expects an error, and checks it starts with
/// `test.toml:LINE:` (line counted in the whole text) and contains `words`.
fn expect_err(extra: &str, words: &str) -> String {
    let text = format!("{BASE}{extra}");
    let err = match parse(&text) {
        Ok(_) => panic!("expected an error containing {words:?} for:\n{extra}"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains(words), "message {err:?} lacks {words:?}");
    assert!(err.starts_with("test.toml:"), "message {err:?} does not name the file");
    err
}

/// The line of the first line of `extra` containing `needle`, in `BASE + extra`.
fn line_of(extra: &str, needle: &str) -> usize {
    let text = format!("{BASE}{extra}");
    text.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0)
}

fn assert_at(err: &str, extra: &str, needle: &str) {
    let line = line_of(extra, needle);
    assert!(err.starts_with(&format!("test.toml:{line}:")), "{err:?} should point at line {line} ({needle})");
}

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
    let err = expect_err("[[objects]]\ntype = \"sphere\"\nradius = = 1\n", "");
    assert_at(&err, "[[objects]]\ntype = \"sphere\"\nradius = = 1\n", "radius = =");
}

#[test]
fn unknown_keys_are_rejected_where_they_are() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\nradios = 2\n";
    let err = expect_err(extra, "unknown field `radios`");
    assert_at(&err, extra, "radios");
    let extra = "[materials.x]\ncolour = [1, 0, 0]\n";
    let err = expect_err(extra, "unknown field `colour`");
    assert_at(&err, extra, "colour");
    let err = parse(&BASE.replace("spp = 2", "widht = 3")).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:5:1:") && err.contains("unknown field `widht`"), "{err}");
}

#[test]
fn wrong_types_say_what_was_expected() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = \"big\"\n";
    let err = expect_err(extra, "expected f64");
    assert_at(&err, extra, "radius");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ncenter = [1, 2]\n";
    let err = expect_err(extra, "expected an array of length 3");
    assert_at(&err, extra, "center");
    let extra = "[[objects]]\ntype = \"blob\"\n";
    let err = expect_err(extra, "unknown variant `blob`");
    assert_at(&err, extra, "blob");
    let extra = "[materials.x]\ncolor = \"red\"\n";
    let err = expect_err(extra, "#rrggbb");
    assert_at(&err, extra, "\"red\"");
}

#[test]
fn missing_required_keys_are_named() {
    let err = parse("[render]\nwidth = 10\n").unwrap_err().to_string();
    assert!(err.contains("missing [camera]"), "{err}");
    let err = parse("[camera]\nposition = [0, 0, 1]\n").unwrap_err().to_string();
    assert!(err.contains("look_at"), "{err}");
    let extra = "[[objects]]\ntype = \"sphere\"\n";
    let err = expect_err(extra, "a sphere needs `radius`");
    assert_at(&err, extra, "[[objects]]");
    expect_err("[[objects]]\ntype = \"cuboid\"\n", "a cuboid needs `size`");
    expect_err("[[objects]]\ntype = \"mesh\"\n", "a mesh needs `path`");
}

#[test]
fn nan_and_infinity_are_refused() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = nan\n";
    let err = expect_err(extra, "must be a finite number");
    assert_at(&err, extra, "nan");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ncenter = [0, inf, 0]\n";
    let err = expect_err(extra, "finite");
    assert_at(&err, extra, "inf");
    // Too large for f32 is infinite too.
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1e300\n";
    expect_err(extra, "finite");
    let extra = "[[lights]]\nposition = [0, 0, 0]\nintensity = -inf\n";
    expect_err(extra, "finite");
}

#[test]
fn zero_and_negative_sizes_are_refused() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 0\n";
    let err = expect_err(extra, "sphere radius must be greater than 0, got 0");
    assert_at(&err, extra, "radius");
    let extra = "[[objects]]\ntype = \"cylinder\"\nradius = 1\nheight = -2\n";
    let err = expect_err(extra, "cylinder height must be greater than 0");
    assert_at(&err, extra, "height = -2");
    let extra = "[[objects]]\ntype = \"cuboid\"\nsize = [1, 0, 1]\n";
    let err = expect_err(extra, "cuboid size must be greater than 0");
    assert_at(&err, extra, "size");
    let extra = "[[objects]]\ntype = \"cuboid\"\nmin = [0, 0, 0]\nmax = [1, 0, 1]\n";
    expect_err(extra, "must be greater than min");
    let extra = "[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\n";
    expect_err(extra, "");
    let extra = "[materials.m]\ntexture = { type = \"checker\", size = 0 }\n";
    expect_err(extra, "checker size must be greater than 0");
}

#[test]
fn singular_transforms_are_refused_at_the_step() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [\n  { translate = [1, 0, 0] },\n  { scale = [1, 0, 1] },\n]\n";
    let err = expect_err(extra, "singular");
    assert_at(&err, extra, "scale");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ shear = { xy = 1, yx = 1 } }]\n";
    expect_err(extra, "singular");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]] }]\n";
    expect_err(extra, "not affine");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotate = { axis = [0, 0, 0], degrees = 3 } }]\n";
    expect_err(extra, "axis is zero");
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ spin = 3 }]\n";
    expect_err(extra, "unknown variant `spin`");
}

#[test]
fn unknown_material_names_list_the_known_ones() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"blue\"\n";
    let err = expect_err(extra, "unknown material `blue`; the scene defines: red");
    assert_at(&err, extra, "\"blue\"");
}

#[test]
fn keys_of_another_shape_are_refused() {
    let extra = "[[objects]]\ntype = \"plane\"\nradius = 1\n";
    let err = expect_err(extra, "`radius` is not a key of a plane");
    assert_at(&err, extra, "radius");
    let extra = "[materials.m]\ntexture = { type = \"checker\", path = \"x.png\" }\n";
    expect_err(extra, "`path` is not a key of a checker texture");
    let extra = "[materials.m]\ncolor = [1, 1, 1]\ntexture = { type = \"checker\" }\n";
    expect_err(extra, "not both");
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
}

#[test]
fn bad_fog_and_materials_are_refused() {
    expect_err("[fog]\nstart = 10\nend = 5\n", "fog end (5) must be greater than fog start (10)");
    expect_err("[fog]\nmode = \"exponential\"\n", "needs `density`");
    expect_err("[fog]\nmode = \"exponential\"\ndensity = 0.1\nend = 3\n", "belong to linear fog");
    expect_err("[fog]\nmode = \"fuzzy\"\n", "unknown variant `fuzzy`");
    let extra = "[materials.m]\nreflectivity = 0.6\ntransparency = 0.6\n";
    let err = expect_err(extra, "must not exceed 1");
    assert_at(&err, extra, "[materials.m]");
    let extra = "[materials.m]\nreflectivity = 1.5\n";
    let err = expect_err(extra, "between 0 and 1");
    assert_at(&err, extra, "reflectivity");
    expect_err("[materials.m]\nior = 0\n", "ior must be greater than 0");
    expect_err("[materials.m]\ncolor = [1, -1, 0]\n", ">= 0");
}

#[test]
fn missing_files_are_named_with_the_resolved_path() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[[objects]]\ntype = \"mesh\"\npath = \"meshes/none.obj\"\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(
        err.contains("cannot read mesh") && err.contains("meshes/none.obj") && err.contains("no such file"),
        "{err}"
    );
    assert_at(&err, extra, "none.obj");
    let extra = "[materials.m]\ntexture = { type = \"image\", path = \"nope.png\" }\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("cannot read texture") && err.contains("nope.png"), "{err}");
    assert_at(&err, extra, "nope.png");
    // A directory where a file is expected.
    fs::create_dir(dir.path().join("d.obj")).unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"d.obj\"\n");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
}

#[test]
fn load_scene_resolves_paths_against_the_scene_file_and_lists_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("scenes");
    fs::create_dir_all(sub.join("m")).unwrap();
    fs::write(sub.join("m/tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"m/tri.obj\"\nmaterial = \"red\"\n");
    fs::write(sub.join("s.toml"), text).unwrap();
    // Loaded from elsewhere: the mesh is found next to the scene, not the cwd.
    let loaded = load_scene(&sub.join("s.toml")).unwrap();
    assert_eq!(loaded.info.stored_triangles, 1);
    let canon = |p: &Path| fs::canonicalize(p).unwrap();
    assert_eq!(loaded.inputs, vec![canon(&sub.join("s.toml")), canon(&sub.join("m/tri.obj"))]);
}

#[test]
fn scene_files_that_are_not_text_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bin.toml");
    fs::write(&p, b"[camera]\nposition = [0, 0, 1]\n\xff\xfe\x00garbage").unwrap();
    let err = load_scene(&p).unwrap_err().to_string();
    assert!(err.contains(":3:1:") && err.contains("UTF-8"), "{err}");
    let p16 = dir.path().join("u16.toml");
    fs::write(&p16, [0xFF, 0xFE, b'[', 0]).unwrap();
    assert!(load_scene(&p16).unwrap_err().to_string().contains("UTF-16"));
    let err = load_scene(dir.path()).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
    let err = load_scene(&dir.path().join("none.toml")).unwrap_err().to_string();
    assert!(err.contains("no such file"), "{err}");
    let empty = dir.path().join("empty.toml");
    fs::write(&empty, "").unwrap();
    assert!(load_scene(&empty).unwrap_err().to_string().contains("missing [camera]"));
}

const CUBE_OBJ: &str = "mtllib cube.mtl
o cube
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl glass
f 1/1 4/4 3/3 2/2
f 5/1 6/2 7/3 8/4
usemtl mirror
f 1/1 2/2 6/3 5/4
f 4/1 8/2 7/3 3/4
usemtl painted
f 1/1 5/2 8/3 4/4
f 2/1 3/2 7/3 6/4
";

const CUBE_MTL: &str = "newmtl glass
Kd 0.9 0.9 1.0
Ks 0.5 0.5 0.5
Ns 200
Ni 1.45
d 0.25
illum 7

newmtl mirror
Kd 0.2 0.2 0.2
Ks 0.8 0.8 0.8
illum 3

newmtl painted
Kd 0.5 0.25 1.0
Ns 10
d 0.5
illum 2
map_Kd tex.png
";

fn write_cube(dir: &Path) {
    fs::write(dir.join("cube.obj"), CUBE_OBJ).unwrap();
    fs::write(dir.join("cube.mtl"), CUBE_MTL).unwrap();
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb([255, 0, 0]));
    img.save(dir.join("tex.png")).unwrap();
}

#[test]
fn mtl_materials_are_mapped() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n");
    fs::write(dir.path().join("s.toml"), &text).unwrap();
    let loaded = load_scene(&dir.path().join("s.toml")).unwrap();
    let info = &loaded.info;
    assert_eq!(info.stored_triangles, 12);
    assert_eq!(info.meshes.len(), 1);
    assert_eq!(info.meshes[0].models, 3);
    assert_eq!(info.materials, ["red", "cube.obj/glass", "cube.obj/mirror", "cube.obj/painted"]);
    let m = &loaded.scene.materials;
    let glass = &m[1];
    assert!((glass.transmission - 0.75).abs() < 1e-6 && glass.transparency == 0.0);
    assert!((glass.ior - 1.45).abs() < 1e-6 && (glass.shininess - 200.0).abs() < 1e-6);
    assert!((glass.specular - 0.5).abs() < 1e-6);
    assert_eq!(glass.texture, Texture::Solid(Vec3::new(0.9, 0.9, 1.0)));
    let mirror = &m[2];
    assert!((mirror.reflectivity - 0.8).abs() < 1e-6);
    let painted = &m[3];
    assert!((painted.transparency - 0.5).abs() < 1e-6 && painted.transmission == 0.0);
    let Texture::Image { mapping, tint, image, .. } = &painted.texture else {
        panic!("map_Kd gives an image")
    };
    assert_eq!(*mapping, Mapping::Uv);
    assert_eq!(*tint, Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(image.width(), 2);
    // Inputs: the scene, the OBJ, the MTL and the texture.
    assert_eq!(loaded.inputs.len(), 4, "{:?}", loaded.inputs);
    let mesh = &loaded.scene.accel.meshes()[0];
    assert!(mesh.uvs().is_some());
    assert!(mesh.normals().is_some(), "smooth normals are computed when the file has none");
}

#[test]
fn a_named_material_overrides_the_mtl() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    // Even a missing MTL file does not matter then.
    fs::remove_file(dir.path().join("cube.mtl")).unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\nmaterial = \"red\"\n");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    assert_eq!(loaded.info.materials, ["red"]);
    assert!(loaded.scene.object_materials.iter().all(|&m| m == 0));
    // Without the override, the missing MTL is an error naming it.
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n");
    let err = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap_err().to_string();
    assert!(err.contains("cube.mtl") && err.contains("used at s.toml:"), "{err}");
}

#[test]
fn meshes_are_loaded_once_and_instanced() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    fs::create_dir(dir.path().join("sub")).unwrap();
    let mut text = BASE.to_string();
    for (i, p) in ["cube.obj", "./cube.obj", "sub/../cube.obj"].iter().enumerate() {
        text += &format!(
            "[[objects]]\ntype = \"mesh\"\npath = \"{p}\"\ntransform = [{{ translate = [{}, 0, 0] }}]\n",
            3 * i
        );
    }
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    let info = &loaded.info;
    assert_eq!(info.meshes.len(), 1);
    assert_eq!(info.meshes[0].instances, 3);
    assert_eq!(loaded.scene.accel.meshes().len(), 3, "three models, stored once");
    assert_eq!(info.objects, 9);
    assert_eq!(info.stored_triangles, 12);
    assert_eq!(info.instanced_triangles, 36);
    // MTL materials converted once, shared by the instances.
    assert_eq!(info.materials.len(), 4);
    assert!((info.bounds.max.x - 7.0).abs() < 1e-5, "{:?}", info.bounds);
}

#[test]
fn malformed_objs_are_reported_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], &str); 6] = [
        (
            "range.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "range.obj:4: face corner `9`: vertex index 9 is out of range",
        ),
        (
            "zero.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "zero.obj:4: face corner `0`: vertex index 0 is invalid",
        ),
        ("two.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n", "two.obj:3: a face needs at least 3 corners"),
        ("lines.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n", "no faces"),
        ("empty.obj", b"", "no faces"),
        ("garbage.obj", b"\x00\xff\xfe\x80binary", "not UTF-8"),
    ];
    for (name, bytes, words) in cases {
        fs::write(dir.path().join(name), bytes).unwrap();
        let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"{name}\"\n");
        let err = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap_err().to_string();
        assert!(err.contains(words), "{name}: {err}");
        assert!(
            err.contains(&format!(
                "(used at s.toml:{}:8)",
                line_of("[[objects]]\ntype = \"mesh\"\npath", "path")
            )),
            "{name}: {err}"
        );
    }
}

#[test]
fn corrupt_textures_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("bad.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let extra =
        "[materials.m]\ntexture = { type = \"image\", path = \"bad.png\", mapping = \"spherical\" }\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("bad.png") && err.contains("cannot use this texture"), "{err}");
    assert!(err.contains(&format!("used at test.toml:{}:", line_of(extra, "bad.png"))), "{err}");
}

#[test]
fn image_textures_load_and_are_shared() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let extra = "[materials.a]\ntexture = { type = \"image\", path = \"tex.png\", mapping = \"spherical\", scale = [2, 1] }\n\
                 [materials.b]\ntexture = { type = \"image\", path = \"./tex.png\", wrap = \"repeat\", tint = [0.5, 0.5, 0.5] }\n";
    let loaded = parse_scene_str(&format!("{BASE}{extra}"), dir.path(), Path::new("t.toml")).unwrap();
    let (Texture::Image { image: a, mapping, scale, .. }, Texture::Image { image: b, .. }) =
        (&loaded.scene.materials[0].texture, &loaded.scene.materials[1].texture)
    else {
        panic!("image textures")
    };
    assert!(std::sync::Arc::ptr_eq(a, b));
    assert_eq!(*mapping, Mapping::Spherical);
    assert_eq!(scale.x, 2.0);
    assert_eq!(loaded.inputs.len(), 1);
}

#[test]
fn the_documented_example_and_every_shipped_scene_load() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let example = doc.split("## A complete example").nth(1).unwrap();
    let toml_block = example.split("```toml").nth(1).unwrap().split("```").next().unwrap();
    let loaded = parse_scene_str(toml_block, &root, Path::new("docs/scene-format.md")).unwrap();
    assert_eq!(loaded.info.objects, 3);
    let mut n = 0;
    for e in fs::read_dir(root.join("scenes")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let loaded = load_scene(&p).unwrap_or_else(|e| panic!("{e}"));
            assert!(loaded.warnings.is_empty(), "{}: {:?}", p.display(), loaded.warnings);
            n += 1;
        }
    }
    assert!(n >= 10, "{n} scenes");
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
    assert!(err.starts_with("test.toml:6:7:") && err.contains("sequence"), "{err}");
    let text = BASE.replace("spp = 2", "spp = 2\naov_preview = 1");
    assert!(parse(&text).unwrap_err().to_string().starts_with("test.toml:6:"));
}

// ----- camera overrides ------------------------------------------------

fn with_overrides(overrides: Overrides) -> Result<LoadedScene, SceneError> {
    let opts = LoadOptions { overrides, ..LoadOptions::default() };
    parse_scene_str_with(BASE, Path::new("."), Path::new("test.toml"), &opts)
}

#[test]
fn camera_overrides_replace_the_file() {
    let loaded = with_overrides(Overrides {
        camera_pos: Some(Vec3::new(1.0, 2.0, 3.0)),
        fov: Some(30.0),
        ..Overrides::default()
    })
    .unwrap();
    let c = &loaded.settings.camera;
    assert_eq!(c.position(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(c.look_at(), Vec3::new(0.0, 1.0, 0.0), "look_at stays the file's");
    assert!((c.vfov_deg() - 30.0).abs() < 1e-5);
    let loaded = with_overrides(Overrides {
        look_at: Some(Vec3::new(0.0, 2.0, 0.0)),
        up: Some(Vec3::X),
        ..Overrides::default()
    })
    .unwrap();
    assert_eq!(loaded.info.camera.look_at(), Vec3::new(0.0, 2.0, 0.0));
    assert_eq!(loaded.info.camera.position(), Vec3::new(0.0, 2.0, 10.0));
}

#[test]
fn bad_camera_overrides_name_the_flag() {
    let cases: [(Overrides, &str, &str); 7] = [
        // The file's camera looks along (0, -1, -10).
        (Overrides { up: Some(Vec3::new(0.0, 1.0, 10.0)), ..Overrides::default() }, "--up: ", "parallel"),
        (Overrides { up: Some(Vec3::ZERO), ..Overrides::default() }, "--up: ", "zero"),
        (
            Overrides { camera_pos: Some(Vec3::new(f32::INFINITY, 0.0, 0.0)), ..Overrides::default() },
            "--camera-pos: ",
            "finite",
        ),
        (Overrides { look_at: Some(Vec3::splat(f32::NAN)), ..Overrides::default() }, "--look-at: ", "finite"),
        (Overrides { fov: Some(180.0), ..Overrides::default() }, "--fov: ", "between 0 and 180"),
        (Overrides { fov: Some(f32::NAN), ..Overrides::default() }, "--fov: ", "between 0 and 180"),
        (
            Overrides { camera_pos: Some(Vec3::new(0.0, 1.0, 0.0)), ..Overrides::default() },
            "--camera-pos: ",
            "must differ",
        ),
    ];
    for (ov, start, words) in cases {
        let err = with_overrides(ov).unwrap_err().to_string();
        assert!(err.starts_with(start) && err.contains(words), "{ov:?}: {err}");
    }
    // Looking straight down along the file's up: the moved end is named.
    let err =
        with_overrides(Overrides { camera_pos: Some(Vec3::new(0.0, 9.0, 0.0)), ..Overrides::default() })
            .unwrap_err()
            .to_string();
    assert!(err.starts_with("--camera-pos: ") && err.contains("--up"), "{err}");
}

// ----- an OBJ file as a scene ------------------------------------------

use prism_shade::Aov;

#[test]
fn an_obj_file_is_a_framed_scene() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let obj = dir.path().join("cube.obj");
    let loaded = load_path(&obj, &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let info = &loaded.info;
    assert_eq!((info.width, info.height), (640, 480));
    assert_eq!(info.objects, 3);
    assert_eq!(info.materials, ["cube.obj/glass", "cube.obj/mirror", "cube.obj/painted"]);
    assert_eq!(info.lights.len(), 1);
    // Bounds [-1, 1]³: centre 0, r = √3; eye at r / sin 20° on +Z.
    let r = 3f32.sqrt();
    let c = &info.camera;
    assert_eq!(c.look_at(), Vec3::ZERO);
    assert!((c.position() - Vec3::new(0.0, 0.0, r / 20f32.to_radians().sin())).length() < 1e-4);
    assert!((c.vfov_deg() - 40.0).abs() < 1e-5);
    assert!((info.lights[0].position - r * Vec3::new(1.0, 2.0, 1.5)).length() < 1e-4);
    // The mesh is in frame: the centre ray hits it, the corners miss.
    let cam = &loaded.settings.camera;
    assert!(loaded.scene.accel.closest_hit(&cam.ray(320.0, 240.0)).is_some());
    assert!(loaded.scene.accel.closest_hit(&cam.ray(0.5, 0.5)).is_none());
    // Inputs: the OBJ, its MTL, the texture.
    assert_eq!(loaded.inputs.len(), 3, "{:?}", loaded.inputs);
    // The extension is matched in any case; load_scene_with would read TOML.
    let upper = dir.path().join("CUBE.OBJ");
    fs::copy(&obj, &upper).unwrap();
    assert!(load_path(&upper, &LoadOptions::default()).is_ok());
    assert!(load_scene_with(&upper, &LoadOptions::default()).is_err());
}

#[test]
fn an_obj_scene_takes_overrides_and_frames_for_them() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let obj = dir.path().join("cube.obj");
    let opts = |overrides| LoadOptions { overrides, ..LoadOptions::default() };
    // A portrait image: the horizontal field of view is the narrower one.
    let loaded =
        load_path(&obj, &opts(Overrides { width: Some(100), height: Some(400), ..Overrides::default() }))
            .unwrap();
    let half_h = (20f32.to_radians().tan() * 0.25).atan();
    let z = loaded.info.camera.position().z;
    assert!((z - 3f32.sqrt() / half_h.sin()).abs() < 1e-3, "{z}");
    // --width alone keeps 4:3; --fov reframes; --camera-pos keeps the look-at.
    let loaded = load_path(
        &obj,
        &opts(Overrides {
            width: Some(64),
            fov: Some(60.0),
            camera_pos: Some(Vec3::new(5.0, 5.0, 5.0)),
            ..Overrides::default()
        }),
    )
    .unwrap();
    assert_eq!((loaded.info.width, loaded.info.height), (64, 48));
    assert_eq!(loaded.info.camera.position(), Vec3::splat(5.0));
    assert_eq!(loaded.info.camera.look_at(), Vec3::ZERO);
    assert!((loaded.info.camera.vfov_deg() - 60.0).abs() < 1e-5);
    let err = load_path(&obj, &opts(Overrides { up: Some(Vec3::Z), ..Overrides::default() }))
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("--up: "), "{err}");
}

#[test]
fn an_obj_without_materials_is_grey_and_errors_point_into_it() {
    let dir = tempfile::tempdir().unwrap();
    let tri = dir.path().join("tri.obj");
    fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let loaded = load_obj_scene(&tri, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.info.materials, ["(default)"]);
    // A material library that is missing: grey, with a warning.
    write_cube(dir.path());
    fs::remove_file(dir.path().join("cube.mtl")).unwrap();
    let loaded = load_path(&dir.path().join("cube.obj"), &LoadOptions::default()).unwrap();
    assert_eq!(loaded.info.materials, ["(default)"]);
    assert!(
        loaded.warnings.iter().any(|w| w.contains("cube.mtl") && w.contains("grey")),
        "{:?}",
        loaded.warnings
    );
    // A malformed OBJ: its own line, not "used at" itself.
    let bad = dir.path().join("bad.obj");
    fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    let err = load_path(&bad, &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.starts_with(&format!("{}:4: face corner `9`", bad.display())), "{err}");
    assert!(!err.contains("used at"), "{err}");
    let err = load_path(&dir.path().join("none.obj"), &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.contains("none.obj") && err.contains("no such file"), "{err}");
    let err = load_path(dir.path(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
    // Size limits apply to the default 640×480 too.
    let opts =
        LoadOptions { limits: Limits { max_side: 100, ..Limits::default() }, ..LoadOptions::default() };
    let err = load_path(&tri, &opts).unwrap_err().to_string();
    assert!(err.starts_with(&format!("{}: image width 640", tri.display())), "{err}");
}
