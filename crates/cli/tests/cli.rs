//! Runs the `prism` binary: good scenes render; bad options fail cleanly;
//! writes are atomic; inputs are never overwritten. (Malformed inputs:
//! tests/malformed.rs; signals and determinism: tests/safety.rs.)

mod common;

use common::{GOOD, listing, prism, text};
use std::fs;

#[test]
fn a_good_scene_renders_with_a_closing_line() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("img.png: 32×18, 1 spp") && stdout.contains("M rays/s"), "{stdout}");
    let img = image::open(dir.path().join("img.png")).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (32, 18));
    // The sphere is red in the middle.
    let p = img.get_pixel(16, 8).0;
    assert!(p[0] > p[1] && p[0] > p[2], "{p:?}");
    assert_eq!(listing(dir.path()), ["img.png", "s.toml"], "no temporary file is left");
}

#[test]
fn the_default_output_is_out_slash_the_scene_name() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("scenes")).unwrap();
    fs::write(dir.path().join("scenes/ball.toml"), GOOD).unwrap();
    let out =
        prism(dir.path(), &["render", "scenes/ball.toml", "--quiet", "--width", "20", "--threads", "1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty(), "--quiet prints nothing: {}", text(&out.stdout));
    let img = image::open(dir.path().join("out/ball.png")).unwrap();
    // --width alone keeps the aspect ratio.
    assert_eq!((img.width(), img.height()), (20, 11));
}

#[test]
fn exr_output_is_linear_float() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.exr", "--spp", "2", "--no-fog"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let img = image::open(dir.path().join("img.exr")).unwrap();
    assert!(matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F), "{:?}", img.color());
    // Linear: the same render as an 8-bit PNG is its sRGB encoding (within
    // a level), which an sRGB-encoded EXR would miss by far in mid-tones.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png", "--spp", "2", "--no-fog"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let png = image::open(dir.path().join("img.png")).unwrap().to_rgb8();
    let exr = img.to_rgb32f();
    assert_eq!(png.dimensions(), exr.dimensions());
    let mut mid = 0;
    for (p, e) in png.pixels().zip(exr.pixels()) {
        for c in 0..3 {
            let encoded = prism_shade::linear_to_srgb8(e[c]);
            assert!(
                encoded.abs_diff(p[c]) <= 1,
                "linear {} encodes to {encoded}, the PNG has {}",
                e[c],
                p[c]
            );
            mid += usize::from((0.1..0.6).contains(&e[c]));
        }
    }
    assert!(mid > 100, "the image has mid-tones to tell linear from sRGB: {mid}");
}

#[test]
fn info_describes_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    for words in [
        "objects    2: 1 plane, 1 sphere",
        "triangles  0 stored",
        "materials  2: red, (default)",
        "lights     1",
        "bounds     (-1, 0, -1) to (1, 2, 1)",
        "image      32×18, 1 spp, box filter, max depth",
    ] {
        assert!(s.contains(words), "{words:?} not in\n{s}");
    }
    let scene = GOOD.replace("spp = 1", "spp = 16\nfilter = \"blackman-harris\"\nadaptive = 0.05");
    fs::write(dir.path().join("a.toml"), scene).unwrap();
    let s = text(&prism(dir.path(), &["info", "a.toml"]).stdout);
    assert!(s.contains("image      32×18, 16 spp, blackman-harris filter, adaptive 0.05, max depth"), "{s}");
}

