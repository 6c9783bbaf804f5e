//! Writing renders and AOV passes to disk, the one image writer of prism
//! (the CLI's output and the viewer's snapshots use it too): 8-bit sRGB
//! PNG and 32-bit float linear OpenEXR, each written atomically (a
//! temporary file `.<name>.<pid>.<n>.tmp` in the same directory, synced,
//! then renamed over the target; removed on any error, so a reader never
//! sees a partial file and a failed write leaves the target as it was).
//!
//! Non-finite values, one policy for every file:
//! - PNG: a non-finite channel is black (as [`linear_to_srgb8`] encodes it);
//! - OpenEXR: `+∞` and `−∞` are stored as they are (the depth pass marks
//!   misses with `+∞`, `docs/aov.md`), and NaN is stored as 0: no render
//!   or pass produces one (non-finite samples count as black), and a NaN
//!   in a file spreads through every filter that reads it.

use crate::{Aov, AovImage, AovImages, BitDepth, Image, PngOptions, linear_to_srgb8};
use image::{ImageBuffer, ImageFormat, Rgb, Rgba};
use prism_geometry::glam::Vec3;
use rayon::prelude::*;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why an output file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The file system refused (directory missing, no permission, disk full…).
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A file to read could not be opened or read (missing, no permission…).
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The image could not be encoded or decoded.
    #[error("image error in {}: {reason}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The request makes no sense (an empty image, a buffer of the wrong
    /// length, a path without a file name).
    #[error("{}: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

pub(crate) fn invalid(path: &Path, reason: impl Into<String>) -> OutputError {
    OutputError::Invalid { path: path.to_path_buf(), reason: reason.into() }
}

fn check_len(path: &Path, width: u32, height: u32, got: usize, per_pixel: usize) -> Result<(), OutputError> {
    if width == 0 || height == 0 {
        return Err(invalid(path, format!("cannot write an empty {width}×{height} image")));
    }
    let want = (width as usize).checked_mul(height as usize).and_then(|n| n.checked_mul(per_pixel));
    if want != Some(got) {
        return Err(invalid(
            path,
            format!("a {width}×{height} image needs {per_pixel} values per pixel, got {got} values"),
        ));
    }
    Ok(())
}

/// The image formats prism writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float linear OpenEXR.
    Exr,
}

impl OutputFormat {
    /// The format named by `path`'s extension (`png` or `exr`, any case).
    ///
    /// # Errors
    /// [`OutputError::Invalid`] for another extension or none.
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        // `a.png/` is `a.png` to `Path`, but no file can be written there.
        if names_a_directory(path) {
            return Err(invalid(
                path,
                "the output name ends in a folder (`/`, `.` or `..`); give a file name ending in .png or .exr",
            ));
        }
        // `a.png.` has an empty extension: no format, as `a` has none.
        let ext =
            path.extension().filter(|e| !e.is_empty()).map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some(other) => {
                Err(invalid(path, format!("cannot write .{other} images; use a .png or .exr output name")))
            }
            None => Err(invalid(path, "the output name needs a .png or .exr extension")),
        }
    }
}

/// Whether `path` as written names a folder: it ends in a separator
/// (`out/a.png/`), or in `.` or `..`, which `Path` reads past (to it
/// `a.png/` is the file `a.png`), where no file can be written.
#[must_use]
pub fn names_a_directory(path: &Path) -> bool {
    let text = path.as_os_str().to_string_lossy();
    let last = text.rsplit(std::path::is_separator).next().unwrap_or("");
    !text.is_empty() && matches!(last, "" | "." | "..")
}

/// Writes a linear [`Image`] to `path` as `format`, atomically: PNG as
/// 8-bit sRGB ([`Image::to_srgb8`]), EXR as linear floats
/// ([`write_image_exr`]).
///
/// # Errors
/// As [`write_exr_rgb`].
pub fn write_image(path: &Path, image: &Image, format: OutputFormat) -> Result<(), OutputError> {
    match format {
        OutputFormat::Png => write_png_rgb8(path, image.width, image.height, &image.to_srgb8()),
        OutputFormat::Exr => write_image_exr(path, image),
    }
}

/// Writes `path` atomically: `encode` fills a new temporary file next to
/// it, which then replaces `path`; on any error the temporary file is
/// removed and `path` is left as it was. Where it writes is
/// [`output_target`]'s choice: the file a symbolic link points to (the
/// link kept), or, for a device, pipe or descriptor, into it directly.
pub(crate) fn write_atomic(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    match output_target(path)? {
        OutputTarget::Replace(target) => replace_atomically(path, &target, encode),
        OutputTarget::Into => {
            let io = |source| OutputError::Io { path: path.to_path_buf(), source };
            // An encoder may seek back (EXR writes its table of offsets
            // last), which a pipe cannot: the file is made whole in an
            // unnamed temporary file, then copied in order. Nothing is
            // written into the pipe if the encoding fails.
            let Some(spool) = spool_file() else {
                let mut w = BufWriter::new(OpenOptions::new().write(true).open(path).map_err(io)?);
                encode(&mut w)?;
                return w.flush().map_err(io);
            };
            let mut w = BufWriter::new(spool);
            encode(&mut w)?;
            let mut spool = w.into_inner().map_err(|e| io(e.into_error()))?;
            spool.seek(std::io::SeekFrom::Start(0)).map_err(io)?;
            let mut out = OpenOptions::new().write(true).open(path).map_err(io)?;
            std::io::copy(&mut spool, &mut out).map_err(io)?;
            out.flush().map_err(io)
        }
    }
}

