//! The brackets of TOML text, read past strings and comments: for
//! messages that must find the array or inline table around a place
//! (`format`'s syntax hints, `set`'s blame of an edit), where a parse
//! tree is not at hand because the text does not parse or the error
//! carries only a place.

/// The brackets `[`, `]`, `{` and `}` of TOML text `b` outside strings
/// and comments, each with its byte offset, in order.
///
/// Strings are basic (`"…"`, with `\` escapes), literal (`'…'`) and
/// their multi-line forms (`"""…"""`, `'''…'''`, which may close on up
/// to five quotes as TOML allows). A one-line string not closed ends at
/// its line's end, and any string not closed ends at `b`'s end, so that
/// a scan of text cut at an error's place stays in step. Only ASCII
/// bytes are compared, so a multi-byte character never matches.
pub(crate) fn brackets(b: &[u8]) -> impl Iterator<Item = (usize, u8)> + '_ {
    let mut i = 0;
    std::iter::from_fn(move || {
        while i < b.len() {
            match b[i] {
                b'#' => i = b[i..].iter().position(|&c| c == b'\n').map_or(b.len(), |n| i + n),
                q @ (b'"' | b'\'') => i = string_end(b, i, q),
                c @ (b'[' | b']' | b'{' | b'}') => {
                    i += 1;
                    return Some((i - 1, c));
                }
                _ => i += 1,
            }
        }
        None
    })
}

/// The 1-based lines of TOML `text` that hold a table header (`[t]`,
/// `[[t]]`): a `[` first on its line, outside any array, inline table,
/// string or comment. In order.
pub(crate) fn header_lines(text: &str) -> Vec<usize> {
    let b = text.as_bytes();
    let (mut depth, mut line, mut counted) = (0usize, 1usize, 0usize);
    let mut headers = Vec::new();
    for (i, c) in brackets(b) {
        if matches!(c, b'[' | b'{') {
            line += b[counted..i].iter().filter(|&&c| c == b'\n').count();
            counted = i;
            // (Looked back only at the top level: a long line of nested
            // arrays is not read again for each of its brackets.)
            let first = || b[..i].iter().rev().take_while(|&&c| c != b'\n').all(|&c| c == b' ' || c == b'\t');
            if depth == 0 && c == b'[' && first() {
                headers.push(line);
            }
            depth += 1;
        } else {
            depth = depth.saturating_sub(1);
        }
    }
    headers
}

/// The end of the string that starts at byte `i` of `b` with quote `q`:
/// the byte after its closing quote, or its line's end (a one-line
/// string) or `b`'s end if it is not closed.
fn string_end(b: &[u8], i: usize, q: u8) -> usize {
    let run = |j: usize| b[j..].iter().take_while(|&&c| c == q).count();
    let triple = run(i) >= 3;
    // `""` is an empty string, not the start of a multi-line one.
    if !triple && run(i) == 2 {
        return i + 2;
    }
    let mut j = if triple { i + 3 } else { i + 1 };
    while j < b.len() {
        match b[j] {
            b'\\' if q == b'"' => j += 2,
            c if c == q => {
                if !triple {
                    return j + 1;
                }
                // A multi-line string closes on three quotes; up to two
                // more before them are content (`"""a""""` is `a"`).
                let n = run(j);
                if n >= 3 {
                    return j + n.min(5);
                }
                j += n;
            }
            b'\n' if !triple => return j,
            _ => j += 1,
        }
    }
    b.len()
}

/// The byte offset of the innermost `[` or `{` still open at byte
/// `offset` of TOML `text`.
pub(crate) fn innermost_open(text: &str, offset: usize) -> Option<usize> {
    let mut open = Vec::new();
    for (i, c) in brackets(&text.as_bytes()[..offset.min(text.len())]) {
        if matches!(c, b'[' | b'{') {
            open.push(i);
        } else {
            open.pop();
        }
    }
    open.pop()
}

/// Where the array or inline table that opens at byte `at` of `text`
/// closes (the byte after its bracket); `None` if no bracket opens there
/// or it is not closed.
pub(crate) fn value_end(text: &str, at: usize) -> Option<usize> {
    let b = text.as_bytes();
    if !matches!(b.get(at), Some(b'[' | b'{')) {
        return None;
    }
    let mut depth = 0usize;
    for (i, c) in brackets(&b[at..]) {
        if matches!(c, b'[' | b'{') {
            depth += 1;
        } else {
            depth -= 1;
            if depth == 0 {
                return Some(at + i + 1);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn found(text: &str) -> String {
        brackets(text.as_bytes()).map(|(_, c)| c as char).collect()
    }

    #[test]
    fn strings_and_comments_hide_their_brackets() {
        assert_eq!(found(r#"a = ["]", '[', "\"]", { b = "}" }] # ]"#), "[{}]");
        assert_eq!(found("a = [\"\"\"\n]\"\n\"\"\", '''\n[''']"), "[]");
        assert_eq!(found(r#"a = ["""x\"""]""", 1]"#), "[]");
        // Multi-line strings close on up to five quotes.
        assert_eq!(found(r#"a = ["""x""""", 1]"#), "[]");
        assert_eq!(found(r#"a = ['''x'''', 1]"#), "[]");
        // `""` is an empty string; the bracket after it counts.
        assert_eq!(found(r#"a = ["", '', ]"#), "[]");
        // A literal string has no escapes.
        assert_eq!(found(r"a = ['\', ]"), "[]");
    }

    #[test]
    fn a_string_not_closed_ends_at_its_line() {
        assert_eq!(found("a = [\"]\nb = {}"), "[{}");
        // A multi-line one runs to the end.
        assert_eq!(found("a = [\"\"\"]\nb = {}"), "[");
    }

    #[test]
    fn header_lines_are_tables_not_arrays() {
        let text = "a = 1\n[camera]\nv = [\n  [0, 1],\n  [2, 3],\n]\ns = \"\"\"\n[x]\n\"\"\"\n# [y]\n  [[objects]]\nt = { u = [1] }\n[materials.m]\n";
        assert_eq!(header_lines(text), vec![2, 11, 13]);
        assert_eq!(header_lines(""), Vec::<usize>::new());
    }

    #[test]
    fn innermost_open_finds_the_bracket_around_a_place() {
        let text = r#"a = [1, { b = """}""", c = [2, 3] }, x"#;
        let at = |s: &str| text.find(s).unwrap();
        assert_eq!(innermost_open(text, at("x")), Some(at("[")));
        assert_eq!(innermost_open(text, at("2")), Some(at("[2")));
        assert_eq!(innermost_open(text, at("c =")), Some(at("{")));
        assert_eq!(innermost_open(text, 0), None);
        // A place past the end is the end.
        assert_eq!(innermost_open("[", 9), Some(0));
    }

    #[test]
    fn value_end_skips_what_strings_hold() {
        // The multi-line string holds a quote and a line break, which a
        // scan that knows only one-line strings reads wrong.
        let text = "t = { s = \"\"\"a \"}\n] b\"\"\", v = [1, \"]\"] } # }";
        let open = text.find('{').unwrap();
        assert_eq!(value_end(text, open), Some(text.rfind(" #").unwrap()));
        let inner = text.find("[1").unwrap();
        assert_eq!(&text[inner..value_end(text, inner).unwrap()], r#"[1, "]"]"#);
        assert_eq!(value_end(text, 0), None);
        assert_eq!(value_end("[1, [2]", 0), None);
        assert_eq!(value_end("[", 5), None);
    }
}
