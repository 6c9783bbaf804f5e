//! The scene loader's error type.

use std::cell::OnceCell;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A place in a file: the file, and the 1-based line and column when known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub file: PathBuf,
    /// 1-based line, if known.
    pub line: Option<usize>,
    /// 1-based column (in characters), if known.
    pub column: Option<usize>,
}

impl Location {
    /// The whole file, no position.
    #[must_use]
    pub fn file(file: &Path) -> Self {
        Self { file: file.to_path_buf(), line: None, column: None }
    }

    /// The position of byte `offset` of `text`, the contents of `file`.
    #[must_use]
    pub fn at_offset(file: &Path, text: &str, offset: usize) -> Self {
        let (line, column) = line_col(text, offset);
        Self { file: file.to_path_buf(), line: Some(line), column: Some(column) }
    }

    /// The start of `span` in `text`, the contents of `file`.
    #[must_use]
    pub fn at_span(file: &Path, text: &str, span: &Range<usize>) -> Self {
        Self::at_offset(file, text, span.start)
    }

    /// A line of `file` (no column).
    #[must_use]
    pub fn at_line(file: &Path, line: usize) -> Self {
        Self { file: file.to_path_buf(), line: Some(line), column: None }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        Ok(())
    }
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
/// Offsets past the end, or inside a character, are clamped.
///
/// Each call counts the lines from the start of `text`: for many places
/// in one text, the loader counts them once (`Lines`, internal).
#[must_use]
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    scanned();
    let offset = char_floor(text, offset);
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// `offset` clamped to `text`: at most its length, and back to the start
/// of the character it falls in.
fn char_floor(text: &str, offset: usize) -> usize {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// A text whose places are wanted as lines and columns, many of them (a
/// scene file: a place for every file it names and every warning). The
/// text is read once, on the first place asked for, for the start of each
/// line and, along a long line, a mark every [`MARK_EVERY`] bytes with its
/// column; each place is then a binary search and a count of at most that
/// many bytes' characters. [`line_col`] for each place instead counts from
/// the start of the text every time, which made loading a scene quadratic
/// in the number of files it names (and so would counting each column
/// from the start of its line, for a scene written on one line).
#[derive(Debug)]
pub(crate) struct Lines<'a> {
    text: &'a str,
    index: OnceCell<LineIndex>,
}

/// At most this many bytes lie between a place and the start of its line
/// or a mark on it.
const MARK_EVERY: usize = 1024;

/// Where the lines of a text start, and marks along its long lines.
#[derive(Debug)]
struct LineIndex {
    /// The byte offset of each line's start (the first is 0).
    starts: Vec<usize>,
    /// Along lines longer than [`MARK_EVERY`]: a byte offset (at a
    /// character, inside the line) and its 1-based column, in order.
    marks: Vec<(usize, usize)>,
}

impl LineIndex {
    fn new(text: &str) -> Self {
        scanned();
        let mut starts = vec![0];
        let mut marks = Vec::new();
        let ends = text.match_indices('\n').map(|(i, _)| i).chain(std::iter::once(text.len()));
        for end in ends {
            let start = starts.last().copied().unwrap_or(0);
            let (mut at, mut column) = (start, 1);
            loop {
                // A step of MARK_EVERY bytes (back to a character's start:
                // still forward, a character being at most 4 bytes).
                let next = char_floor(text, at + MARK_EVERY);
                if next >= end {
                    break;
                }
                column += text[at..next].chars().count();
                marks.push((next, column));
                at = next;
            }
            if end < text.len() {
                starts.push(end + 1);
            }
        }
        Self { starts, marks }
    }

    /// For byte `offset` (at a character): its 1-based line, and the
    /// place on that line to count its column from, with that place's
    /// column: the line's start or its last mark before `offset`.
    fn anchor(&self, offset: usize) -> (usize, usize, usize) {
        // The lines that start at or before `offset`; the first always does.
        let line = self.starts.partition_point(|&s| s <= offset);
        let start = self.starts[..line].last().copied().unwrap_or(0);
        let marked = self.marks.partition_point(|&(at, _)| at <= offset);
        match self.marks[..marked].last() {
            // A mark at or after the line's start is on this line.
            Some(&(at, column)) if at >= start => (line, at, column),
            _ => (line, start, 1),
        }
    }
}

impl<'a> Lines<'a> {
    /// The lines of `text`, not yet counted.
    pub fn new(text: &'a str) -> Self {
        Self { text, index: OnceCell::new() }
    }

    /// The text.
    pub fn text(&self) -> &'a str {
        self.text
    }

    /// [`line_col`] of `offset` in the text: the same line and column.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = char_floor(self.text, offset);
        let (line, from, column) = self.index().anchor(offset);
        (line, column + self.text[from..offset].chars().count())
    }

    fn index(&self) -> &LineIndex {
        self.index.get_or_init(|| LineIndex::new(self.text))
    }
}