/// A new temporary file that no name leads to (made in the system's
/// temporary folder and unlinked at once, so nothing is left behind
/// whatever ends the process), if one can be made there.
#[cfg(unix)]
fn spool_file() -> Option<File> {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = std::env::temp_dir().join(format!(".prism-spool-{}-{n}", std::process::id()));
    use std::os::unix::fs::OpenOptionsExt;
    let file = OpenOptions::new().read(true).write(true).create_new(true).mode(0o600).open(&path).ok()?;
    std::fs::remove_file(&path).ok()?;
    Some(file)
}

/// Elsewhere an open file cannot be unlinked: written directly.
#[cfg(not(unix))]
fn spool_file() -> Option<File> {
    None
}

/// Where an output path leads ([`output_target`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OutputTarget {
    /// A regular file, or none yet, at this path (symbolic links
    /// followed): replaced atomically, by a temporary file in its folder
    /// renamed over it.
    Replace(PathBuf),
    /// A device, a named pipe or a descriptor (`/dev/null`, `/dev/stdout`,
    /// a FIFO): written into through the path given, as a shell
    /// redirection would, since renaming over it would replace it with a
    /// regular file. A pipe with no reader waits for one.
    Into,
}

/// Where writing `path` goes: for the writers, and for the checks a
/// front end makes before rendering (the folder to probe, the files that
/// must not be the same).
///
/// Symbolic links are followed to the file they name, even one not made
/// yet, except a link in a shared sticky folder (such as `/tmp`) that the
/// folder's owner did not make, which could point anywhere (the kernel's
/// `protected_symlinks` rule, made stricter). Where they lead to an
/// existing path under `/dev` or `/proc` (`/dev/stdout`, `/dev/fd/3`), or
/// to one that is not a regular file or a folder, it is written into.
///
/// # Errors
/// [`OutputError::Io`] for a loop of links (more than 40) or a link in a
/// shared folder as above.
pub fn output_target(path: &Path) -> Result<OutputTarget, OutputError> {
    let io = |source| OutputError::Io { path: path.to_path_buf(), source };
    let mut p = path.to_path_buf();
    for _ in 0..=40 {
        let Ok(here) = std::fs::symlink_metadata(&p) else {
            // Not there yet (or a folder on the way is a file, which the
            // writer reports): a new file.
            return Ok(OutputTarget::Replace(p));
        };
        // The kernel's own links (`/dev/stdout` → `/proc/self/fd/1` →
        // `pipe:[…]`) are followed by opening, not by reading them.
        if p.starts_with("/dev") || p.starts_with("/proc") {
            return Ok(OutputTarget::Into);
        }
        if !here.file_type().is_symlink() {
            let regular = here.is_file() || here.is_dir();
            return Ok(if regular { OutputTarget::Replace(p) } else { OutputTarget::Into });
        }
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        // Checked before any link is followed, into a device as well.
        if shared_folder_link(&dir, &here) {
            return Err(io(std::io::Error::other(format!(
                "a symbolic link in the shared folder {}, not made by its owner: prism does not follow it \
                 (give the path of the file it points to)",
                dir.display()
            ))));
        }
        p = dir.join(std::fs::read_link(&p).map_err(io)?);
    }
    Err(io(std::io::Error::other("too many levels of symbolic links")))
}

/// Whether `dir` is sticky and writable by all (such as `/tmp`) and the
/// link, of metadata `link`, is not its owner's.
#[cfg(unix)]
fn shared_folder_link(dir: &Path, link: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(dir).is_ok_and(|d| not_followed(d.mode(), d.uid(), link.uid()))
}

/// [`shared_folder_link`]'s rule on a folder's mode and owner and a link's
/// owner: sticky (`0o1000`) and writable by all (`0o0002`), and another's.
#[cfg(unix)]
fn not_followed(dir_mode: u32, dir_owner: u32, link_owner: u32) -> bool {
    dir_mode & 0o1002 == 0o1002 && link_owner != dir_owner
}

#[cfg(not(unix))]
fn shared_folder_link(_: &Path, _: &std::fs::Metadata) -> bool {
    false
}

