//! The scene file as written: serde definitions mirroring
//! `docs/scene-format.md`. Every table rejects unknown keys; fields that
//! are validated after deserialising keep their spans.

use crate::error::{Location, SceneError};
use crate::obj::NormalMode;
use crate::scan::innermost_open;
use prism_shade::Wrap;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use toml::Spanned;

/// A spanned number.
pub type Num = Spanned<f64>;

/// The names of a `transform` list's steps.
pub(crate) const TRANSFORM_STEPS: [&str; 9] =
    ["translate", "rotate_x", "rotate_y", "rotate_z", "rotate", "scale", "shear", "shear_angle", "matrix"];

/// A struct that is written as a table and nothing else. serde's derived
/// structs also take an array, field by field in declaration order, and
/// drop the elements past the last field without a word
/// (`camera = [[0, 0, 5], [0, 0, 0]]` would be a camera): the fields
/// holding these structs read them through [`table`], which refuses an
/// array with an example of the table.
pub trait Keyed {
    /// A short example of the table, shown when something else is given:
    /// `` `{ position = [0, 2, 8], look_at = [0, 0, 0] }` ``.
    const EXAMPLE: &'static str;
}

/// `deserialize_with` functions for fields holding [`Keyed`] structs,
/// one per container the scene format puts them in.
pub mod table {
    use super::Keyed;
    use serde::de::{self, Deserialize, Deserializer, MapAccess, Visitor};
    use std::collections::BTreeMap;
    use std::fmt;
    use std::marker::PhantomData;
    use toml::Spanned;

    /// `T` read from a table only.
    struct Table<T>(T);

    impl<'de, T: Deserialize<'de> + Keyed> Deserialize<'de> for Table<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V<T>(PhantomData<T>);
            impl<'de, T: Deserialize<'de> + Keyed> Visitor<'de> for V<T> {
                type Value = Table<T>;
                fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                    write!(f, "a table of named keys such as {}", T::EXAMPLE)
                }
                fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Table<T>, A::Error> {
                    T::deserialize(de::value::MapAccessDeserializer::new(map)).map(Table)
                }
            }
            d.deserialize_map(V(PhantomData))
        }
    }

    fn unwrapped<T>(t: Spanned<Table<T>>) -> Spanned<T> {
        let span = t.span();
        Spanned::new(span, t.into_inner().0)
    }

    /// `key = { ... }`.
    pub fn one<'de, D: Deserializer<'de>, T: Deserialize<'de> + Keyed>(d: D) -> Result<Spanned<T>, D::Error> {
        Spanned::<Table<T>>::deserialize(d).map(unwrapped)
    }

    /// An optional `key = { ... }` (or `[key]`); the field also needs
    /// `#[serde(default)]`.
    pub fn opt<'de, D: Deserializer<'de>, T: Deserialize<'de> + Keyed>(
        d: D,
    ) -> Result<Option<Spanned<T>>, D::Error> {
        Ok(Option::<Spanned<Table<T>>>::deserialize(d)?.map(unwrapped))
    }

    /// `[[key]]` entries (or `key = [{ ... }, ...]`).
    pub fn vec<'de, D: Deserializer<'de>, T: Deserialize<'de> + Keyed>(
        d: D,
    ) -> Result<Vec<Spanned<T>>, D::Error> {
        Ok(Vec::<Spanned<Table<T>>>::deserialize(d)?.into_iter().map(unwrapped).collect())
    }

    /// `[key.name]` tables by name.
    pub fn named<'de, D: Deserializer<'de>, T: Deserialize<'de> + Keyed>(
        d: D,
    ) -> Result<BTreeMap<Spanned<String>, Spanned<T>>, D::Error> {
        let tables = BTreeMap::<Spanned<String>, Spanned<Table<T>>>::deserialize(d)?;
        Ok(tables.into_iter().map(|(k, v)| (k, unwrapped(v))).collect())
    }
}
/// A spanned 3-vector.
pub type V3 = Spanned<Exact<f64, 3>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default, deserialize_with = "table::opt")]
    pub render: Option<Spanned<RenderDef>>,
    /// The camera; optional where `[[cameras]]` names some.
    #[serde(default, deserialize_with = "table::opt")]
    pub camera: Option<Spanned<CameraDef>>,
    /// Named cameras (`--camera NAME`); the first is the default where
    /// there is no `[camera]`.
    #[serde(default, deserialize_with = "table::vec")]
    pub cameras: Vec<Spanned<CameraDef>>,
    #[serde(default, deserialize_with = "table::vec")]
    pub lights: Vec<Spanned<LightDef>>,
    #[serde(default, deserialize_with = "table::opt")]
    pub fog: Option<Spanned<FogDef>>,
    #[serde(default, deserialize_with = "table::named")]
    pub materials: BTreeMap<Spanned<String>, Spanned<MaterialDef>>,
    #[serde(default, deserialize_with = "table::vec")]
    pub objects: Vec<Spanned<ObjectDef>>,
}

