//! Ctrl-C (SIGINT), SIGTERM and SIGHUP during `prism render`.
//!
//! The three are treated alike: SIGTERM is what `kill`, `timeout`,
//! systemd, Slurm (`scancel`, a time limit) and Kubernetes send, SIGHUP
//! what a closing terminal sends. While the image renders, the first such
//! signal sets the render's cancel flag ([`prism_shade::RenderHooks::cancel`]):
//! the workers stop before their next pixel (or within 1024 samples of a
//! long one), dropping a row left midway, and prism exits with status
//! 128 + the signal's number (130 for SIGINT, 143 for SIGTERM, 129 for
//! SIGHUP) without writing anything, or, with `--partial`, writes the rows
//! finished so far (the rest black) to the output path the usual atomic way
//! and says so (still that status: the image is not the render that was
//! asked for). Without `--partial`, the output folders the run made are
//! removed again (`writable::MadeDirs`). A signal that comes while the
//! finished image is being written lets the write finish (the image is
//! whole, and no temporary file is left); a turntable then stops before
//! its next frame. A second signal exits at once, with 128 + its number,
//! after taking away the temporary files of a write in progress
//! (`prism_shade::stop_unfinished_outputs`): each output then holds
//! either what it held before or, where the renames had already been
//! made, the whole new file, never a mix of a render's image and another
//! render's AOV files. The handlers only note a signal; a thread of their
//! own (signal-hook's iterator) sets the flag or exits. Two deliveries of
//! the same signal before that thread wakes count as one (`kill -INT`
//! twice in a row from a script), as the kernel itself merges a pending
//! signal's repeats.
//!
//! The handlers are installed once, just before the output folders are
//! made; before that (while the scene loads) the signals have their default
//! effect and end prism at once, and nothing has been written then. A
//! SIGHUP that was ignored when prism started (`nohup`) stays ignored.
//!
//! Images are written by `prism_shade::write_image` to a temporary file
//! `.<name>.<pid>.<n>.tmp` in the output's own directory, synced and
//! renamed over the output path; the temporary file exists only while the
//! finished image is being encoded. A SIGKILL (which cannot be caught)
//! during the render therefore leaves nothing; one during that short write
//! can leave such a `.tmp` file, but never a truncated file at the output
//! path. A render's image and its AOV files are shown together
//! (`prism_shade::all_or_nothing`): a failure while writing any of them
//! (a full disk) leaves every output as it was.

use prism_shade::OutputError;
use std::fmt;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// The exit status of a render interrupted by Ctrl-C (128 + SIGINT, as
/// shells use); other signals give 128 + their number.
pub const EXIT_INTERRUPTED: u8 = 130;

/// The signals that stop a render, each with the words that name it in
/// messages.
fn signals() -> Vec<(i32, &'static str)> {
    let mut v = vec![(signal_hook::consts::SIGINT, "Ctrl-C")];
    #[cfg(unix)]
    v.extend([(signal_hook::consts::SIGTERM, "SIGTERM"), (signal_hook::consts::SIGHUP, "SIGHUP")]);
    v
}

/// The process's handlers, installed once for all the renders of a run
/// (a turntable's frames share them).
struct Handlers {
    /// Set by the first signal: the render's cancel flag.
    flag: Arc<AtomicBool>,
    /// The number of the first signal (0 before one came).
    signal: Arc<AtomicUsize>,
}

static HANDLERS: OnceLock<Result<Handlers, String>> = OnceLock::new();

/// Whether `signal` was ignored when prism started (`nohup` ignores
/// SIGHUP), as Linux's `/proc/self/status` tells; false where it cannot
/// be told.
#[cfg(unix)]
fn ignored_at_start(signal: i32) -> bool {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return false;
    };
    let mask = status
        .lines()
        .find_map(|l| l.strip_prefix("SigIgn:"))
        .and_then(|m| u64::from_str_radix(m.trim(), 16).ok());
    matches!((mask, u32::try_from(signal)), (Some(m), Ok(n @ 1..=64)) if (m >> (n - 1)) & 1 == 1)
}