/// [`write_atomic`] of `path` (named in errors) into `target`, a regular
/// file or a missing one: a temporary file beside `target`, renamed over it.
fn replace_atomically(
    path: &Path,
    target: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let io = |source| OutputError::Io { path: path.to_path_buf(), source };
    let named = path;
    let path = target;
    let name = path.file_name().ok_or_else(|| invalid(path, "not a file path"))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
    let tmp = dir.join(tmp_name);
    // Readable too: a writer may read back what it wrote (the EXR header).
    let file = OpenOptions::new().read(true).write(true).create_new(true).open(&tmp).map_err(io)?;
    let unfinished = Unfinished::note(&tmp);
    let result = (|| {
        let mut w = BufWriter::new(file);
        encode(&mut w)?;
        w.flush().map_err(io)?;
        let file = w.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        drop(file);
        // Inside [`all_or_nothing`]: shown with the others at its end.
        let pending = Pending { tmp: tmp.clone(), target: path.to_path_buf(), named: named.to_path_buf() };
        match STAGED.with(|s| s.borrow_mut().as_mut().map(|list| list.push(pending.clone()))) {
            Some(()) => {
                std::mem::forget(unfinished);
                Ok(())
            }
            None => pending.show(),
        }
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A temporary file written and synced, waiting to be renamed over its
/// target ([`all_or_nothing`]).
#[derive(Clone, Debug)]
struct Pending {
    tmp: PathBuf,
    target: PathBuf,
    /// The path the caller gave (named in errors).
    named: PathBuf,
}

impl Pending {
    /// Renames the temporary file over the target, no longer unfinished.
    fn show(&self) -> Result<(), OutputError> {
        show_all(std::slice::from_ref(self))
    }
}

/// Renames each of `pending` over its target, in order, holding the
/// [`UNFINISHED`] lock throughout: a forced exit's clean-up
/// ([`stop_unfinished_outputs`]) comes wholly before or after them, so
/// that the files are replaced together or not at all. After a failed
/// rename the rest are removed. Each is forgotten as unfinished.
fn show_all(pending: &[Pending]) -> Result<(), OutputError> {
    let mut list = UNFINISHED.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut shown = Ok(());
    for p in pending {
        if shown.is_ok() {
            shown = std::fs::rename(&p.tmp, &p.target)
                .map_err(|source| OutputError::Io { path: p.named.clone(), source });
        }
        if shown.is_err() {
            let _ = std::fs::remove_file(&p.tmp);
        }
        if let Some(k) = list.iter().position(|t| *t == p.tmp) {
            list.swap_remove(k);
        }
    }
    shown
}

/// The files held back by the [`all_or_nothing`] running on this thread;
/// those still there when it is dropped (its write failed or panicked)
/// are removed, and the thread's staging ends either way.
struct Staging;

impl Staging {
    /// The files held back, now the caller's to show.
    fn take(&self) -> Vec<Pending> {
        STAGED.with(|s| s.borrow_mut().as_mut().map(std::mem::take)).unwrap_or_default()
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        for p in STAGED.with(|s| s.borrow_mut().take()).unwrap_or_default() {
            let _ = std::fs::remove_file(&p.tmp);
            Unfinished::forget(&p.tmp);
        }
    }
}

thread_local! {
    /// The files [`all_or_nothing`] holds back on this thread (`None`
    /// outside one).
    static STAGED: std::cell::RefCell<Option<Vec<Pending>>> = const { std::cell::RefCell::new(None) };
}

/// Runs `write`, whose atomic file writes on this thread (every writer of
/// this module) are then shown together: each file is written and synced
/// to its temporary file as usual, and only when `write` has succeeded
/// are they all renamed over their targets, in order. If `write` fails
/// (a full disk at the third of five passes), every temporary file is
/// removed and no target changes: a render's image and its AOV files are
/// replaced together or not at all. (A rename failing midway, which
/// needs the folder to change under the render, leaves the files before
/// it replaced.) Nested calls join the outer one.
///
/// # Errors
/// `write`'s error, or the first failed rename.
pub fn all_or_nothing<R>(write: impl FnOnce() -> Result<R, OutputError>) -> Result<R, OutputError> {
    let outer = STAGED.with(|s| {
        let mut s = s.borrow_mut();
        let outer = s.is_some();
        if !outer {
            *s = Some(Vec::new());
        }
        outer
    });
    if outer {
        return write();
    }
    // Removes what is still held back if `write` fails or panics.
    let staging = Staging;
    let r = write()?;
    show_all(&staging.take()).map(|()| r)
}

/// The temporary files being written or held back, in every thread, so
/// that a forced exit can take them away ([`stop_unfinished_outputs`]).
static UNFINISHED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary file noted in [`UNFINISHED`] while it lives: forgotten when
/// dropped (written and renamed, or removed after an error).
struct Unfinished(PathBuf);

impl Unfinished {
    fn note(tmp: &Path) -> Self {
        if let Ok(mut list) = UNFINISHED.lock() {
            list.push(tmp.to_path_buf());
        }
        Self(tmp.to_path_buf())
    }

    fn forget(tmp: &Path) {
        if let Ok(mut list) = UNFINISHED.lock()
            && let Some(k) = list.iter().position(|p| p == tmp)
        {
            list.swap_remove(k);
        }
    }
}

impl Drop for Unfinished {
    fn drop(&mut self) {
        Self::forget(&self.0);
    }
}

/// A hold on every write's temporary files ([`stop_unfinished_outputs`]):
/// while it lives, no write notes a new one or renames one over its
/// target.
#[must_use = "the hold ends when it is dropped"]
pub struct UnfinishedHold(#[allow(dead_code)] std::sync::MutexGuard<'static, Vec<PathBuf>>);

/// Removes the temporary files of every write in progress and returns a
/// hold on the lock the renames take: a process about to exit (a second
/// Ctrl-C while the image is written) keeps it until it ends, so that a
/// render's files held back by [`all_or_nothing`] are either all shown
/// already or none is, and no new temporary file is noted after the
/// clean-up.
pub fn stop_unfinished_outputs() -> UnfinishedHold {
    let list = UNFINISHED.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    for tmp in list.iter() {
        let _ = std::fs::remove_file(tmp);
    }
    UnfinishedHold(list)
}

/// Removes the unfinished temporary files that `which` picks (and forgets
/// them): [`stop_unfinished_outputs`]'s clean-up, for some of them.
#[cfg(test)]
fn remove_unfinished(which: impl Fn(&Path) -> bool) {
    let picked: Vec<PathBuf> = match UNFINISHED.lock() {
        Ok(mut list) => {
            let (picked, kept) = std::mem::take(&mut *list).into_iter().partition(|t| which(t));
            *list = kept;
            picked
        }
        Err(_) => return,
    };
    for tmp in picked {
        let _ = std::fs::remove_file(tmp);
    }
}

/// Writes `bytes` to `path` atomically (as every image: a temporary file
/// in the same directory, synced, renamed over `path`), for the other
/// files a render produces (e.g. statistics).
///
/// # Errors
/// [`OutputError::Io`] if writing fails; the target is then untouched.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic(path, |w| {
        w.write_all(bytes).map_err(|source| OutputError::Io { path: path.to_path_buf(), source })
    })
}

/// Writes a 32-bit float RGB OpenEXR file (channels `R`, `G`, `B`, no
/// alpha, row 0 at the top) from `width · height · 3` interleaved floats,
/// atomically. Floats are stored as they are, `±∞` included; NaN is
/// stored as 0 (the module's policy).
///
/// # Errors
/// [`OutputError::Invalid`] for an empty image or a buffer of the wrong
/// length, [`OutputError::Io`] or [`OutputError::Image`] if writing fails
/// (the target is then untouched and no temporary file is left).
pub fn write_exr_rgb(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<(), OutputError> {
    if rgb.iter().any(|v| v.is_nan()) {
        let clean: Vec<f32> = rgb.iter().map(|&v| if v.is_nan() { 0.0 } else { v }).collect();
        return write_rgb::<f32>(path, width, height, &clean, ImageFormat::OpenExr);
    }
    write_rgb::<f32>(path, width, height, rgb, ImageFormat::OpenExr)
}

/// Writes `width · height · 3` interleaved RGB values as `format`, atomically.
fn write_rgb<T>(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[T],
    format: ImageFormat,
) -> Result<(), OutputError>
where
    Rgb<T>: image::PixelWithColorType<Subpixel = T>,
    T: image::Primitive,
    [T]: image::EncodableLayout,
{
    write_pixels::<Rgb<T>>(path, width, height, rgb, format)
}

/// Writes `width · height` pixels of type `P` (interleaved channels) as
/// `format`, atomically.
fn write_pixels<P>(
    path: &Path,
    width: u32,
    height: u32,
    data: &[P::Subpixel],
    format: ImageFormat,
) -> Result<(), OutputError>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
{
    check_len(path, width, height, data.len(), usize::from(P::CHANNEL_COUNT))?;
    let buffer: ImageBuffer<P, &[P::Subpixel]> =
        ImageBuffer::from_raw(width, height, data).ok_or_else(|| invalid(path, "buffer too small"))?;
    write_atomic(path, |w| encode_into(path, w, |w| buffer.write_to(w, format)))
}

/// Runs the encoder `encode` on `w` for `path`, reporting a failure of
/// the file system underneath as [`OutputError::Io`] (the `image` crate
/// turns one from its EXR encoder into the text "Format error decoding
/// OpenExr: No space left on device"), and any other as
/// [`OutputError::Image`].
pub(crate) fn encode_into<W: Write + Seek, E: std::fmt::Display>(
    path: &Path,
    w: &mut W,
    encode: impl FnOnce(&mut Watched<'_, W>) -> Result<(), E>,
) -> Result<(), OutputError> {
    let mut watched = Watched { inner: w, failed: None };
    encode(&mut watched).map_err(|e| match watched.failed.take() {
        Some(source) => OutputError::Io { path: path.to_path_buf(), source },
        None => OutputError::Image { path: path.to_path_buf(), reason: e.to_string() },
    })
}

/// A writer that keeps the first error of the one it wraps (see
/// [`encode_into`]).
pub(crate) struct Watched<'a, W> {
    inner: &'a mut W,
    failed: Option<std::io::Error>,
}

impl<W> Watched<'_, W> {
    fn note<T>(&mut self, r: std::io::Result<T>) -> std::io::Result<T> {
        if let Err(e) = &r
            && self.failed.is_none()
        {
            self.failed = Some(std::io::Error::new(e.kind(), e.to_string()));
        }
        r
    }
}

impl<W: Write> Write for Watched<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let r = self.inner.write(buf);
        self.note(r)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.inner.flush();
        self.note(r)
    }
}