#[cfg(test)]
thread_local! {
    /// How many times this thread has counted a text's lines from its start.
    static SCANS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Notes (in tests) that a text's lines were counted from its start.
fn scanned() {
    #[cfg(test)]
    SCANS.with(|n| n.set(n.get() + 1));
}

/// How many times this thread has counted a text's lines from its start
/// ([`line_col`], or [`Lines`] finding its line starts).
#[cfg(test)]
pub(crate) fn scans() -> usize {
    SCANS.with(std::cell::Cell::get)
}

/// Why a scene could not be loaded. Every variant's message starts with
/// where the problem is (`file:line:column` when known) and says what was
/// expected.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read (the scene itself, or a mesh, material
    /// library or texture it names; `location` is where it was named).
    #[error("{}", read_message(location, what, path, reason))]
    Read {
        /// Where the file was named (the scene file itself: no position).
        location: Location,
        /// What kind of file ("scene file", "mesh", "texture", ...).
        what: &'static str,
        /// The path tried.
        path: PathBuf,
        /// Why it failed.
        reason: String,
    },
    /// The scene file is not valid TOML, or a value has the wrong type,
    /// a required key is missing, or a key is unknown.
    #[error("{location}: {message}")]
    Syntax {
        /// Where.
        location: Location,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A value is well-formed but not acceptable: NaN, a zero radius, a
    /// singular transform, an unknown material name, a resolution over
    /// the limit...
    #[error("{location}: {message}")]
    Invalid {
        /// Where.
        location: Location,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A mesh, material library or texture file named by the scene is
    /// malformed. `location` is the place in that file when known;
    /// `referenced_at` is where the scene names it.
    #[error("{location}: {message} (used at {referenced_at})")]
    Asset {
        /// Where in the asset file.
        location: Location,
        /// What was wrong.
        message: String,
        /// Where the scene names the asset.
        referenced_at: Box<Location>,
    },
    /// A value given on the command line (through [`crate::Overrides`]) is
    /// not acceptable.
    #[error("{flag}: {message}")]
    Option {
        /// The option, e.g. `--width`.
        flag: &'static str,
        /// What was wrong.
        message: String,
    },
}

/// `location: cannot read WHAT PATH: reason`, or, where the location is
/// the file itself (a scene file given on the command line), the path
/// once: `PATH: cannot read WHAT: reason`.
fn read_message(location: &Location, what: &str, path: &Path, reason: &str) -> String {
    if location.line.is_none() && location.file == path {
        format!("{location}: cannot read {what}: {reason}")
    } else {
        format!("{location}: cannot read {what} {}: {reason}", path.display())
    }
}

impl SceneError {
    /// The location the error points at, if it has one.
    #[must_use]
    pub fn location(&self) -> Option<&Location> {
        match self {
            Self::Read { location, .. }
            | Self::Syntax { location, .. }
            | Self::Invalid { location, .. }
            | Self::Asset { location, .. } => Some(location),
            Self::Option { .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based_and_count_characters() {
        let text = "ab\ncdé f\n";
        assert_eq!(line_col(text, 0), (1, 1));
        assert_eq!(line_col(text, 3), (2, 1));
        // 'f' is after "cdé " which is 5 bytes but 4 characters.
        assert_eq!(line_col(text, 3 + 5), (2, 5));
        assert_eq!(line_col(text, 1000), (3, 1));
    }

    #[test]
    fn lines_give_the_line_and_column_line_col_gives() {
        // Long lines (marked along), of 1- to 4-byte characters, between
        // short ones.
        let long = format!("{}\n{}\nend", "é€a𝄞".repeat(2000), "ab".repeat(MARK_EVERY));
        let texts =
            ["", "\n", "ab\ncdé f\n", "a\r\n\r\nb", "é\n\nxyz", "no newline at all", "\n\nlast", &long];
        for text in texts {
            let lines = Lines::new(text);
            for offset in 0..text.len() + 3 {
                assert_eq!(lines.line_col(offset), line_col(text, offset), "{text:?} at {offset}");
            }
        }
    }

    /// A scene written on one line (an array of inline tables): counting
    /// each place's column from the start of the line would be quadratic
    /// too. Each place counts from a mark at most MARK_EVERY bytes back.
    #[test]
    fn a_place_on_a_long_line_is_counted_from_a_mark_near_it() {
        let text = format!("a = [{}]\n", "{ b = \"é\" }, ".repeat(10_000));
        let lines = Lines::new(&text);
        for offset in (0..text.len()).filter(|&o| text.is_char_boundary(o)) {
            let (line, from, _) = lines.index().anchor(offset);
            assert_eq!(line, 1);
            assert!(from <= offset && offset - from <= MARK_EVERY, "{offset} counted from {from}");
        }
    }

    #[test]
    fn lines_count_their_text_once_for_any_number_of_places() {
        let text = "a = 1\n".repeat(500);
        let lines = Lines::new(&text);
        let before = scans();
        for offset in (0..text.len()).step_by(7) {
            let _ = lines.line_col(offset);
        }
        assert_eq!(scans() - before, 1);
    }
}