#[test]
fn info_counts_mesh_triangles_and_instances() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("t.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let scene = format!(
        "{GOOD}[[objects]]\ntype = \"mesh\"\npath = \"t.obj\"\n[[objects]]\ntype = \"mesh\"\npath = \"t.obj\"\ntransform = [{{ translate = [2, 0, 0] }}]\n"
    );
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let out = prism(dir.path(), &["info", "s.toml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(s.contains("2 triangles, 2 instances") && s.contains("triangles  2 stored, 4 instanced"), "{s}");
}

#[test]
fn inputs_are_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let png = image::RgbImage::from_pixel(2, 2, image::Rgb([1, 2, 3]));
    png.save(dir.path().join("tex.png")).unwrap();
    let before = fs::read(dir.path().join("tex.png")).unwrap();
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"tex.png\" }");
    fs::write(dir.path().join("s.toml"), &scene).unwrap();
    for target in ["tex.png", "./tex.png"] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", target]);
        assert!(!out.status.success());
        let err = text(&out.stderr);
        assert!(err.contains("refusing to write") && !err.contains("panicked"), "{err}");
        assert_eq!(fs::read(dir.path().join("tex.png")).unwrap(), before);
    }
    let out = prism(dir.path(), &["render", "s.toml", "-o", "s.toml"]);
    assert!(!out.status.success());
    assert_eq!(fs::read_to_string(dir.path().join("s.toml")).unwrap(), scene);
    assert_eq!(listing(dir.path()), ["s.toml", "tex.png"]);
}

#[test]
fn missing_files_are_named_as_the_scene_names_them() {
    // A scene in the current directory: its files are named as written,
    // not `./tex.png`; one in a folder names them with the folder.
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("sub")).unwrap();
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"tex.png\" }");
    fs::write(dir.path().join("s.toml"), &scene).unwrap();
    fs::write(dir.path().join("sub").join("s.toml"), &scene).unwrap();
    for (scene, named) in [("s.toml", "tex.png"), ("./s.toml", "tex.png"), ("sub/s.toml", "sub/tex.png")] {
        let out = prism(dir.path(), &["info", scene]);
        assert!(!out.status.success());
        let err = text(&out.stderr);
        assert!(err.contains(&format!("cannot read texture {named}: no such file")), "{scene}: {err}");
    }
}

// The malformed-input table (every class of bad scene, mesh, texture and
// option) is in tests/malformed.rs.

