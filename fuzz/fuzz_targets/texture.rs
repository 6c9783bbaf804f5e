//! Texture decoding: the input is an image file (PNG, JPEG, BMP, EXR or
//! anything else) given to `ImageTexture::load`, the function the scene
//! loader uses.
#![no_main]

use libfuzzer_sys::fuzz_target;
use prism_shade::{ImageTexture, Wrap};
use std::path::PathBuf;
use std::sync::OnceLock;

fn path() -> &'static PathBuf {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let d = DIR.get_or_init(|| tempfile::tempdir().expect("a temporary directory"));
        d.path().join("t.img")
    })
}

fuzz_target!(|data: &[u8]| {
    if std::fs::write(path(), data).is_err() {
        return;
    }
    if let Ok(t) = ImageTexture::load(path(), Wrap::Repeat) {
        // Sampling a decoded texture must be finite everywhere.
        for uv in [(0.0, 0.0), (0.5, 0.5), (-3.2, 7.9), (1.0, 1.0)] {
            let c = t.sample(prism_geometry::glam::Vec2::new(uv.0, uv.1));
            assert!(c.is_finite() && c.min_element() >= 0.0, "texel {c}");
        }
    }
});
