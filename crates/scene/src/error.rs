//! The scene loader's error type.

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
#[must_use]
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
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
}