impl SceneFile {
    /// Parses the scene text `text` of `file_name` (used in messages).
    ///
    /// # Errors
    /// [`SceneError::Syntax`] at the place toml names.
    pub fn parse(text: &str, file_name: &Path) -> Result<Self, SceneError> {
        toml::from_str(text).map_err(|e| {
            // serde's own limit on nesting (a table header of a hundred
            // dotted keys) comes without a place: the deepest line is it.
            let span =
                e.span().or_else(|| (e.message().trim() == "recursion limit").then(|| deepest_line(text)));
            let location = match &span {
                Some(span) => Location::at_span(file_name, text, span),
                None => Location::file(file_name),
            };
            let entry = e.span().and_then(|s| crate::suggest::entry_at(text, s.start, e.message()));
            let mut message = if e.message().trim() == "recursion limit" {
                "tables nested too deep for the reader (recursion limit): a scene nests a few levels, \
                 such as [materials.NAME] or an object's transform steps"
                    .to_owned()
            } else {
                syntax_message(e.message(), entry)
            };
            if let Some(span) = e.span() {
                message = with_the_text(text, span.clone(), message);
                message.push_str(&unclosed_note(text, span.start, &message));
            }
            SceneError::Syntax { location, message }
        })
    }
}

/// The span of the line of `text` that nests deepest (a table header's
/// dotted keys, or the arrays and inline tables open on it), for an
/// error that comes without a place.
fn deepest_line(text: &str) -> std::ops::Range<usize> {
    let mut best = (0, 0..0);
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let body = line.split('#').next().unwrap_or("").trim();
        let marks = if body.starts_with('[') && !body.contains('=') {
            body.bytes().filter(|&b| b == b'.').count() + 1
        } else {
            // The deepest nesting of brackets and braces on the line.
            let mut depth = 0usize;
            let mut deepest = 0;
            for b in body.bytes() {
                match b {
                    b'[' | b'{' => {
                        depth += 1;
                        deepest = deepest.max(depth);
                    }
                    b']' | b'}' => depth = depth.saturating_sub(1),
                    _ => {}
                }
            }
            deepest
        };
        if marks > best.0 {
            best = (marks, start..start + line.trim_end().len());
        }
        start += line.len();
    }
    best.1
}

/// For a message about an unfinished array or inline table (toml reports
/// it where it gave up, often the next line), where that array or table
/// was opened, if on an earlier line: `; the array opened at line 2,
/// column 12 is not closed`. Otherwise nothing.
fn unclosed_note(text: &str, offset: usize, message: &str) -> String {
    let what = if message.starts_with("missing comma between array elements") {
        "array"
    } else if message.starts_with("missing comma between key-value pairs") {
        "inline table"
    } else {
        return String::new();
    };
    let Some(open) = innermost_open(text, offset) else { return String::new() };
    let (line, column) = crate::error::line_col(text, open);
    if line >= crate::error::line_col(text, offset).0 {
        return String::new();
    }
    format!("; the {what} opened at line {line}, column {column} is not closed")
}