#[test]
fn bad_options_and_files_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let cases: [(&[&str], &str); 12] = [
        (&["render", "s.toml", "--width", "0"], "--width: image width must be at least 1"),
        // A name ending in a dot has an empty extension, not a `.` format.
        (
            &["render", "s.toml", "-o", "a.png."],
            "error: a.png.: the output name needs a .png or .exr extension",
        ),
        (&["render", "s.toml", "-o", ".png"], "error: .png: the output name needs a .png or .exr extension"),
        (&["render", "s.toml", "--spp", "0"], "--spp:"),
        (&["render", "s.toml", "--width", "100000"], "--max-side"),
        (&["render", "s.toml", "-o", "x.jpg"], "use a .png or .exr"),
        (&["render", "none.toml"], "none.toml: cannot read scene file"),
        (&["render", "."], "directory"),
        (&["render", "s.toml", "--max-depth", "1000"], "--max-depth:"),
        (&["render", "s.toml", "--max-spp", "0"], "--max-spp <N>': must be at least 1"),
        // A negative value is the flag's, refused naming it.
        (&["render", "s.toml", "--spp", "-1"], "invalid value '-1' for '--spp <N>'"),
        (&["render", "s.toml", "--fov", "-5"], "--fov: the vertical field of view"),
    ];
    for (args, words) in cases {
        let out = prism(dir.path(), args);
        let err = text(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(err.contains(words), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert_eq!(listing(dir.path()), ["s.toml"]);
    // Clap's own usage errors exit with 2.
    let out = prism(dir.path(), &["render", "s.toml", "--fog", "--no-fog"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_missing_scene_file_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = prism(dir.path(), &["render", "none.toml", "-o", "x.png"]);
    let err = text(&out.stderr);
    assert_eq!(err.trim_end(), "error: none.toml: cannot read scene file: no such file");
    assert_eq!(err.matches("none.toml").count(), 1, "{err}");
}

#[test]
fn an_unwritable_output_fails_before_the_scene_is_read_or_rendered() {
    let dir = tempfile::tempdir().unwrap();
    // The scene is broken: had it been read first, its error would show.
    fs::write(dir.path().join("s.toml"), GOOD.replace("radius = 1", "radius = -1")).unwrap();
    let ro = dir.path().join("ro");
    fs::create_dir(&ro).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&ro, fs::Permissions::from_mode(0o555)).unwrap();
    }
    // Root may write anywhere; then a directory no one can create files in.
    let ro_target = if fs::write(ro.join("probe"), b"").is_ok() {
        fs::remove_file(ro.join("probe")).unwrap();
        "/proc/prism-no-such-dir/img.png".to_owned()
    } else {
        "ro/sub/img.png".to_owned()
    };
    #[cfg(unix)]
    std::os::unix::fs::symlink("/proc/prism-no-such-dir/img.png", dir.path().join("dangling.png")).unwrap();
    for (target, words) in [
        (ro_target.as_str(), "cannot write the image: no file can be created in"),
        ("s.toml/img.png", "s.toml is a file, not a directory"),
        #[cfg(unix)]
        ("dangling.png", "links to /proc/prism-no-such-dir/img.png, whose folder does not exist"),
    ] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", target]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{target}: {err}");
        assert!(err.starts_with(&format!("error: {target}: ")) && err.contains(words), "{target}: {err}");
        assert!(!err.contains("radius") && !err.contains("rendering"), "{target}: {err}");
    }
    assert!(!ro.join("sub").exists());
    // The default output, `out/s.png`, with a file named `out` in the way.
    fs::write(dir.path().join("out"), b"").unwrap();
    let out = prism(dir.path(), &["render", "s.toml"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: out/s.png: ") && err.contains("out is a file, not a directory"), "{err}");
    assert!(!err.contains("radius"), "{err}");
}

#[test]
fn an_output_that_is_a_directory_fails_before_the_scene_is_read() {
    let dir = tempfile::tempdir().unwrap();
    // The scene is broken: had it been read first, its error would show.
    fs::write(dir.path().join("s.toml"), GOOD.replace("radius = 1", "radius = -1")).unwrap();
    for d in ["d.png", "sj", "x.aov.exr", "y.depth.png"] {
        fs::create_dir(dir.path().join(d)).unwrap();
    }
    for (args, words) in [
        (
            &["-o", "d.png"][..],
            "error: d.png: the output is a directory; give a file name ending in .png or .exr",
        ),
        (
            &["-o", "x.png", "--stats-json", "sj"],
            "error: --stats-json: sj: the output is a directory; give a file name such as stats.json",
        ),
        (
            &["-o", "x.png", "--aov", "depth"],
            "error: x.aov.exr: the output is a directory; give a file name ending in .png or .exr",
        ),
        (
            &["-o", "y.exr", "--aov", "depth", "--aov-preview"],
            "error: y.depth.png: the output is a directory; give a file name ending in .png or .exr",
        ),
        // A name that ends in a folder as written, which `Path` reads as
        // the file before it: found before the render, not at the write.
        (
            &["-o", "new/x.png/"],
            "error: new/x.png/: the output name ends in a folder (`/`, `.` or `..`); give a file name ending in .png or .exr",
        ),
        (
            &["-o", "x.png/.", "--frames", "2"],
            "error: x.png/.: the output name ends in a folder (`/`, `.` or `..`); give a file name ending in .png or .exr",
        ),
        (
            &["-o", "x.png", "--stats-json", "new/s.json/"],
            "error: --stats-json: new/s.json/: the output name ends in a folder (`/`, `.` or `..`); give a file name such as stats.json",
        ),
    ] {
        let out = prism(dir.path(), &[&["render", "s.toml"][..], args].concat());
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.trim_end(), words, "{args:?}");
    }
    let out = prism(dir.path(), &["merge", "a.exr", "b.exr", "-o", "m.png/"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: m.png/: the output name ends in a folder"), "{err}");
    assert_eq!(listing(dir.path()), ["d.png", "s.toml", "sj", "x.aov.exr", "y.depth.png"]);
}

#[test]
fn a_bad_stats_json_path_fails_before_the_render() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    for (target, words) in [
        (".", ".: the output is a directory; give a file name such as stats.json"),
        ("s.toml", "s.toml: refusing to write the statistics over an input of this command"),
        ("s.toml/x.json", "--stats-json: s.toml/x.json: cannot write the statistics there: s.toml is a file"),
        (
            "/proc/prism-no-such-dir/s.json",
            "--stats-json: /proc/prism-no-such-dir/s.json: cannot write the statistics: no file can be created in /proc",
        ),
        // A link into a folder that does not exist: not made at the far end.
        (
            "dangling.json",
            "--stats-json: dangling.json: cannot write the statistics: it links to /proc/prism-no-such-dir/s.json, \
             whose folder does not exist",
        ),
    ] {
        #[cfg(unix)]
        if target == "dangling.json" {
            std::os::unix::fs::symlink("/proc/prism-no-such-dir/s.json", dir.path().join(target)).unwrap();
        }
        let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png", "--stats-json", target]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{target}: {err}");
        assert!(err.starts_with("error: ") && err.contains(words), "{target}: {err}");
        assert!(!err.contains("rendering"), "{target}: {err}");
        // No image either: the render never started.
        let _ = fs::remove_file(dir.path().join("dangling.json"));
        assert_eq!(listing(dir.path()), ["s.toml"], "{target}");
    }
    // A missing directory is made, as the image's is.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png", "--stats-json", "a/b/s.json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json = fs::read_to_string(dir.path().join("a/b/s.json")).unwrap();
    assert!(json.contains("\"rays\""), "{json}");
}

#[test]
fn eight_bit_colours_warn_and_samples_aliases_work() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD.replace("[0.8, 0.1, 0.1]", "[255, 0, 0]")).unwrap();
    for flag in ["--samples", "-s", "--spp"] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", "img.png", flag, "2"]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let err = text(&out.stderr);
        assert!(
            err.contains("warning: s.toml:14:9: color [255, 0, 0] looks like 8-bit values: colour components are 0–1 (or \"#ff0000\")"),
            "{err}"
        );
        assert!(text(&out.stdout).contains("32×18, 2 spp"), "{flag}: {}", text(&out.stdout));
    }
}

