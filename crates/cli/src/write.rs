//! Writing the image: PNG or EXR by extension, atomically (a temporary
//! file in the same directory, renamed over the target once complete and
//! synced; removed on any error), never over an input of the render.

use anyhow::{Context, Result, bail};
use image::{ImageFormat, Rgb32FImage, RgbImage};
use prism_shade::Image;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float linear OpenEXR.
    Exr,
}

impl Format {
    /// The format named by `path`'s extension.
    pub fn from_path(path: &Path) -> Result<Self> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some(other) => {
                bail!("{}: cannot write .{other} images; use a .png or .exr output name", path.display())
            }
            None => bail!("{}: the output name needs a .png or .exr extension", path.display()),
        }
    }
}

/// Refuses an output path that is (or will replace) one of `inputs`, or
/// that is a directory.
pub fn check_not_an_input(output: &Path, inputs: &[PathBuf]) -> Result<()> {
    if output.is_dir() {
        bail!("{}: the output is a directory; give a file name ending in .png or .exr", output.display());
    }
    let target = match std::fs::canonicalize(output) {
        Ok(p) => Some(p),
        Err(_) => {
            // Not there yet: its directory (if it exists) plus its name.
            let dir = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
            match (std::fs::canonicalize(dir), output.file_name()) {
                (Ok(d), Some(name)) => Some(d.join(name)),
                _ => None,
            }
        }
    };
    if let Some(t) = target
        && inputs.contains(&t)
    {
        bail!(
            "{}: refusing to write the image over an input of this render (the scene, a mesh, a material library or a texture)",
            output.display()
        );
    }
    Ok(())
}

/// Writes `image` to `path` atomically.
pub fn write_image(image: &Image, path: &Path, format: Format) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let context = || format!("cannot write {}", path.display());
    let mut tmp =
        tempfile::Builder::new().prefix(".prism-").suffix(".tmp").tempfile_in(dir).with_context(context)?;
    {
        let mut out = BufWriter::new(tmp.as_file_mut());
        match format {
            Format::Png => {
                let buf = RgbImage::from_raw(image.width, image.height, image.to_srgb8())
                    .context("internal error: the image buffer does not match its size")?;
                buf.write_to(&mut out, ImageFormat::Png).with_context(context)?;
            }
            Format::Exr => {
                let data: Vec<f32> = image
                    .pixels
                    .iter()
                    .flat_map(|p| p.to_array().map(|c| if c.is_finite() { c } else { 0.0 }))
                    .collect();
                let buf = Rgb32FImage::from_raw(image.width, image.height, data)
                    .context("internal error: the image buffer does not match its size")?;
                buf.write_to(&mut out, ImageFormat::OpenExr).with_context(context)?;
            }
        }
        out.flush().with_context(context)?;
    }
    tmp.as_file().sync_all().with_context(context)?;
    #[cfg(unix)]
    {
        // tempfile creates 0600 files; an image is an ordinary file.
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o644)).with_context(context)?;
    }
    tmp.persist(path).map_err(|e| e.error).with_context(context)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::glam::Vec3;
    use prism_shade::Image;

    #[test]
    fn formats_follow_the_extension() {
        assert_eq!(Format::from_path(Path::new("a/b.PNG")).unwrap(), Format::Png);
        assert_eq!(Format::from_path(Path::new("b.exr")).unwrap(), Format::Exr);
        assert!(Format::from_path(Path::new("b.jpg")).is_err());
        assert!(Format::from_path(Path::new("b")).is_err());
    }

    #[test]
    fn exr_round_trips_linear_values() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::new(0.25, 2.5, 0.0), Vec3::new(f32::NAN, 1.0, 7.0)],
        };
        let p = dir.path().join("x.exr");
        write_image(&img, &p, Format::Exr).unwrap();
        let back = image::open(&p).unwrap().to_rgb32f();
        assert_eq!(back.get_pixel(0, 0).0, [0.25, 2.5, 0.0]);
        assert_eq!(back.get_pixel(1, 0).0, [0.0, 1.0, 7.0]);
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, ["x.exr"]);
    }

    #[test]
    fn a_failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image { width: 1, height: 1, pixels: vec![Vec3::ONE] };
        // The target is a non-empty directory: rename fails, the temp file goes.
        let target = dir.path().join("busy.png");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("f"), b"x").unwrap();
        assert!(write_image(&img, &target, Format::Png).is_err());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, ["busy.png"]);
    }
}
