//! Messages in scene terms (issue 15): no Rust types, "did you mean …?"
//! with the keys of the shape at hand, the `rotate` form explained, and a
//! warning for colours that look like 8-bit values.

use super::*;

#[test]
fn messages_name_no_rust_types() {
    refused(&[
        (
            "[[objects]]\ntype = \"sphere\"\nradius = \"1\"\n",
            "expected a number, got the string \"1\"",
            Some("radius"),
        ),
        ("[[objects]]\ntype = \"sphere\"\nradius = true\n", "expected a number, got true", Some("radius")),
    ]);
    let err = parse(&BASE.replace("width = 320", "width = 640.0")).unwrap_err().to_string();
    assert!(err.contains("expected a whole number (0 or more), got the number 640.0"), "{err}");
    let err = parse(&BASE.replace("spp = 2", "spp = -1")).unwrap_err().to_string();
    assert!(err.contains("expected a whole number (0 or more), got the number -1"), "{err}");
    for err in [&err, &parse(&BASE.replace("width = 320", "width = 640.0")).unwrap_err().to_string()] {
        for rust in ["f64", "u64", "u32", "usize", "struct", "sequence"] {
            assert!(!err.contains(rust), "{err} names {rust}");
        }
    }
}

#[test]
fn a_misspelt_key_gets_a_suggestion_and_the_keys_of_its_shape() {
    let err = expect_err(
        "[[objects]]\ntype = \"cylinder\"\nradius = 1\nhieght = 2\n",
        "unknown key `hieght` in a cylinder; did you mean `height`?",
    );
    assert!(
        err.contains("a cylinder takes: base, radius, height, plus type, material, transform, name"),
        "{err}"
    );
    // Only the cylinder's keys, not every shape's.
    assert!(!err.contains("vertices") && !err.contains("normals"), "{err}");
    // No suggestion for a word that is nothing like a key.
    let err = expect_err(
        "[[objects]]\ntype = \"plane\"\nxyzzy = 1\n",
        "unknown key `xyzzy` in a plane (a plane takes: point, normal",
    );
    assert!(!err.contains("did you mean"), "{err}");
    // Other tables: the keys serde lists, from the struct itself.
    let err =
        parse(&BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nfvo = 3")).unwrap_err().to_string();
    assert!(err.contains("unknown key `fvo`; did you mean `fov`?"), "{err}");
    assert!(err.contains("expected one of: position, look_at, up, fov"), "{err}");
    expect_err("[[lights]]\nposition = [0, 1, 0]\nintensty = 2\n", "did you mean `intensity`?");
    expect_err("[[objects]]\ntype = \"spere\"\n", "unknown name `spere`; did you mean `sphere`?");
    expect_err(
        "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotatey = 3 }]\n",
        "did you mean `rotate_y`?",
    );
    // A texture's keys, listed by kind.
    expect_err(
        "[materials.m]\ntexture = { type = \"checker\", sise = 2 }\n",
        "unknown key `sise`; did you mean `size`? (a checker texture takes: type, a, b, size, space; \
         an image texture: type, path, mapping, wrap, scale, offset, tint)",
    );
    // Pass and filter names.
    let with =
        |line: &str| parse(&BASE.replace("spp = 2", &format!("spp = 2\n{line}"))).unwrap_err().to_string();
    assert!(with("aov = [\"depht\"]").contains("unknown AOV pass `depht`; did you mean `depth`?"));
    assert!(with("filter = \"gauss\"").contains("unknown pixel filter `gauss`; did you mean `gaussian`?"));
}

#[test]
fn rotate_with_three_angles_explains_the_form() {
    let extra = "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotate = [0, 30, 0] }]\n";
    let err = expect_err(extra, "`rotate = { axis = [x, y, z], degrees = D }`");
    assert!(err.contains("rotate_y = D") && !err.contains("length 3"), "{err}");
    assert_at(&err, extra, "rotate");
    // The table form still works, and still checks its keys.
    expect_err(
        "[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{ rotate = { axis = [0, 1, 0], degres = 3 } }]\n",
        "did you mean `degrees`?",
    );
    let ok = format!(
        "{BASE}[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{{ rotate = {{ axis = [0, 1, 0], degrees = 30 }} }}]\n"
    );
    parse(&ok).unwrap();
}

#[test]
fn colours_that_look_8_bit_warn_and_hex_is_offered() {
    let text = BASE.replace("color = [0.8, 0.1, 0.1]", "color = [255, 0, 0]");
    let loaded = parse(&text).unwrap();
    let line = text.lines().position(|l| l.contains("[255, 0, 0]")).unwrap() + 1;
    let w: Vec<&String> = loaded.warnings.iter().filter(|w| w.contains("8-bit")).collect();
    assert_eq!(w.len(), 1, "{:?}", loaded.warnings);
    assert!(w[0].starts_with(&format!("test.toml:{line}:9: color [255, 0, 0] looks like 8-bit")), "{}", w[0]);
    assert!(w[0].contains("colour components are 0–1 (or \"#ff0000\")"), "{}", w[0]);
    // The hex form it offers is accepted, and 0–1 colours (or HDR ones that are not whole numbers) say nothing.
    for c in ["\"#ff0000\"", "[1, 0, 0]", "[0.8, 0.1, 0.1]", "[2.5, 2.5, 2.5]"] {
        let loaded = parse(&BASE.replace("[0.8, 0.1, 0.1]", c)).unwrap();
        assert!(loaded.warnings.iter().all(|w| !w.contains("8-bit")), "{c}: {:?}", loaded.warnings);
    }
    // Small whole numbers are more likely meant as above 1 than as a
    // near-black 8-bit colour: the surface's "above 1" warning instead.
    let loaded = parse(&BASE.replace("[0.8, 0.1, 0.1]", "[0, 0, 2]")).unwrap();
    assert!(loaded.warnings.iter().all(|w| !w.contains("8-bit")), "{:?}", loaded.warnings);
    assert!(loaded.warnings.iter().any(|w| w.contains("is above 1")), "{:?}", loaded.warnings);
    let bg = BASE.replace("spp = 2", "spp = 2\nbackground = [128, 128, 128]");
    assert!(parse(&bg).unwrap().warnings.iter().any(|w| w.contains("background") && w.contains("#808080")));
    // Light colours (HDR radiance) and absorption coefficients are not reflectances: no warning.
    let hdr = BASE.replace("[[lights]]", "[[lights]]\ncolor = [20, 20, 20]");
    assert!(hdr.contains("color = [20, 20, 20]"));
    let loaded = parse(&hdr).unwrap();
    assert!(loaded.warnings.iter().all(|w| !w.contains("8-bit")), "{:?}", loaded.warnings);
    // But a light's colour with a 255, or channels that differ and one of
    // 100 or more, is almost surely 8-bit values (a white picture).
    for (c, hex) in
        [("[255, 200, 150]", "#ffc896"), ("[255, 255, 255]", "#ffffff"), ("[128, 64, 0]", "#804000")]
    {
        let text = BASE.replace("[[lights]]", &format!("[[lights]]\ncolor = {c}"));
        let w = parse(&text).unwrap().warnings;
        assert!(
            w.iter().any(|w| w.contains("light colour")
                && w.contains("looks like 8-bit values")
                && w.contains(hex)
                && w.contains("`intensity`")),
            "{c}: {w:?}"
        );
    }
    for c in ["[100, 100, 100]", "[99, 50, 0]", "[2.5, 200, 100]"] {
        let text = BASE.replace("[[lights]]", &format!("[[lights]]\ncolor = {c}"));
        let w = parse(&text).unwrap().warnings;
        assert!(w.iter().all(|w| !w.contains("8-bit")), "{c}: {w:?}");
    }
    let glass = BASE.replace("color = [0.8, 0.1, 0.1]", "color = [0.8, 0.1, 0.1]\nabsorption = [0, 2, 3]");
    assert!(glass.contains("absorption = [0, 2, 3]"));
    let loaded = parse(&glass).unwrap();
    assert!(loaded.warnings.iter().all(|w| !w.contains("8-bit")), "{:?}", loaded.warnings);
}

#[test]
fn surface_colours_above_1_warn_and_light_colours_do_not() {
    let above = |w: &String| w.contains("is above 1");
    let text = BASE.replace("color = [0.8, 0.1, 0.1]", "color = [1.5, 0, 0]");
    let line = text.lines().position(|l| l.contains("[1.5, 0, 0]")).unwrap() + 1;
    let w: Vec<String> = parse(&text).unwrap().warnings.into_iter().filter(above).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].starts_with(&format!("test.toml:{line}:9: color [1.5, 0, 0] is above 1")), "{}", w[0]);
    let checker = BASE.replace(
        "color = [0.8, 0.1, 0.1]",
        "texture = { type = \"checker\", a = [2, 2, 2.5], b = [0, 0, 0] }",
    );
    assert!(parse(&checker).unwrap().warnings.iter().any(|w| w.contains("checker colour a") && above(w)));
    // 0–1 colours, 8-bit-looking ones (their own warning), lights and the
    // background say nothing of it.
    for c in ["[1, 1, 1]", "[0.8, 0.1, 0.1]", "[255, 0, 0]"] {
        let loaded = parse(&BASE.replace("[0.8, 0.1, 0.1]", c)).unwrap();
        assert!(!loaded.warnings.iter().any(above), "{c}: {:?}", loaded.warnings);
    }
    let hdr = BASE
        .replace("[[lights]]", "[[lights]]\ncolor = [20, 20, 20]")
        .replace("spp = 2", "spp = 2\nbackground = [3, 3, 3.5]");
    assert!(!parse(&hdr).unwrap().warnings.iter().any(above));
}