#[test]
fn camera_chooses_a_named_camera_and_lists_the_names_when_unknown() {
    let dir = tempfile::tempdir().unwrap();
    let above_keys = "position = [0, 9, 0.01]\nlook_at = [0, 0, 0]\nprojection = \"orthographic\"\n";
    let scene = format!("{GOOD}\n[[cameras]]\nname = \"above\"\n{above_keys}");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    // The same scene with only `[camera]`, and with "above" as `[camera]`.
    fs::write(dir.path().join("plain.toml"), GOOD).unwrap();
    let camera_table = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n";
    assert!(GOOD.contains(camera_table));
    fs::write(dir.path().join("top.toml"), GOOD.replace(camera_table, &format!("[camera]\n{above_keys}")))
        .unwrap();
    let renders = [
        ("s.toml", "a.png", None),
        ("s.toml", "b.png", Some("above")),
        ("plain.toml", "plain.png", None),
        ("top.toml", "top.png", None),
    ];
    for (scene, png, camera) in renders {
        let mut args = vec!["render", scene, "-o", png, "--quiet"];
        args.extend(camera.iter().flat_map(|c| ["--camera", c]));
        let out = prism(dir.path(), &args);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    }
    let pixels = |png: &str| image::open(dir.path().join(png)).unwrap().to_rgb8().into_raw();
    // Without --camera the render uses `[camera]`, not the first named one;
    // with it, the named camera's picture, not merely another one.
    assert_eq!(pixels("a.png"), pixels("plain.png"), "the default is `[camera]`");
    assert_eq!(pixels("b.png"), pixels("top.png"), "--camera above renders from \"above\"");
    assert_ne!(pixels("a.png"), pixels("b.png"), "another camera, another picture");
    let out = prism(dir.path(), &["render", "s.toml", "-o", "c.png", "--camera", "side"]);
    common::assert_clean_failure("unknown camera", &out);
    let err = text(&out.stderr);
    assert!(err.contains("--camera") && err.contains("`side`") && err.contains("above"), "{err}");
    assert!(!dir.path().join("c.png").exists());
}

