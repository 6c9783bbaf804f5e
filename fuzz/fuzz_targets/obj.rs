//! OBJ and MTL through prism's loader: the input is split at the first
//! `\n#MTL\n` into an OBJ file and its MTL library (`m.mtl`), written next
//! to a small PNG; scenes that use the mesh with its own materials and with
//! a scene material are loaded.
#![no_main]

use libfuzzer_sys::fuzz_target;
use prism_scene::{LoadOptions, load_scene_with};
use std::path::PathBuf;
use std::sync::OnceLock;

#[path = "common.rs"]
mod common;

fn dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = common::asset_dir();
        let scene = |material: &str| {
            format!(
                "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n[materials.red]\ncolor = [1, 0, 0]\n\
                 [[objects]]\ntype = \"mesh\"\npath = \"f.obj\"\n{material}"
            )
        };
        let _ = std::fs::write(d.join("own.toml"), scene(""));
        let _ = std::fs::write(d.join("red.toml"), scene("material = \"red\"\nnormals = \"smooth\"\n"));
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let (obj, mtl) = split(data);
    let d = dir();
    if std::fs::write(d.join("f.obj"), obj).is_err() || std::fs::write(d.join("m.mtl"), mtl).is_err() {
        return;
    }
    for scene in ["own.toml", "red.toml"] {
        if let Err(e) = load_scene_with(&d.join(scene), &LoadOptions::default()) {
            common::check_message(&e);
        }
    }
});

fn split(data: &[u8]) -> (&[u8], &[u8]) {
    const SEP: &[u8] = b"\n#MTL\n";
    match data.windows(SEP.len()).position(|w| w == SEP) {
        Some(i) => (&data[..i + 1], &data[i + SEP.len()..]),
        None => (data, b""),
    }
}
