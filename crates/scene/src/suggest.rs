//! Messages in scene terms: serde's and toml's wording ("expected f64",
//! "unknown field `radios`, expected one of ...") rewritten to say what a
//! scene author wrote and what was expected ("a number", "a whole
//! number"), and "did you mean …?" for a misspelt key or name.
//!
//! The key lists come from the types themselves: serde's unknown-field
//! error lists the fields of the struct it was filling, so a key added to
//! a struct in `format.rs` joins the suggestions with no change here. For
//! an object or a light, whose struct holds the keys of every kind, the
//! list is narrowed to the keys its `type` takes
//! ([`crate::object::shape_keys`], [`crate::light::light_keys`]).

use crate::format::{LightKindDef, ObjectKind};

/// Keys every object takes, whatever its `type`.
pub(crate) const OBJECT_KEYS: [&str; 4] = ["type", "material", "transform", "name"];

/// Keys every light takes, whatever its `type`.
pub(crate) const LIGHT_KEYS: [&str; 4] = ["type", "color", "radiance", "intensity"];

/// An `[[objects]]` or `[[lights]]` entry of a known `type`, whose keys a
/// message about an unknown key lists instead of every kind's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Entry {
    Object(ObjectKind),
    Light(LightKindDef),
}

impl Entry {
    /// "a sphere", "a quad light".
    fn what(self) -> String {
        match self {
            Entry::Object(k) => k.name().to_owned(),
            Entry::Light(k) => format!("{} light", k.name()),
        }
    }

    /// Its own keys, then the keys every entry of its table takes.
    fn keys(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            Entry::Object(k) => (crate::object::shape_keys(k), &OBJECT_KEYS),
            Entry::Light(k) => (crate::light::light_keys(k), &LIGHT_KEYS),
        }
    }
}

/// The object or light whose entry holds byte `offset` of the scene
/// `text` (the last `[[objects]]` or `[[lights]]` entry starting before
/// it), if `message` is about an unknown key of one (serde then lists
/// every key of its table). A light without `type` is a point light.
pub(crate) fn entry_at(text: &str, offset: usize, message: &str) -> Option<Entry> {
    #[derive(serde::Deserialize)]
    struct Tables {
        #[serde(default)]
        objects: Vec<toml::Spanned<toml::Table>>,
        #[serde(default)]
        lights: Vec<toml::Spanned<toml::Table>>,
    }
    let lists = |keys: &[&str]| keys.iter().all(|k| message.contains(&format!("`{k}`")));
    if !message.starts_with("unknown field") {
        return None;
    }
    let tables = || -> Option<Tables> { toml::from_str(text).ok() };
    let last = |v: &[toml::Spanned<toml::Table>]| v.iter().rfind(|o| o.span().start <= offset).cloned();
    if lists(&OBJECT_KEYS) {
        let object = last(&tables()?.objects)?;
        return object.get_ref().get("type")?.clone().try_into().ok().map(Entry::Object);
    }
    if lists(&LIGHT_KEYS) {
        let light = last(&tables()?.lights)?;
        return match light.get_ref().get("type") {
            None => Some(Entry::Light(LightKindDef::Point)),
            Some(t) => t.clone().try_into().ok().map(Entry::Light),
        };
    }
    None
}

use prism_shade::did_you_mean;

/// The words between backticks in `s`, in order.
fn backticked(s: &str) -> Vec<&str> {
    s.split('`').skip(1).step_by(2).collect()
}

