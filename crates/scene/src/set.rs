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

/// One edit: where a set's value went in the edited text.
#[derive(Clone, Debug)]
struct Edit {
    /// The set as given (`KEY=VALUE`).
    set: String,
    /// 1-based line in the edited text.
    line: usize,
    /// Whole lines inserted from `line` on (0: a value replaced on `line`).
    lines: usize,
    /// For a replaced value: the 1-based column where it starts.
    column: usize,
}

/// The scene text with every set applied.
#[derive(Clone, Debug)]
pub(crate) struct Edited {
    /// The edited text.
    pub text: String,
    edits: Vec<Edit>,
}

/// Applies `sets` (each `KEY=VALUE`) to the scene `text`, in order.
///
/// # Errors
/// [`SceneError::Option`] naming `--set`, for a set that is not
/// `KEY=VALUE`, a path through something that is not a table or array, an
/// index past the end, or a whole table replaced by a value.
/// [`SceneError::Syntax`] when `text` itself is not TOML (at its place).
pub(crate) fn apply(text: &str, sets: &[String], file: &Path) -> Result<Edited, SceneError> {
    let mut edited = Edited { text: text.to_owned(), edits: Vec::new() };
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
        let line_of = |offset: usize| crate::error::line_col(text, offset);
        let (new_text, edit) = match target {
            Target::Replace(span) => {
                let (line, column) = line_of(span.start);
                let t = format!("{}{repr}{}", &text[..span.start], &text[span.end..]);
                (t, Edit { set: set.to_owned(), line, lines: 0, column })
            }
            Target::Line(header, key) => {
                // On the line after the table's header (the top of the file for the top level).
                let at = text[header..].find('\n').map_or(text.len(), |i| header + i + 1);
                let lead =
                    if at == text.len() && !text.is_empty() && !text.ends_with('\n') { "\n" } else { "" };
                let (line, _) = line_of(at);
                let line = if lead.is_empty() { line } else { line + 1 };
                let t = format!("{}{lead}{key} = {repr}\n{}", &text[..at], &text[at..]);
                (t, Edit { set: set.to_owned(), line, lines: 1, column: 1 })
            }
            Target::Top(key) => {
                let t = format!("{key} = {repr}\n{text}");
                (t, Edit { set: set.to_owned(), line: 1, lines: 1, column: 1 })
            }
            Target::Inline { close, key, last } => {
                // At the closing brace itself, which is never in a comment
                // (a line break or comment before it stays as it is), with
                // a comma unless the table is empty or ends with one.
                let (line, column) = line_of(close);
                let comma = last.is_some_and(|end| !has_comma(text.get(end..close).unwrap_or_default()));
                let sep = if comma { ", " } else { " " };
                let t = format!("{}{sep}{key} = {repr} {}", &text[..close], &text[close..]);
                (t, Edit { set: set.to_owned(), line, lines: 0, column })
            }
            Target::NewTable(table, key) => {
                let sep = if text.is_empty() || text.ends_with('\n') { "" } else { "\n" };
                let (line, _) = line_of(text.len());
                let line = if sep.is_empty() { line } else { line + 1 };
                let t = format!("{text}{sep}[{table}]\n{key} = {repr}\n");
                (t, Edit { set: set.to_owned(), line, lines: 2, column: 1 })
            }
        };
        if edit.lines > 0 {
            for e in &mut self.edits {
                if e.line >= edit.line {
                    e.line += edit.lines;
                } else if edit.line < e.line + e.lines {
                    // Inserted inside an earlier set's lines (a key added
                    // under the table an earlier set created): that set's
                    // lines now span the new ones too (the later set is
                    // matched first, `remap`).
                    e.lines += edit.lines;
                }
            }
        }
        still_toml(set, &new_text)?;
        self.text = new_text;
        self.edits.push(edit);
        Ok(())
    }

    /// `e` (from the edited text) in the terms of the file as written: a
    /// problem at a set value names the flag and the set; any other
    /// place's line is the file's own.
    pub(crate) fn remap(&self, e: SceneError, file: &Path) -> SceneError {
        // An asset's own place stays; where the scene names it is mapped.
        if let SceneError::Asset { location, message, mut referenced_at } = e {
            return match self.place(&referenced_at, file) {
                Some(Place::Set(set)) => flag_error(set, format!("{location}: {message}")),
                Some(Place::Line(line) | Place::Table(line, _)) => {
                    referenced_at.line = Some(line);
                    SceneError::Asset { location, message, referenced_at }
                }
                None => SceneError::Asset { location, message, referenced_at },
            };
        }
        let Some(place) = e.location().and_then(|l| self.place(l, file)) else { return e };
        let mut e = e;
        match place {
            Place::Set(set) => {
                let message = match &e {
                    SceneError::Syntax { message, .. } | SceneError::Invalid { message, .. } => {
                        message.clone()
                    }
                    SceneError::Read { what, path, reason, .. } => {
                        format!("cannot read {what} {}: {reason}", path.display())
                    }
                    other => other.to_string(),
                };
                return flag_error(set, message);
            }
            Place::Line(line) => {
                if let SceneError::Syntax { location, .. }
                | SceneError::Invalid { location, .. }
                | SceneError::Read { location, .. } = &mut e
                {
                    location.line = Some(line);
                }
            }
            Place::Table(line, sets) => {
                if let SceneError::Syntax { location, message } | SceneError::Invalid { location, message } =
                    &mut e
                {
                    location.line = Some(line);
                    let sets: Vec<String> = sets.iter().map(|s| format!("{FLAG} {s}")).collect();
                    let values = if sets.len() == 1 { "a value" } else { "values" };
                    message
                        .push_str(&format!(" (this table holds {values} given by {})", sets.join(" and ")));
                }
            }
        }
        e
    }

    /// What place `loc` of the edited text is in the file's terms: a set
    /// (at its value, or in an array or inline table starting at `loc`
    /// that holds it) or the file's own line; `None` for a place in
    /// another file or without a line.
    fn place(&self, loc: &Location, file: &Path) -> Option<Place<'_>> {
        if loc.file != file {
            return None;
        }
        let line = loc.line?;
        let column = loc.column.unwrap_or(1);
        // The array or inline table that starts where the error points, if
        // one does: an error about the whole value (`position` must be
        // three finite numbers) is about a set that changed a part of it.
        let at = offset_of(&self.text, line, column);
        let whole = at.and_then(|a| value_end(&self.text, a).map(|end| a..end));
        for edit in self.edits.iter().rev() {
            let hit = if edit.lines == 0 {
                (line == edit.line && column >= edit.column)
                    || whole.as_ref().is_some_and(|w| {
                        offset_of(&self.text, edit.line, edit.column).is_some_and(|o| w.contains(&o))
                    })
            } else {
                (edit.line..edit.line + edit.lines).contains(&line)
            };
            if hit {
                return Some(Place::Set(&edit.set));
            }
        }
        let shift: usize = self.edits.iter().filter(|d| d.lines > 0 && d.line < line).map(|d| d.lines).sum();
        let own = line - shift.min(line - 1);
        // A problem with a whole table (a camera's up along its view, a
        // mesh without `path`), told at its header: the sets that changed
        // a value in that table take part in it.
        if !self.edits.is_empty() {
            let headers = crate::scan::header_lines(&self.text);
            if headers.binary_search(&line).is_ok() {
                let end = headers.iter().copied().find(|&h| h > line).unwrap_or(usize::MAX);
                // Each key's last set: an earlier one of the same key was
                // replaced by it.
                let key = |set: &str| set.split_once('=').map_or(set, |(k, _)| k).trim().to_owned();
                let inside: Vec<&Edit> =
                    self.edits.iter().filter(|e| e.line > line && e.line < end).collect();
                let mut sets: Vec<&str> = Vec::new();
                for (k, edit) in inside.iter().enumerate() {
                    let replaced = inside[k + 1..].iter().any(|later| key(&later.set) == key(&edit.set));
                    if !replaced && !sets.contains(&edit.set.as_str()) {
                        sets.push(&edit.set);
                    }
                }
                if !sets.is_empty() {
                    return Some(Place::Table(own, sets));
                }
            }
        }
        Some(Place::Line(own))
    }
}

/// A place of the edited text in the file's terms ([`Edited::remap`]).
enum Place<'a> {
    /// At or in the value of this set (`KEY=VALUE` as given).
    Set(&'a str),
    /// The file's own line.
    Line(usize),
    /// The file's own line of a table's header, the table holding values
    /// of these sets.
    Table(usize, Vec<&'a str>),
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
/// `text`, if there is such a place.
fn offset_of(text: &str, line: usize, column: usize) -> Option<usize> {
    let start =
        if line == 1 { 0 } else { text.match_indices('\n').nth(line.checked_sub(2)?).map(|(i, _)| i + 1)? };
    let rest = &text[start..];
    let end = rest.find('\n').unwrap_or(rest.len());
    rest[..end].char_indices().nth(column.checked_sub(1)?).map(|(i, _)| start + i)
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
