//! Fail fast on an output that cannot be written: before the scene is
//! loaded and rendered, check that the output's directory exists or can
//! be created (no part of its path is a file) and that a file can be
//! created in it, so that a long render never ends in "cannot write".
//! Nothing is created by the check itself.

use anyhow::{Result, bail};
use std::path::Path;

/// Checks that `output` can be written: the deepest existing directory
/// on its path is a directory (not a file) and accepts a new file (a
/// probe, created and removed at once). Directories that do not exist
/// yet are not created here.
pub fn check_writable(output: &Path) -> Result<()> {
    let shown = output.display();
    let parent = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut dir = parent;
    loop {
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                bail!("{shown}: cannot write the image there: {} is a file, not a directory", dir.display())
            }
            Err(_) => match dir.parent().filter(|d| !d.as_os_str().is_empty()) {
                Some(up) => dir = up,
                None => {
                    dir = Path::new(".");
                    break;
                }
            },
        }
    }
    let probe = dir.join(format!(".prism-write-check-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            // Best effort: the probe is empty and named for this process.
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => {
            let why = match e.kind() {
                std::io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
                std::io::ErrorKind::ReadOnlyFilesystem => "the file system is read-only".to_owned(),
                std::io::ErrorKind::StorageFull => "the disk is full".to_owned(),
                _ => e.to_string(),
            };
            bail!("{shown}: cannot write the image: no file can be created in {} ({why})", dir.display())
        }
    }
}