#[test]
fn unknown_values_of_the_tracing_variables_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let run = |vars: &[(&str, &str)], args: &[&str]| {
        let mut cmd = common::prism_cmd(dir.path());
        for v in ["PRISM_BVH_KERNEL", "PRISM_PACKETS", "PRISM_BVH_BLAS", "PRISM_BVH_NO_SIMD"] {
            cmd.env_remove(v);
        }
        let out = cmd.envs(vars.iter().copied()).args(args).output().unwrap();
        assert!(out.status.success(), "{vars:?}: {}", text(&out.stderr));
        text(&out.stderr)
    };
    let bad = [("PRISM_BVH_KERNEL", "sse9"), ("PRISM_PACKETS", "yes"), ("PRISM_BVH_BLAS", "bvh4")];
    for args in [&["render", "s.toml", "-o", "a.png", "--quiet"][..], &["info", "s.toml"]] {
        let err = run(&bad, args);
        for needle in [
            "warning: PRISM_BVH_KERNEL=\"sse9\" is not a kernel (portable, avx2, avx512); using ",
            "warning: PRISM_PACKETS=\"yes\" is not one of camera, shadow, all, 0; every ray is traced alone",
            "warning: PRISM_BVH_BLAS=\"bvh4\" is not a layout (cwbvh, bvh2, wide); using the default",
        ] {
            assert!(err.contains(needle), "{args:?}: {err}");
        }
    }
    // Known values say nothing.
    let good = [("PRISM_BVH_KERNEL", "portable"), ("PRISM_PACKETS", "0"), ("PRISM_BVH_BLAS", "bvh2")];
    assert_eq!(run(&good, &["render", "s.toml", "-o", "b.png", "--quiet"]), "");
}

/// Light that overflows f32 only where two lights meet renders black
/// there, and the render says so, even with --quiet.
#[test]
fn samples_that_are_not_finite_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let scene = "[render]\nwidth = 16\nheight = 12\nspp = 1\n\
                 [camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n\
                 [[lights]]\nposition = [2, 5, 5]\nintensity = 3e38\n\
                 [[lights]]\nposition = [-2, 5, 5]\nintensity = 3e38\n\
                 [[objects]]\ntype = \"sphere\"\nradius = 1\n";
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "s.png", "--threads", "1", "-q"]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("samples were not finite") && err.contains("lower the lights' intensity"), "{err}");
    // A sane scene says nothing of the kind.
    std::fs::write(dir.path().join("s.toml"), scene.replace("3e38", "1")).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "s.png", "--threads", "1", "-q"]);
    assert!(!text(&out.stderr).contains("not finite"), "{}", text(&out.stderr));
}

#[test]
fn escape_sequences_in_a_scene_reach_the_terminal_escaped() {
    // A name in someone else's scene could recolour or clear the terminal
    // through an error, a warning or `prism info`.
    let dir = tempfile::tempdir().unwrap();
    let named = GOOD
        .replace("[materials.red]", "[materials.\"r\\u001b[2Jed\"]")
        .replace("material = \"red\"", "material = \"r\\u001b[2Jed\"");
    fs::write(dir.path().join("named.toml"), &named).unwrap();
    let unknown = GOOD.replace("material = \"red\"", "material = \"x\\u001b[31my\"");
    fs::write(dir.path().join("unknown.toml"), &unknown).unwrap();
    let info = prism(dir.path(), &["info", "named.toml"]);
    assert!(info.status.success(), "{}", text(&info.stderr));
    let render = prism(dir.path(), &["render", "unknown.toml", "-o", "u.png"]);
    assert!(!render.status.success());
    for (what, bytes, shown) in
        [("info", &info.stdout, "r\\u{1b}[2Jed"), ("error", &render.stderr, "x\\u{1b}[31my")]
    {
        let t = text(bytes);
        assert!(!t.contains('\u{1b}') && t.contains(shown), "{what}: {t:?}");
    }
}
