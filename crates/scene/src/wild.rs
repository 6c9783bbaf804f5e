//! OBJ and MTL text as other tools write it, made readable for tobj: text
//! that is not UTF-8 read as Latin-1, Windows paths (`.\tex.jpg`), colours
//! given as one value (`Ks 0`), empty material names. Each guess is a
//! warning naming the file and line; the line count never changes, so
//! later messages keep their lines.

use std::borrow::Cow;

/// The name given to a material whose `newmtl`/`usemtl` name is empty.
pub(crate) const UNNAMED: &str = "(unnamed)";

/// A file's text, and the warning its decoding gave, if any.
pub(crate) type Decoded<'a> = (Cow<'a, str>, Option<String>);

/// The text of `bytes`: UTF-8 (a byte-order mark dropped), or, for bytes
/// that are not UTF-8 but hold no NUL, Latin-1 with a warning. UTF-16 and
/// binary data (NUL bytes) are errors: the line, where there is one, and
/// what is wrong.
pub(crate) fn decode_text(bytes: &[u8]) -> Result<Decoded<'_>, (Option<usize>, String)> {
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err((None, "the file is UTF-16 text; expected UTF-8 (or ASCII) text".into()));
    }
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if let Some(at) = bytes.iter().position(|&b| b == 0) {
        let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        return Err((Some(line), "a NUL byte: is it a binary file? (expected text)".into()));
    }
    match std::str::from_utf8(bytes) {
        Ok(t) => Ok((Cow::Borrowed(t), None)),
        Err(e) => {
            let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
            let text: String = bytes.iter().map(|&b| char::from(b)).collect();
            Ok((
                Cow::Owned(text),
                Some(format!("line {line}: the text is not UTF-8; read it as Latin-1 (ISO 8859-1)")),
            ))
        }
    }
}

/// A path with Windows separators (`\`) turned into `/`, if it has any.
fn unixify(path: &str) -> Option<String> {
    path.contains('\\').then(|| path.replace('\\', "/"))
}

/// Rewrites the OBJ lines tobj cannot take: `mtllib` without a name or
/// with Windows separators, `usemtl` without a name or with more than
/// `usemtl NAME` on its line (a comment, indentation); and, silently,
/// valid forms it refuses or misreads: `vt u` (read as `vt u 0`), vertex
/// colours (`v x y z r g b`, read as `v x y z`: prism does not use them,
/// and tobj refuses a file where only some vertices have them), a comment
/// after a statement (`f 1 2 3 # top`), and a line continued on the next
/// by a `\` at its end (joined, the next line left empty). Polylines
/// (`l`) and points (`p`) are dropped, with one warning at the first:
/// prism renders surfaces, and tobj would make them into triangles.
/// Returns the text and the warnings (`line N: ...`).
pub(crate) fn fix_obj(text: &str) -> (Cow<'_, str>, Vec<String>) {
    match join_continued(text) {
        Cow::Borrowed(text) => fix_obj_lines(text),
        Cow::Owned(joined) => {
            let (fixed, warnings) = fix_obj_lines(&joined);
            (Cow::Owned(fixed.into_owned()), warnings)
        }
    }
}

/// `text` with each line that ends in `\` (the OBJ format's line
/// continuation) joined with the next, which is left empty, so that every
/// statement keeps the line it starts on. Only statements of numbers and
/// indices are continued (`v`, `vt`, `vn`, `vp`, `f`, `l`, `p`), and no line
/// with a comment: a `\` at the end of a name or a comment ends a Windows
/// path.
fn join_continued(text: &str) -> Cow<'_, str> {
    // Whether a line (`body`, its end trimmed) goes on on the next;
    // `joining`: it is itself the continuation of a statement.
    let continued = |body: &str, joining: bool| {
        let key = body.split_whitespace().next().unwrap_or("");
        body.ends_with('\\')
            && !body.contains('#')
            && (joining || matches!(key, "v" | "vt" | "vn" | "vp" | "f" | "l" | "p"))
    };
    if !text.lines().any(|l| continued(l.trim_end(), false)) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut emptied = 0;
    let mut joining = false;
    for line in text.split_inclusive('\n') {
        let ending = &line[line.trim_end_matches(['\n', '\r']).len()..];
        let body = line[..line.len() - ending.len()].trim_end();
        let (body, more) = match body.strip_suffix('\\') {
            Some(b) if continued(body, joining) => (b, true),
            _ => (body, false),
        };
        if joining {
            out.push(' ');
        }
        out.push_str(body);
        if more {
            emptied += 1;
            joining = true;
        } else {
            out.push_str(ending);
            // The lines joined into this one, left empty after it.
            for _ in 0..emptied {
                out.push_str(if ending.is_empty() { "\n" } else { ending });
            }
            emptied = 0;
            joining = false;
        }
    }
    // A continuation on the last line: nothing to join.
    for _ in 0..emptied {
        out.push('\n');
    }
    Cow::Owned(out)
}

