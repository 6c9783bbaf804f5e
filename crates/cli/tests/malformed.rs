//! The malformed-input table: every class of bad scene, mesh, texture and
//! option, each with the exit status and the words it must produce. Each
//! case runs in a fresh directory with `prism render s.toml -o out/img.png`
//! (plus its own flags) and must fail with that status, print one `error: `
//! naming the file and the place (`file:line:column` where the problem is
//! inside a file), print no panic text, and create nothing (not even `out/`).
//! Cases about the scene also go through `prism info`.

mod common;

use common::{GOOD, assert_clean_failure, line_of, listing, png_bytes, prism, text};
use std::fs;

/// One malformed input.
struct Case {
    name: &'static str,
    /// The scene file's bytes (`s.toml`).
    scene: Vec<u8>,
    /// Other files next to it.
    files: Vec<(&'static str, Vec<u8>)>,
    /// Directories next to it.
    dirs: Vec<&'static str>,
    /// Extra flags for `prism render`.
    flags: Vec<&'static str>,
    /// The scene argument (default `s.toml`).
    scene_arg: &'static str,
    /// Expected exit status.
    code: i32,
    /// Text naming the place, e.g. `s.toml:12:10`.
    place: String,
    /// Words the message must contain.
    words: String,
}

impl Case {
    fn new(
        name: &'static str,
        scene: impl Into<Vec<u8>>,
        place: impl Into<String>,
        words: impl Into<String>,
    ) -> Self {
        Self {
            name,
            scene: scene.into(),
            files: Vec::new(),
            dirs: Vec::new(),
            flags: Vec::new(),
            scene_arg: "s.toml",
            code: 1,
            place: place.into(),
            words: words.into(),
        }
    }
    fn file(mut self, name: &'static str, bytes: impl Into<Vec<u8>>) -> Self {
        self.files.push((name, bytes.into()));
        self
    }
    fn dir(mut self, name: &'static str) -> Self {
        self.dirs.push(name);
        self
    }
    fn flags(mut self, flags: &[&'static str]) -> Self {
        self.flags.extend_from_slice(flags);
        self
    }
    fn code(mut self, code: i32) -> Self {
        self.code = code;
        self
    }
    fn arg(mut self, scene: &'static str) -> Self {
        self.scene_arg = scene;
        self
    }
}

/// `s.toml:LINE:COL` of byte `offset` of `scene`.
fn place(scene: &str, offset: usize) -> String {
    let before = &scene[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("s.toml:{line}:{col}")
}

/// The place of the first occurrence of `needle` in `scene`.
fn at(scene: &str, needle: &str) -> String {
    place(scene, scene.find(needle).unwrap_or_else(|| panic!("{needle:?} not in the scene")))
}

/// The place just after the first occurrence of `prefix` (a value after its key).
fn after(scene: &str, prefix: &str) -> String {
    place(scene, scene.find(prefix).unwrap_or_else(|| panic!("{prefix:?} not in the scene")) + prefix.len())
}

/// The place of the last `[[objects]]` header (errors about a whole object).
fn last_objects(scene: &str) -> String {
    place(scene, scene.rfind("[[objects]]").unwrap_or(0))
}

/// `s.toml:LINE:` of the first line containing `needle` (column not fixed).
fn on(scene: &str, needle: &str) -> String {
    format!("s.toml:{}:", line_of(scene, needle))
}

fn with(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "{from}");
    GOOD.replace(from, to)
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

fn cases() -> Vec<Case> {
    let mesh = |extra: &str| format!("{GOOD}[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\n{extra}");
    let textured = |path: &str| {
        with("color = [0.8, 0.1, 0.1]", &format!("texture = {{ type = \"image\", path = \"{path}\" }}"))
    };
    let obj_case = |name, obj: &[u8], place: &str, words: &str| {
        let s = mesh("");
        Case::new(name, s.clone(), place.replace("@", &on(&s, "m.obj")), words).file("m.obj", obj.to_vec())
    };
    let mut v = Vec::new();

    // TOML syntax errors.
    let s = with("radius = 1", "radius = = 1");
    v.push(Case::new("toml: value missing", s.clone(), after(&s, "radius = "), "extra `=`"));
    let s = with("material = \"red\"", "material = \"red");
    v.push(Case::new("toml: unterminated string", s.clone(), on(&s, "material = \"red"), "string"));
    let s = with("radius = 1", "radius = 1\nradius = 2");
    v.push(Case::new("toml: duplicate key", s.clone(), on(&s, "radius = 2"), "duplicate key"));
    let s = with("[render]", "[render");
    v.push(Case::new("toml: unclosed table header", s.clone(), "s.toml:1:", "expected"));
    // toml gives up on the next line; the message says where the array began.
    let s = with("center = [0, 1, 0]", "center = [0, 1, 0");
    let (line, column) = (line_of(&s, "center = [0, 1, 0"), "center = [".len());
    let opened = format!(
        "missing comma between array elements, expected `,`; the array opened at line {line}, column {column} is not closed"
    );
    v.push(Case::new("toml: unclosed array", s.clone(), format!("s.toml:{}:", line + 1), opened));

    // Wrong types.
    let s = with("radius = 1", "radius = \"one\"");
    v.push(Case::new(
        "type: string for a number",
        s.clone(),
        at(&s, "\"one\""),
        "expected a number, got the string \"one\"",
    ));
    let s = with("width = 32", "width = -32");
    v.push(Case::new(
        "type: negative width",
        s.clone(),
        at(&s, "-32"),
        "expected a whole number (0 or more), got the number -32",
    ));
    let s = with("spp = 1", "spp = 1.5");
    v.push(Case::new("type: fractional spp", s.clone(), at(&s, "1.5"), "expected a whole number"));
    let s = with("center = [0, 1, 0]", "center = [0, 1]");
    v.push(Case::new(
        "type: two numbers for a point",
        s.clone(),
        at(&s, "[0, 1]"),
        "expected an array of 3 numbers, got 2 values",
    ));
    let s = with("type = \"sphere\"", "type = \"torus\"");
    v.push(Case::new("type: unknown object type", s.clone(), at(&s, "\"torus\""), "unknown name `torus`"));

    // Unknown keys.
    let s = with("radius = 1", "radius = 1\nradios = 2");
    v.push(Case::new("unknown key in an object", s.clone(), at(&s, "radios"), "unknown key `radios` in a sphere; did you mean `radius`? (a sphere takes: center, radius, plus type, material, transform, name)"));
    let s = format!("{GOOD}[rendr]\nwidth = 3\n");
    v.push(Case::new(
        "unknown table",
        s.clone(),
        at(&s, "rendr"),
        "unknown key `rendr`; did you mean `render`?",
    ));
    let s = with("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nfov_deg = 40");
    v.push(Case::new(
        "unknown camera key",
        s.clone(),
        at(&s, "fov_deg"),
        "unknown key `fov_deg`; did you mean `fov`?",
    ));

    // Messages in scene terms, with suggestions (issue 15).
    let s = with("width = 32", "width = 640.0");
    v.push(Case::new(
        "type: fractional width",
        s.clone(),
        at(&s, "640.0"),
        "expected a whole number (0 or more), got the number 640.0",
    ));
    let s = with("radius = 1", "radius = \"1\"");
    v.push(Case::new(
        "type: quoted number",
        s.clone(),
        at(&s, "\"1\""),
        "expected a number, got the string \"1\"",
    ));
    let s = format!("{GOOD}[[objects]]\ntype = \"cylinder\"\nradius = 1\nhieght = 2\n");
    v.push(Case::new(
        "misspelt cylinder key",
        s.clone(),
        at(&s, "hieght"),
        "did you mean `height`? (a cylinder takes: base, radius, height, plus",
    ));
    let s = with("[camera]", "[camra]");
    v.push(Case::new(
        "misspelt table",
        s.clone(),
        at(&s, "camra"),
        "unknown key `camra`; did you mean `camera`?",
    ));
    let s = with("radius = 1", "radius = 1\ntransform = [{ rotate = [0, 30, 0] }]");
    v.push(Case::new(
        "rotate with three angles",
        s.clone(),
        at(&s, "[0, 30, 0]"),
        "`rotate = { axis = [x, y, z], degrees = D }`",
    ));
    let s = with("radius = 1", "radius = 1\ntransform = [{ rotate_y = \"30\" }]");
    v.push(Case::new("quoted rotation angle", s.clone(), at(&s, "\"30\""), "expected a number"));

    // Missing required keys.
    let s = with("radius = 1\n", "");
    v.push(Case::new("missing radius", s.clone(), last_objects(&s), "a sphere needs `radius`"));
    let s = with("look_at = [0, 1, 0]\n", "");
    v.push(Case::new("missing camera look_at", s.clone(), on(&s, "[camera]"), "missing key `look_at`"));
    let s = format!("{GOOD}[[objects]]\ntype = \"mesh\"\n");
    v.push(Case::new("mesh without path", s.clone(), last_objects(&s), "a mesh needs `path`"));
    v.push(Case::new("empty scene file", "", "s.toml", "missing [camera]"));

    // NaN and infinity.
    let s = with("radius = 1", "radius = nan");
    v.push(Case::new("nan radius", s.clone(), at(&s, "nan"), "finite"));
    let s = with("center = [0, 1, 0]", "center = [0, inf, 0]");
    v.push(Case::new("infinite centre", s.clone(), at(&s, "[0, inf, 0]"), "finite"));
    let s = with("position = [0, 1, 5]", "position = [0, -inf, 5]");
    v.push(Case::new("infinite camera position", s.clone(), at(&s, "[0, -inf, 5]"), "finite"));
    let s = with("position = [3, 5, 4]", "position = [3, 5, 4]\nintensity = nan");
    v.push(Case::new("nan light intensity", s.clone(), at(&s, "nan"), "finite"));

    // Zero and negative sizes.
    let s = with("radius = 1", "radius = -2");
    v.push(Case::new("negative radius", s.clone(), at(&s, "-2"), "greater than 0"));
    let s = with("radius = 1", "radius = 0");
    v.push(Case::new("zero radius", s.clone(), after(&s, "radius = "), "greater than 0"));
    let s = with("width = 32", "width = 0");
    v.push(Case::new("zero width", s.clone(), after(&s, "width = "), "at least 1 pixel"));
    let s = format!("{GOOD}[[objects]]\ntype = \"cylinder\"\nradius = 1\nheight = -1\n");
    v.push(Case::new("negative cylinder height", s.clone(), at(&s, "-1"), "greater than 0"));

    // Singular transforms.
    let s = with("radius = 1", "radius = 1\ntransform = [{ scale = [1, 0, 1] }]");
    v.push(Case::new("zero scale", s.clone(), at(&s, "[1, 0, 1]"), "singular"));
    let zero = "[[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]";
    let s = with("radius = 1", &format!("radius = 1\ntransform = [{{ matrix = {zero} }}]"));
    v.push(Case::new("singular matrix", s.clone(), at(&s, zero), "singular"));
    let s = with("radius = 1", "radius = 1\ntransform = [{ rotate = { axis = [0, 0, 0], degrees = 30 } }]");
    v.push(Case::new("rotation about a zero axis", s.clone(), at(&s, "{ axis"), "axis"));

    // Missing and broken files.
    let s = mesh("");
    v.push(Case::new("missing mesh", s.clone(), at(&s, "\"m.obj\""), "no such file"));
    let s = textured("none.png");
    v.push(Case::new("missing texture", s.clone(), at(&s, "\"none.png\""), "cannot read texture"));
    let s = textured("bad.png");
    v.push(
        Case::new("corrupt png", s.clone(), at(&s, "\"bad.png\""), "cannot use this texture")
            .file("bad.png", b"\x89PNG\r\n\x1a\ngarbage".to_vec()),
    );
    let s = with("spp = 1", "spp = 1\nbackground = { image = \"sky.png\" }");
    v.push(
        Case::new(
            "corrupt background image",
            s.clone(),
            at(&s, "\"sky.png\""),
            "cannot use this background image",
        )
        .file("sky.png", b"\x89PNG\r\n\x1a\ngarbage".to_vec()),
    );
    let png = png_bytes();
    let s = textured("half.png");
    v.push(
        Case::new(
            "truncated png",
            s.clone(),
            at(&s, "\"half.png\""),
            "cannot use this texture: the PNG data is cut short",
        )
        .file("half.png", png[..png.len() / 2].to_vec()),
    );
    let s = textured("notes.txt");
    v.push(
        Case::new("text file as a texture", s.clone(), at(&s, "\"notes.txt\""), "not a recognised image")
            .file("notes.txt", b"these are not pixels\n".to_vec()),
    );
    let s = textured("notes.png");
    v.push(
        Case::new("text file named .png", s.clone(), at(&s, "\"notes.png\""), "Invalid PNG signature")
            .file("notes.png", b"these are not pixels\n".to_vec()),
    );
    let s = textured("tex");
    v.push(Case::new("texture is a directory", s.clone(), at(&s, "\"tex\""), "directory").dir("tex"));
    let s = mesh("");
    v.push(Case::new("mesh is a directory", s.clone(), at(&s, "\"m.obj\""), "directory").dir("m.obj"));
    v.push(
        Case::new("scene is a directory", GOOD, "scene.toml", "directory")
            .dir("scene.toml")
            .arg("scene.toml"),
    );
    let s = mesh("");
    v.push(
        Case::new("missing material library", s.clone(), "m.obj", "cannot use material library")
            .file("m.obj", format!("mtllib none.mtl\nusemtl x\n{TRIANGLE}")),
    );
    let s = mesh("");
    v.push(
        Case::new("material library with a nan colour", s.clone(), "m.obj", "Kd")
            .file("m.obj", format!("mtllib m.mtl\nusemtl x\n{TRIANGLE}"))
            .file("m.mtl", "newmtl x\nKd nan 0 0\n"),
    );
    // A material library naming a missing texture is not malformed: it
    // loads with a warning and the material's colour (issue 12;
    // crates/scene/tests/obj_wild.rs).
    let s = mesh("");
    v.push(
        Case::new("material library colour of two numbers", s.clone(), "m.mtl:2", "`Kd` needs 3 numbers")
            .file("m.obj", format!("mtllib m.mtl\nusemtl x\n{TRIANGLE}"))
            .file("m.mtl", "newmtl x\nKd 0.75 0.975\n"),
    );
    #[cfg(unix)]
    {
        let s = textured("/dev/zero");
        v.push(Case::new("texture is a device", s.clone(), at(&s, "\"/dev/zero\""), "not a regular file"));
    }

    // OBJ files.
    v.push(obj_case(
        "obj: index out of range",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
        "m.obj:4",
        "out of range",
    ));
    v.push(obj_case("obj: zero index", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "m.obj:4", "index 0"));
    v.push(obj_case(
        "obj: negative index too far back",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n",
        "m.obj:4",
        "out of range",
    ));
    v.push(obj_case(
        "obj: texture index out of range",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
        "m.obj:5",
        "texture coordinate index 2",
    ));
    v.push(obj_case(
        "obj: two-corner face",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
        "m.obj:4",
        "at least 3 corners",
    ));
    v.push(obj_case("obj: lines only", b"v 0 0 0\nv 1 0 0\nl 1 2\n", "m.obj:3", "no faces"));
    v.push(obj_case("obj: points only", b"v 0 0 0\nv 1 0 0\np 1 2\n", "m.obj:3", "no faces"));
    v.push(obj_case("obj: empty file", b"", "m.obj:1", "no faces"));
    v.push(obj_case("obj: binary garbage", &[0, 159, 146, 150, 255, 0, 1], "m.obj", "m.obj:1: a NUL byte"));
    v.push(obj_case("obj: utf-16 text", &utf16("v 0 0 0\n"), "m.obj", "UTF-16"));
    v.push(obj_case("obj: nan vertex", b"v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "m.obj:1", "not finite"));
    v.push(obj_case("obj: word for a number", b"v 0 zero 0\n", "m.obj:1", "not a number"));

    // Whole scene files that are not text.
    v.push(Case::new(
        "scene: binary garbage",
        b"[render]\n\x00\x9f\x92\x96\xff".to_vec(),
        "s.toml:2:",
        "UTF-8",
    ));
    v.push(Case::new("scene: utf-16 text", utf16(GOOD), "s.toml", "UTF-16"));
    let zeros = [GOOD.as_bytes(), &[0; 4096]].concat();
    let past_the_text = format!("s.toml:{}:1:", GOOD.lines().count() + 1);
    v.push(Case::new("scene: zeros after the text", zeros, &past_the_text, "a NUL byte here"));

    // Absurd and zero numbers.
    let s = with("width = 32\nheight = 18", "width = 1000000\nheight = 1000000");
    v.push(Case::new("10^6 x 10^6 resolution", s.clone(), at(&s, "1000000"), "--max-side"));
    let s = with("width = 32\nheight = 18", "width = 16000\nheight = 16000");
    v.push(Case::new("too many pixels", s.clone(), at(&s, "16000"), "--max-pixels"));
    v.push(
        Case::new("10^6 x 10^6 from flags", GOOD, "--width", "--max-side")
            .flags(&["--width", "1000000", "--height", "1000000"]),
    );
    v.push(Case::new("10^12 pixels from flags", GOOD, "--width/--height", "--max-pixels").flags(&[
        "--width",
        "1000000",
        "--height",
        "1000000",
        "--max-side",
        "1000000",
    ]));
    let s = with("spp = 1", "spp = 0");
    v.push(Case::new("zero samples", s.clone(), after(&s, "spp = "), "at least 1"));
    let s = with("spp = 1", "spp = 1000000000");
    v.push(Case::new("10^9 samples", s.clone(), at(&s, "1000000000"), "--max-spp"));
    let s = with("spp = 1", "max_depth = 1000000000");
    v.push(Case::new("depth 10^9", s.clone(), at(&s, "1000000000"), "over the limit"));
    let s = with("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nup = [0, 0, -3]");
    v.push(Case::new("up parallel to the view", s.clone(), at(&s, "[0, 0, -3]"), "parallel"));
    let s = with("look_at = [0, 1, 0]", "look_at = [0, 1, 5]");
    v.push(Case::new("camera looks at itself", s.clone(), at(&s, "[camera]"), "look_at"));
    let s = with("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\nfov = 180");
    v.push(Case::new("fov of 180 degrees", s.clone(), at(&s, "180"), "between 0 and 180"));
    let s = format!("{GOOD}[fog]\nstart = 10\nend = 2\n");
    v.push(Case::new("fog ends before it starts", s.clone(), on(&s, "end = 2"), "greater than fog start"));
    let s = with("material = \"red\"", "material = \"blue\"");
    v.push(Case::new("unknown material", s.clone(), at(&s, "\"blue\""), "unknown material `blue`"));

    // Bad flags: the flag is the place.
    v.push(Case::new("flag: zero width", GOOD, "--width", "at least 1").flags(&["--width", "0"]));
    v.push(Case::new("flag: zero spp", GOOD, "--spp", "at least 1").flags(&["--spp", "0"]));
    v.push(
        Case::new("flag: depth 10^9", GOOD, "--max-depth", "over the limit")
            .flags(&["--max-depth", "1000000000"]),
    );
    v.push(
        Case::new("flag: not a number", GOOD, "--spp", "expected a whole number")
            .flags(&["--spp", "many"])
            .code(2),
    );
    v.push(Case::new("flag: unknown output format", GOOD, "x.jpg", ".png or .exr").flags(&["-o", "x.jpg"]));
    v.push(
        Case::new("flag: --set zero samples", GOOD, "--set: render.spp=0", "at least 1")
            .flags(&["--set", "render.spp=0"]),
    );
    v.push(
        Case::new("flag: --set misspelt key", GOOD, "--set: render.sp=2", "did you mean `spp`?")
            .flags(&["--set", "render.sp=2"]),
    );
    v.push(
        Case::new("flag: --view on a scene file", GOOD, "--view", "applies to an OBJ file")
            .flags(&["--view", "top"]),
    );
    v.push(
        Case::new("flag: --set without =", GOOD, "--set: spp", "expected KEY=VALUE").flags(&["--set", "spp"]),
    );
    v.push(
        Case::new("flag: misspelt --samples", GOOD, "--smaples", "--samples")
            .flags(&["--smaples", "3"])
            .code(2),
    );
    v.push(
        Case::new("missing scene file", GOOD, "none.toml: cannot read scene file: no such file", "none.toml")
            .arg("none.toml"),
    );
    v.push(
        Case::new("output under a file", GOOD, "s.toml/img.png", "s.toml is a file, not a directory")
            .flags(&["-o", "s.toml/img.png"]),
    );
    v.push(
        Case::new(
            "output under a file, deeper",
            GOOD,
            "s.toml/a/b/img.png",
            "s.toml is a file, not a directory",
        )
        .flags(&["-o", "s.toml/a/b/img.png"]),
    );
    v
}

fn utf16(s: &str) -> Vec<u8> {
    let mut out = vec![0xFF, 0xFE];
    for u in s.encode_utf16() {
        out.extend_from_slice(&u.to_le_bytes());
    }
    out
}

#[test]
fn every_malformed_input_fails_cleanly() {
    let cases = cases();
    assert!(cases.len() >= 40, "{} cases", cases.len());
    let mut failures = Vec::new();
    for case in &cases {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("s.toml"), &case.scene).unwrap();
        for (name, bytes) in &case.files {
            fs::write(dir.path().join(name), bytes).unwrap();
        }
        for d in &case.dirs {
            fs::create_dir(dir.path().join(d)).unwrap();
        }
        let before = listing(dir.path());
        let mut args = vec!["render", case.scene_arg];
        if !case.flags.contains(&"-o") {
            args.extend(["-o", "out/img.png"]);
        }
        args.extend(&case.flags);
        let out = prism(dir.path(), &args);
        let err = text(&out.stderr);
        let name = case.name;
        assert_clean_failure(name, &out);
        let mut problems = Vec::new();
        if out.status.code() != Some(case.code) {
            problems.push(format!("exit status {:?}, expected {}", out.status.code(), case.code));
        }
        if !err.starts_with("error: ") {
            problems.push("does not start with `error: `".into());
        }
        if !err.contains(&case.place) {
            problems.push(format!("does not name {}", case.place));
        }
        if !err.contains(&case.words) {
            problems.push(format!("lacks {:?}", case.words));
        }
        if listing(dir.path()) != before {
            problems.push("created a file or directory".into());
        }
        if case.flags.is_empty() {
            let info = prism(dir.path(), &["info", case.scene_arg]);
            assert_clean_failure(name, &info);
            if !text(&info.stderr).contains(&case.place) {
                problems.push(format!("info does not name {}: {}", case.place, text(&info.stderr)));
            }
        }
        if !problems.is_empty() {
            failures.push(format!("{name}: {}\n    {err}", problems.join("; ")));
        }
    }
    assert!(failures.is_empty(), "{} of {} cases:\n{}", failures.len(), cases.len(), failures.join("\n"));
}