impl<W: Seek> Seek for Watched<'_, W> {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        let r = self.inner.seek(pos);
        self.note(r)
    }
}

/// Writes a linear image as a PNG file through `options` (exposure, tone
/// mapping, sRGB, 8 or 16 bits), atomically. With `alpha` (one coverage
/// value per pixel, `image` then premultiplied by it, as
/// [`crate::render_with_alpha`] gives), the file is RGBA with *straight*
/// alpha, as PNG defines it: the colour is `image / alpha` where alpha > 0,
/// black where it is 0, and alpha is stored linearly (`⌊a · (2^bits − 1) + ½⌋`).
///
/// # Errors
/// [`OutputError::Invalid`] if `alpha` is not one value per pixel; else as
/// [`write_exr_rgb`].
pub fn write_png(
    path: &Path,
    image: &Image,
    alpha: Option<&[f32]>,
    options: &PngOptions,
) -> Result<(), OutputError> {
    let (w, h) = (image.width, image.height);
    let straight = |k: usize, p: Vec3| -> (Vec3, Option<f32>) {
        match alpha.and_then(|a| a.get(k)) {
            Some(&a) if a > 0.0 => (p / a, Some(a.min(1.0))),
            Some(_) => (Vec3::ZERO, Some(0.0)),
            None => (p, None),
        }
    };
    if let Some(a) = alpha {
        check_len(path, w, h, a.len(), 1)?;
    }
    let channels = if alpha.is_some() { 4 } else { 3 };
    // Rows are encoded in parallel (a transfer function per channel is
    // most of a PNG's writing time).
    macro_rules! encode {
        ($encode:ident, $max:expr) => {{
            let row = (w as usize).max(1);
            let mut out = vec![0; image.pixels.len() * channels];
            out.par_chunks_mut(row * channels).zip(image.pixels.par_chunks(row)).enumerate().for_each(
                |(j, (o, pixels))| {
                    for (i, (&p, o)) in pixels.iter().zip(o.chunks_exact_mut(channels)).enumerate() {
                        let (c, a) = straight(j * row + i, p);
                        for (o, x) in o.iter_mut().zip(c.to_array()) {
                            *o = options.$encode(x);
                        }
                        if let Some(a) = a {
                            o[3] = (a * $max + 0.5) as _;
                        }
                    }
                },
            );
            out
        }};
    }
    match (options.bit_depth, alpha.is_some()) {
        (BitDepth::Eight, false) => write_rgb::<u8>(path, w, h, &encode!(encode8, 255.0), ImageFormat::Png),
        (BitDepth::Sixteen, false) => {
            write_rgb::<u16>(path, w, h, &encode!(encode16, 65535.0), ImageFormat::Png)
        }
        (BitDepth::Eight, true) => {
            write_pixels::<Rgba<u8>>(path, w, h, &encode!(encode8, 255.0), ImageFormat::Png)
        }
        (BitDepth::Sixteen, true) => {
            write_pixels::<Rgba<u16>>(path, w, h, &encode!(encode16, 65535.0), ImageFormat::Png)
        }
    }
}

