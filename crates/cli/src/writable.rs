//! Fail fast on an output that cannot be written: before the scene is
//! loaded and rendered, check that the output's directory exists or can
//! be created (no part of its path is a file) and that a file can be
//! created in it, so that a long render never ends in "cannot write".
//! Nothing is created by the check itself; [`MadeDirs`] makes the
//! missing folders later and removes them again if nothing was written.
//! Once the image's size is known (after the load, before the render),
//! [`check_space`] refuses a full disk and warns when the files may not
//! fit.

use crate::overwrite::{Output, check_not_a_directory};
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// Checks that `output` (`what` it holds: the image, the statistics)
/// can be written: it is not itself a directory, the deepest existing
/// directory on its path is a directory (not a file) and accepts a new file (a probe, created and
/// removed at once). Directories that do not exist yet are not created
/// here; a symbolic link must lead into one that exists.
pub fn check_writable(output: &Path, kind: Output) -> Result<()> {
    check_not_a_directory(output, kind)?;
    let what = kind.noun();
    let shown = output.display();
    // The file the writer will replace (through links); a device or pipe
    // is written into, and a path that cannot be followed is refused here.
    let target = match prism_shade::output_target(output)? {
        prism_shade::OutputTarget::Replace(t) => t,
        prism_shade::OutputTarget::Into => return Ok(()),
    };
    let dir = existing_dir(&target, what)?;
    if target != output && target.parent().is_some_and(|p| p != dir && !p.as_os_str().is_empty()) {
        // Folders are made for an output's own path, not at the far end
        // of a link.
        bail!("{shown}: cannot write {what}: it links to {}, whose folder does not exist", target.display());
    }
    let probe = dir.join(format!(".prism-write-check-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(file) => {
            let refused = another_users_file(&target, dir, &file);
            // Best effort: the probe is empty and named for this process.
            let _ = std::fs::remove_file(&probe);
            match refused {
                Some(owner) => bail!(
                    "{shown}: cannot write {what}: {} belongs to another user (uid {owner}) in {}, a shared folder \
                     (sticky, as /tmp) where only a file's owner may replace it; remove it or choose another name",
                    target.display(),
                    dir.display()
                ),
                None => Ok(()),
            }
        }
        Err(e) => {
            let why = match e.kind() {
                std::io::ErrorKind::PermissionDenied => "permission denied".to_owned(),
                std::io::ErrorKind::ReadOnlyFilesystem => "the file system is read-only".to_owned(),
                std::io::ErrorKind::StorageFull => "the disk is full".to_owned(),
                _ => e.to_string(),
            };
            bail!("{shown}: cannot write {what}: no file can be created in {} ({why})", dir.display())
        }
    }
}

/// The owner of `target`, if it exists and this process (the owner of
/// `probe`, a file it just made in `dir`) may not replace it: `dir` is
/// sticky (as /tmp) and neither the file nor the folder is this user's
/// (the kernel refuses the rename then, after the render).
#[cfg(unix)]
fn another_users_file(target: &Path, dir: &Path, probe: &std::fs::File) -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    let me = probe.metadata().ok()?.uid();
    let folder = std::fs::metadata(dir).ok()?;
    let file = std::fs::symlink_metadata(target).ok()?;
    replace_refused(folder.mode(), folder.uid(), file.uid(), me).then_some(file.uid())
}

#[cfg(not(unix))]
fn another_users_file(_: &Path, _: &Path, _: &std::fs::File) -> Option<u32> {
    None
}

/// [`another_users_file`]'s rule on a folder's mode and owner, a file's
/// owner and this user: in a sticky folder only the file's owner, the
/// folder's owner and root may rename over a file.
#[cfg(unix)]
fn replace_refused(dir_mode: u32, dir_owner: u32, file_owner: u32, me: u32) -> bool {
    dir_mode & 0o1000 != 0 && me != 0 && file_owner != me && dir_owner != me
}

/// The deepest directory on `output`'s path that exists (`.` if none is
/// named); an error if a part of the path is a file.
fn existing_dir<'p>(output: &'p Path, what: &str) -> Result<&'p Path> {
    let mut dir = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    loop {
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => return Ok(dir),
            Ok(_) => bail!(
                "{}: cannot write {what} there: {} is a file, not a directory",
                output.display(),
                dir.display()
            ),
            Err(_) => match dir.parent().filter(|d| !d.as_os_str().is_empty()) {
                Some(up) => dir = up,
                None => return Ok(Path::new(".")),
            },
        }
    }
}

/// The folders an output needs that this run made, so that a run that
/// ends without writing can take them away again.
#[derive(Default)]
pub struct MadeDirs(Vec<PathBuf>);