/// toml's messages that say less than the text at their span shows:
/// - a value missing, or two values with no comma between them, which
///   toml reads as one unquoted string (`a = `, `[0, 1 2]`, `a = 1 2`):
///   it says "string values must be quoted";
/// - a duplicate key or table, which toml does not name.
///
/// Other messages are returned as they are.
fn with_the_text(text: &str, span: std::ops::Range<usize>, message: String) -> String {
    let Some(at) = text.get(span.clone()) else { return message };
    // toml 0.9 hands a date over as a table.
    let date = |s: &str| {
        let b = s.as_bytes();
        b.len() >= 8 && b[..4].iter().all(u8::is_ascii_digit) && b[4] == b'-'
            || b.len() >= 5 && b[..2].iter().all(u8::is_ascii_digit) && b[2] == b':'
    };
    if let Some(head) = message.strip_suffix("got a table")
        && date(at)
    {
        return format!("{head}got the date {at}");
    }
    // Where a table is read field by field, a date is a table with one
    // odd key (`texture = 07:32:00`).
    if message.starts_with("unknown key `a date`") && date(at) {
        return format!("expected a table, got the date {}", at.trim());
    }
    // A transform step is a one-key table; serde's words for another count.
    // Steps are written inline (`transform = [{ scale = 2 }]`) or as
    // `[[objects.transform]]` tables, where toml points at the header.
    let in_transform = || {
        innermost_open(text, span.start).is_some_and(|o| {
            text[..o].trim_end().strip_suffix('=').is_some_and(|k| k.trim_end().ends_with("transform"))
        }) || at.starts_with("[[")
            && at.lines().next().is_some_and(|h| {
                // `[[ objects . transform ]]` too.
                h.split('#')
                    .next()
                    .unwrap_or(h)
                    .split_whitespace()
                    .collect::<String>()
                    .ends_with(".transform]]")
            })
    };
    // A step that is not a table at all: a number, a bare name, an array.
    if (message.starts_with("wanted string or table") || message.starts_with("expected newtype variant"))
        && in_transform()
    {
        return format!(
            "expected a transform step, a table of one key such as `{{ scale = 2 }}` or `{{ rotate_y = 30 }}`, got {}",
            value_words(at)
        );
    }
    if message.starts_with("wanted exactly 1 element") && in_transform() {
        let step = crate::check::joined(&TRANSFORM_STEPS, "or");
        return if message.ends_with("more than 1 element") {
            "a transform step takes one key; give each step its own table, in order: \
             `transform = [{ scale = 2 }, { translate = [0, 1, 0] }]`"
                .into()
        } else {
            format!("a transform step needs one key: {step}")
        };
    }
    // A name (`type`, `projection`, ...) given as a number, an array or
    // a table: toml says only "wanted string or table".
    if (message.starts_with("wanted string or table")
        || message.starts_with("wanted exactly 1 element")
        || message.starts_with("expected table, found"))
        && let Some(m) = name_wanted(text, span.clone(), at)
    {
        return m;
    }
    // `[objects]` written for `[[objects]]`, or `[[camera]]` for `[camera]`.
    let header = at.trim_start();
    for (name, list) in [
        ("objects", true),
        ("lights", true),
        ("cameras", true),
        ("camera", false),
        ("render", false),
        ("fog", false),
    ] {
        if list && message.starts_with("expected an array") && header.starts_with(&format!("[{name}]")) {
            return format!(
                "`{name}` is a list: write each entry under its own `[[{name}]]` header (double brackets), not `[{name}]`"
            );
        }
        if !list && message.ends_with("got an array") && header.starts_with(&format!("[[{name}]]")) {
            return format!("`{name}` is one table: write `[{name}]` (single brackets), not `[[{name}]]`");
        }
    }
    if message.starts_with("duplicate key") && !at.is_empty() {
        return format!("duplicate key `{at}`: it is already defined above");
    }
    let quoted = message.starts_with("string values must be quoted");
    // toml points a bad float at its first odd character (`45deg` at the
    // `d`): the number before it is read too.
    let number_start = text[..span.start]
        .rfind(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | '_')))
        .map_or(0, |i| i + 1);
    let from_number = if quoted { at } else { text.get(number_start..).unwrap_or(at) };
    if (quoted || message.starts_with("invalid float") || message.starts_with("invalid integer"))
        && let Some(m) = number_with_unit(from_number.trim())
    {
        return m;
    }
    if !quoted {
        return message;
    }
    let at = at.trim();
    if at.is_empty() {
        return "a value is missing here (a number, a \"string\", true or false, an [array] or a { table })"
            .into();
    }
    let first = at.split_whitespace().next().unwrap_or(at);
    // A value by TOML's own rules (`1_000`, `0x10`, `inf`; not `Infinity`).
    let a_value = toml::from_str::<toml::Table>(&format!("v = {first}")).is_ok();
    if a_value && first.len() < at.len() {
        let wanted = match innermost_open(text, span.start).map(|o| text.as_bytes()[o]) {
            Some(b'[') => "`,` or `]`",
            Some(b'{') => "`,` or `}`",
            _ => "the end of the line",
        };
        return format!("expected {wanted} after `{first}`");
    }
    format!("`{at}` is not a value: a string must be quoted ({})", toml::Value::String(at.to_owned()))
}