/// Writes a linear [`Image`] (the beauty) as a float RGB OpenEXR file; see
/// [`write_exr_rgb`].
///
/// # Errors
/// As [`write_exr_rgb`].
pub fn write_image_exr(path: &Path, image: &Image) -> Result<(), OutputError> {
    let rgb: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
    write_exr_rgb(path, image.width, image.height, &rgb)
}

/// Writes one AOV pass as a float RGB OpenEXR file: three-channel passes
/// as `R, G, B = x, y, z`, one-channel passes (depth, object id) with the
/// value repeated in `R`, `G` and `B` (the image crate writes RGB or RGBA
/// only); see [`write_exr_rgb`].
///
/// # Errors
/// As [`write_exr_rgb`].
pub fn write_aov_exr(path: &Path, pass: &AovImage) -> Result<(), OutputError> {
    check_len(path, pass.width, pass.height, pass.data.len(), pass.channels())?;
    write_exr_rgb(path, pass.width, pass.height, &pass.to_rgb())
}

/// Reads an OpenEXR (or any image the crate decodes) as `(width, height,
/// interleaved RGB floats)`, e.g. to check a pass written by
/// [`write_aov_exr`]. A one-channel pass reads back from `R`.
///
/// # Errors
/// [`OutputError::Read`] if the file cannot be opened,
/// [`OutputError::Image`] if it cannot be decoded.
pub fn read_exr_rgb(path: &Path) -> Result<(u32, u32, Vec<f32>), OutputError> {
    let reader = image::ImageReader::open(path)
        .map_err(|source| OutputError::Read { path: path.to_path_buf(), source })?;
    let image = reader
        .with_guessed_format()
        .map_err(|source| OutputError::Read { path: path.to_path_buf(), source })?
        .decode()
        .map_err(|e| OutputError::Image { path: path.to_path_buf(), reason: e.to_string() })?
        .into_rgb32f();
    let (w, h) = image.dimensions();
    Ok((w, h, image.into_raw()))
}

/// The file of pass `aov` that goes with the output `base`, with extension
/// `ext`: `<dir>/<stem>.<pass name>.<ext>` where `<stem>` is `base`'s file
/// name without its last extension. For `renders/out.exr` and `"exr"`:
/// `renders/out.depth.exr`, `renders/out.normal.exr`, …; for `out.png` the
/// same `out.depth.exr` (passes are always float files); previews use
/// `"png"`: `out.depth.png`.
///
/// # Errors
/// [`OutputError::Invalid`] if `base` has no file name (e.g. `..`).
pub fn aov_path(base: &Path, aov: Aov, ext: &str) -> Result<PathBuf, OutputError> {
    let stem = base.file_stem().ok_or_else(|| invalid(base, "the output path has no file name"))?;
    let mut name = stem.to_os_string();
    name.push(format!(".{}.{ext}", aov.name()));
    Ok(base.with_file_name(name))
}

/// Writes every pass of `aovs` next to the output `base` as
/// `<stem>.<pass>.exr` ([`aov_path`], [`write_aov_exr`]), and with
/// `previews` also `<stem>.<pass>.png` ([`write_aov_preview_png`]). The
/// beauty itself is the caller's to write (e.g. [`write_image_exr`] to
/// `base`). Returns the files written, in order.
///
/// # Errors
/// The first [`OutputError`]; files written before it stay.
pub fn write_aov_files(base: &Path, aovs: &AovImages, previews: bool) -> Result<Vec<PathBuf>, OutputError> {
    let mut written = Vec::new();
    for pass in &aovs.passes {
        let exr = aov_path(base, pass.aov, "exr")?;
        write_aov_exr(&exr, pass)?;
        written.push(exr);
        if previews {
            let png = aov_path(base, pass.aov, "png")?;
            write_aov_preview_png(&png, pass)?;
            written.push(png);
        }
    }
    Ok(written)
}

