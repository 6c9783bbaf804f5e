//! Inputs found by (or written for) the fuzz targets in `fuzz/`, kept as
//! regression tests: every file under `tests/fuzz-regressions/TARGET/` is
//! loaded the way its target loads it (see `fuzz/fuzz_targets/` and
//! docs/fuzzing.md) and must give a result or an error that names a place
//! in a file; never a panic.

use prism_scene::{LoadOptions, SceneError, load_scene_with};
use prism_shade::{ImageTexture, Wrap};
use std::fs;
use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions").join(target);
    let mut v: Vec<PathBuf> = fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.is_file())
        .collect();
    assert!(!v.is_empty(), "{} holds no inputs: the test would check nothing", dir.display());
    v.sort();
    v
}

/// The fuzz targets' asset directory: `m.obj` using material `m` of
/// `m.mtl`, which textures it with `t.png`.
fn asset_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n";
    fs::write(d.join("m.obj"), obj).expect("m.obj");
    fs::write(d.join("m.mtl"), "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd t.png\n").expect("m.mtl");
    let png = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x * 200) as u8, (y * 200) as u8, 7]));
    png.save(d.join("t.png")).expect("t.png");
    dir
}

fn check(input: &Path, result: Result<prism_scene::LoadedScene, SceneError>) {
    if let Err(e) = result {
        assert!(e.location().is_some(), "{}: an error without a place: {e}", input.display());
    }
}

#[test]
fn scene_inputs() {
    let dir = asset_dir();
    for input in inputs("scene") {
        let path = dir.path().join("s.toml");
        fs::copy(&input, &path).expect("copy");
        check(&input, load_scene_with(&path, &LoadOptions::default()));
    }
}

#[test]
fn obj_inputs() {
    const SEP: &[u8] = b"\n#MTL\n";
    let dir = asset_dir();
    let d = dir.path();
    let scene = |material: &str| {
        format!(
            "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n[materials.red]\ncolor = [1, 0, 0]\n\
             [[objects]]\ntype = \"mesh\"\npath = \"f.obj\"\n{material}"
        )
    };
    fs::write(d.join("own.toml"), scene("")).expect("own.toml");
    fs::write(d.join("red.toml"), scene("material = \"red\"\nnormals = \"smooth\"\n")).expect("red.toml");
    for input in inputs("obj") {
        let data = fs::read(&input).expect("read");
        let (obj, mtl) = match data.windows(SEP.len()).position(|w| w == SEP) {
            Some(i) => (&data[..i + 1], &data[i + SEP.len()..]),
            None => (&data[..], &b""[..]),
        };
        fs::write(d.join("f.obj"), obj).expect("f.obj");
        fs::write(d.join("m.mtl"), mtl).expect("m.mtl");
        for scene in ["own.toml", "red.toml"] {
            check(&input, load_scene_with(&d.join(scene), &LoadOptions::default()));
        }
    }
}

#[test]
fn texture_inputs() {
    for input in inputs("texture") {
        if let Ok(t) = ImageTexture::load(&input, Wrap::Repeat) {
            for uv in [(0.0, 0.0), (0.5, 0.5), (-3.2, 7.9), (1.0, 1.0)] {
                let c = t.sample(prism_geometry::glam::Vec2::new(uv.0, uv.1));
                assert!(c.is_finite() && c.min_element() >= 0.0, "{}: texel {c}", input.display());
            }
        }
    }
}

/// A mesh or texture path naming a device would be read forever.
#[cfg(unix)]
#[test]
fn devices_are_not_read_as_meshes_or_textures() {
    let dir = tempfile::tempdir().expect("temp dir");
    let base = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n";
    for (what, extra) in [
        ("mesh", "[[objects]]\ntype = \"mesh\"\npath = \"/dev/zero\"\n"),
        (
            "texture",
            "[materials.t]\ntexture = { type = \"image\", path = \"/dev/zero\" }\n[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"t\"\n",
        ),
    ] {
        let path = dir.path().join("s.toml");
        fs::write(&path, format!("{base}{extra}")).expect("write");
        let e = load_scene_with(&path, &LoadOptions::default()).expect_err(what);
        let text = e.to_string();
        assert!(text.contains("not a regular file") && text.contains("s.toml:"), "{what}: {text}");
    }
}

/// The same through an OBJ's material library and its `map_Kd`.
#[cfg(unix)]
#[test]
fn devices_are_not_read_as_material_libraries_or_their_textures() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    fs::write(d.join("s.toml"), "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\n").expect("s.toml");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
    fs::write(d.join("m.obj"), format!("mtllib /dev/zero\n{tri}")).expect("m.obj");
    let e = load_scene_with(&d.join("s.toml"), &LoadOptions::default()).expect_err("mtllib");
    let text = e.to_string();
    assert!(text.contains("cannot use material library /dev/zero") && e.location().is_some(), "{text}");
    // A texture that cannot be read is not read: a warning, and the colour.
    fs::write(d.join("m.obj"), format!("mtllib m.mtl\n{tri}")).expect("m.obj");
    fs::write(d.join("m.mtl"), "newmtl m\nmap_Kd /dev/zero\n").expect("m.mtl");
    let loaded = load_scene_with(&d.join("s.toml"), &LoadOptions::default()).expect("map_Kd");
    assert!(
        loaded.warnings.iter().any(|w| w.contains("/dev/zero: it is not a regular file")),
        "{:?}",
        loaded.warnings
    );
    assert!(matches!(loaded.scene.materials[0].texture, prism_shade::Texture::Solid(_)));
}