fn fix_obj_lines(text: &str) -> (Cow<'_, str>, Vec<String>) {
    let first_element = std::cell::Cell::new(true);
    fix_lines(text, |no, key, rest, body| {
        match key {
        "l" | "p" => Some((
            String::new(),
            first_element.replace(false).then(|| {
                format!("line {no}: `{key}` elements (polylines and points) are not rendered; this one and any others are ignored")
            }),
        )),
        "mtllib" if rest.is_empty() => {
            Some((String::new(), Some(format!("line {no}: `mtllib` without a file name; ignored"))))
        }
        "mtllib" => unixify(rest)
            .map(|p| {
                (
                    format!("mtllib {p}"),
                    Some(format!("line {no}: `mtllib {rest}` has Windows separators; read as `{p}`")),
                )
            })
            .or_else(|| body.contains('#').then(|| (format!("mtllib {rest}"), None))),
        "vt" if rest.split_whitespace().count() == 1 => Some((format!("vt {rest} 0"), None)),
        // Colours dropped only where all six are numbers; a bad one is
        // left for the check of the line to name.
        "v" if rest.split_whitespace().count() == 6
            && rest.split_whitespace().all(|v| v.parse::<f32>().is_ok_and(f32::is_finite)) =>
        {
            Some((format!("v {}", rest.split_whitespace().take(3).collect::<Vec<_>>().join(" ")), None))
        }
        "usemtl" if rest.is_empty() => Some((
            format!("usemtl {UNNAMED}"),
            Some(format!("line {no}: `usemtl` without a name; using the material named `{UNNAMED}`")),
        )),
        // tobj takes everything after the line's first space as the name
        // (a comment, the keyword of an indented line): the name alone.
        "usemtl" if body != format!("usemtl {rest}") => Some((
            format!("usemtl {rest}"),
            Some(format!(
                "line {no}: `{}`{} read as `usemtl {rest}`",
                body.trim(),
                if body.starts_with(char::is_whitespace) { " (indented)" } else { "" }
            )),
        )),
        // tobj reads a comment after a statement as part of it: `f 1 2 3
        // # top` as a fourth corner, `mtllib a.mtl # mats` as the name.
        "v" | "vt" | "vn" | "vp" | "f" | "o" | "g" | "s" if body.contains('#') => {
            Some((format!("{key} {rest}"), None))
        }
        _ => None,
    }
    })
}

/// Rewrites the MTL lines tobj cannot take: colours with one value (grey),
/// numbers with a comment stuck to them, `newmtl` without a name, texture
/// paths with Windows separators.
/// Returns the text and the warnings (`line N: ...`).
pub(crate) fn fix_mtl(text: &str) -> (Cow<'_, str>, Vec<String>) {
    fix_lines(text, |no, key, rest, full| {
        // A key prism reads written in another case (`KD`, `Map_Kd`):
        // MTL keys are case-sensitive, and tobj would pass it by in
        // silence.
        let Some(known) = MTL_KEYS.iter().find(|k| **k != key && k.eq_ignore_ascii_case(key)) else {
            return fix_mtl_line(no, key, rest, full);
        };
        let line = if rest.is_empty() { (*known).to_owned() } else { format!("{known} {rest}") };
        let warning = format!("line {no}: `{key}` read as `{known}` (MTL keys are case-sensitive)");
        Some(match fix_mtl_line(no, known, rest, &line) {
            Some((fixed, more)) => {
                // One warning for the line: the fix's own without its `line N: `.
                let prefix = format!("line {no}: ");
                let more = more.map(|m| m.strip_prefix(&prefix).map_or(m.clone(), str::to_owned));
                (fixed, Some(more.map_or(warning.clone(), |m| format!("{warning}; {m}"))))
            }
            None => (line, Some(warning)),
        })
    })
}

/// The MTL keys prism reads (`material::from_mtl`, the texture maps).
const MTL_KEYS: [&str; 11] = ["newmtl", "Kd", "Ks", "Ke", "Ns", "Ni", "d", "Tr", "Tf", "illum", "map_Kd"];

