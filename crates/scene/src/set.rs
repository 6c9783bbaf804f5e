//! `--set KEY=VALUE`: scene values replaced by their dotted path
//! (`render.spp=16`, `fog.enabled=false`, `objects.1.radius=2`,
//! `materials.red.color=[1, 0, 0]`) in the scene *text*, before it is
//! parsed, so that a set reaches every key the format has, checked exactly
//! like the file's own.
//!
//! The text is edited in place (toml_edit's spans): a value that exists is
//! replaced where it is written, on its line; a key that does not exist is
//! added on a new line under its table's header (as a dotted key after
//! the last line of a table the file writes with dotted keys,
//! `camera.fov = 30` after `camera.look_at = …`; or at the end of the
//! file, under a new header, for a table the file does not have). Every
//! other line keeps its text, and [`Edited::remap`] turns an error back
//! into the file's own line numbers, or, for an error in a set value, into
//! an error that names the flag.

use crate::error::{Location, SceneError};
use crate::scan::value_end;
use std::ops::Range;
use std::path::Path;
use toml_edit::{Document, Item, Key, Table, Value};

/// The flag, in messages.
const FLAG: &str = "--set";

/// Where a stretch of the edited text came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Origin {
    /// The file's own text, from this byte of it on.
    File(usize),
    /// The text set number `i` wrote (its key and value, or its value).
    Set(usize),
    /// The header (`[fog]`) of a table the file lacks, written by a set
    /// for its key.
    Made,
}

/// A stretch of the edited text: its length in bytes, and where it came from.
#[derive(Clone, Copy, Debug)]
struct Piece {
    len: usize,
    origin: Origin,
}

/// The scene text with every set applied.
#[derive(Clone, Debug)]
pub(crate) struct Edited {
    /// The edited text.
    pub text: String,
    /// The file as written.
    file_text: String,
    /// The sets as given (`KEY=VALUE`), in order.
    sets: Vec<String>,
    /// Where each stretch of `text` came from, in order: their lengths add
    /// up to `text.len()`. A set's text stays its own until a later set
    /// replaces it; every byte of the file that no set replaced keeps its
    /// offset in the file, so a place maps back exactly whatever the sets
    /// did around it (a value over several lines replaced by one line, a
    /// value on a line that another value follows).
    pieces: Vec<Piece>,
}

/// Applies `sets` (each `KEY=VALUE`) to the scene `text`, in order.
///
/// # Errors
/// [`SceneError::Option`] naming `--set`, for a set that is not
/// `KEY=VALUE`, a path through something that is not a table or array, an
/// index past the end, or a whole table replaced by a value.
/// [`SceneError::Syntax`] when `text` itself is not TOML (at its place).
pub(crate) fn apply(text: &str, sets: &[String], file: &Path) -> Result<Edited, SceneError> {
    let pieces =
        if text.is_empty() { Vec::new() } else { vec![Piece { len: text.len(), origin: Origin::File(0) }] };
    let mut edited = Edited { text: text.to_owned(), file_text: text.to_owned(), sets: Vec::new(), pieces };
    for set in sets {
        edited.apply_one(set, file)?;
    }
    Ok(edited)
}

fn flag_error(set: &str, message: impl std::fmt::Display) -> SceneError {
    SceneError::Option { flag: FLAG, message: format!("{set}: {message}") }
}

/// Where a set's value goes.
enum Target {
    /// Replace the value written at this span.
    Replace(Range<usize>),
    /// A new line `KEY = VALUE` (KEY dotted) after the line holding this
    /// byte offset: a table's header, or the last value of a table made by
    /// dotted keys.
    Line(usize, String),
    /// A new line `KEY = VALUE` at the top of the file.
    Top(String),
    /// `KEY = VALUE` inside the inline table whose closing brace is at
    /// this offset (`last`: where its last value ends; `None` for an
    /// empty table).
    Inline { close: usize, key: String, last: Option<usize> },
    /// A new `[TABLE]` with `KEY = VALUE` at the end of the file.
    NewTable(String, String),
}