/// `m`, a message of serde or toml, in scene terms. `entry` is the
/// object or light the message is about, if it is about one (its keys are
/// then its kind's, not every kind's).
pub(crate) fn friendly(m: &str, entry: Option<Entry>) -> String {
    let m = m.trim();
    if let Some(rest) = m.strip_prefix("unknown field ") {
        return unknown(rest, "key", entry);
    }
    if let Some(rest) = m.strip_prefix("unknown variant ") {
        return unknown(rest, "name", None);
    }
    if let Some(key) = m.strip_prefix("missing field ") {
        return format!("missing key {key}");
    }
    if let Some(rest) = m.strip_prefix("invalid length ")
        && let Some((n, expected)) = rest.split_once(", expected ")
    {
        let values = if n == "1" { "1 value" } else { &format!("{n} values") };
        return format!("expected {}, got {values}", expected_words(expected));
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
fn unknown(rest: &str, what: &str, entry: Option<Entry>) -> String {
    let (word, expected) = match rest.split_once(", expected ") {
        Some((w, e)) => (w.trim_matches('`'), backticked(e)),
        None => (rest.split(',').next().unwrap_or(rest).trim_matches('`'), Vec::new()),
    };
    // The key as shown: a long one cut short (a stray paste would fill the
    // terminal); the suggestion is made from the whole of it.
    let shown = shortened(word);
    if let Some(entry) = entry {
        let (own, common) = entry.keys();
        let all: Vec<&str> = own.iter().chain(common.iter()).copied().collect();
        let name = entry.what();
        let hint = entry_home(word, &all, entry).unwrap_or_else(|| did_you_mean(word, &all));
        return format!(
            "unknown key `{shown}` in a {name}{hint} (a {name} takes: {}, plus {})",
            own.join(", "),
            common.join(", ")
        );
    }
    if expected.is_empty() {
        return format!("unknown {what} `{shown}`: this table takes no keys");
    }
    // A texture's keys are those of both kinds: list them by kind.
    let (checker, image) = (crate::material::CHECKER_KEYS, crate::material::IMAGE_KEYS);
    let mut texture: Vec<&str> = std::iter::once("type").chain(checker).chain(image).collect();
    let mut given = expected.clone();
    texture.sort_unstable();
    given.sort_unstable();
    if given == texture {
        return format!(
            "unknown key `{shown}`{} (a checker texture takes: type, {}; an image texture: type, {})",
            did_you_mean(word, &expected),
            checker.join(", "),
            image.join(", ")
        );
    }
    // A key of another table (`fov` written under `[render]`): where it
    // goes, not the nearest spelling of this table's keys.
    let hint = match home_of(word, &expected) {
        Some(table) if what == "key" => format!("; it is a key of `{table}`"),
        _ => did_you_mean(word, &expected),
    };
    format!("unknown {what} `{shown}`{hint} (expected one of: {})", expected.join(", "))
}

/// Where a key that an object or light (`entry`, whose keys are `all`)
/// does not take belongs, if elsewhere: a material's (`color` on a
/// sphere, the commonest slip), a `transform` step's, or another table's
/// ([`home_of`]).
fn entry_home(word: &str, all: &[&str], entry: Entry) -> Option<String> {
    if all.contains(&word) {
        return None;
    }
    if matches!(entry, Entry::Object(_)) {
        if keys_of::<crate::format::MaterialDef>().iter().any(|k| k == word) {
            return Some(
                "; it is a key of a material: write it under `[materials.NAME]` and give the object `material = \"NAME\"`"
                    .to_owned(),
            );
        }
        if crate::format::TRANSFORM_STEPS.contains(&word) {
            return Some(format!("; it is a step of `transform`: `transform = [{{ {word} = … }}]`"));
        }
    }
    home_of(word, all).map(|table| format!("; it is a key of `{table}`"))
}

/// The keys of the table type `T`, from the list serde gives for an
/// unknown one.
fn keys_of<T: serde::de::DeserializeOwned>() -> Vec<String> {
    match toml::from_str::<T>("\"\\u0000\" = 0") {
        Err(e) => backticked(e.message()).into_iter().skip(1).map(str::to_owned).collect(),
        Ok(_) => Vec::new(),
    }
}

/// The table of a scene file other than the one whose keys are
/// `expected` that takes the key `word`, if one does: `[camera]` for
/// `fov`. The keys come from the types, through the list serde gives for
/// an unknown one.
fn home_of(word: &str, expected: &[&str]) -> Option<&'static str> {
    use crate::format::{CameraDef, FogDef, RenderDef};
    if expected.contains(&word) {
        return None;
    }
    [
        ("[render]", keys_of::<RenderDef>()),
        ("[camera]", keys_of::<CameraDef>()),
        ("[fog]", keys_of::<FogDef>()),
    ]
    .into_iter()
    .find(|(_, keys)| keys.iter().any(|k| k == word))
    .map(|(table, _)| table)
}

/// `word`, cut to its first 60 characters and "…" when it is longer.
fn shortened(word: &str) -> std::borrow::Cow<'_, str> {
    const SHOWN: usize = 60;
    match word.char_indices().nth(SHOWN) {
        Some((end, _)) => format!("{}…", &word[..end]).into(),
        None => word.into(),
    }
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
    if e.starts_with("struct ") || e == "a map" {
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
            // toml hands a whole number beyond 64 bits over as `` `N` as i128 ``.
            if let Some(n) = v.strip_suffix(" as i128").or_else(|| v.strip_suffix(" as u128")) {
                return format!("the whole number {}, beyond the 64-bit range", n.trim_matches('`'));
            }
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
            "expected an array of 3 numbers, got 2 values"
        );
        let m = friendly("unknown field `widht`, expected one of `width`, `height`, `spp`", None);
        assert_eq!(m, "unknown key `widht`; did you mean `width`? (expected one of: width, height, spp)");
        let m = friendly("unknown field `zzz`, expected `a` or `b`", None);
        assert_eq!(m, "unknown key `zzz` (expected one of: a, b)");
        // A long key is shown cut short, whatever its characters.
        let long = "ké".repeat(50_000);
        let m = friendly(&format!("unknown field `{long}`, expected `a` or `b`"), None);
        assert_eq!(m, format!("unknown key `{}…` (expected one of: a, b)", "ké".repeat(30)));
        let sixty = "k".repeat(60);
        let m = friendly(&format!("unknown field `{sixty}`, expected `a` or `b`"), None);
        assert_eq!(m, format!("unknown key `{sixty}` (expected one of: a, b)"));
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
        let m = friendly(
            &format!("unknown field `radios`, expected one of {all}"),
            Some(Entry::Object(ObjectKind::Sphere)),
        );
        assert!(m.starts_with("unknown key `radios` in a sphere; did you mean `radius`?"), "{m}");
        assert!(m.contains("a sphere takes: center, radius, plus type, material"), "{m}");
        assert!(!m.contains("vertices") && !m.contains("normal"), "{m}");
    }

    #[test]
    fn a_light_lists_only_its_own_keys() {
        let text = "[[lights]]\ntype = \"quad\"\ncorner = [0, 1, 0]\nedge_uu = [1, 0, 0]\n\n[[lights]]\nposition = [0, 1, 0]\nfallof = \"none\"\n";
        let all =
            "`type`, `position`, `color`, `radiance`, `intensity`, `falloff`, `corner`, `edge_u`, `edge_v`";
        let msg = format!("unknown field `edge_uu`, expected one of {all}");
        let quad = entry_at(text, text.find("edge_uu").unwrap(), &msg);
        assert_eq!(quad, Some(Entry::Light(LightKindDef::Quad)));
        let m = friendly(&msg, quad);
        assert!(m.starts_with("unknown key `edge_uu` in a quad light; did you mean `edge_u`?"), "{m}");
        assert!(m.contains("(a quad light takes: corner, edge_u, edge_v, samples"), "{m}");
        assert!(!m.contains("falloff") && !m.contains("position"), "{m}");
        // A light without `type` is a point light.
        let msg = format!("unknown field `fallof`, expected one of {all}");
        let point = entry_at(text, text.find("fallof").unwrap(), &msg);
        assert_eq!(point, Some(Entry::Light(LightKindDef::Point)));
        assert!(
            friendly(&msg, point).contains("did you mean `falloff`? (a point light takes: position, falloff")
        );
    }
}
