//! Unit tests of the loader, by topic: parsing and every class of error
//! with its place (`parse`), files the scene names (`files`), overrides and
//! an OBJ file as a scene (`overrides`), the pure build from a string and
//! in-memory resources (`build`). Shared here: a base scene and helpers.

use super::*;
use std::fs;

mod build;
mod files;
mod lights;
mod messages;
mod obj_mode;
mod overrides;
mod parse;
mod set;

pub(super) const BASE: &str = r#"
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

pub(super) fn parse(text: &str) -> Result<LoadedScene, SceneError> {
    parse_scene_str(text, Path::new("."), Path::new("test.toml"))
}

/// Parses `BASE + extra`, expects an error, and checks it starts with
/// `test.toml:` and contains `words` (its line: [`assert_at`]).
pub(super) fn expect_err(extra: &str, words: &str) -> String {
    assert!(!words.is_empty(), "name the words the message must hold");
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
pub(super) fn line_of(extra: &str, needle: &str) -> usize {
    let text = format!("{BASE}{extra}");
    text.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0)
}

/// For each `(extra, words, at)`: `BASE + extra` is refused with a
/// message containing `words`, at the line of `at` when given.
pub(super) fn refused(cases: &[(&str, &str, Option<&str>)]) {
    for (extra, words, at) in cases {
        let err = expect_err(extra, words);
        if let Some(needle) = at {
            assert_at(&err, extra, needle);
        }
    }
}

pub(super) fn assert_at(err: &str, extra: &str, needle: &str) {
    let line = line_of(extra, needle);
    assert!(err.starts_with(&format!("test.toml:{line}:")), "{err:?} should point at line {line} ({needle})");
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
Ke 0.25 0.5 0
Ns 10
d 0.5
illum 2
map_Kd tex.png
";

pub(super) fn write_cube(dir: &Path) {
    fs::write(dir.join("cube.obj"), CUBE_OBJ).unwrap();
    fs::write(dir.join("cube.mtl"), CUBE_MTL).unwrap();
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb([255, 0, 0]));
    img.save(dir.join("tex.png")).unwrap();
}
