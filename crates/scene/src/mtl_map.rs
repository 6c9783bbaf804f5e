//! An MTL texture statement's value, such as `-s 2 2 1 -clamp on
//! wood.png` after `map_Kd`: its options, then the file name.
//!
//! The options are those of the MTL format's texture maps (Wavefront's
//! "MTL material format", Lewis Moore 1995): `-s u [v [w]]` scales the
//! texture coordinates, `-o u [v [w]]` offsets them (read at `uv * s + o`,
//! as three.js's loader and tinyobjloader read them), `-clamp on` clamps
//! them to the image instead of repeating it. prism applies these three
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
    /// cannot be told from the name), the value's last word.
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

/// How many words an option takes: an exact count, or 1 to 3 numbers.
#[derive(Clone, Copy)]
enum Takes {
    Words(usize),
    Numbers,
}

/// The options of MTL texture maps and what each takes.
fn takes(option: &str) -> Option<Takes> {
    Some(match option {
        "-blendu" | "-blendv" | "-cc" | "-clamp" | "-boost" | "-texres" | "-bm" | "-imfchan" | "-type" => {
            Takes::Words(1)
        }
        "-mm" => Takes::Words(2),
        "-s" | "-o" | "-t" => Takes::Numbers,
        _ => return None,
    })
}

/// Reads `value`, the text after an MTL texture statement's keyword
/// (anything from a `#` on is a comment, as prism reads every MTL line).
pub(crate) fn parse(value: &str) -> MapStatement<'_> {
    let value = value.split('#').next().unwrap_or("");
    let mut m =
        MapStatement { name: "", scale: Vec2::ONE, offset: Vec2::ZERO, clamp: false, ignored: Vec::new() };
    let mut rest = value.trim();
    while rest.starts_with('-') {
        let (option, after) = split_word(rest);
        let Some(kind) = takes(option) else {
            m.ignored.push(format!(
                "`{option}` (not an MTL texture option; the file name taken as the last word)"
            ));
            m.name = value.split_whitespace().last().unwrap_or("");
            return m;
        };
        let mut words = Vec::new();
        let mut after = after;
        match kind {
            Takes::Words(n) => {
                for _ in 0..n {
                    let (w, a) = split_word(after);
                    if w.is_empty() {
                        break;
                    }
                    words.push(w);
                    after = a;
                }
            }
            Takes::Numbers => {
                while words.len() < 3 {
                    let (w, a) = split_word(after);
                    if w.parse::<f32>().is_err() {
                        break;
                    }
                    words.push(w);
                    after = a;
                }
            }
        }
        apply(&mut m, option, &words);
        rest = after;
    }
    m.name = rest;
    m
}

/// Applies one option with its words to `m`, or notes it as ignored.
fn apply(m: &mut MapStatement<'_>, option: &str, words: &[&str]) {
    let written =
        if words.is_empty() { format!("`{option}`") } else { format!("`{option} {}`", words.join(" ")) };
    let numbers: Vec<f32> = words.iter().filter_map(|w| w.parse().ok()).collect();
    let uv = |default: f32| Vec2::new(numbers[0], numbers.get(1).copied().unwrap_or(default));
    match (option, words) {
        ("-s" | "-o", []) => m.ignored.push(format!("{written} (it needs 1 to 3 numbers)")),
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
        ("-clamp", ["off"]) | ("-blendu" | "-blendv", ["on"]) | ("-cc", ["off"]) => {}
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
        assert!(m.ignored[2].contains("needs 1 to 3 numbers"), "{:?}", m.ignored);
    }

    #[test]
    fn an_unknown_option_leaves_the_last_word_as_the_name() {
        let m = parse("-s 2 2 -halo 3 4 t.png");
        assert_eq!((m.scale, m.name), (Vec2::new(2.0, 2.0), "t.png"));
        assert!(m.ignored[0].contains("`-halo`"), "{:?}", m.ignored);
    }
}