#[test]
fn a_name_given_as_another_type_says_a_string_is_wanted() {
    let objects = "(one of: sphere, plane, cuboid, cylinder, cone, disk, triangle, mesh)";
    refused(&[
        (
            "[[objects]]\ntype = 3\n",
            &format!("`type` must be a string such as \"sphere\" {objects}, got the number 3"),
            Some("type = 3"),
        ),
        ("[[objects]]\ntype = true\n", "`type` must be a string such as \"sphere\"", Some("type = true")),
        ("[[objects]]\ntype = [1]\n", "got an array", Some("type = [1]")),
        ("[[objects]]\ntype = {}\n", "`type` must be a string such as \"sphere\"", Some("type = {}")),
        (
            "[[lights]]\ntype = 2\n",
            "`type` must be a string such as \"point\" (one of: point, spot, directional, quad, disk, sphere), got the number 2",
            Some("type = 2"),
        ),
        (
            "[materials.m]\ntexture = { type = 1 }\n",
            "`type` must be a string such as \"checker\" (one of: checker, image), got the number 1",
            Some("texture"),
        ),
    ]);
    let err = parse(&BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nprojection = 1")).unwrap_err();
    let err = err.to_string();
    assert!(
        err.contains("`projection` must be a string such as \"perspective\" (one of: perspective, orthographic), got the number 1"),
        "{err}"
    );
    assert!(!err.contains("wanted"), "{err}");
}

#[test]
fn glass_without_a_cut_off_at_a_high_depth_is_warned_about() {
    let glass = "[materials.glass]\ntransmission = 1\n[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"glass\"\n";
    let splits = |w: &String| w.contains("splits each ray in two");
    let with = |render: &str| {
        let text = format!("{BASE}{glass}").replace("spp = 2", &format!("spp = 2\n{render}"));
        parse(&text).unwrap().warnings
    };
    let w = with("min_contribution = 0\nmax_depth = 40");
    assert!(w.iter().any(|w| splits(w) && w.contains("up to 2^40 rays")), "{w:?}");
    // The default cut-off, a low depth, or no glass: nothing said.
    assert!(!with("max_depth = 40").iter().any(splits));
    assert!(!with("min_contribution = 0\nmax_depth = 12").iter().any(splits));
    let mirror = "[[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"red\"\n";
    let text = format!("{BASE}{mirror}").replace("spp = 2", "spp = 2\nmin_contribution = 0\nmax_depth = 40");
    assert!(!parse(&text).unwrap().warnings.iter().any(splits));
}

/// A table given as an array is refused where it stands, with an example
/// of the table: serde's derived structs would read the array field by
/// field and drop what is left over (fuzz finding 6).
#[test]
fn a_table_given_as_an_array_is_refused() {
    let camera = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let cases: &[(String, &str, &str)] = &[
        (
            "camera = [[0, 0, 5], [0, 0, 0], [0, 1, 0], 45, \"main\", 0, 1, \"perspective\", \"x\", 42]\n"
                .into(),
            "[[0, 0, 5]",
            "`{ position = [0, 2, 8], look_at = [0, 0, 0] }`",
        ),
        (
            "cameras = [[[0, 5, 0], [0, 0, 0], [0, 0, -1], 45, \"top\", 0, 1, \"orthographic\", 99]]\n"
                .into(),
            "[[0, 5, 0]",
            "`{ position = [0, 2, 8], look_at = [0, 0, 0] }`",
        ),
        (
            format!(
                "render = [64, 36, 1, 2, 0.001, [0, 0, 0], [1, 1, 1], [], false, \"box\", 0.1, \"x\"]\n{camera}"
            ),
            "[64",
            "`{ width = 640, height = 360 }`",
        ),
        (
            format!("lights = [[[0, 5, 5]]]\n{camera}"),
            "[[0, 5, 5]]]",
            "`{ position = [0, 5, 5], intensity = 1 }`",
        ),
        (format!("fog = [[]]\n{camera}"), "[[]]", "`{ mode = \"linear\", start = 5, end = 30 }`"),
        (
            format!("objects = [[\"sphere\", \"m\"]]\n{camera}"),
            "[\"sphere\"",
            "`{ type = \"sphere\", center = [0, 1, 0], radius = 1 }`",
        ),
        (
            format!("{camera}[materials]\nm = [[1, 0, 0], [0, 0, 0]]\n"),
            "[[1, 0, 0]",
            "`{ color = [0.8, 0.2, 0.2], reflectivity = 0.3 }`",
        ),
        (
            format!("{camera}[materials.m]\ntexture = [\"checker\", [1, 1, 1]]\n"),
            "[\"checker\"",
            "`{ type = \"checker\", a = [1, 1, 1], b = [0, 0, 0] }`",
        ),
        (
            format!(
                "{camera}[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{{ shear = [1, 2, 3, 4, 5, 6, 7] }}]\n"
            ),
            "[1, 2, 3, 4",
            "`{ xy = 0.5 }` (keys xy, xz, yx, yz, zx, zy)",
        ),
        (
            format!(
                "{camera}[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{{ shear_angle = [89] }}]\n"
            ),
            "[89]",
            "`{ xy = 0.5 }` (keys xy, xz, yx, yz, zx, zy)",
        ),
    ];
    for (text, at, example) in cases {
        let err = parse(text).err().unwrap_or_else(|| panic!("accepted:\n{text}")).to_string();
        let offset = text.find(at).unwrap_or_else(|| panic!("{at:?} in {text:?}"));
        let (line, column) = crate::error::line_col(text, offset);
        assert_eq!(
            err,
            format!(
                "test.toml:{line}:{column}: expected a table of named keys such as {example}, got an array"
            ),
            "{text}"
        );
    }
    // The same tables written as tables are read.
    let shear = format!(
        "{camera}[[objects]]\ntype = \"sphere\"\nradius = 1\ntransform = [{{ shear = {{ xy = 0.5 }} }}]\n"
    );
    assert!(parse(&shear).is_ok());
}

/// A transform step that is not a one-key table, and a texture given as
/// a date, are described in scene terms (fuzz finding 9).
#[test]
fn a_step_that_is_not_a_table_is_named_in_scene_terms() {
    let step =
        "expected a transform step, a table of one key such as `{ scale = 2 }` or `{ rotate_y = 30 }`, got";
    refused(&[
        ("[[objects]]\ntype = \"sphere\"\ntransform = [2]\n", &format!("{step} the number 2"), Some("2]")),
        ("[[objects]]\ntype = \"sphere\"\ntransform = [true]\n", &format!("{step} true"), Some("true")),
        ("[[objects]]\ntype = \"sphere\"\ntransform = [[2]]\n", &format!("{step} an array"), Some("[2]]")),
        (
            "[[objects]]\ntype = \"sphere\"\ntransform = [\"scale\"]\n",
            &format!("{step} the string \"scale\""),
            Some("\"scale\""),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\ntransform = [{ rotate = { axis = [0, 1, 0] } }]\n",
            "missing key `degrees`",
            Some("{ axis"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\n[[objects.transform]]\nscale = 2\ntranslate = [0, 1, 0]\n",
            "a transform step takes one key; give each step its own table",
            Some("[[objects.transform]]"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\n[[objects.transform]]\n",
            "a transform step needs one key: translate, rotate_x",
            Some("[[objects.transform]]"),
        ),
        (
            "[[objects]]\ntype = \"sphere\"\n[[ objects . transform ]] # a step\nscale = 2\ntranslate = [0, 1, 0]\n",
            "a transform step takes one key; give each step its own table",
            Some("[[ objects . transform ]]"),
        ),
        (
            "[materials.m]\ntexture = 1979-05-27T07:32:00Z\n",
            "expected a table, got the date 1979-05-27T07:32:00Z",
            Some("1979"),
        ),
    ]);
    // Materials are a table of named tables, not an array of them.
    let text = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[materials]]\ncolor = [1, 0, 0]\n";
    let err = parse(text).err().map(|e| e.to_string()).unwrap_or_default();
    assert_eq!(err, "test.toml:4:1: expected a table, got an array", "{err}");
}

/// A background is a colour or a table: a date (which toml hands over as a
/// table with one private key) is named as neither, not as an environment
/// image with an odd key.
#[test]
fn a_date_as_background_is_a_value_of_the_wrong_kind() {
    let expected = "expected a colour ([r, g, b] or \"#rrggbb\") or an environment image { image = \"file\", rotation = degrees }";
    for date in ["1979-05-27", "07:32:00", "1979-05-27T07:32:00Z"] {
        let text =
            format!("[render]\nbackground = {date}\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n");
        let err = parse(&text).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(err, format!("test.toml:2:14: {expected}, got the date {date}"));
    }
    // An environment table with a misspelt key still says so.
    let text = "[render]\nbackground = { image = \"sky.hdr\", rotaton = 3 }\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let err = parse(text).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("unknown key `rotaton`; did you mean `rotation`?"), "{err}");
}
