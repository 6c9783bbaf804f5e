//! `prism render --aov --aov-files`: the passes are written next to the
//! image as separate files and read back with the right sizes and values
//! (the default, one multi-layer EXR, is tested in tests/outputs.rs); unknown pass names are refused
//! before anything is written; an OBJ file renders on its own, framed; the
//! camera flags move the camera and bad values are refused naming the flag.

use prism_shade::read_exr_rgb;
use std::fs;
use std::path::Path;
use std::process::{Command, Output};

/// A unit sphere at the origin, seen from (0, 0, 5): d = 5, r = 1. An odd
/// size puts the centre of pixel (16, 12) on the optical axis.
const SPHERE: &str = r#"[render]
width = 33
height = 25
spp = 1

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 30

[[lights]]
position = [3, 5, 4]

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
"#;

/// A tetrahedron, with no material library.
const TETRA: &str = "v 0 1 0\nv -1 -1 1\nv 1 -1 1\nv 0 -1 -1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n";

fn prism(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_prism")).current_dir(dir).args(args).output().expect("run prism")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Pixel `(i, j)` of an EXR file: its R, G, B.
fn exr_pixel(path: &Path, i: u32, j: u32) -> [f32; 3] {
    let (w, _, data) = read_exr_rgb(path).unwrap_or_else(|e| panic!("{e}"));
    let k = 3 * (j * w + i) as usize;
    [data[k], data[k + 1], data[k + 2]]
}

fn exr_size(path: &Path) -> (u32, u32) {
    let (w, h, _) = read_exr_rgb(path).unwrap_or_else(|e| panic!("{e}"));
    (w, h)
}

fn scene_dir(scene: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    dir
}

#[test]
fn aov_flag_writes_every_pass_with_analytic_values() {
    let dir = scene_dir(SPHERE);
    let out = prism(
        dir.path(),
        &[
            "render",
            "s.toml",
            "-o",
            "out.exr",
            "--aov-files",
            "--aov",
            "depth,normal,geo_normal,albedo,object_id",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let names = ["depth", "normal", "geo_normal", "albedo", "object_id"];
    let stdout = text(&out.stdout);
    for n in names {
        assert!(stdout.contains(&format!("wrote out.{n}.exr")), "{stdout}");
    }
    let mut want: Vec<String> = names.iter().map(|n| format!("out.{n}.exr")).collect();
    want.extend(["out.exr".into(), "s.toml".into()]);
    want.sort();
    assert_eq!(listing(dir.path()), want);
    let p = |n: &str| dir.path().join(format!("out.{n}.exr"));
    for n in names {
        assert_eq!(exr_size(&p(n)), (33, 25), "{n}");
    }
    assert_eq!(exr_size(&dir.path().join("out.exr")), (33, 25));

    // Depth at the centre: d − r = 4; a corner misses: +inf, id −1.
    let depth = exr_pixel(&p("depth"), 16, 12)[0];
    assert!((depth - 4.0).abs() <= 4e-4, "{depth}");
    assert_eq!(exr_pixel(&p("depth"), 0, 0)[0], f32::INFINITY);
    assert_eq!(exr_pixel(&p("object_id"), 16, 12)[0], 0.0);
    assert_eq!(exr_pixel(&p("object_id"), 0, 0)[0], -1.0);
    assert_eq!(exr_pixel(&p("object_id"), 32, 24)[0], -1.0);
    // The normal at the centre faces the camera; misses are 0.
    for n in ["normal", "geo_normal"] {
        let [x, y, z] = exr_pixel(&p(n), 16, 12);
        assert!(x.abs() < 1e-4 && y.abs() < 1e-4 && (z - 1.0).abs() < 1e-4, "{n}: {x} {y} {z}");
        assert_eq!(exr_pixel(&p(n), 0, 0), [0.0; 3]);
    }
    // The default material's colour, unlit.
    let [r, g, b] = exr_pixel(&p("albedo"), 16, 12);
    assert!(r > 0.0 && r == g && g == b, "{r} {g} {b}");
    assert_eq!(exr_pixel(&p("albedo"), 0, 0), [0.0; 3]);
}

#[test]
fn aov_previews_are_written_when_asked() {
    let dir = scene_dir(SPHERE);
    let out = prism(
        dir.path(),
        &["render", "s.toml", "-o", "img.png", "--aov-files", "--aov", "depth,normal", "--aov-preview"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        listing(dir.path()),
        ["img.depth.exr", "img.depth.png", "img.normal.exr", "img.normal.png", "img.png", "s.toml"]
    );
    for n in ["depth", "normal"] {
        let img = image::open(dir.path().join(format!("img.{n}.png"))).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (33, 25));
        assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0], "misses are black");
        assert_ne!(img.get_pixel(16, 12).0, [0, 0, 0], "{n}: the sphere shows");
    }
    // Without --aov-preview, no previews.
    let out =
        prism(dir.path(), &["render", "s.toml", "-o", "b.png", "--aov-files", "--aov", "object_id", "-q"]);
    assert!(out.status.success() && out.stdout.is_empty(), "{}", text(&out.stderr));
    assert!(dir.path().join("b.object_id.exr").is_file());
    assert!(!dir.path().join("b.object_id.png").exists());
}

#[test]
fn the_scene_file_can_ask_for_passes() {
    let scene = SPHERE.replace("spp = 1", "spp = 1\naov = [\"depth\", \"object_id\"]\naov_preview = true");
    let dir = scene_dir(&scene);
    let out = prism(dir.path(), &["render", "s.toml", "-o", "x.exr", "--aov-files"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        listing(dir.path()),
        ["s.toml", "x.depth.exr", "x.depth.png", "x.exr", "x.object_id.exr", "x.object_id.png"]
    );
    let depth = exr_pixel(&dir.path().join("x.depth.exr"), 16, 12)[0];
    assert!((depth - 4.0).abs() <= 4e-4, "{depth}");
    // --aov replaces the scene's list.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "y.exr", "--aov-files", "--aov", "normal"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("y.normal.exr").is_file() && !dir.path().join("y.depth.exr").exists());
    // --aov none clears it (the scene's previews then make nothing, with a warning).
    let out = prism(dir.path(), &["render", "s.toml", "-o", "z.png", "--aov", "none"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        listing(dir.path()).iter().all(|f| !f.starts_with("z.") || f == "z.png"),
        "{:?}",
        listing(dir.path())
    );
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(
        text(&out.stdout).contains("aov        depth, object_id, with PNG previews"),
        "{}",
        text(&out.stdout)
    );
}

#[test]
fn unknown_pass_names_are_refused_and_nothing_is_written() {
    let dir = scene_dir(SPHERE);
    for list in ["depth,dept", "Depth"] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", "out.exr", "--aov-files", "--aov", list]);
        assert!(!out.status.success(), "{list:?}");
        let err = text(&out.stderr);
        assert!(
            err.starts_with("error: --aov: unknown AOV pass")
                && err.contains("depth, normal, geo_normal, albedo, object_id"),
            "{list:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(listing(dir.path()), ["s.toml"]);
    }
    // In the scene file: the place, and the valid names.
    let scene = SPHERE.replace("spp = 1", "spp = 1\naov = [\"depth\", \"normals\"]");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "out.exr"]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.starts_with("error: s.toml:5:17: unknown AOV pass `normals`"), "{err}");
    assert!(err.contains("geo_normal, albedo, object_id"), "{err}");
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

#[test]
fn empty_lists_and_none_say_what_is_wrong() {
    let dir = scene_dir(SPHERE);
    for (list, words) in [
        ("", "error: --aov: the list of AOV passes is empty: give pass names"),
        (" ", "error: --aov: the list of AOV passes is empty: give pass names"),
        (",,", "error: --aov: the list of AOV passes has an empty entry"),
        ("depth,,normal", "error: --aov: the list of AOV passes has an empty entry"),
        ("depth,none", "error: --aov: `none` means no pass and stands alone"),
    ] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", "out.exr", "--aov", list]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{list:?}: {err}");
        assert!(err.starts_with(words), "{list:?}: {err}");
        assert!(!err.contains("did you mean") && !err.contains("unknown"), "{list:?}: {err}");
        assert_eq!(listing(dir.path()), ["s.toml"]);
    }
    // In a scene file, `["none"]` is no pass, as `--aov none`; the
    // previews the file asks for are then warned of by its key.
    let scene = SPHERE.replace("spp = 1", "spp = 1\naov = [\"none\"]\naov_preview = true");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "out.png"]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: s.toml: `aov_preview = true` without AOV passes")
            && !err.contains("--aov-preview"),
        "{err}"
    );
    assert_eq!(listing(dir.path()), ["out.png", "s.toml"]);
    // The flag is named when it was the flag.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "out.png", "--aov-preview"]);
    assert!(text(&out.stderr).contains("warning: --aov-preview without AOV passes"), "{}", text(&out.stderr));
    for (list, words) in [
        (r#"["depth", "none"]"#, "s.toml:5:17: `none` means no pass and stands alone"),
        (r#"["depth", ""]"#, "s.toml:5:17: the list of AOV passes has an empty entry"),
    ] {
        fs::write(dir.path().join("s.toml"), SPHERE.replace("spp = 1", &format!("spp = 1\naov = {list}")))
            .unwrap();
        let out = prism(dir.path(), &["render", "s.toml", "-o", "x.png"]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{list}: {err}");
        assert!(err.starts_with(&format!("error: {words}")), "{list}: {err}");
    }
}

#[test]
fn an_obj_file_renders_on_its_own_in_frame() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("tetra.obj"), TETRA).unwrap();
    let out = prism(
        dir.path(),
        &[
            "render",
            "tetra.obj",
            "-o",
            "t.exr",
            "--width",
            "32",
            "--spp",
            "1",
            "--aov-files",
            "--aov",
            "object_id,depth",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("t.exr: 32×24, 1 spp"), "{}", text(&out.stdout));
    let id = |i, j| exr_pixel(&dir.path().join("t.object_id.exr"), i, j)[0];
    assert!(id(16, 12) >= 0.0, "the mesh is at the centre");
    assert_eq!(id(0, 0), -1.0, "and inside the frame");
    assert_eq!(id(31, 23), -1.0);
    // The beauty is not blank: the lit mesh differs from the background.
    let beauty = dir.path().join("t.exr");
    let (centre, corner) = (exr_pixel(&beauty, 16, 12), exr_pixel(&beauty, 0, 0));
    assert!(centre.iter().sum::<f32>() > corner.iter().sum::<f32>() + 0.05, "{centre:?} {corner:?}");
    assert!(corner.iter().sum::<f32>() > 0.0, "the background is not black");
    // `prism info` reads it too; the default output is named after it.
    let out = prism(dir.path(), &["info", "tetra.obj"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("640×480") && text(&out.stdout).contains("(default)"));
    // The tetrahedron is closed (a solid); without its last face it is open.
    assert!(text(&out.stdout).contains("1 model (1 closed), 4 triangles"), "{}", text(&out.stdout));
    fs::write(dir.path().join("open.obj"), TETRA.trim_end().rsplit_once('\n').unwrap().0).unwrap();
    let out = prism(dir.path(), &["info", "open.obj"]);
    assert!(text(&out.stdout).contains("1 model (0 closed), 3 triangles"), "{}", text(&out.stdout));
    let out = prism(dir.path(), &["render", "tetra.obj", "--width", "16", "-q"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("out/tetra.png").is_file());
    // A malformed OBJ names its line, and writes nothing.
    fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let out = prism(dir.path(), &["render", "bad.obj", "-o", "bad.png"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).starts_with("error: bad.obj:3: face corner `3`"), "{}", text(&out.stderr));
    assert!(!dir.path().join("bad.png").exists());
}

#[test]
fn the_shipped_gem_renders_with_its_material() {
    let gem = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/gem.obj");
    let dir = tempfile::tempdir().unwrap();
    let out = prism(
        dir.path(),
        &[
            "render",
            gem.to_str().unwrap(),
            "-o",
            "g.exr",
            "--width",
            "24",
            "--spp",
            "1",
            "--aov-files",
            "--aov",
            "object_id",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(exr_pixel(&dir.path().join("g.object_id.exr"), 12, 9)[0], 0.0);
    let out = prism(dir.path(), &["info", gem.to_str().unwrap()]);
    assert!(text(&out.stdout).contains("gem.obj/gem"), "{}", text(&out.stdout));
}

#[test]
fn camera_flags_move_the_camera() {
    let dir = scene_dir(SPHERE);
    let depth_at_centre = |args: &[&str]| {
        let mut all = vec!["render", "s.toml", "-o", "c.exr", "--aov-files", "--aov", "depth", "-q"];
        all.extend_from_slice(args);
        let out = prism(dir.path(), &all);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        exr_pixel(&dir.path().join("c.depth.exr"), 16, 12)[0]
    };
    assert!((depth_at_centre(&[]) - 4.0).abs() < 4e-4);
    // Twice as far: depth 9.
    let d = depth_at_centre(&["--camera-pos", "0,0,10"]);
    assert!((d - 9.0).abs() < 9e-4, "{d}");
    // From below, with a negative coordinate and another up.
    let d = depth_at_centre(&["--camera-pos", "0,-6,0", "--up", "0,0,1"]);
    assert!((d - 5.0).abs() < 5e-4, "{d}");
    // Looking past the sphere: the centre misses.
    assert_eq!(depth_at_centre(&["--look-at", "5,0,0"]), f32::INFINITY);
    // A wider field of view leaves the centre as it is, and changes the image.
    let before = fs::read(dir.path().join("c.exr")).unwrap();
    assert!((depth_at_centre(&["--fov", "90"]) - 4.0).abs() < 4e-4);
    assert_ne!(fs::read(dir.path().join("c.exr")).unwrap(), before);
}

#[test]
fn bad_camera_flags_are_refused_naming_the_flag() {
    let dir = scene_dir(SPHERE);
    let cases: [(&[&str], &str); 9] = [
        (&["--up", "0,0,1"], "error: --up: "),
        (&["--up", "0,0,0"], "error: --up: "),
        (&["--camera-pos", "0,0,0.0", "--look-at", "0,0,0"], "error: --camera-pos: "),
        (&["--camera-pos", "nan,0,1"], "error: --camera-pos: "),
        (&["--look-at", "1e39,0,0"], "error: --look-at: "),
        (&["--fov", "0"], "error: --fov: "),
        (&["--fov", "180"], "error: --fov: "),
        (&["--camera-pos", "1,2"], "--camera-pos"),
        (&["--up", "a,b,c"], "--up"),
    ];
    for (args, start) in cases {
        let mut all = vec!["render", "s.toml", "-o", "x.png"];
        all.extend_from_slice(args);
        let out = prism(dir.path(), &all);
        assert!(!out.status.success(), "{args:?}");
        let err = text(&out.stderr);
        assert!(err.contains(start) && !err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(listing(dir.path()), ["s.toml"], "{args:?}");
    }
}

/// The ids docs/aov.md gives: the render's objects, a mesh entry once per
/// model of its OBJ file (`o` groups here), the entries after it
/// numbered on from there, as `prism info` counts them.
#[test]
fn object_ids_count_a_mesh_once_per_model() {
    let obj = "o left\nv -2 -1 0\nv -0.5 -1 0\nv -0.5 1 0\nv -2 1 0\nf 1 2 3 4\n\
               o right\nv 0.5 -1 0\nv 2 -1 0\nv 2 1 0\nv 0.5 1 0\nf 5 6 7 8\n";
    let scene = "[render]\nwidth = 64\nheight = 48\nspp = 1\n\
                 [camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\n\
                 [[lights]]\nposition = [0, 0, 5]\n\
                 [[objects]]\ntype = \"mesh\"\npath = \"two.obj\"\n\
                 [[objects]]\ntype = \"sphere\"\ncenter = [0, 1.6, 0]\nradius = 0.3\n";
    let dir = scene_dir(scene);
    fs::write(dir.path().join("two.obj"), obj).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "t.exr", "--aov-files", "--aov", "object_id"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let id = |i, j| exr_pixel(&dir.path().join("t.object_id.exr"), i, j)[0];
    // 45° vertical field of view at 6: 1 unit is about 9.66 pixels.
    assert_eq!([id(18, 24), id(45, 24), id(32, 9), id(32, 24)], [0.0, 1.0, 2.0, -1.0]);
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(text(&out.stdout).contains("objects    3: 2 mesh, 1 sphere"), "{}", text(&out.stdout));
}