impl Edited {
    fn apply_one(&mut self, set: &str, file: &Path) -> Result<(), SceneError> {
        let Some((path, value)) = set.split_once('=') else {
            return Err(flag_error(set, "expected KEY=VALUE, such as render.spp=16 or fog.enabled=false"));
        };
        let (path, value) = (path.trim(), value.trim());
        let keys = Key::parse(path).map_err(|_| {
            flag_error(
                set,
                format!("`{path}` is not a dotted key path (such as render.spp or objects.0.radius)"),
            )
        })?;
        let keys: Vec<String> = keys.iter().map(|k| k.get().to_owned()).collect();
        if value.contains('\n') {
            return Err(flag_error(set, "the value must be on one line"));
        }
        // A TOML value as written, or else a string (`material=blue`); but
        // a whole number TOML cannot hold is not meant as a string.
        let repr = match value.parse::<Value>() {
            Ok(_) => value.to_owned(),
            Err(_) if toml_integer_digits(value) => {
                return Err(flag_error(set, format!("{value} is beyond the 64-bit range of whole numbers")));
            }
            Err(_) => Value::from(value).to_string().trim().to_owned(),
        };
        let doc = Document::parse(self.text.as_str()).map_err(|e| {
            let location = match e.span() {
                Some(s) => crate::error::Location::at_span(file, &self.text, &s),
                None => crate::error::Location::file(file),
            };
            SceneError::Syntax { location, message: e.message().trim().to_owned() }
        })?;
        let target = locate(doc.as_table(), &keys, set, "", &[])?;
        let text = &self.text;
        let i = self.sets.len();
        let set_piece = |len: usize| Piece { len, origin: Origin::Set(i) };
        // The edited text's bytes `range` give way to `inserted`, made of
        // these pieces.
        let (range, inserted, pieces) = match target {
            Target::Replace(span) => (span, repr.clone(), vec![set_piece(repr.len())]),
            Target::Line(header, key) => {
                // On the line after the table's header (the top of the file for the top level).
                let at = text[header..].find('\n').map_or(text.len(), |i| header + i + 1);
                let lead =
                    if at == text.len() && !text.is_empty() && !text.ends_with('\n') { "\n" } else { "" };
                let line = format!("{lead}{key} = {repr}\n");
                let n = line.len();
                (at..at, line, vec![set_piece(n)])
            }
            Target::Top(key) => {
                let line = format!("{key} = {repr}\n");
                let n = line.len();
                (0..0, line, vec![set_piece(n)])
            }
            Target::Inline { close, key, last } => {
                // At the closing brace itself, which is never in a comment
                // (a line break or comment before it stays as it is), with
                // a comma unless the table is empty or ends with one.
                let comma = last.is_some_and(|end| !has_comma(text.get(end..close).unwrap_or_default()));
                let sep = if comma { ", " } else { " " };
                let part = format!("{sep}{key} = {repr} ");
                let n = part.len();
                (close..close, part, vec![set_piece(n)])
            }
            Target::NewTable(table, key) => {
                let sep = if text.is_empty() || text.ends_with('\n') { "" } else { "\n" };
                let header = format!("{sep}[{table}]\n");
                let line = format!("{key} = {repr}\n");
                let pieces = vec![Piece { len: header.len(), origin: Origin::Made }, set_piece(line.len())];
                let end = text.len();
                (end..end, header + &line, pieces)
            }
        };
        let new_text = format!("{}{inserted}{}", &text[..range.start], &text[range.end..]);
        still_toml(set, &new_text)?;
        self.text = new_text;
        self.splice(range, pieces);
        self.sets.push(set.to_owned());
        Ok(())
    }

    /// The pieces give way to `inserted` over the edited text's bytes
    /// `range` (as the text did).
    fn splice(&mut self, range: Range<usize>, inserted: Vec<Piece>) {
        let total = self.pieces.iter().map(|p| p.len).sum();
        let mut pieces = cut(&self.pieces, 0..range.start);
        pieces.extend(inserted.into_iter().filter(|p| p.len > 0));
        pieces.extend(cut(&self.pieces, range.end..total));
        self.pieces = pieces;
    }

    /// Where byte `at` of the edited text came from (the end of the text
    /// is the end of the file), with its offset in the file for the file's
    /// own text.
    fn origin(&self, at: usize) -> Origin {
        let mut start = 0;
        for p in &self.pieces {
            if at < start + p.len {
                return match p.origin {
                    Origin::File(o) => Origin::File(o + (at - start)),
                    other => other,
                };
            }
            start += p.len;
        }
        Origin::File(self.file_text.len())
    }

    /// The sets whose text lies in (or meets) the edited text's bytes
    /// `range`, by number, each once, in order.
    fn sets_in(&self, range: &Range<usize>) -> Vec<usize> {
        let mut start = 0;
        let mut found = Vec::new();
        for p in &self.pieces {
            let end = start + p.len;
            if let Origin::Set(i) = p.origin
                && start < range.end.max(range.start + 1)
                && range.start < end
                && !found.contains(&i)
            {
                found.push(i);
            }
            start = end;
        }
        found.sort_unstable();
        found
    }

