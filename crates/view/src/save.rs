//! PNG snapshots: numbered names, written atomically.

use crate::ViewError;
use crate::worker::pixels_to_rgb8;
use std::path::{Path, PathBuf};

/// The first free path `dir/{stem}-view-NNN.png` with `NNN >= from`
/// (numbered from 001), and its number (pass number + 1 as the next
/// `from`, so that saves still in flight do not collide).
#[must_use]
pub fn next_snapshot_path(dir: &Path, stem: &str, from: u32) -> (PathBuf, u32) {
    let mut n = from.max(1);
    loop {
        let p = dir.join(format!("{stem}-view-{n:03}.png"));
        if !p.exists() || n == u32::MAX {
            return (p, n);
        }
        n += 1;
    }
}

/// Writes `0x00RRGGBB` pixels as an 8-bit RGB PNG at `path`, atomically,
/// with the one image writer ([`prism_shade::write_png_rgb8`]): a reader
/// never sees a partial file; on error no temporary file is left.
///
/// # Errors
/// [`ViewError::Save`] if the file cannot be written or renamed.
pub fn save_png_atomic(path: &Path, width: u32, height: u32, pixels: &[u32]) -> Result<(), ViewError> {
    Ok(prism_shade::write_png_rgb8(path, width, height, &pixels_to_rgb8(pixels))?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saves_a_readable_png_and_leaves_no_temp_file() {
        let dir = std::env::temp_dir().join(format!("prism-view-save-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (p, n) = next_snapshot_path(&dir, "scene", 0);
        assert!(p.ends_with("scene-view-001.png"));
        assert_eq!(n, 1);
        save_png_atomic(&p, 2, 1, &[0x00ff_0000, 0x0000_80ff]).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (2, 1));
        assert_eq!(img.get_pixel(0, 0).0, [255, 0, 0]);
        assert_eq!(img.get_pixel(1, 0).0, [0, 0x80, 0xff]);
        assert!(next_snapshot_path(&dir, "scene", 1).0.ends_with("scene-view-002.png"));
        assert!(next_snapshot_path(&dir, "scene", 5).0.ends_with("scene-view-005.png"));
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1, "{names:?}");
        assert!(matches!(save_png_atomic(&p, 3, 1, &[0; 2]), Err(ViewError::Save(_))));
        let missing = dir.join("no-such-dir").join("x.png");
        assert!(matches!(save_png_atomic(&missing, 1, 1, &[0]), Err(ViewError::Save(_))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