/// An 8-bit RGB preview of a pass (`width · height · 3` bytes, row 0 at
/// the top), for looking rather than measuring:
/// - `normal`, `geo_normal`: each component `n` as `(n + 1) / 2` of 255
///   (so +X is red, +Y green, +Z blue); pixels whose value is exactly 0
///   (nothing hit) black;
/// - `depth`: grey from white at the 1st percentile of the finite depths
///   to 10% grey at the 99th, logarithmic in depth between them and
///   clamped outside (all white if they are equal), so that a plane
///   reaching the horizon does not wash the rest out; `+∞` (misses) black;
/// - `albedo`: sRGB-encoded, clamped to `[0, 1]`;
/// - `object_id`: a distinct colour per id from a hash of the id (each
///   channel at least 64, so never black); −1 (nothing hit) black.
#[must_use]
pub fn aov_preview_rgb8(pass: &AovImage) -> Vec<u8> {
    let n = pass.width as usize * pass.height as usize;
    let c = pass.channels();
    let px = |k: usize| pass.data.get(k * c..k * c + c).unwrap_or(&[]);
    let unit = |x: f32| -> u8 {
        let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
        (x * 255.0 + 0.5) as u8
    };
    let mut out = Vec::with_capacity(n * 3);
    match pass.aov {
        Aov::Normal | Aov::GeoNormal => {
            for k in 0..n {
                match px(k) {
                    [x, y, z] if [*x, *y, *z] != [0.0; 3] => {
                        out.extend([*x, *y, *z].map(|v| unit((v + 1.0) * 0.5)));
                    }
                    _ => out.extend([0; 3]),
                }
            }
        }
        Aov::Albedo => {
            for k in 0..n {
                match px(k) {
                    [x, y, z] => out.extend([*x, *y, *z].map(linear_to_srgb8)),
                    _ => out.extend([0; 3]),
                }
            }
        }
        Aov::Depth => {
            let scale = DepthScale::of(&pass.data);
            for k in 0..n {
                match px(k) {
                    [d] if d.is_finite() => out.extend([unit(1.0 - 0.9 * scale.t(*d)); 3]),
                    _ => out.extend([0; 3]),
                }
            }
        }
        Aov::ObjectId => {
            for k in 0..n {
                match px(k) {
                    [id] if *id >= 0.0 => out.extend(id_color(*id)),
                    _ => out.extend([0; 3]),
                }
            }
        }
    }
    out
}

/// How the depth preview maps a depth to grey: logarithmically between
/// the 1st and 99th percentiles of the finite depths (`lo`, `hi`), so that
/// a floor running to the horizon (a few huge depths) or a speck very near
/// the camera does not squash everything else into one grey:
/// `t = (ln d − ln lo) / (ln hi − ln lo)`, clamped to `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct DepthScale {
    ln_lo: f32,
    ln_hi: f32,
}

impl DepthScale {
    /// Smallest depth the logarithm sees (a hit at the eye).
    const FLOOR: f32 = 1e-6;

    fn of(depths: &[f32]) -> Self {
        let mut finite: Vec<f32> = depths.iter().copied().filter(|d| d.is_finite()).collect();
        if finite.is_empty() {
            return Self { ln_lo: 0.0, ln_hi: 0.0 };
        }
        finite.sort_unstable_by(f32::total_cmp);
        let at = |q: f64| finite[((finite.len() - 1) as f64 * q).round() as usize];
        let ln = |d: f32| d.max(Self::FLOOR).ln();
        Self { ln_lo: ln(at(0.01)), ln_hi: ln(at(0.99)) }
    }