impl MadeDirs {
    /// Makes the missing folders of `dir` (its ancestors first), noting
    /// each one this call made; folders that exist (or that another
    /// process makes meanwhile) are not noted.
    ///
    /// # Errors
    /// A folder that cannot be made, named by `what` ("the output
    /// directory").
    pub fn make(&mut self, dir: &Path, what: &str) -> Result<()> {
        if dir.as_os_str().is_empty() {
            return Ok(());
        }
        let mut missing: Vec<&Path> =
            dir.ancestors().take_while(|d| !d.as_os_str().is_empty() && !d.exists()).collect();
        missing.reverse();
        for d in missing {
            match std::fs::create_dir(d) {
                Ok(()) => self.0.push(d.to_path_buf()),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(e) => {
                    return Err(
                        anyhow::Error::new(e).context(format!("cannot create {what} {}", dir.display()))
                    );
                }
            }
        }
        Ok(())
    }

    /// Removes the folders [`MadeDirs::make`] made that are still empty,
    /// deepest first: after a run that wrote nothing, none of them stays.
    /// A folder something was written into stays, and so do those above it.
    pub fn remove_empty(&self) {
        for d in self.0.iter().rev() {
            // Fails, and keeps the folder, when it is not empty.
            let _ = std::fs::remove_dir(d);
        }
    }
}

/// Below this many free bytes a file system counts as full: no image
/// file, not even a small compressed one, can be expected to fit.
const FULL_BELOW: u64 = 64 * 1024;

/// What the free space says about files of `needed` bytes uncompressed
/// (an upper bound: PNG and the EXR writer compress).
#[derive(Debug, PartialEq, Eq)]
enum Space {
    Enough,
    /// Less free than the uncompressed size: the files may still fit.
    Tight,
    /// Full: fewer bytes free than the smaller of [`FULL_BELOW`] and `needed`.
    Full,
}

fn judge(available: u64, needed: u64) -> Space {
    if available < FULL_BELOW.min(needed) {
        Space::Full
    } else if available < needed {
        Space::Tight
    } else {
        Space::Enough
    }
}

/// Checks the free space of the file system that will hold `output`
/// against `needed`, the files' uncompressed size in bytes: an error if it
/// is full, a warning (returned) if the files may not fit. Where the
/// system does not tell (not Unix, or statvfs fails), nothing is checked.
pub fn check_space(output: &Path, needed: u64) -> Result<Option<String>> {
    let target = match prism_shade::output_target(output)? {
        prism_shade::OutputTarget::Replace(t) => t,
        prism_shade::OutputTarget::Into => return Ok(None),
    };
    let dir = existing_dir(&target, "the image")?;
    let Some(available) = available_bytes(dir) else { return Ok(None) };
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    match judge(available, needed) {
        Space::Enough => Ok(None),
        Space::Tight => Ok(Some(format!(
            "{}: {:.1} MiB free on {}'s file system, less than the {:.1} MiB the image files take uncompressed; \
             they may not fit",
            output.display(),
            mib(available),
            dir.display(),
            mib(needed)
        ))),
        Space::Full => bail!(
            "{}: cannot write the image: the disk holding {} is full ({available} bytes free)",
            output.display(),
            dir.display()
        ),
    }
}

#[cfg(unix)]
fn available_bytes(dir: &Path) -> Option<u64> {
    let s = rustix::fs::statvfs(dir).ok()?;
    Some(s.f_bavail.saturating_mul(s.f_frsize))
}

#[cfg(not(unix))]
fn available_bytes(_dir: &Path) -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn another_users_file_in_a_sticky_folder_cannot_be_replaced() {
        // /tmp: 0o1777, root's; a file of user 1000 there, and user 1001.
        assert!(super::replace_refused(0o41777, 0, 1000, 1001));
        assert!(!super::replace_refused(0o41777, 0, 1001, 1001), "one's own file");
        assert!(!super::replace_refused(0o41777, 1001, 1000, 1001), "one's own folder");
        assert!(!super::replace_refused(0o41777, 0, 1000, 0), "root");
        assert!(!super::replace_refused(0o40777, 0, 1000, 1001), "not sticky");
    }

    #[test]
    fn a_full_disk_is_refused_and_a_tight_one_warned() {
        assert_eq!(judge(0, 10), Space::Full);
        assert_eq!(judge(1000, 5_000_000), Space::Full);
        assert_eq!(judge(FULL_BELOW, 5_000_000), Space::Tight);
        // A tiny image fits where a little space is left.
        assert_eq!(judge(2000, 1500), Space::Enough);
        assert_eq!(judge(1000, 1500), Space::Full);
        assert_eq!(judge(10_000_000, 5_000_000), Space::Enough);
    }

    #[test]
    fn the_space_of_an_existing_directory_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("not/yet/img.png");
        assert_eq!(existing_dir(&out, "the image").unwrap(), dir.path());
        if cfg!(unix) {
            let free = available_bytes(dir.path()).expect("statvfs answers for a temporary directory");
            assert!(free > 0);
            // Nobody has u64::MAX bytes free: the check says so (a warning
            // here; an error only on a full disk).
            let w = check_space(&out, u64::MAX).unwrap().expect("a warning");
            assert!(w.contains("img.png") && w.contains("may not fit"), "{w}");
            assert_eq!(check_space(&out, 1).unwrap(), None);
        }
    }
}