/// For a number written with a unit (`45°`, `1m`, `30deg`), which toml
/// reads as an unquoted string or a bad float: "a number takes no unit".
fn number_with_unit(at: &str) -> Option<String> {
    let word = at.split(|c: char| c.is_whitespace() || matches!(c, ',' | ']' | '}' | '#')).next()?;
    let end = word.find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | '_' | 'e' | 'E')))?;
    let num = word[..end].trim_end_matches(['e', 'E']);
    let unit = &word[num.len()..];
    let value = toml::from_str::<toml::Table>(&format!("v = {num}")).ok()?;
    matches!(value.get("v"), Some(toml::Value::Integer(_) | toml::Value::Float(_)))
        .then(|| format!("`{word}` is not a value: a number takes no unit (`{unit}`); write `{num}`"))
}

/// For a name key (`type = 3`) whose value at `span` of `text` is not a
/// string: "`type` must be a string such as "sphere" (one of: sphere,
/// plane, ...), got the number 3". The names are those serde lists when
/// the value is replaced by an unknown name; `None` where the key or the
/// names cannot be found.
fn name_wanted(text: &str, span: std::ops::Range<usize>, at: &str) -> Option<String> {
    let before = text.get(..span.start)?.trim_end().strip_suffix('=')?.trim_end();
    let key_start =
        before.rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '-')).map_or(0, |i| i + 1);
    let key = &before[key_start..];
    if key.is_empty() {
        return None;
    }
    let probe = format!("{}\"?\"{}", &text[..span.start], text.get(span.end..)?);
    let err = toml::from_str::<SceneFile>(&probe).err()?;
    let names = err.message().strip_prefix("unknown variant `?`, expected ")?;
    let names = names.lines().next()?.trim();
    let names: Vec<&str> = names.split('`').skip(1).step_by(2).collect();
    let first = names.first()?;
    let got = value_words(at);
    Some(format!("`{key}` must be a string such as \"{first}\" (one of: {}), got {got}", names.join(", ")))
}

/// A value as written, in words for "got ...": "an array", "a table",
/// "true", "the number 3", "the string \"scale\"", or the text itself.
fn value_words(at: &str) -> String {
    let at = at.trim();
    match at.as_bytes().first() {
        Some(b'[') => return "an array".to_owned(),
        Some(b'{') => return "a table".to_owned(),
        _ => {}
    }
    match toml::from_str::<toml::Table>(&format!("v = {at}")).ok().and_then(|mut t| t.remove("v")) {
        Some(toml::Value::Boolean(b)) => b.to_string(),
        Some(toml::Value::Integer(_) | toml::Value::Float(_)) => format!("the number {at}"),
        Some(toml::Value::String(_)) => format!("the string {at}"),
        Some(toml::Value::Datetime(_)) => format!("the date {at}"),
        _ => format!("`{at}`"),
    }
}

