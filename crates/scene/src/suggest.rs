//! Messages in scene terms: serde's and toml's wording ("expected f64",
//! "unknown field `radios`, expected one of ...") rewritten to say what a
//! scene author wrote and what was expected ("a number", "a whole
//! number"), and "did you mean …?" for a misspelt key or name.
//!
//! The key lists come from the types themselves: serde's unknown-field
//! error lists the fields of the struct it was filling, so a key added to
//! a struct in `format.rs` joins the suggestions with no change here. For
//! an object, whose struct holds the keys of every shape, the list is
//! narrowed to the keys its `type` takes ([`crate::object::shape_keys`]).

use crate::format::ObjectKind;

/// Keys every object takes, whatever its `type`.
pub(crate) const OBJECT_KEYS: [&str; 4] = ["type", "material", "transform", "name"];

/// The candidate closest to `word`, if it is close enough to be what was
/// meant: at most one edit in four characters (at least one edit), or
/// one of the two is a prefix of the other (`fov_deg` → `fov`).
pub(crate) fn closest<'c>(word: &str, candidates: &[&'c str]) -> Option<&'c str> {
    let lower = word.to_ascii_lowercase();
    let (best, dist) =
        candidates.iter().map(|c| (*c, strsim::damerau_levenshtein(&lower, c))).min_by_key(|&(_, d)| d)?;
    let limit = (word.chars().count() / 4).max(1);
    if dist <= limit {
        return Some(best);
    }
    candidates.iter().copied().find(|c| c.len() >= 2 && (lower.starts_with(c) || c.starts_with(&lower)))
}

/// The `type` of the object whose entry holds byte `offset` of the scene
/// `text` (the last `[[objects]]` entry starting before it), if `message`
/// is about an unknown key of an object (serde lists every object key).
pub(crate) fn object_at(text: &str, offset: usize, message: &str) -> Option<ObjectKind> {
    #[derive(serde::Deserialize)]
    struct Objects {
        #[serde(default)]
        objects: Vec<toml::Spanned<toml::Table>>,
    }
    if !message.starts_with("unknown field")
        || !OBJECT_KEYS.iter().all(|k| message.contains(&format!("`{k}`")))
    {
        return None;
    }
    let objects: Objects = toml::from_str(text).ok()?;
    let object = objects.objects.iter().rfind(|o| o.span().start <= offset)?;
    object.get_ref().get("type")?.clone().try_into().ok()
}

/// ` Did you mean `x`?` for `word` among `candidates`, or nothing.
fn did_you_mean(word: &str, candidates: &[&str]) -> String {
    closest(word, candidates).map_or_else(String::new, |c| format!("; did you mean `{c}`?"))
}

/// The words between backticks in `s`, in order.
fn backticked(s: &str) -> Vec<&str> {
    s.split('`').skip(1).step_by(2).collect()
}

/// `m`, a message of serde or toml, in scene terms. `object` is the
/// `type` of the `[[objects]]` entry the message is about, if it is about
/// one (its keys are then the shape's, not every shape's).
pub(crate) fn friendly(m: &str, object: Option<ObjectKind>) -> String {
    let m = m.trim();
    if let Some(rest) = m.strip_prefix("unknown field ") {
        return unknown(rest, "key", object);
    }
    if let Some(rest) = m.strip_prefix("unknown variant ") {
        return unknown(rest, "name", None);
    }
    if let Some(rest) = m.strip_prefix("invalid length ")
        && let Some((n, expected)) = rest.split_once(", expected ")
    {
        let values = if n == "1" { "1 value" } else { &format!("{n} values") };
        return format!("invalid length {n}: expected {}, got {values}", expected_words(expected));
    }
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = m.strip_prefix(prefix)
            && let Some((got, expected)) = rest.split_once(", expected ")
        {
            return format!("expected {}, got {}", expected_words(expected), got_words(got));
        }
    }
    m.to_owned()
}

/// `` `radios`, expected one of `a`, `b` `` as an unknown key (or name)
/// with a suggestion and the list of what is accepted.
fn unknown(rest: &str, what: &str, object: Option<ObjectKind>) -> String {
    let (word, expected) = match rest.split_once(", expected ") {
        Some((w, e)) => (w.trim_matches('`'), backticked(e)),
        None => (rest.split(',').next().unwrap_or(rest).trim_matches('`'), Vec::new()),
    };
    if let Some(kind) = object {
        let own = crate::object::shape_keys(kind);
        let all: Vec<&str> = own.iter().chain(OBJECT_KEYS.iter()).copied().collect();
        return format!(
            "unknown key `{word}` in a {}{} (a {} takes: {}, plus {})",
            kind.name(),
            did_you_mean(word, &all),
            kind.name(),
            own.join(", "),
            OBJECT_KEYS.join(", ")
        );
    }
    if expected.is_empty() {
        return format!("unknown {what} `{word}`: this table takes no keys");
    }
    format!(
        "unknown {what} `{word}`{} (expected one of: {})",
        did_you_mean(word, &expected),
        expected.join(", ")
    )
}