/// [`fix_mtl`] for one line whose key is as prism reads it.
fn fix_mtl_line(no: usize, key: &str, rest: &str, full: &str) -> Option<(String, Option<String>)> {
    match key {
        "Ka" | "Kd" | "Ks" | "Ke" | "Tf" if rest.split_whitespace().count() == 1 => Some((
            format!("{key} {rest} {rest} {rest}"),
            Some(format!(
                "line {no}: `{key} {rest}` has one value; read as grey `{key} {rest} {rest} {rest}`"
            )),
        )),
        // A comment stuck to a value (`Kd 1 0 0#red`): tobj would read
        // `0#red` as the number and refuse the whole library.
        "Ka" | "Kd" | "Ks" | "Ke" | "Tf" | "Ns" | "Ni" | "d" | "Tr" | "illum"
            if full.contains('#') && !rest.is_empty() =>
        {
            Some((format!("{key} {rest}"), None))
        }
        "newmtl" if rest.is_empty() => Some((
            format!("newmtl {UNNAMED}"),
            Some(format!("line {no}: `newmtl` without a name; naming the material `{UNNAMED}`")),
        )),
        k if k.starts_with("map_") || k == "bump" || k == "disp" || k == "decal" => unixify(rest).map(|p| {
            (
                format!("{key} {p}"),
                Some(format!("line {no}: `{key} {rest}` has Windows separators; read as `{p}`")),
            )
        }),
        _ => None,
    }
}