/// toml's messages, made to say what was expected in scene terms
/// (`entry`: the object or light the message is about, if any).
fn syntax_message(m: &str, entry: Option<crate::suggest::Entry>) -> String {
    let m = m.trim();
    if m.starts_with("missing field `camera`") {
        return "missing [camera] table (position and look_at are required)".into();
    }
    let m = m.replace("`$__toml_private_datetime`", "a date").replace("a spanned value", "a value");
    // toml puts what it expected on a line of its own; one line reads
    // better after `file:line:column:`.
    let m = m.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(": ");
    // toml 0.9 ends some messages with ", expected nothing" (`a = = 1`).
    let m = m.strip_suffix(", expected nothing").unwrap_or(&m);
    crate::suggest::friendly(m, entry)
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RenderDef {
    pub width: Option<Spanned<u64>>,
    pub height: Option<Spanned<u64>>,
    pub spp: Option<Spanned<u64>>,
    pub max_depth: Option<Spanned<u64>>,
    pub min_contribution: Option<Num>,
    pub background: Option<Spanned<BackgroundDef>>,
    pub ambient: Option<Spanned<Color>>,
    /// AOV pass names (`"depth"`, ..., `"all"`), checked with spans.
    pub aov: Option<Spanned<Vec<Spanned<String>>>>,
    pub aov_preview: Option<bool>,
    /// Pixel filter name (`"box"`, `"gaussian"`, `"blackman-harris"`).
    pub filter: Option<Spanned<String>>,
    /// Adaptive supersampling threshold.
    pub adaptive: Option<Num>,
}

impl Keyed for RenderDef {
    const EXAMPLE: &'static str = "`{ width = 640, height = 360 }`";
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    pub position: V3,
    pub look_at: V3,
    pub up: Option<V3>,
    pub fov: Option<Num>,
    /// The name `--camera` chooses it by.
    pub name: Option<Spanned<String>>,
    /// Lens radius (0: pinhole).
    pub aperture: Option<Num>,
    /// Distance of the plane in focus (default: to `look_at`).
    pub focus_distance: Option<Num>,
    pub projection: Option<Spanned<ProjectionDef>>,
}

impl Keyed for CameraDef {
    const EXAMPLE: &'static str = "`{ position = [0, 2, 8], look_at = [0, 0, 0] }`";
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum ProjectionDef {
    Perspective,
    Orthographic,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug, Default)]
#[serde(rename_all = "snake_case")]
pub enum LightKindDef {
    #[default]
    Point,
    Spot,
    Directional,
    Quad,
    Disk,
    Sphere,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum FalloffDef {
    None,
    InverseSquare,
}

/// One light; which keys a `type` takes is checked in `light.rs`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    #[serde(rename = "type")]
    pub kind: Option<Spanned<LightKindDef>>,
    pub position: Option<V3>,
    pub color: Option<Spanned<Color>>,
    pub radiance: Option<Spanned<Color>>,
    pub intensity: Option<Num>,
    pub falloff: Option<Spanned<FalloffDef>>,
    pub direction: Option<V3>,
    pub inner_angle: Option<Num>,
    pub outer_angle: Option<Num>,
    pub corner: Option<V3>,
    pub edge_u: Option<V3>,
    pub edge_v: Option<V3>,
    pub center: Option<V3>,
    pub normal: Option<V3>,
    pub radius: Option<Num>,
    pub samples: Option<Spanned<u64>>,
    pub two_sided: Option<Spanned<bool>>,
    pub adaptive: Option<Spanned<bool>>,
}

impl Keyed for LightDef {
    const EXAMPLE: &'static str = "`{ position = [0, 5, 5], intensity = 1 }`";
}

/// `[render] background`: a colour, or an environment image
/// `{ image = "sky.hdr", rotation = 90 }`.
pub enum BackgroundDef {
    Color(Color),
    Image(EnvironmentDef),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDef {
    pub image: Spanned<String>,
    pub rotation: Option<Num>,
}

impl BackgroundDef {
    /// The environment image's path, if the background is one.
    pub fn image(&self) -> Option<&Spanned<String>> {
        match self {
            Self::Image(e) => Some(&e.image),
            Self::Color(_) => None,
        }
    }
}

impl<'de> Deserialize<'de> for BackgroundDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = BackgroundDef;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a colour ([r, g, b] or \"#rrggbb\") or an environment image { image = \"file\", rotation = degrees }",
                )
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<BackgroundDef, A::Error> {
                Color::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(BackgroundDef::Color)
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<BackgroundDef, E> {
                Color::deserialize(de::value::StrDeserializer::new(s)).map(BackgroundDef::Color)
            }
            fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<BackgroundDef, A::Error> {
                // toml hands a date over as a table with one private key: a
                // value of the wrong kind, not an environment with a bad key
                // (the message then names the date, `with_the_text`).
                EnvironmentDef::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(BackgroundDef::Image)
                    .map_err(|e| {
                        if e.to_string().contains("$__toml_private_datetime") {
                            de::Error::invalid_type(de::Unexpected::Map, &V)
                        } else {
                            e
                        }
                    })
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum FogModeDef {
    Linear,
    Exponential,
    ExponentialSquared,
}

/// `[fog] measure`: what linear fog's distance is.
#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum FogMeasureDef {
    Depth,
    Distance,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FogDef {
    pub mode: Option<Spanned<FogModeDef>>,
    pub measure: Option<Spanned<FogMeasureDef>>,
    pub start: Option<Num>,
    pub end: Option<Num>,
    pub density: Option<Num>,
    pub color: Option<Spanned<Color>>,
    pub enabled: Option<bool>,
}

impl Keyed for FogDef {
    const EXAMPLE: &'static str = "`{ mode = \"linear\", start = 5, end = 30 }`";
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    pub color: Option<Spanned<Color>>,
    #[serde(default, deserialize_with = "table::opt")]
    pub texture: Option<Spanned<TextureDef>>,
    pub ambient: Option<Num>,
    pub diffuse: Option<Num>,
    pub specular: Option<Num>,
    pub shininess: Option<Num>,
    pub specular_color: Option<Spanned<Color>>,
    pub reflectivity: Option<Num>,
    pub transparency: Option<Num>,
    pub transmission: Option<Num>,
    pub ior: Option<Num>,
    pub absorption: Option<Spanned<Color>>,
    pub filter_color: Option<Spanned<Color>>,
}

impl Keyed for MaterialDef {
    const EXAMPLE: &'static str = "`{ color = [0.8, 0.2, 0.2], reflectivity = 0.3 }`";
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum TextureKind {
    Checker,
    Image,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum SpaceDef {
    World,
    Uv,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum MappingDef {
    Uv,
    Spherical,
    Cylindrical,
    Planar,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum WrapDef {
    Repeat,
    Clamp,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDef {
    #[serde(rename = "type")]
    pub kind: Spanned<TextureKind>,
    // checker
    pub a: Option<Spanned<Color>>,
    pub b: Option<Spanned<Color>>,
    pub size: Option<Num>,
    pub space: Option<Spanned<SpaceDef>>,
    // image
    pub path: Option<Spanned<String>>,
    pub mapping: Option<Spanned<MappingDef>>,
    pub wrap: Option<Spanned<WrapDef>>,
    pub scale: Option<Spanned<Scale2>>,
    pub offset: Option<Spanned<Scale2>>,
    pub tint: Option<Spanned<Color>>,
}

impl Keyed for TextureDef {
    const EXAMPLE: &'static str = "`{ type = \"checker\", a = [1, 1, 1], b = [0, 0, 0] }`";
}

impl TextureDef {
    /// How an image texture wraps (`repeat` unless `wrap = "clamp"`).
    pub fn wrap(&self) -> Wrap {
        match self.wrap.as_ref().map(|w| *w.get_ref()) {
            Some(WrapDef::Clamp) => Wrap::Clamp,
            _ => Wrap::Repeat,
        }
    }
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum ObjectKind {
    Sphere,
    Plane,
    Cuboid,
    Cylinder,
    Cone,
    Disk,
    Triangle,
    Mesh,
}

impl ObjectKind {
    pub fn name(self) -> &'static str {
        match self {
            Self::Sphere => "sphere",
            Self::Plane => "plane",
            Self::Cuboid => "cuboid",
            Self::Cylinder => "cylinder",
            Self::Cone => "cone",
            Self::Disk => "disk",
            Self::Triangle => "triangle",
            Self::Mesh => "mesh",
        }
    }
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "snake_case")]
pub enum NormalsDef {
    Auto,
    Smooth,
    Flat,
}

/// One object. The shape fields are all optional here; which are required
/// or allowed depends on `type` and is checked after deserialising, with
/// spans.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDef {
    #[serde(rename = "type")]
    pub kind: Spanned<ObjectKind>,
    pub material: Option<Spanned<String>>,
    #[serde(default)]
    pub transform: Option<Spanned<Vec<Spanned<Step>>>>,
    /// A label for the user; not used by the renderer.
    #[allow(dead_code)]
    pub name: Option<Spanned<String>>,
    // shape fields
    pub center: Option<V3>,
    pub radius: Option<Num>,
    pub point: Option<V3>,
    pub normal: Option<V3>,
    pub min: Option<V3>,
    pub max: Option<V3>,
    pub size: Option<Spanned<Scale3>>,
    pub base: Option<V3>,
    pub height: Option<Num>,
    pub vertices: Option<Spanned<Exact<Point, 3>>>,
    pub path: Option<Spanned<String>>,
    pub normals: Option<Spanned<NormalsDef>>,
    pub crease_angle: Option<Num>,
}

impl Keyed for ObjectDef {
    const EXAMPLE: &'static str = "`{ type = \"sphere\", center = [0, 1, 0], radius = 1 }`";
}

impl ObjectDef {
    /// How a mesh's vertex normals are chosen (`auto` unless `normals` says).
    pub fn normal_mode(&self) -> NormalMode {
        match self.normals.as_ref().map(|n| *n.get_ref()) {
            None | Some(NormalsDef::Auto) => match &self.crease_angle {
                // Checked in range by the build; hundredths of a degree.
                Some(n) if n.get_ref().is_finite() => {
                    NormalMode::AutoCrease((n.get_ref().clamp(0.0, 180.0) * 100.0).round() as u32)
                }
                _ => NormalMode::Auto,
            },
            Some(NormalsDef::Smooth) => NormalMode::Smooth,
            Some(NormalsDef::Flat) => NormalMode::Flat,
        }
    }
}

/// One transform step, a table with a single key; the value keeps its
/// span, so that a step written as `[[objects.transform]]` is refused at
/// its value, not its header.
#[derive(Deserialize, Debug)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Step {
    Translate(Spanned<Exact<f64, 3>>),
    RotateX(Num),
    RotateY(Num),
    RotateZ(Num),
    Rotate(Spanned<AxisAngle>),
    Scale(Spanned<Scale3>),
    Shear(#[serde(deserialize_with = "table::one")] Spanned<ShearDef>),
    ShearAngle(#[serde(deserialize_with = "table::one")] Spanned<ShearDef>),
    Matrix(Spanned<Exact<Row, 4>>),
}

impl Step {
    /// Where the step's value is written.
    pub fn value_span(&self) -> std::ops::Range<usize> {
        match self {
            Self::Translate(v) => v.span(),
            Self::RotateX(v) | Self::RotateY(v) | Self::RotateZ(v) => v.span(),
            Self::Rotate(v) => v.span(),
            Self::Scale(v) => v.span(),
            Self::Shear(v) | Self::ShearAngle(v) => v.span(),
            Self::Matrix(v) => v.span(),
        }
    }
}

#[derive(Debug)]
pub struct AxisAngle {
    pub axis: Exact<f64, 3>,
    pub degrees: f64,
}

/// `rotate` as written: a table, explained when it is not one (such as
/// `rotate = [0, 30, 0]`).
impl<'de> Deserialize<'de> for AxisAngle {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Fields {
            axis: Exact<f64, 3>,
            degrees: f64,
        }
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = AxisAngle;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "`rotate = { axis = [x, y, z], degrees = D }` (a rotation about an axis; \
                     to turn about X, Y or Z use the steps `rotate_x = D`, `rotate_y = D`, `rotate_z = D`, \
                     e.g. `transform = [{ rotate_y = 30 }]`)",
                )
            }
            fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<AxisAngle, A::Error> {
                let f = Fields::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(AxisAngle { axis: f.axis, degrees: f.degrees })
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct ShearDef {
    #[serde(default)]
    pub xy: f64,
    #[serde(default)]
    pub xz: f64,
    #[serde(default)]
    pub yx: f64,
    #[serde(default)]
    pub yz: f64,
    #[serde(default)]
    pub zx: f64,
    #[serde(default)]
    pub zy: f64,
}

impl Keyed for ShearDef {
    const EXAMPLE: &'static str = "`{ xy = 0.5 }` (keys xy, xz, yx, yz, zx, zy)";
}

/// A colour: `[r, g, b]` (linear) or `"#rrggbb"` (sRGB, decoded to linear).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Color(pub [f64; 3]);

impl<'de> Deserialize<'de> for Color {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Color;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a colour: an array [r, g, b] of linear values or a \"#rrggbb\" sRGB string")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Color, A::Error> {
                Ok(Color(seq_n(seq, &self)?))
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Color, E> {
                parse_hex(s).map(Color).ok_or_else(|| E::invalid_value(de::Unexpected::Str(s), &self))
            }
        }
        d.deserialize_any(V)
    }
}

fn parse_hex(s: &str) -> Option<[f64; 3]> {
    let hex = s.strip_prefix('#')?;
    if hex.len() != 6 || !hex.is_ascii() {
        return None;
    }
    let mut out = [0.0; 3];
    for (i, c) in out.iter_mut().enumerate() {
        let byte = u8::from_str_radix(hex.get(2 * i..2 * i + 2)?, 16).ok()?;
        *c = f64::from(prism_shade::srgb8_to_linear(byte));
    }
    Some(out)
}

/// Exactly `N` numbers from `seq`.
fn seq_n<'de, A: SeqAccess<'de>, const N: usize>(
    seq: A,
    exp: &dyn de::Expected,
) -> Result<[f64; N], A::Error> {
    exactly(seq, exp)
}

/// Exactly `N` items from `seq`: fewer or more are refused, the message
/// counting every value given (serde's arrays, and toml, drop the values
/// past the `N`th without a word).
fn exactly<'de, A: SeqAccess<'de>, T: Deserialize<'de>, const N: usize>(
    mut seq: A,
    exp: &dyn de::Expected,
) -> Result<[T; N], A::Error> {
    let mut out: Vec<T> = Vec::with_capacity(N);
    while out.len() < N {
        match seq.next_element()? {
            Some(v) => out.push(v),
            None => return Err(de::Error::invalid_length(out.len(), exp)),
        }
    }
    let mut extra = 0;
    while seq.next_element::<de::IgnoredAny>()?.is_some() {
        extra += 1;
    }
    if extra > 0 {
        return Err(de::Error::invalid_length(N + extra, exp));
    }
    out.try_into().map_err(|_| de::Error::invalid_length(N, exp))
}

/// What an array's items are, in messages: "an array of 3 {numbers}".
pub trait Item {
    /// The items, plural.
    const MANY: &'static str;
}

impl Item for f64 {
    const MANY: &'static str = "numbers";
}

/// Exactly `N` items, `[a, b, c]`: an array of another length is refused
/// at its place, longer as well as shorter.
#[derive(Clone, Copy, PartialEq)]
pub struct Exact<T, const N: usize>(pub [T; N]);

impl<T, const N: usize> std::ops::Deref for Exact<T, N> {
    type Target = [T; N];
    fn deref(&self) -> &[T; N] {
        &self.0
    }
}

impl<T: fmt::Debug, const N: usize> fmt::Debug for Exact<T, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl<'de, T: Deserialize<'de> + Item, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Item, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "an array of {N} {}", T::MANY)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Exact<T, N>, A::Error> {
                exactly(seq, &self).map(Exact)
            }
        }
        d.deserialize_seq(V::<T, N>(std::marker::PhantomData))
    }
}

/// A triangle's vertex, `[x, y, z]`.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Point(pub [f64; 3]);

impl Item for Point {
    const MANY: &'static str = "points [x, y, z]";
}

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Exact::<f64, 3>::deserialize(d).map(|e| Point(e.0))
    }
}

/// A matrix row, `[a, b, c, d]`.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Row(pub [f64; 4]);

impl Item for Row {
    const MANY: &'static str = "rows [a, b, c, d]";
}

impl<'de> Deserialize<'de> for Row {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Exact::<f64, 4>::deserialize(d).map(|e| Row(e.0))
    }
}

/// A number (the same on every axis) or an array of `N` numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Uniform<const N: usize>(pub [f64; N]);

/// A number (uniform) or `[x, y, z]`.
pub type Scale3 = Uniform<3>;
/// A number (uniform) or `[u, v]`.
pub type Scale2 = Uniform<2>;

impl<'de, const N: usize> Deserialize<'de> for Uniform<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = Uniform<N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let names = if N == 2 { "[u, v]" } else { "[x, y, z]" };
                write!(f, "a number or an array {names} of numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Uniform<N>, A::Error> {
                Ok(Uniform(seq_n(seq, &self)?))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Uniform<N>, E> {
                Ok(Uniform([v; N]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Uniform<N>, E> {
                Ok(Uniform([v as f64; N]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Uniform<N>, E> {
                Ok(Uniform([v as f64; N]))
            }
        }
        d.deserialize_any(V::<N>)
    }
}
