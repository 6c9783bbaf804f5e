//! An MTL texture statement's value, such as `-s 2 2 1 -clamp on
//! wood.png` after `map_Kd`: its options, then the file name.
//!
//! The options are those of the MTL format's texture maps (Wavefront's
//! "MTL material format", Lewis Moore 1995): `-s u [v [w]]` scales the
//! texture coordinates, `-o u [v [w]]` offsets them (read at `uv * s + o`
//! in the OBJ file's own coordinates, `v` up from the image's bottom, as
//! three.js's loader and Blender's importer read them; the material turns
//! that into prism's `v` down from the top), `-clamp on` clamps them to
//! the image's edge texels instead of repeating it. prism applies these three
//! (the third coordinate of a 2D image's `-s` and `-o` means nothing). The
//! others (`-blendu`, `-blendv`, `-boost`, `-mm`, `-t`, `-texres`, `-cc`,
//! `-bm`, `-imfchan`, `-type`) are read past and listed in
//! [`MapStatement::ignored`], so that the loader can say so, unless their
//! value is what prism does anyway (`-blendu on`, `-blendv on`, `-cc
//! off`).

use prism_geometry::glam::Vec2;

/// The parts of an MTL texture statement's value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MapStatement<'a> {
    /// The file name: the rest of the value after the options, spaces
    /// inside it kept. After an option prism does not know (its values
    /// cannot be told from the name), or where the options took every
    /// word, the value's last word.
    pub name: &'a str,
    /// `-s`: the texture coordinates' scale (1 where not given).
    pub scale: Vec2,
    /// `-o`: their offset, added after the scale (0 where not given).
    pub offset: Vec2,
    /// `-clamp on`.
    pub clamp: bool,
    /// Options given that prism does not apply, as written (`-mm 0.2 1`),
    /// and options with values it could not read (`-s` with no number, a
    /// scale of 0), each with what is wrong.
    pub ignored: Vec<String>,
}

/// What an option takes after it.
#[derive(Clone, Copy)]
enum Takes {
    /// One word of these.
    Word(&'static [&'static str]),
    /// Up to this many numbers (at least one).
    Numbers(usize),
}

/// The options of MTL texture maps and what each takes.
fn takes(option: &str) -> Option<Takes> {
    const ON_OFF: &[&str] = &["on", "off"];
    Some(match option {
        "-blendu" | "-blendv" | "-cc" | "-clamp" => Takes::Word(ON_OFF),
        "-imfchan" => Takes::Word(&["r", "g", "b", "m", "l", "z"]),
        "-type" => Takes::Word(&[
            "sphere",
            "cube_top",
            "cube_bottom",
            "cube_front",
            "cube_back",
            "cube_left",
            "cube_right",
        ]),
        "-boost" | "-texres" | "-bm" => Takes::Numbers(1),
        "-mm" => Takes::Numbers(2),
        "-s" | "-o" | "-t" => Takes::Numbers(3),
        _ => return None,
    })
}

/// Reads `value`, the text after an MTL texture statement's keyword. A
/// `#` at its start or after a space begins a comment, as on every MTL
/// line prism reads; one inside a word (`tex#1.png`) is part of it.
pub(crate) fn parse(value: &str) -> MapStatement<'_> {
    let value = match value.find('#') {
        Some(0) => "",
        _ => value
            .match_indices('#')
            .find(|&(i, _)| value[..i].ends_with(char::is_whitespace))
            .map_or(value, |(i, _)| &value[..i]),
    };
    let mut m =
        MapStatement { name: "", scale: Vec2::ONE, offset: Vec2::ZERO, clamp: false, ignored: Vec::new() };
    let last_word = || value.split_whitespace().last().unwrap_or("");
    let mut rest = value.trim();
    while rest.starts_with('-') {
        let (option, mut after) = split_word(rest);
        let Some(kind) = takes(option) else {
            m.ignored.push(format!(
                "`{option}` (not an MTL texture option; the file name taken as the last word)"
            ));
            m.name = last_word();
            return m;
        };
        let mut words = Vec::new();
        let (max, fits): (usize, &dyn Fn(&str) -> bool) = match kind {
            Takes::Word(allowed) => (1, &|w: &str| allowed.contains(&w)),
            Takes::Numbers(n) => (n, &|w: &str| w.parse::<f32>().is_ok()),
        };
        while words.len() < max {
            let (w, a) = split_word(after);
            if w.is_empty() || !fits(w) {
                break;
            }
            words.push(w);
            after = a;
        }
        apply(&mut m, option, &words);
        rest = after;
    }
    m.name = rest;
    if m.name.is_empty() {
        // The options took every word (`-s 1 1 1.5`, a name that reads
        // as a number): the last word is the best guess at the name.
        m.name = last_word();
        m.ignored.push(format!("no file name after the options; `{}` taken as the name", m.name));
    }
    m
}