    /// `e` (from the edited text) in the terms of the file as written: a
    /// problem at a set value names the flag and the set; any other
    /// place's line and column are the file's own.
    pub(crate) fn remap(&self, e: SceneError, file: &Path) -> SceneError {
        // An asset's own place stays; where the scene names it is mapped.
        if let SceneError::Asset { location, message, mut referenced_at } = e {
            return match self.place(&referenced_at, file) {
                Some(Place::Set(set)) => flag_error(set, format!("{location}: {message}")),
                Some(Place::Made(sets)) => made_error(&sets, format!("{location}: {message}")),
                Some(Place::Line(line, column) | Place::Table(line, column, _)) => {
                    referenced_at.line = Some(line);
                    referenced_at.column = referenced_at.column.map(|_| column);
                    SceneError::Asset { location, message, referenced_at }
                }
                None => SceneError::Asset { location, message, referenced_at },
            };
        }
        let Some(place) = e.location().and_then(|l| self.place(l, file)) else { return e };
        let message = |e: &SceneError| match e {
            SceneError::Syntax { message, .. } | SceneError::Invalid { message, .. } => message.clone(),
            SceneError::Read { what, path, reason, .. } => {
                format!("cannot read {what} {}: {reason}", path.display())
            }
            other => other.to_string(),
        };
        let mut e = e;
        match place {
            Place::Set(set) => return flag_error(set, message(&e)),
            Place::Made(sets) => return made_error(&sets, message(&e)),
            Place::Line(line, column) => {
                if let SceneError::Syntax { location, .. }
                | SceneError::Invalid { location, .. }
                | SceneError::Read { location, .. } = &mut e
                {
                    location.line = Some(line);
                    location.column = location.column.map(|_| column);
                }
            }
            Place::Table(line, column, sets) => {
                if let SceneError::Syntax { location, message } | SceneError::Invalid { location, message } =
                    &mut e
                {
                    location.line = Some(line);
                    location.column = location.column.map(|_| column);
                    let sets: Vec<String> = sets.iter().map(|s| format!("{FLAG} {s}")).collect();
                    let values = if sets.len() == 1 { "a value" } else { "values" };
                    message.push_str(&format!(
                        " (this table holds {values} given by {})",
                        crate::check::joined(&sets, "and")
                    ));
                }
            }
        }
        e
    }

    /// What place `loc` of the edited text is in the file's terms: a set
    /// (at its value, or in an array or inline table starting at `loc`
    /// that holds it), the header of a table sets made, or the file's own
    /// line and column; `None` for a place in another file or without a
    /// line.
    fn place(&self, loc: &Location, file: &Path) -> Option<Place<'_>> {
        if loc.file != file {
            return None;
        }
        let line = loc.line?;
        let at = offset_of(&self.text, line, loc.column.unwrap_or(1))?;
        // The array or inline table that starts where the error points, if
        // one does: an error about the whole value (`position` must be
        // three finite numbers) is about a set that changed a part of it.
        if let Some(end) = value_end(&self.text, at)
            && let Some(&i) = self.sets_in(&(at..end)).last()
        {
            return Some(Place::Set(&self.sets[i]));
        }
        let own = match self.origin(at) {
            Origin::Set(i) => return Some(Place::Set(&self.sets[i])),
            Origin::Made => return Some(Place::Made(self.table_sets(line))),
            Origin::File(o) => crate::error::line_col(&self.file_text, o),
        };
        // A problem with a whole table (a camera's up along its view, a
        // mesh without `path`), told at its header: the sets that changed
        // a value in that table take part in it.
        let sets = self.table_sets(line);
        if sets.is_empty() { Some(Place::Line(own.0, own.1)) } else { Some(Place::Table(own.0, own.1, sets)) }
    }

    /// The sets that wrote a value in the table whose header is on `line`
    /// of the edited text (none if no header is there), each key's last
    /// set only (an earlier one of the same key was replaced by it).
    fn table_sets(&self, line: usize) -> Vec<&str> {
        let headers = crate::scan::header_lines(&self.text);
        if self.sets.is_empty() || headers.binary_search(&line).is_err() {
            return Vec::new();
        }
        let start = offset_of(&self.text, line + 1, 1).unwrap_or(self.text.len());
        let end = headers
            .iter()
            .find(|&&h| h > line)
            .and_then(|&h| offset_of(&self.text, h, 1))
            .unwrap_or(self.text.len());
        let key = |set: &str| set.split_once('=').map_or(set, |(k, _)| k).trim().to_owned();
        let inside = self.sets_in(&(start..end));
        let mut sets: Vec<&str> = Vec::new();
        for (k, &i) in inside.iter().enumerate() {
            let set = self.sets[i].as_str();
            let replaced = inside[k + 1..].iter().any(|&later| key(&self.sets[later]) == key(set));
            if !replaced && !sets.contains(&set) {
                sets.push(set);
            }
        }
        sets
    }
}