    /// `0` at `lo` (and nearer), `1` at `hi` (and farther).
    fn t(self, d: f32) -> f32 {
        if self.ln_hi > self.ln_lo {
            ((d.max(Self::FLOOR).ln() - self.ln_lo) / (self.ln_hi - self.ln_lo)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// A colour for object id `id`: a hash of it, each channel in `[64, 255]`.
fn id_color(id: f32) -> [u8; 3] {
    let mut z = u64::from(id.to_bits()).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    [0u32, 16, 32].map(|shift| (64 + ((z >> shift) & 0xFFFF) as u32 * 192 / 0x1_0000) as u8)
}

/// Writes 8-bit RGB bytes (`width · height · 3`, row 0 at the top) as a
/// PNG file, atomically.
///
/// # Errors
/// As [`write_exr_rgb`].
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), OutputError> {
    write_rgb::<u8>(path, width, height, rgb, ImageFormat::Png)
}

/// Writes the preview of a pass ([`aov_preview_rgb8`]) as a PNG file,
/// atomically.
///
/// # Errors
/// As [`write_exr_rgb`].
pub fn write_aov_preview_png(path: &Path, pass: &AovImage) -> Result<(), OutputError> {
    check_len(path, pass.width, pass.height, pass.data.len(), pass.channels())?;
    write_png_rgb8(path, pass.width, pass.height, &aov_preview_rgb8(pass))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn links_in_shared_sticky_folders_are_followed_only_if_the_owner_made_them() {
        // /tmp: 0o1777, root's. A link made by user 1000 there is not followed.
        assert!(not_followed(0o41777, 0, 1000));
        assert!(!not_followed(0o41777, 0, 0), "root's own link in /tmp");
        assert!(!not_followed(0o40755, 0, 1000), "not writable by all");
        assert!(!not_followed(0o40777, 0, 1000), "not sticky");
    }

    #[test]
    fn a_name_that_ends_in_a_folder_is_no_output_file() {
        for folder in ["a.png/", "out/a.png/", "a.png/.", "a.png/..", ".", "/", "out//"] {
            assert!(names_a_directory(Path::new(folder)), "{folder}");
            let e = OutputFormat::from_path(Path::new(folder)).unwrap_err().to_string();
            assert!(e.contains("ends in a folder"), "{folder}: {e}");
        }
        for file in ["a.png", "out/a.png", "./a.png", "../a.png", "a..png", ""] {
            assert!(!names_a_directory(Path::new(file)), "{file}");
        }
        assert_eq!(OutputFormat::from_path(Path::new("out/a.PNG")).unwrap(), OutputFormat::Png);
    }

    #[test]
    fn output_targets_follow_links_and_write_into_devices() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        assert_eq!(output_target(&p.join("new.png")).unwrap(), OutputTarget::Replace(p.join("new.png")));
        assert_eq!(output_target(Path::new("/dev/stdout")).unwrap(), OutputTarget::Into);
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("b.png", p.join("a.png")).unwrap();
            std::os::unix::fs::symlink("sub/c.png", p.join("b.png")).unwrap();
            assert_eq!(output_target(&p.join("a.png")).unwrap(), OutputTarget::Replace(p.join("sub/c.png")));
            std::os::unix::fs::symlink("loop.png", p.join("loop.png")).unwrap();
            let e = output_target(&p.join("loop.png")).unwrap_err().to_string();
            assert!(e.contains("loop.png") && e.to_lowercase().contains("symbolic links"), "{e}");
            assert_eq!(output_target(Path::new("/dev/null")).unwrap(), OutputTarget::Into);
        }
    }
    use prism_geometry::glam::Vec3;

    fn listing(dir: &Path) -> Vec<std::ffi::OsString> {
        let mut v: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        v.sort();
        v
    }

    #[test]
    fn formats_follow_the_extension() {
        assert_eq!(OutputFormat::from_path(Path::new("a/b.PNG")).unwrap(), OutputFormat::Png);
        assert_eq!(OutputFormat::from_path(Path::new("b.exr")).unwrap(), OutputFormat::Exr);
        let e = OutputFormat::from_path(Path::new("b.jpg")).unwrap_err().to_string();
        assert_eq!(e, "b.jpg: cannot write .jpg images; use a .png or .exr output name");
        assert!(matches!(OutputFormat::from_path(Path::new("b")), Err(OutputError::Invalid { .. })));
    }

    #[test]
    fn exr_keeps_infinities_and_stores_nan_as_zero() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image {
            width: 3,
            height: 1,
            pixels: vec![
                Vec3::new(0.25, 2.5, 0.0),
                Vec3::new(f32::NAN, 1.0, 7.0),
                Vec3::new(f32::INFINITY, f32::NEG_INFINITY, -0.5),
            ],
        };
        let p = dir.path().join("x.exr");
        write_image(&p, &img, OutputFormat::Exr).unwrap();
        let (w, h, back) = read_exr_rgb(&p).unwrap();
        assert_eq!((w, h), (3, 1));
        assert_eq!(back[..6], [0.25, 2.5, 0.0, 0.0, 1.0, 7.0]);
        assert_eq!(back[6..], [f32::INFINITY, f32::NEG_INFINITY, -0.5]);
        assert_eq!(listing(dir.path()), ["x.exr"], "no temporary file is left");
    }

