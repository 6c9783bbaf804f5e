//! Runs the `prism` binary: good scenes render; every class of bad scene
//! gives a non-zero exit, a message naming the file and line, no panic
//! text and no output file; writes are atomic; inputs are never
//! overwritten.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

const GOOD: &str = r#"[render]
width = 32
height = 18
spp = 1

[camera]
position = [0, 1, 5]
look_at = [0, 1, 0]

[[lights]]
position = [3, 5, 4]

[materials.red]
color = [0.8, 0.1, 0.1]

[[objects]]
type = "plane"

[[objects]]
type = "sphere"
center = [0, 1, 0]
radius = 1
material = "red"
"#;

fn prism(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_prism")).current_dir(dir).args(args).output().expect("run prism")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Files in `dir` (names), sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_good_scene_renders_with_a_closing_line() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("img.png: 32×18, 1 spp") && stdout.contains("M rays/s"), "{stdout}");
    let img = image::open(dir.path().join("img.png")).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (32, 18));
    // The sphere is red in the middle.
    let p = img.get_pixel(16, 8).0;
    assert!(p[0] > p[1] && p[0] > p[2], "{p:?}");
    assert_eq!(listing(dir.path()), ["img.png", "s.toml"], "no temporary file is left");
}

#[test]
fn the_default_output_is_out_slash_the_scene_name() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("scenes")).unwrap();
    fs::write(dir.path().join("scenes/ball.toml"), GOOD).unwrap();
    let out =
        prism(dir.path(), &["render", "scenes/ball.toml", "--quiet", "--width", "20", "--threads", "1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty(), "--quiet prints nothing: {}", text(&out.stdout));
    let img = image::open(dir.path().join("out/ball.png")).unwrap();
    // --width alone keeps the aspect ratio.
    assert_eq!((img.width(), img.height()), (20, 11));
}

#[test]
fn exr_output_is_linear_float() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.exr", "--spp", "2", "--no-fog"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let img = image::open(dir.path().join("img.exr")).unwrap();
    assert!(matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F), "{:?}", img.color());
}

#[test]
fn info_describes_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    for words in [
        "objects    2: 1 plane, 1 sphere",
        "triangles  0 stored",
        "materials  2: red, (default)",
        "lights     1",
        "bounds     (-1, 0, -1) to (1, 2, 1)",
    ] {
        assert!(s.contains(words), "{words:?} not in\n{s}");
    }
}

#[test]
fn info_counts_mesh_triangles_and_instances() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("t.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let scene = format!(
        "{GOOD}[[objects]]\ntype = \"mesh\"\npath = \"t.obj\"\n[[objects]]\ntype = \"mesh\"\npath = \"t.obj\"\ntransform = [{{ translate = [2, 0, 0] }}]\n"
    );
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(s.contains("2 triangles, 2 instances") && s.contains("triangles  2 stored, 4 instanced"), "{s}");
}

#[test]
fn inputs_are_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let png = image::RgbImage::from_pixel(2, 2, image::Rgb([1, 2, 3]));
    png.save(dir.path().join("tex.png")).unwrap();
    let before = fs::read(dir.path().join("tex.png")).unwrap();
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"tex.png\" }");
    fs::write(dir.path().join("s.toml"), &scene).unwrap();
    for target in ["tex.png", "./tex.png"] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", target]);
        assert!(!out.status.success());
        let err = text(&out.stderr);
        assert!(err.contains("refusing to write") && !err.contains("panicked"), "{err}");
        assert_eq!(fs::read(dir.path().join("tex.png")).unwrap(), before);
    }
    let out = prism(dir.path(), &["render", "s.toml", "-o", "s.toml"]);
    assert!(!out.status.success());
    assert_eq!(fs::read_to_string(dir.path().join("s.toml")).unwrap(), scene);
    assert_eq!(listing(dir.path()), ["s.toml", "tex.png"]);
}