/// The pieces of `pieces` over the bytes `range` of the text they make.
fn cut(pieces: &[Piece], range: Range<usize>) -> Vec<Piece> {
    let mut out = Vec::new();
    let mut start = 0;
    for p in pieces {
        let end = start + p.len;
        let (a, b) = (start.max(range.start), end.min(range.end));
        if a < b {
            let origin = match p.origin {
                Origin::File(o) => Origin::File(o + (a - start)),
                other => other,
            };
            out.push(Piece { len: b - a, origin });
        }
        start = end;
    }
    out
}

/// A problem of a whole table that sets made (the file has no such table):
/// every set in it is named, as no one of them alone is at fault.
fn made_error(sets: &[&str], message: String) -> SceneError {
    match sets {
        [set] => flag_error(set, message),
        _ => {
            let sets: Vec<String> = sets.iter().map(|s| format!("{FLAG} {s}")).collect();
            SceneError::Option {
                flag: FLAG,
                message: format!("{message} (in a table made by {})", crate::check::joined(&sets, "and")),
            }
        }
    }
}

/// A place of the edited text in the file's terms ([`Edited::remap`]).
enum Place<'a> {
    /// At or in the value of this set (`KEY=VALUE` as given).
    Set(&'a str),
    /// At the header of a table that the file lacks, made by these sets.
    Made(Vec<&'a str>),
    /// The file's own line and column.
    Line(usize, usize),
    /// The file's own line and column of a table's header, the table
    /// holding values of these sets.
    Table(usize, usize, Vec<&'a str>),
}

impl Edited {
    /// A warning of the build (`FILE:LINE[:COLUMN]: message`, places in
    /// the edited text) in the file's own terms, as [`Edited::remap`] does
    /// for errors.
    pub(crate) fn remap_warning(&self, w: String, file: &Path) -> String {
        let prefix = format!("{}:", file.display());
        let Some(rest) = w.strip_prefix(&prefix) else { return w };
        let number = |s: &str| -> Option<(usize, usize)> {
            let digits = s.bytes().take_while(u8::is_ascii_digit).count();
            s[..digits].parse().ok().map(|n| (n, digits))
        };
        let Some((line, n)) = number(rest) else { return w };
        let rest = &rest[n..];
        let (column, rest) = match rest.strip_prefix(':').and_then(|r| number(r).map(|c| (c, r))) {
            Some(((c, n), r)) => (Some(c), &r[n..]),
            None => (None, rest),
        };
        let Some(message) = rest.strip_prefix(": ") else { return w };
        let location = crate::error::Location { file: file.to_path_buf(), line: Some(line), column };
        self.remap(SceneError::Invalid { location, message: message.to_owned() }, file).to_string()
    }
}

/// That the text `edited`, a readable scene with the set `set` applied,
/// is still TOML: an edit must not make a readable file unreadable, and
/// if one did, the error is the set's, not a place in the file (which
/// might be a line the file does not have).
fn still_toml(set: &str, edited: &str) -> Result<(), SceneError> {
    match Document::parse(edited) {
        Ok(_) => Ok(()),
        Err(e) => Err(flag_error(
            set,
            format!(
                "cannot add this to the scene as the file writes it ({}); write the key in the file",
                e.message().trim()
            ),
        )),
    }
}

/// Whether `value` is written as a TOML decimal integer (an optional sign,
/// then `0` or digits not starting with `0`), whatever its size: one
/// toml cannot hold is a number too large, not a string (`007` is a name).
fn toml_integer_digits(value: &str) -> bool {
    let digits = value.strip_prefix(['+', '-']).unwrap_or(value);
    !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit())
        && (digits == "0" || !digits.starts_with('0'))
}

/// The byte offset of 1-based `line` and `column` (in characters) in
/// `text`, if there is such a line (a column past its end is its end).
fn offset_of(text: &str, line: usize, column: usize) -> Option<usize> {
    let start =
        if line == 1 { 0 } else { text.match_indices('\n').nth(line.checked_sub(2)?).map(|(i, _)| i + 1)? };
    let rest = &text[start..];
    let end = rest.find('\n').unwrap_or(rest.len());
    let column = column.checked_sub(1)?;
    Some(start + rest[..end].char_indices().nth(column).map_or(end, |(i, _)| i))
}

/// `keys` as a dotted key, each part quoted where TOML needs it.
fn dotted(keys: &[String]) -> String {
    keys.iter().map(|k| Key::new(k.as_str()).to_string()).collect::<Vec<_>>().join(".")
}

/// `here` joined with `more`, for messages.
fn join(here: &str, more: &str) -> String {
    if here.is_empty() { more.to_owned() } else { format!("{here}.{more}") }
}

/// The index `key` into a list of `len` entries at `here`.
fn index(key: &str, len: usize, here: &str, set: &str) -> Result<usize, SceneError> {
    match key.parse::<usize>() {
        Ok(n) if n < len => Ok(n),
        Ok(n) => {
            let has = match len {
                0 => "has no entries".to_owned(),
                1 => "has 1 entry (0)".to_owned(),
                _ => format!("has {len} entries (0 to {})", len - 1),
            };
            Err(flag_error(set, format!("`{here}` {has}, there is no entry {n}")))
        }
        Err(_) => Err(flag_error(set, format!("`{here}` is a list; expected an index from 0, got `{key}`"))),
    }
}

/// What a value is, for messages.
fn describe(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) | Value::Float(_) => "a number",
        Value::Boolean(_) => "true or false",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "a list",
        Value::InlineTable(_) => "a table",
    }
}