/// Applies `fix(line number, key, rest of the line, trimmed)` to every
/// line; a `Some((new line, warning))` replaces the line.
fn fix_lines(
    text: &str,
    fix: impl Fn(usize, &str, &str, &str) -> Option<(String, Option<String>)>,
) -> (Cow<'_, str>, Vec<String>) {
    let mut warnings = Vec::new();
    let mut out: Option<String> = None;
    let mut done = 0;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let body = line.trim_end_matches(['\n', '\r']);
        let trimmed = body.trim_start();
        let key = trimmed.split_whitespace().next().unwrap_or("");
        let rest = trimmed[key.len()..].split('#').next().unwrap_or("").trim();
        if let Some((new, warning)) = fix(i + 1, key, rest, body) {
            let o = out.get_or_insert_with(|| String::with_capacity(text.len() + 64));
            let start = line.as_ptr() as usize - text.as_ptr() as usize;
            o.push_str(&text[done..start]);
            o.push_str(&new);
            o.push_str(&line[body.len()..]);
            done = start + line.len();
            warnings.extend(warning);
        }
    }
    match out {
        Some(mut o) => {
            o.push_str(&text[done..]);
            (Cow::Owned(o), warnings)
        }
        None => (Cow::Borrowed(text), warnings),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latin1_is_read_with_a_warning_and_binary_refused() {
        let (t, w) = decode_text(b"# caf\xe9\nusemtl m\xe9tal\n").unwrap();
        assert_eq!(t, "# café\nusemtl métal\n");
        assert!(w.unwrap().starts_with("line 1:"));
        assert_eq!(decode_text(b"\xEF\xBB\xBFv 1 2 3").unwrap(), (Cow::Borrowed("v 1 2 3"), None));
        assert_eq!(
            decode_text(&[0x80, 0x81, 0x00]).unwrap_err(),
            (Some(1), "a NUL byte: is it a binary file? (expected text)".to_owned())
        );
        assert_eq!(decode_text(b"v 0 0 0\nf 1 2 3\0\x01\n").unwrap_err().0, Some(2));
        assert!(decode_text(&[0xFF, 0xFE, b'v', 0]).unwrap_err().1.contains("UTF-16"));
    }

    #[test]
    fn obj_lines_are_fixed_in_place() {
        let (t, w) = fix_obj("v 0 0 0\r\nmtllib .\\mats\\a.mtl\r\nusemtl \r\nusemtl b\n");
        assert_eq!(t, "v 0 0 0\r\nmtllib ./mats/a.mtl\r\nusemtl (unnamed)\r\nusemtl b\n");
        assert_eq!(w.len(), 2);
        assert!(w[0].starts_with("line 2:") && w[1].starts_with("line 3:"), "{w:?}");
        let (t, w) = fix_obj("v 0 0 0\nf 1 1 1");
        assert!(matches!(t, Cow::Borrowed(_)) && w.is_empty());
        // Valid forms tobj refuses, read silently; `mtllib` alone dropped.
        let (t, w) = fix_obj("v 1 2 3 0.5 0.5 0.5 # rgb\nv 1 2 3 2\nvt 0.5\nvt 0.5 1\nmtllib\r\nf 1 2 3\n");
        assert_eq!(t, "v 1 2 3\nv 1 2 3 2\nvt 0.5 0\nvt 0.5 1\n\r\nf 1 2 3\n");
        assert_eq!(w, ["line 5: `mtllib` without a file name; ignored"]);
        // tobj would read `red # body` and `usemtl red` as the names.
        let (t, w) = fix_obj("usemtl red # body\n  usemtl red\nusemtl\tred\nusemtl red\n");
        assert_eq!(t, "usemtl red\nusemtl red\nusemtl red\nusemtl red\n");
        assert_eq!(
            w,
            [
                "line 1: `usemtl red # body` read as `usemtl red`",
                "line 2: `usemtl red` (indented) read as `usemtl red`",
                "line 3: `usemtl\tred` read as `usemtl red`"
            ]
        );
        // Polylines and points dropped (a malformed one too), one warning.
        let (t, w) = fix_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nl 1 2 3\np 1\nl 1 x \\\n");
        assert_eq!(t, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\n\n\n");
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("line 5: `l` elements (polylines and points) are not rendered"), "{w:?}");
    }

    /// A comment after a statement is cut (tobj would read `# top` as
    /// corners or as part of a name); a line ending in `\\` is joined with
    /// the next, which is left empty, so the lines keep their numbers; a
    /// comment line ending in `\\` (a Windows folder) continues nothing.
    #[test]
    fn obj_comments_are_cut_and_continued_lines_joined() {
        let (t, w) =
            fix_obj("v 0 0 0 # origin\nvt 1 0#uv\nf 1 2 3 # top\nmtllib a.mtl # mats\ng body # of it\n");
        assert_eq!(t, "v 0 0 0\nvt 1 0\nf 1 2 3\nmtllib a.mtl\ng body\n");
        assert!(w.is_empty(), "{w:?}");
        let (t, w) = fix_obj("f 1 \\\r\n 2 3\r\n# C:\\models\\\r\nf 4 \\\n\\\n5 6 \\\n");
        assert_eq!(t, "f 1   2 3\r\n\r\n# C:\\models\\\r\nf 4   5 6 \n\n\n");
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(t.lines().count(), 6);
        // A name that ends in `\\` goes on on no other line.
        let (t, _) = fix_obj("g C:\\parts\\\nv 0 0 0\n");
        assert_eq!(t, "g C:\\parts\\\nv 0 0 0\n");
    }

    #[test]
    fn mtl_lines_are_fixed_in_place() {
        let (t, w) = fix_mtl(
            "newmtl\nKs 0\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1 .\\tex.jpg\nKa 0.25 # grey\nKd 1 0 0#red\nd 0.5#half\n",
        );
        assert_eq!(
            t,
            "newmtl (unnamed)\nKs 0 0 0\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1 ./tex.jpg\nKa 0.25 0.25 0.25\nKd 1 0 0\nd 0.5\n"
        );
        // The comments cut from values are not worth a warning.
        let lines: Vec<&str> = w.iter().map(|w| &w[..7]).collect();
        assert_eq!(lines, ["line 1:", "line 2:", "line 4:", "line 5:"]);
    }

    #[test]
    fn mtl_keys_in_another_case_are_read_with_a_warning() {
        let (t, w) = fix_mtl("NEWMTL red\nKD 1 0 0\nks 0.5\nMap_Kd a\\b.png\nKa 1 1 1\nKA 1 1 1\nD 0.5\n");
        assert_eq!(t, "newmtl red\nKd 1 0 0\nKs 0.5 0.5 0.5\nmap_Kd a/b.png\nKa 1 1 1\nKA 1 1 1\nd 0.5\n");
        assert_eq!(
            w,
            [
                "line 1: `NEWMTL` read as `newmtl` (MTL keys are case-sensitive)",
                "line 2: `KD` read as `Kd` (MTL keys are case-sensitive)",
                "line 3: `ks` read as `Ks` (MTL keys are case-sensitive); `Ks 0.5` has one value; read as grey `Ks 0.5 0.5 0.5`",
                "line 4: `Map_Kd` read as `map_Kd` (MTL keys are case-sensitive); `map_Kd a\\b.png` has Windows separators; read as `a/b.png`",
                "line 7: `D` read as `d` (MTL keys are case-sensitive)",
            ]
        );
    }
}