/// Applies one option with its words to `m`, or notes it as ignored.
fn apply(m: &mut MapStatement<'_>, option: &str, words: &[&str]) {
    let written =
        if words.is_empty() { format!("`{option}`") } else { format!("`{option} {}`", words.join(" ")) };
    let numbers: Vec<f32> = words.iter().filter_map(|w| w.parse().ok()).collect();
    let uv = |default: f32| match numbers[..] {
        [u] => Vec2::new(u, default),
        [u, v, ..] => Vec2::new(u, v),
        [] => Vec2::splat(default),
    };
    match (option, words) {
        (_, []) => m.ignored.push(format!("{written} (its value is missing)")),
        ("-s", _) => {
            let s = uv(1.0);
            if s.is_finite() && s.cmpne(Vec2::ZERO).all() {
                m.scale = s;
            } else {
                m.ignored.push(format!("{written} (a scale must be finite and not 0)"));
            }
        }
        ("-o", _) => {
            let o = uv(0.0);
            if o.is_finite() {
                m.offset = o;
            } else {
                m.ignored.push(format!("{written} (an offset must be finite)"));
            }
        }
        ("-clamp", ["on"]) => m.clamp = true,
        ("-clamp", ["off"]) => m.clamp = false,
        ("-blendu" | "-blendv", ["on"]) | ("-cc", ["off"]) => {}
        _ => m.ignored.push(written),
    }
}

/// The first word of `s` and the rest after the spaces that follow it.
fn split_word(s: &str) -> (&str, &str) {
    let s = s.trim_start();
    let end = s.find(char::is_whitespace).unwrap_or(s.len());
    (&s[..end], s[end..].trim_start())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_name_is_the_whole_value() {
        let m = parse("  my texture.png ");
        assert_eq!(m.name, "my texture.png");
        assert_eq!((m.scale, m.offset, m.clamp), (Vec2::ONE, Vec2::ZERO, false));
        assert!(m.ignored.is_empty());
    }

    #[test]
    fn a_comment_is_not_part_of_the_name() {
        assert_eq!(parse("-s 2 2 wood.png  # the floor").name, "wood.png");
        assert_eq!(parse("# only a comment").name, "");
        assert_eq!(parse("tex#1.png").name, "tex#1.png");
    }

    #[test]
    fn scale_offset_and_clamp_are_read_before_the_name() {
        let m = parse("-s 2 4 1 -o 0.5 0.25 0 -clamp on wood grain.png");
        assert_eq!(m.name, "wood grain.png");
        assert_eq!(m.scale, Vec2::new(2.0, 4.0));
        assert_eq!(m.offset, Vec2::new(0.5, 0.25));
        assert!(m.clamp);
        assert!(m.ignored.is_empty(), "{:?}", m.ignored);
    }

    /// `-s u` alone scales u (v keeps 1); `-o u` alone offsets u.
    #[test]
    fn missing_coordinates_take_the_defaults() {
        let m = parse("-s 3 -o 0.5 t.png");
        assert_eq!((m.scale, m.offset, m.name), (Vec2::new(3.0, 1.0), Vec2::new(0.5, 0.0), "t.png"));
    }

    /// A name that reads as a number after `-s`'s three is the name.
    #[test]
    fn numbers_after_three_are_the_name() {
        let m = parse("-s 1 2 3 4.png");
        assert_eq!((m.scale, m.name), (Vec2::new(1.0, 2.0), "4.png"));
    }

    #[test]
    fn options_prism_does_not_apply_are_listed() {
        let m =
            parse("-mm 0.1 0.9 -blendu on -cc off -t 0.1 0.1 -bm 2 -imfchan l -boost 2 -texres 512 t.png");
        assert_eq!(m.name, "t.png");
        assert_eq!(
            m.ignored,
            ["`-mm 0.1 0.9`", "`-t 0.1 0.1`", "`-bm 2`", "`-imfchan l`", "`-boost 2`", "`-texres 512`"]
        );
    }

    #[test]
    fn bad_values_are_listed_not_applied() {
        let m = parse("-s 0 1 -o nan -s t.png");
        assert_eq!((m.scale, m.offset, m.name), (Vec2::ONE, Vec2::ZERO, "t.png"));
        assert_eq!(m.ignored.len(), 3, "{:?}", m.ignored);
        assert!(m.ignored[0].contains("`-s 0 1`") && m.ignored[0].contains("not 0"), "{:?}", m.ignored);
        assert!(m.ignored[1].contains("`-o nan`"), "{:?}", m.ignored);
        assert!(m.ignored[2].contains("`-s` (its value is missing)"), "{:?}", m.ignored);
        // The last of a repeated option counts.
        assert!(!parse("-clamp on -clamp off t.png").clamp);
        assert_eq!(parse("-s 2 -s 3 t.png").scale, Vec2::new(3.0, 1.0));
    }

    /// An option short of values does not take the name: `-mm` wants two
    /// numbers, `-clamp` on or off.
    #[test]
    fn an_option_takes_only_values_of_its_kind() {
        let m = parse("-mm 0.2 labels.png");
        assert_eq!((m.name, m.ignored.as_slice()), ("labels.png", ["`-mm 0.2`".to_string()].as_slice()));
        let m = parse("-clamp labels.png");
        assert_eq!((m.name, m.clamp), ("labels.png", false));
        assert!(m.ignored[0].contains("`-clamp` (its value is missing)"), "{:?}", m.ignored);
        assert_eq!(parse("-imfchan l -type sphere t.png").name, "t.png");
    }

    /// Options that take every word leave the last word as the name.
    #[test]
    fn a_name_taken_as_an_option_value_is_the_last_word() {
        let m = parse("-s 1 1 2");
        assert_eq!((m.name, m.scale), ("2", Vec2::ONE));
        assert!(m.ignored[0].contains("no file name after the options"), "{:?}", m.ignored);
    }

    #[test]
    fn an_unknown_option_leaves_the_last_word_as_the_name() {
        let m = parse("-s 2 2 -halo 3 4 t.png");
        assert_eq!((m.scale, m.name), (Vec2::new(2.0, 2.0), "t.png"));
        assert!(m.ignored[0].contains("`-halo`"), "{:?}", m.ignored);
    }
}