fn is_a_table(set: &str, here: &str) -> SceneError {
    flag_error(set, format!("`{here}` is a table; set its keys one by one (such as {here}.KEY=VALUE)"))
}

/// Where `keys` (at least one) go in the table `t` at `here`; `prefix`:
/// the dotted keys that name `t` under the table whose section holds it
/// (`red` for `[materials]` / `red.color = …`; empty for a table with a
/// header, or the top level).
fn locate(
    t: &Table,
    keys: &[String],
    set: &str,
    here: &str,
    prefix: &[String],
) -> Result<Target, SceneError> {
    let key = &keys[0];
    let at = join(here, key);
    match t.get(key) {
        None | Some(Item::None) => missing(t, keys, set, here, prefix),
        Some(Item::Table(sub)) if keys.len() > 1 => {
            let prefix: Vec<String> =
                if sub.is_dotted() { prefix.iter().chain([key]).cloned().collect() } else { Vec::new() };
            locate(sub, &keys[1..], set, &at, &prefix)
        }
        Some(Item::Table(_)) => Err(is_a_table(set, &at)),
        Some(Item::ArrayOfTables(a)) => {
            let Some(k) = keys.get(1) else {
                return Err(flag_error(
                    set,
                    format!("`{at}` is a list of tables; set one entry's key (such as {at}.0.KEY=VALUE)"),
                ));
            };
            let n = index(k, a.len(), &at, set)?;
            let at = format!("{at}.{n}");
            match (a.get(n), keys.len() > 2) {
                (Some(sub), true) => locate(sub, &keys[2..], set, &at, &[]),
                _ => Err(is_a_table(set, &at)),
            }
        }
        Some(Item::Value(v)) => locate_value(v, &keys[1..], set, &at),
    }
}

/// Where `keys` (perhaps none: the value itself) go in the value `v` at `here`.
fn locate_value(v: &Value, keys: &[String], set: &str, here: &str) -> Result<Target, SceneError> {
    let Some(key) = keys.first() else {
        return v.span().map(Target::Replace).ok_or_else(|| flag_error(set, "cannot place this value"));
    };
    match v {
        Value::InlineTable(t) => match t.get(key) {
            Some(inner) => locate_value(inner, &keys[1..], set, &join(here, key)),
            None => {
                let span = t.span().ok_or_else(|| flag_error(set, "cannot place this value"))?;
                let close = span.end.saturating_sub(1);
                let last = match inline_last_end(t) {
                    None if !t.is_empty() => return Err(flag_error(set, "cannot place this value")),
                    last => last,
                };
                Ok(Target::Inline { close, key: dotted(keys), last })
            }
        },
        Value::Array(a) => {
            let n = index(key, a.len(), here, set)?;
            let inner = a.get(n).ok_or_else(|| flag_error(set, "cannot place this value"))?;
            locate_value(inner, &keys[1..], set, &format!("{here}.{n}"))
        }
        other => Err(flag_error(set, format!("`{here}` is {}, not a table", describe(other)))),
    }
}