/// A bad scene: the text, extra files, the expected line and words.
struct Bad {
    name: &'static str,
    scene: String,
    files: Vec<(&'static str, Vec<u8>)>,
    /// The location that must appear, e.g. `s.toml:7` (file and line).
    place: String,
    words: &'static str,
}

fn bad(name: &'static str, scene: String, place: &str, words: &'static str) -> Bad {
    Bad { name, scene, files: Vec::new(), place: place.to_string(), words }
}

fn line_of(scene: &str, needle: &str) -> usize {
    scene.lines().position(|l| l.contains(needle)).map_or(0, |i| i + 1)
}

fn bad_scenes() -> Vec<Bad> {
    let obj = |extra: &str| format!("{GOOD}[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\n{extra}");
    let with = |from: &str, to: &str| GOOD.replace(from, to);
    let at = |s: &str, needle: &str| format!("s.toml:{}:", line_of(s, needle));
    let mut v = Vec::new();

    let s = with("radius = 1", "radius = = 1");
    v.push(bad("toml syntax", s.clone(), &at(&s, "radius"), "expected"));
    let s = with("radius = 1", "radius = 1\nradios = 2");
    v.push(bad("unknown key", s.clone(), &at(&s, "radios"), "unknown field `radios`"));
    let s = with("radius = 1", "radius = \"one\"");
    v.push(bad("wrong type", s.clone(), &at(&s, "radius"), "expected f64"));
    let s = with("radius = 1\n", "");
    v.push(bad(
        "missing key",
        s.clone(),
        &format!("s.toml:{}:", s.lines().count() - 3),
        "a sphere needs `radius`",
    ));
    let s = with("radius = 1", "radius = nan");
    v.push(bad("nan", s.clone(), &at(&s, "radius"), "finite"));
    let s = with("center = [0, 1, 0]", "center = [0, inf, 0]");
    v.push(bad("infinity", s.clone(), &at(&s, "center"), "finite"));
    let s = with("radius = 1", "radius = -2");
    v.push(bad("negative radius", s.clone(), &at(&s, "radius"), "greater than 0"));
    let s = with("radius = 1", "radius = 1\ntransform = [{ scale = [1, 0, 1] }]");
    v.push(bad("singular transform", s.clone(), &at(&s, "transform"), "singular"));
    let s = with("material = \"red\"", "material = \"blue\"");
    v.push(bad("unknown material", s.clone(), &at(&s, "blue"), "unknown material `blue`"));
    let s = obj("");
    v.push(bad("missing mesh", s.clone(), &at(&s, "m.obj"), "no such file"));
    let s = with("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"none.png\" }");
    v.push(bad("missing texture", s.clone(), &at(&s, "none.png"), "cannot read texture"));
    let s = with("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"bad.png\" }");
    let mut b = bad("corrupt texture", s.clone(), &at(&s, "bad.png"), "cannot use this texture");
    b.files.push(("bad.png", b"\x89PNG\r\n\x1a\ntruncated".to_vec()));
    v.push(b);
    let s = obj("");
    let mut b = bad("obj index out of range", s.clone(), "m.obj:4", "out of range");
    b.files.push(("m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n".to_vec()));
    v.push(b);
    let s = obj("");
    let mut b = bad("obj binary garbage", s.clone(), &at(&s, "m.obj"), "not UTF-8");
    b.files.push(("m.obj", vec![0, 159, 146, 150, 255, 0, 1]));
    v.push(b);
    let s = obj("");
    let mut b = bad("obj lines only", s.clone(), &at(&s, "m.obj"), "no faces");
    b.files.push(("m.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n".to_vec()));
    v.push(b);
    let s = with("width = 32", "width = 1000000");
    v.push(bad("absurd resolution", s.clone(), &at(&s, "width"), "over the limit"));
    let s = with("spp = 1", "spp = 0");
    v.push(bad("zero samples", s.clone(), &at(&s, "spp"), "at least 1"));
    let s = with("spp = 1", "max_depth = 1000000000");
    v.push(bad("huge depth", s.clone(), &at(&s, "max_depth"), "over the limit"));
    let s = with("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nup = [0, 0, -3]");
    v.push(bad("up parallel to view", s.clone(), &at(&s, "up ="), "parallel"));
    let s = format!("{GOOD}[fog]\nstart = 10\nend = 2\n");
    v.push(bad("fog end before start", s.clone(), &at(&s, "end = 2"), "greater than fog start"));
    v.push(bad("empty file", String::new(), "s.toml", "missing [camera]"));
    v
}

#[test]
fn every_class_of_bad_scene_fails_cleanly() {
    let cases = bad_scenes();
    assert!(cases.len() >= 10);
    for case in cases {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("s.toml"), &case.scene).unwrap();
        for (name, bytes) in &case.files {
            fs::write(dir.path().join(name), bytes).unwrap();
        }
        let before = listing(dir.path());
        let out = prism(dir.path(), &["render", "s.toml", "-o", "out/img.png"]);
        let err = text(&out.stderr);
        let name = case.name;
        assert!(!out.status.success(), "{name}: expected failure, got success");
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(err.starts_with("error: "), "{name}: {err}");
        assert!(err.contains(&case.place), "{name}: {err:?} does not name {}", case.place);
        assert!(err.contains(case.words), "{name}: {err:?} lacks {:?}", case.words);
        assert!(!err.contains("panicked") && !err.contains("RUST_BACKTRACE"), "{name}: {err}");
        assert_eq!(listing(dir.path()), before, "{name}: no output file or directory may be created");
        // prism info reports the same error.
        let info = prism(dir.path(), &["info", "s.toml"]);
        assert!(!info.status.success() && text(&info.stderr).contains(&case.place), "{name}: info");
    }
}

#[test]
fn bad_options_and_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let cases: [(&[&str], &str); 7] = [
        (&["render", "s.toml", "--width", "0"], "--width: image width must be at least 1"),
        (&["render", "s.toml", "--spp", "0"], "--spp:"),
        (&["render", "s.toml", "--width", "100000"], "--max-side"),
        (&["render", "s.toml", "-o", "x.jpg"], "use a .png or .exr"),
        (&["render", "none.toml"], "none.toml: cannot read scene file"),
        (&["render", "."], "directory"),
        (&["render", "s.toml", "--max-depth", "1000"], "--max-depth:"),
    ];
    for (args, words) in cases {
        let out = prism(dir.path(), args);
        let err = text(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(err.contains(words), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert_eq!(listing(dir.path()), ["s.toml"]);
    // Clap's own usage errors exit with 2.
    let out = prism(dir.path(), &["render", "s.toml", "--fog", "--no-fog"]);
    assert_eq!(out.status.code(), Some(2));
}
