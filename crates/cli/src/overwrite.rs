//! The CLI's rule for output paths: never over an input of the render.
//! Writing itself (PNG or EXR by extension, atomically) is
//! `prism_shade::write_image`.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// Refuses an image output path that is (or will replace) one of
/// `inputs`, or that is a directory.
pub fn check_not_an_input(output: &Path, inputs: &[PathBuf]) -> Result<()> {
    check_output(output, inputs, Output::Image)
}

/// What an output file holds, for the messages of [`check_output`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// An image (or an AOV pass, a tile).
    Image,
    /// The statistics of `--stats-json`.
    Stats,
    /// A farm job's scripts, in its work directory.
    Scripts,
}

impl Output {
    /// What the file holds, in words: "the image", "the statistics".
    pub fn noun(self) -> &'static str {
        match self {
            Self::Image => "the image",
            Self::Stats => "the statistics",
            Self::Scripts => "the job's scripts",
        }
    }

    fn name_hint(self) -> &'static str {
        match self {
            Self::Image => "a file name ending in .png or .exr",
            Self::Stats => "a file name such as stats.json",
            Self::Scripts => "another --work-dir",
        }
    }
}

/// Refuses an output path of kind `what` that is (or will replace) one of
/// `inputs`, or that is a directory.
pub fn check_output(output: &Path, inputs: &[PathBuf], what: Output) -> Result<()> {
    check_not_a_directory(output, what)?;
    if let Some(t) = written(output)
        && inputs.contains(&t)
    {
        let named = if t.as_path() == output { String::new() } else { format!(" ({})", t.display()) };
        bail!(
            "{}: refusing to write {} over an input of this command{named}, a file it reads",
            output.display(),
            what.noun()
        );
    }
    Ok(())
}

/// Refuses an output path of kind `what` that is an existing directory
/// (or a link to one), or that ends in a folder as written (`s.json/`,
/// which `Path` reads as `s.json`): no file can be written there.
pub fn check_not_a_directory(output: &Path, what: Output) -> Result<()> {
    if output.is_dir() {
        bail!("{}: the output is a directory; give {}", output.display(), what.name_hint());
    }
    if prism_shade::names_a_directory(output) {
        bail!(
            "{}: the output name ends in a folder (`/`, `.` or `..`); give {}",
            output.display(),
            what.name_hint()
        );
    }
    Ok(())
}

/// The absolute path of the file writing `path` replaces (links followed
/// as the writer follows them, `prism_shade::output_target`); `None` for
/// a device or pipe, which replaces no file.
fn written(path: &Path) -> Option<PathBuf> {
    match prism_shade::output_target(path) {
        Ok(prism_shade::OutputTarget::Replace(target)) => resolved(&target),
        Ok(prism_shade::OutputTarget::Into) => None,
        Err(_) => resolved(path),
    }
}

/// The absolute path `path` names, links followed: the path itself if it
/// exists, else its directory's (if that exists) joined with its name.
fn resolved(path: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(path).ok().or_else(|| {
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        match (std::fs::canonicalize(dir), path.file_name()) {
            (Ok(d), Some(name)) => Some(d.join(name)),
            _ => None,
        }
    })
}

/// Refuses a `--stats-json` path that is also one of `images`, the files
/// the render writes (the image, its AOV files and previews), which the
/// statistics would replace.
pub fn check_stats_apart(stats: &Path, images: &[PathBuf]) -> Result<()> {
    let Some(s) = written(stats) else { return Ok(()) };
    if let Some(image) = images.iter().find(|i| written(i).as_ref() == Some(&s)) {
        bail!(
            "--stats-json {}: that is also where this render writes {}; give the statistics another name",
            stats.display(),
            image.display()
        );
    }
    Ok(())
}