/// Where `keys`, whose first is not in the table `t` at `here`, go
/// (`prefix`: as for [`locate`]).
fn missing(
    t: &Table,
    keys: &[String],
    set: &str,
    here: &str,
    prefix: &[String],
) -> Result<Target, SceneError> {
    let (last, table) = keys.split_last().ok_or_else(|| flag_error(set, "empty key"))?;
    // No key of the format is a number: one last is an index into a list
    // that is not there (`objects.0.center.1=2` where the sphere has no
    // `center`), which a new table `center = { 1 = 2 }` would not be.
    if !table.is_empty() && !last.is_empty() && last.bytes().all(|b| b.is_ascii_digit()) {
        let at = join(here, &dotted(table));
        return Err(flag_error(
            set,
            format!(
                "`{at}` is not in the scene, so it has no entry {last}; set the whole list (such as {at}=[…])"
            ),
        ));
    }
    let key = Key::new(last.as_str()).to_string();
    if t.is_dotted() {
        // A table made by dotted keys (`camera.position = …`): the key
        // joins them, a dotted key on the line after the last, in the same
        // section (a header `[camera]` would define the table twice).
        let end = last_value_end(t).ok_or_else(|| flag_error(set, "cannot place this value"))?;
        let path: Vec<String> = prefix.iter().chain(keys).cloned().collect();
        return Ok(Target::Line(end.saturating_sub(1), dotted(&path)));
    }
    if here.is_empty() {
        // The scene's lists of tables: an entry cannot be made by a set (it
        // would be a table named `0`).
        if let [list, entry, ..] = keys
            && matches!(list.as_str(), "cameras" | "lights" | "objects")
            && entry.parse::<usize>().is_ok()
        {
            return Err(flag_error(
                set,
                format!(
                    "the scene has no `{list}`; a set changes entries of a list but cannot add one (write [[{list}]] in the file)"
                ),
            ));
        }
        // The top level: a key before the first table, or a new table.
        return Ok(if table.is_empty() { Target::Top(key) } else { Target::NewTable(dotted(table), key) });
    }
    if t.is_implicit() {
        // Named only by its sub-tables (`[materials.red]` makes `materials`).
        let path: Vec<String> = here.split('.').map(str::to_owned).chain(table.iter().cloned()).collect();
        return Ok(Target::NewTable(dotted(&path), key));
    }
    match t.span() {
        Some(span) if !t.is_dotted() => Ok(Target::Line(span.start, dotted(keys))),
        _ => Err(flag_error(
            set,
            format!(
                "cannot add `{}` to `{here}` as the file writes it; add the key in the file",
                dotted(keys)
            ),
        )),
    }
}

/// The end of the last value written in the table `t` made by dotted keys
/// (its own and those of the dotted tables under it), if any has a span.
fn last_value_end(t: &Table) -> Option<usize> {
    t.iter()
        .filter_map(|(_, item)| match item {
            Item::Value(v) => v.span().map(|s| s.end),
            Item::Table(sub) if sub.is_dotted() => last_value_end(sub),
            _ => None,
        })
        .max()
}

/// The end of the last value written in the inline table `t` (dotted
/// keys within it included), if any has a span.
fn inline_last_end(t: &toml_edit::InlineTable) -> Option<usize> {
    t.iter()
        .filter_map(|(_, v)| match v {
            Value::InlineTable(sub) if sub.is_dotted() => inline_last_end(sub),
            v => v.span().map(|s| s.end),
        })
        .max()
}

/// Whether `between`, the text from an inline table's last value to its
/// closing brace, holds its trailing comma (outside comments).
fn has_comma(between: &str) -> bool {
    between.lines().any(|l| l.split('#').next().unwrap_or_default().contains(','))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edit_that_breaks_the_text_is_the_sets_error() {
        assert!(still_toml("a.b=1", "[a]\nb = 1\n").is_ok());
        let err = still_toml("a.b=1", "[a]\nc = 1\n[a]\nb = 1\n").unwrap_err().to_string();
        assert!(
            err.starts_with("--set: a.b=1: cannot add this to the scene as the file writes it ("),
            "{err}"
        );
        assert!(err.ends_with("); write the key in the file"), "{err}");
    }
}
