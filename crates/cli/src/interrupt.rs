//! Ctrl-C (SIGINT) during `prism render`.
//!
//! While the image renders, the first SIGINT sets the render's cancel
//! flag ([`prism_shade::RenderHooks::cancel`]): the workers stop before
//! their next pixel (or within 1024 samples of a long one), dropping a row
//! left midway, and prism exits with status 130 without writing anything, or,
//! with `--partial`, writes the rows finished so far (the rest black) to
//! the output path the usual atomic way and says so (still status 130: the
//! image is not the render that was asked for). Without `--partial`, the
//! output folders the run made are removed again (`writable::MadeDirs`).
//! A second SIGINT exits at
//! once, also with 130. Before the render starts (while the scene loads)
//! SIGINT has its default effect and ends prism at once; nothing has been
//! written then.
//!
//! Images are written by `prism_shade::write_image` to a temporary file
//! `.<name>.<pid>.<n>.tmp` in the output's own directory, synced and
//! renamed over the output path; the temporary file exists only while the
//! finished image is being encoded. A SIGKILL (which cannot be caught)
//! during the render therefore leaves nothing; one during that short write
//! can leave such a `.tmp` file, but never a truncated file at the output
//! path.

use prism_shade::OutputError;
use signal_hook::consts::SIGINT;
use std::fmt;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// The exit status of an interrupted render (128 + SIGINT, as shells use).
pub const EXIT_INTERRUPTED: u8 = 130;

/// SIGINT handling for one render.
pub struct Interrupt {
    flag: Arc<AtomicBool>,
    rows: AtomicU32,
}

impl Interrupt {
    /// Installs the handlers: the first SIGINT sets [`Interrupt::flag`],
    /// a second one exits with [`EXIT_INTERRUPTED`].
    ///
    /// # Errors
    /// If the handlers cannot be installed.
    pub fn install() -> anyhow::Result<Self> {
        let flag = Arc::new(AtomicBool::new(false));
        // Registered first, so it sees the flag as the first signal left it.
        signal_hook::flag::register_conditional_shutdown(
            SIGINT,
            i32::from(EXIT_INTERRUPTED),
            Arc::clone(&flag),
        )?;
        signal_hook::flag::register(SIGINT, Arc::clone(&flag))?;
        Ok(Self { flag, rows: AtomicU32::new(0) })
    }

    /// The render's cancel flag.
    pub fn flag(&self) -> &AtomicBool {
        &self.flag
    }

    /// Records `done` rows finished (from the progress callback).
    pub fn note_rows(&self, done: u32) {
        self.rows.fetch_max(done, Ordering::Relaxed);
    }

    /// The error that ends an interrupted render of `height` rows: with
    /// `partial`, after `write` has written the rows done so far to `output`.
    pub fn finish(
        &self,
        height: u32,
        output: &Path,
        partial: bool,
        write: impl FnOnce() -> Result<(), OutputError>,
    ) -> anyhow::Error {
        let rows = self.rows.load(Ordering::Relaxed).min(height);
        let done = format!("interrupted (Ctrl-C) after {rows} of {height} rows");
        let message = if !partial {
            format!("{done}; nothing was written (--partial writes the rows done)")
        } else {
            match write() {
                Ok(()) => format!(
                    "{done}; wrote the partial image to {} (rows not rendered are black)",
                    output.display()
                ),
                Err(e) => format!("{done}; the partial image could not be written: {e:#}"),
            }
        };
        Interrupted { message }.into()
    }
}

/// A render stopped by SIGINT (exit status [`EXIT_INTERRUPTED`]).
#[derive(Debug)]
pub struct Interrupted {
    message: String,
}

impl fmt::Display for Interrupted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Interrupted {}

/// `e` with the turntable's frame named, if it is an interrupt: frame
/// `index` (`output`) was the one stopped, and the `written` frames before
/// it were written whole.
pub fn in_frame(e: anyhow::Error, index: usize, output: &Path, written: usize) -> anyhow::Error {
    match e.downcast::<Interrupted>() {
        Ok(i) => {
            let before = match written {
                0 => "no frame before it was written".to_owned(),
                1 => "the frame before it was written".to_owned(),
                n => format!("the {n} frames before it were written"),
            };
            Interrupted { message: format!("frame {index} ({}): {}; {before}", output.display(), i.message) }
                .into()
        }
        Err(e) => e,
    }
}

/// The exit status for a failed command: 130 after an interrupt, else 1.
pub fn exit_code(e: &anyhow::Error) -> ExitCode {
    if e.downcast_ref::<Interrupted>().is_some() {
        ExitCode::from(EXIT_INTERRUPTED)
    } else {
        ExitCode::FAILURE
    }
}
