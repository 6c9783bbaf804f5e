//! The scene parser through the real loading path: the input is a scene
//! file (any bytes) in a directory that also holds a small OBJ, MTL and
//! PNG, so that scenes naming `m.obj`, `m.mtl` or `t.png` load them too.
#![no_main]

use libfuzzer_sys::fuzz_target;
use prism_scene::{LoadOptions, load_scene_with};
use std::path::PathBuf;
use std::sync::OnceLock;

#[path = "common.rs"]
mod common;

fn dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(common::asset_dir)
}

fuzz_target!(|data: &[u8]| {
    let path = dir().join("s.toml");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Err(e) = load_scene_with(&path, &LoadOptions::default()) {
        common::check_message(&e);
    }
});