fn install_handlers() -> Result<Handlers, std::io::Error> {
    let flag = Arc::new(AtomicBool::new(false));
    let first = Arc::new(AtomicUsize::new(0));
    #[cfg_attr(not(unix), allow(unused_mut))]
    let mut wanted: Vec<i32> = signals().into_iter().map(|(sig, _)| sig).collect();
    #[cfg(unix)]
    wanted.retain(|&sig| !(sig == signal_hook::consts::SIGHUP && ignored_at_start(sig)));
    // signal-hook's handlers only note the signals; this thread acts on
    // them. The first sets the number, then the flag that makes the
    // render stop and read it. A second (of any of them) ends prism at
    // once: with the image being written, its temporary files are taken
    // away first, so that none is left beside the output.
    let mut incoming = signal_hook::iterator::Signals::new(&wanted)?;
    let (flag_seen, first_seen) = (Arc::clone(&flag), Arc::clone(&first));
    std::thread::Builder::new().name("prism-signals".into()).spawn(move || {
        for sig in incoming.forever() {
            if flag_seen.load(Ordering::SeqCst) {
                let name = signals().into_iter().find(|(s, _)| *s == sig).map_or("a signal", |(_, n)| n);
                errln!("error: {name} again: stopped at once; no output is left half-written");
                // Held to the end: no rename or new temporary file after.
                let _hold = prism_shade::stop_unfinished_outputs();
                std::process::exit(128 + sig);
            }
            first_seen.store(usize::try_from(sig).unwrap_or(0), Ordering::SeqCst);
            flag_seen.store(true, Ordering::SeqCst);
        }
    })?;
    Ok(Handlers { flag, signal: first })
}

/// Signal handling for one render (or one frame of a turntable).
pub struct Interrupt {
    handlers: &'static Handlers,
    rows: AtomicU32,
}

impl Interrupt {
    /// Installs the handlers (once per process; later calls share them):
    /// the first SIGINT, SIGTERM or SIGHUP sets [`Interrupt::flag`], a
    /// second one exits with 128 + its number.
    ///
    /// # Errors
    /// If the handlers cannot be installed.
    pub fn install() -> anyhow::Result<Self> {
        match HANDLERS.get_or_init(|| install_handlers().map_err(|e| e.to_string())) {
            Ok(handlers) => Ok(Self { handlers, rows: AtomicU32::new(0) }),
            Err(e) => Err(anyhow::anyhow!("cannot install the signal handlers: {e}")),
        }
    }

    /// The render's cancel flag.
    pub fn flag(&self) -> &AtomicBool {
        &self.handlers.flag
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
        // Stored before the flag was set; SIGINT should it not be.
        let signal = match self.handlers.signal.load(Ordering::SeqCst) {
            0 => signal_hook::consts::SIGINT,
            n => i32::try_from(n).unwrap_or(signal_hook::consts::SIGINT),
        };
        let name = signals().into_iter().find(|(s, _)| *s == signal).map_or("a signal", |(_, n)| n);
        let done = format!("interrupted ({name}) after {rows} of {height} rows");
        let message = if !partial {
            format!("{done}; nothing was written (--partial writes the rows done)")
        } else {
            match write() {
                Ok(()) => format!(
                    "{done}; wrote the partial image to {} (rows not rendered are black; no passes, previews or statistics)",
                    output.display()
                ),
                Err(e) => format!("{done}; the partial image could not be written: {e:#}"),
            }
        };
        Interrupted { message, signal }.into()
    }
}

/// A render stopped by a signal (exit status 128 + its number:
/// [`EXIT_INTERRUPTED`] for SIGINT).
#[derive(Debug)]
pub struct Interrupted {
    message: String,
    /// The signal's number.
    signal: i32,
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
            Interrupted {
                message: format!("frame {index} ({}): {}; {before}", output.display(), i.message),
                signal: i.signal,
            }
            .into()
        }
        Err(e) => e,
    }
}

/// The exit status for a failed command: 128 + the signal's number after
/// an interrupt (130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP), else 1.
pub fn exit_code(e: &anyhow::Error) -> ExitCode {
    match e.downcast_ref::<Interrupted>() {
        Some(i) => ExitCode::from(u8::try_from(128 + i.signal).unwrap_or(EXIT_INTERRUPTED)),
        None => ExitCode::FAILURE,
    }
}