/// What serde expected, in scene terms.
fn expected_words(e: &str) -> String {
    let e = e.trim();
    match e {
        "f64" | "f32" => return "a number".into(),
        "u64" | "u32" | "u16" | "u8" | "usize" => return "a whole number (0 or more)".into(),
        "i64" | "i32" => return "a whole number".into(),
        "a boolean" => return "true or false".into(),
        "a string" | "a char" => return "a string".into(),
        _ => {}
    }
    if let Some(n) = e.strip_prefix("an array of length ") {
        return format!("an array of {n} numbers");
    }
    if e.starts_with("struct ") {
        return "a table".into();
    }
    if e.starts_with("a sequence") {
        return "an array".into();
    }
    e.to_owned()
}

/// What serde found, in scene terms.
fn got_words(g: &str) -> String {
    let g = g.trim();
    for prefix in ["floating point ", "integer "] {
        if let Some(v) = g.strip_prefix(prefix) {
            return format!("the number {}", v.trim_matches('`'));
        }
    }
    if let Some(v) = g.strip_prefix("boolean ") {
        return v.trim_matches('`').to_owned();
    }
    if let Some(v) = g.strip_prefix("string ") {
        return format!("the string {v}");
    }
    match g {
        "sequence" => "an array".into(),
        "map" => "a table".into(),
        other => other.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_words_are_suggested_and_far_ones_are_not() {
        let keys = ["center", "radius", "type", "material"];
        assert_eq!(closest("radios", &keys), Some("radius"));
        assert_eq!(closest("centre", &keys), Some("center"));
        assert_eq!(closest("Radius", &keys), Some("radius"));
        assert_eq!(closest("colour", &keys), None);
        assert_eq!(closest("fov_deg", &["fov", "up"]), Some("fov"));
        assert_eq!(closest("x", &["fov", "up"]), None);
        assert_eq!(closest("x", &[]), None);
    }

    #[test]
    fn serde_words_become_scene_words() {
        assert_eq!(
            friendly("invalid type: string \"1\", expected f64", None),
            "expected a number, got the string \"1\""
        );
        assert_eq!(
            friendly("invalid type: floating point `640.0`, expected u64", None),
            "expected a whole number (0 or more), got the number 640.0"
        );
        assert_eq!(
            friendly("invalid value: integer `-1`, expected u64", None),
            "expected a whole number (0 or more), got the number -1"
        );
        assert_eq!(
            friendly("invalid length 2, expected an array of length 3", None),
            "invalid length 2: expected an array of 3 numbers, got 2 values"
        );
        let m = friendly("unknown field `widht`, expected one of `width`, `height`, `spp`", None);
        assert_eq!(m, "unknown key `widht`; did you mean `width`? (expected one of: width, height, spp)");
        let m = friendly("unknown field `zzz`, expected `a` or `b`", None);
        assert_eq!(m, "unknown key `zzz` (expected one of: a, b)");
        let m = friendly("unknown variant `spheer`, expected one of `sphere`, `plane`", None);
        assert_eq!(m, "unknown name `spheer`; did you mean `sphere`? (expected one of: sphere, plane)");
        for m in ["f64", "u64", "struct Fields", "a sequence"] {
            let out = friendly(&format!("invalid type: map, expected {m}"), None);
            assert!(!out.contains("f64") && !out.contains("u64"), "{out}");
        }
    }

    #[test]
    fn an_object_lists_only_its_own_keys() {
        let all =
            "`type`, `material`, `transform`, `name`, `center`, `radius`, `point`, `normal`, `vertices`";
        let m = friendly(&format!("unknown field `radios`, expected one of {all}"), Some(ObjectKind::Sphere));
        assert!(m.starts_with("unknown key `radios` in a sphere; did you mean `radius`?"), "{m}");
        assert!(m.contains("a sphere takes: center, radius, plus type, material"), "{m}");
        assert!(!m.contains("vertices") && !m.contains("normal"), "{m}");
    }
}