    #[test]
    fn png_is_the_srgb_encoding_with_non_finite_as_black() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image { width: 2, height: 1, pixels: vec![Vec3::new(1.0, 0.5, f32::NAN), Vec3::INFINITY] };
        let p = dir.path().join("x.png");
        write_image(&p, &img, OutputFormat::Png).unwrap();
        let back = image::open(&p).unwrap().to_rgb8();
        assert_eq!(back.get_pixel(0, 0).0, [255, linear_to_srgb8(0.5), 0]);
        assert_eq!(back.get_pixel(1, 0).0, [0, 0, 0]);
    }

    /// Every pixel of every row (the rows are encoded in parallel) is the
    /// per-value encoding of its colour, straight alpha where there is one.
    #[test]
    fn png_pixels_are_their_encoded_values_in_every_row() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (7u32, 5u32);
        let pixels: Vec<Vec3> =
            (0..w * h).map(|k| Vec3::new(k as f32 / 40.0, 0.9 - k as f32 / 50.0, 0.3)).collect();
        let alpha: Vec<f32> = (0..w * h).map(|k| [1.0, 0.5, 0.0, 0.25][k as usize % 4]).collect();
        let img = Image { width: w, height: h, pixels: pixels.clone() };
        let p = dir.path().join("x.png");
        for bit_depth in [BitDepth::Eight, BitDepth::Sixteen] {
            let o = PngOptions { exposure: 0.5, bit_depth, ..PngOptions::default() };
            write_png(&p, &img, None, &o).unwrap();
            let rgb = image::open(&p).unwrap().to_rgb16();
            write_png(&p, &img, Some(&alpha), &o).unwrap();
            let rgba = image::open(&p).unwrap().to_rgba16();
            for (k, &c) in pixels.iter().enumerate() {
                let (i, j) = (k as u32 % w, k as u32 / w);
                let want = |c: Vec3| match bit_depth {
                    BitDepth::Eight => c.to_array().map(|x| u16::from(o.encode8(x)) * 257),
                    BitDepth::Sixteen => c.to_array().map(|x| o.encode16(x)),
                };
                assert_eq!(rgb.get_pixel(i, j).0[..3], want(c), "pixel {k}");
                let a = alpha[k];
                let straight = if a > 0.0 { c / a } else { Vec3::ZERO };
                let max = if bit_depth == BitDepth::Eight { 255.0 } else { 65535.0 };
                let scale = if bit_depth == BitDepth::Eight { 257 } else { 1 };
                assert_eq!(rgba.get_pixel(i, j).0[..3], want(straight), "pixel {k}");
                assert_eq!(rgba.get_pixel(i, j).0[3], (a * max + 0.5) as u16 * scale, "alpha {k}");
            }
        }
    }

    #[test]
    fn the_depth_preview_stays_readable_to_the_horizon() {
        // A camera 1 above an infinite floor, looking level: row j of 200
        // sees the floor at depth 1 / sin(angle below the horizon), from 1.2
        // at the bottom to thousands at the horizon row; the top half is sky.
        let (w, h) = (4u32, 200u32);
        let mut data = Vec::new();
        for j in 0..h {
            let below = (j as f32 + 0.5 - 100.0) / 100.0 * 0.9; // radians below the horizon
            let d = if below > 0.0 { 1.0 / below.sin() } else { f32::INFINITY };
            data.extend([d; 4]);
        }
        let pass = AovImage { aov: Aov::Depth, width: w, height: h, data };
        let grey = aov_preview_rgb8(&pass);
        let floor: Vec<u8> = (100..h).map(|j| grey[(j * w) as usize * 3]).collect();
        // Sky is black; the floor (listed from the horizon down) brightens
        // monotonically toward the camera...
        assert_eq!(grey[0], 0);
        assert!(floor.windows(2).all(|p| p[0] <= p[1]), "{floor:?}");
        // ...and uses the grey range: white near, 10% far, the median row
        // well below white and at most 15% of the rows within 5 levels of
        // white (the old min–max scale puts the median row at 254 and 83% there).
        assert_eq!((floor[0], floor[floor.len() - 1]), (26, 255));
        let near_white = floor.iter().filter(|&&g| g >= 250).count();
        assert!(near_white * 100 <= 15 * floor.len(), "{near_white} of {}: {floor:?}", floor.len());
        assert!(floor[floor.len() / 2] <= 225, "{floor:?}");
        let mut levels = floor.clone();
        levels.dedup();
        assert!(levels.len() > 60, "{} grey levels", levels.len());
    }

    #[test]
    fn writes_held_together_show_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image { width: 1, height: 1, pixels: vec![Vec3::ONE] };
        let (a, b) = (dir.path().join("a.png"), dir.path().join("a.depth.exr"));
        std::fs::write(&a, b"OLD").unwrap();
        // The third write fails (its folder is missing): the first two
        // targets stay as they were and no temporary file is left.
        let missing = dir.path().join("no-such-dir").join("x.exr");
        let failed = all_or_nothing(|| {
            write_image(&a, &img, OutputFormat::Png)?;
            write_image(&b, &img, OutputFormat::Exr)?;
            assert_eq!(std::fs::read(&a).unwrap(), b"OLD", "held back until the end");
            write_image(&missing, &img, OutputFormat::Exr)
        });
        assert!(matches!(failed, Err(OutputError::Io { .. })));
        assert_eq!(std::fs::read(&a).unwrap(), b"OLD");
        assert_eq!(listing(dir.path()), ["a.png"]);
        assert!(!UNFINISHED.lock().unwrap().iter().any(|t| t.starts_with(dir.path())), "forgotten");
        // All succeed: all are shown, nested calls joining the outer one.
        all_or_nothing(|| {
            write_image(&a, &img, OutputFormat::Png)?;
            all_or_nothing(|| write_image(&b, &img, OutputFormat::Exr))?;
            assert!(!b.exists() && std::fs::read(&a).unwrap() == b"OLD", "nothing shown yet");
            Ok(())
        })
        .unwrap();
        assert_eq!(listing(dir.path()), ["a.depth.exr", "a.png"]);
        assert_ne!(std::fs::read(&a).unwrap(), b"OLD");
        // A temporary file of a write in progress is noted, and taken away
        // by the clean-up of a forced exit (`stop_unfinished_outputs`:
        // here only this test's, as other tests write at the same time).
        let stray = Unfinished::note(&dir.path().join(".a.png.1.0.tmp"));
        std::fs::write(&stray.0, b"part").unwrap();
        remove_unfinished(|t| t.starts_with(dir.path()));
        assert_eq!(listing(dir.path()), ["a.depth.exr", "a.png"]);
    }

    #[test]
    fn a_failed_write_leaves_the_target_and_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image { width: 1, height: 1, pixels: vec![Vec3::ONE] };
        // The target is a non-empty directory: the rename fails, the temporary file goes.
        let target = dir.path().join("busy.png");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("f"), b"x").unwrap();
        assert!(matches!(write_image(&target, &img, OutputFormat::Png), Err(OutputError::Io { .. })));
        assert_eq!(listing(dir.path()), ["busy.png"]);
        // A missing directory: nothing is created.
        let missing = dir.path().join("no-such-dir").join("x.exr");
        assert!(matches!(write_image(&missing, &img, OutputFormat::Exr), Err(OutputError::Io { .. })));
        assert_eq!(listing(dir.path()), ["busy.png"]);
    }
}
