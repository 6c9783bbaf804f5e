//! Shared by the scene and OBJ targets: a directory with a small OBJ, MTL
//! and PNG, and a check that every error names its place.

use prism_scene::SceneError;
use std::path::PathBuf;

/// A fresh directory (kept for the life of the process) holding `m.obj`
/// (a triangle using material `m` of `m.mtl`), `m.mtl` (with `map_Kd t.png`)
/// and `t.png` (2×2).
pub fn asset_dir() -> PathBuf {
    let dir = tempfile::tempdir().expect("a temporary directory").keep();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n";
    std::fs::write(dir.join("m.obj"), obj).expect("write m.obj");
    std::fs::write(dir.join("m.mtl"), "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd t.png\n").expect("write m.mtl");
    let png = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x * 200) as u8, (y * 200) as u8, 7]));
    png.save(dir.join("t.png")).expect("write t.png");
    dir
}

/// Errors from loading a file always point into a file, with a message.
pub fn check_message(e: &SceneError) {
    let text = e.to_string();
    assert!(e.location().is_some(), "an error without a place: {text}");
    assert!(!text.trim().is_empty(), "an empty message");
}
