//! The CLI conventions: `--version`, `completions SHELL`, the man pages,
//! `info --json` and `render --stats-json`.

mod common;

use common::{GOOD, listing, prism, text};
use std::fs;

#[test]
fn version_names_the_version_the_commit_and_the_simd_paths() {
    let dir = tempfile::tempdir().unwrap();
    let out = prism(dir.path(), &["--version"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    let lines: Vec<&str> = s.lines().collect();
    assert_eq!(lines[0], format!("prism {}", env!("CARGO_PKG_VERSION")), "{s}");
    let commit = lines[1].strip_prefix("commit: ").unwrap_or_else(|| panic!("{s}"));
    assert!(
        commit == "unknown" || (commit.len() == 12 && commit.bytes().all(|b| b.is_ascii_hexdigit())),
        "{s}"
    );
    let simd = lines[2].strip_prefix("simd:   ").unwrap_or_else(|| panic!("{s}"));
    // The default node test is the fastest measured that the CPU has:
    // AVX-512, else AVX2; without AVX2 everything runs the scalar builds.
    let expected = if prism_bvh::Kernel::Avx512.supported() {
        "bvh-avx2 bvh8-avx512 ("
    } else if prism_bvh::Kernel::Avx2.supported() {
        "bvh-avx2 bvh8-avx2 ("
    } else {
        "scalar ("
    };
    assert!(simd.starts_with(expected), "expected {expected:?}: {s}");
    if simd.starts_with("bvh-avx2 ") {
        let out = common::prism_cmd(dir.path())
            .arg("--version")
            .env("PRISM_BVH_KERNEL", "portable")
            .output()
            .unwrap();
        assert!(text(&out.stdout).contains("simd:   bvh-avx2 ("), "{}", text(&out.stdout));
    }
    // The switch that turns the AVX2 walk off is honoured.
    let out = common::prism_cmd(dir.path()).arg("--version").env("PRISM_BVH_NO_SIMD", "1").output().unwrap();
    assert!(text(&out.stdout).contains("simd:   scalar "), "{}", text(&out.stdout));
}

#[test]
fn completions_generate_for_each_shell() {
    let dir = tempfile::tempdir().unwrap();
    for (shell, marker) in [("bash", "complete -F"), ("zsh", "#compdef prism"), ("fish", "complete -c prism")]
    {
        let out = prism(dir.path(), &["completions", shell]);
        assert!(out.status.success(), "{shell}: {}", text(&out.stderr));
        let s = text(&out.stdout);
        assert!(s.contains(marker), "{shell}: no {marker:?} in\n{s}");
        // The values of --filter and --tonemap, not file names.
        for word in ["render", "info", "spp", "aov-preview", "stats-json", "blackman-harris", "reinhard"] {
            assert!(s.contains(word), "{shell}: {word} missing");
        }
        // The hidden `man` (behind `cargo xtask man`) is not offered.
        assert!(
            !s.contains("Write the man pages") && !s.contains("prism,man)"),
            "{shell}: the hidden man command is offered"
        );
        if shell == "bash" {
            // The bash script parses (zsh and fish are not required here).
            let file = dir.path().join("prism.bash");
            fs::write(&file, &s).unwrap();
            match std::process::Command::new("bash").arg("-n").arg(&file).output() {
                Ok(o) => assert!(o.status.success(), "bash -n: {}", text(&o.stderr)),
                Err(_) => prism_testkit::skip("bash is not installed"),
            }
        }
    }
    let out = prism(dir.path(), &["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn man_pages_are_written_per_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = prism(dir.path(), &["man", "pages"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let pages = listing(&dir.path().join("pages"));
    for p in ["prism.1", "prism-render.1", "prism-info.1", "prism-view.1", "prism-completions.1"] {
        assert!(pages.iter().any(|x| x == p), "{p} not in {pages:?}");
    }
    let render = fs::read_to_string(dir.path().join("pages/prism-render.1")).unwrap();
    assert!(render.starts_with(".ie \\n(.g .ds Aq") || render.contains(".TH prism-render"), "{render}");
    assert!(render.contains("stats\\-json"), "{render}");
}

fn json(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(bytes).unwrap_or_else(|e| panic!("not JSON ({e}): {}", text(bytes)))
}

#[test]
fn info_json_holds_the_scene_in_numbers() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(dir.path(), &["info", "s.toml", "--json", "--width", "64"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let j = json(&out.stdout);
    assert_eq!(j["image"]["width"], 64);
    assert_eq!(j["image"]["height"], 36);
    assert_eq!(
        (&j["image"]["filter"], &j["image"]["adaptive"]),
        (&serde_json::json!("box"), &serde_json::Value::Null)
    );
    // The pixel filter and adaptive threshold a render would use, from the flags or the scene.
    let out = prism(dir.path(), &["info", "s.toml", "--json", "--filter", "gaussian", "--adaptive", "0.05"]);
    let f = json(&out.stdout);
    assert_eq!(
        (&f["image"]["filter"], &f["image"]["adaptive"]),
        (&serde_json::json!("gaussian"), &serde_json::json!(0.05))
    );
    assert_eq!(j["objects"], 2);
    assert_eq!(j["objects_by_kind"]["sphere"], 1);
    assert_eq!(j["materials"], serde_json::json!(["red", "(default)"]));
    assert_eq!(j["lights"][0]["position"], serde_json::json!([3.0, 5.0, 4.0]));
    assert_eq!(j["camera"]["position"], serde_json::json!([0.0, 1.0, 5.0]));
    assert_eq!(j["bounds"]["min"], serde_json::json!([-1.0, 0.0, -1.0]));
    assert_eq!(j["bvh"]["unbounded_objects"], 1, "the plane");
    assert!(j["bvh"]["nodes"].as_u64().unwrap() >= 1);
    assert!(j["bvh"]["build_seconds"].as_f64().unwrap() >= 0.0);
    assert_eq!(j["fog"], serde_json::Value::Null);
    assert_eq!(
        (&j["camera"]["projection"], &j["camera"]["aperture"]),
        (&serde_json::json!("perspective"), &serde_json::json!(0.0))
    );
    // The lens and the projection, in the text and in JSON.
    let lens = GOOD.replace(
        "look_at = [0, 1, 0]",
        "look_at = [0, 1, 0]\nprojection = \"orthographic\"\naperture = 0.25\nfocus_distance = 3",
    );
    fs::write(dir.path().join("lens.toml"), lens).unwrap();
    let out = prism(dir.path(), &["info", "lens.toml"]);
    assert!(
        text(&out.stdout).contains(", orthographic, lens aperture 0.25 focused at 3\n"),
        "{}",
        text(&out.stdout)
    );
    let j = json(&prism(dir.path(), &["info", "lens.toml", "--json"]).stdout);
    assert_eq!(j["camera"]["projection"], "orthographic");
    assert_eq!(
        (j["camera"]["aperture"].as_f64(), j["camera"]["focus_distance"].as_f64()),
        (Some(0.25), Some(3.0))
    );
}

#[test]
fn stats_json_holds_real_figures() {
    let dir = tempfile::tempdir().unwrap();
    // A mirror ball: camera, shadow, secondary and AOV rays all happen.
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "color = [0.8, 0.1, 0.1]\nreflectivity = 0.5");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let args = [
        "render",
        "s.toml",
        "-o",
        "o.png",
        "--spp",
        "2",
        "--aov",
        "depth",
        "--stats-json",
        "st/s.json",
        "--filter",
        "gaussian",
        "--adaptive",
        "0.05",
    ];
    fs::create_dir(dir.path().join("st")).unwrap();
    let out = prism(dir.path(), &args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let j = json(&fs::read(dir.path().join("st/s.json")).unwrap());
    let u = |a: &str, b: &str| j[a][b].as_u64().unwrap_or_else(|| panic!("{a}.{b} in {j}"));
    let f = |a: &str, b: &str| j[a][b].as_f64().unwrap_or_else(|| panic!("{a}.{b} in {j}"));
    assert_eq!(u("image", "width") * u("image", "height"), 32 * 18);
    // The pixel filter and adaptive threshold the render used, as `info --json` has them.
    assert_eq!(
        (&j["image"]["filter"], &j["image"]["adaptive"]),
        (&serde_json::json!("gaussian"), &serde_json::json!(0.05))
    );
    // One camera ray per sample; the depth pass traces its own.
    assert_eq!(u("rays", "camera"), 32 * 18 * 2);
    assert_eq!(u("rays", "aov"), 32 * 18 * 2);
    assert!(u("rays", "shadow") > 0 && u("rays", "secondary") > 0, "{j}");
    assert_eq!(
        u("rays", "total"),
        u("rays", "camera") + u("rays", "shadow") + u("rays", "secondary") + u("rays", "aov")
    );
    for phase in ["load", "bvh_build", "render", "write"] {
        assert!(f("seconds", phase) >= 0.0, "{phase}");
    }
    let total = f("seconds", "load") + f("seconds", "render") + f("seconds", "write");
    assert!((f("seconds", "total") - total).abs() < 1e-9);
    assert!(f("seconds", "bvh_build") <= f("seconds", "load"));
    assert!(u("bvh", "nodes") >= 1);
    if cfg!(target_os = "linux") {
        // The process held at least its image buffers.
        assert!(j["peak_memory_bytes"].as_u64().unwrap() > 32 * 18 * 12);
    }
    assert_eq!(j["outputs"], serde_json::json!(["o.png", "o.aov.exr"]));
    assert_eq!(listing(&dir.path().join("st")), ["s.json"], "written atomically");
}

#[test]
fn a_closed_standard_output_is_not_a_crash() {
    // `prism info --json | head -c 10`: the reader is gone before prism writes.
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    for args in [&["info", "s.toml", "--json"][..], &["info", "s.toml"], &["completions", "bash"]] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = common::prism_cmd(dir.path()).args(args).stdout(writer).output().unwrap();
        let err = text(&out.stderr);
        assert!(out.status.success(), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // A render whose closing line cannot be printed still writes its image.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = common::prism_cmd(dir.path())
        .args(["render", "s.toml", "-o", "img.png"])
        .stdout(writer)
        .output()
        .unwrap();
    assert!(out.status.success() && !text(&out.stderr).contains("panicked"), "{}", text(&out.stderr));
    assert!(dir.path().join("img.png").is_file());
}

#[test]
fn data_that_cannot_be_written_to_standard_output_is_an_error() {
    // A full disk under `prism info --json > info.json` must not leave a
    // cut-off file behind an exit status of 0 (a closed pipe, above, is
    // not an error: the reader chose to stop).
    let full = std::path::Path::new("/dev/full");
    if !full.exists() {
        return prism_testkit::skip("/dev/full is not on this system");
    }
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let cases: [(&[&str], &str); 4] = [
        (&["info", "s.toml", "--json"], "cannot write the description to standard output"),
        (&["info", "s.toml"], "cannot write the description to standard output"),
        (&["completions", "bash"], "cannot write the completion script to standard output"),
        (
            &["render", "s.toml", "-o", "a.png", "-q", "--stats-json", "-"],
            "cannot write the statistics (--stats-json -) to standard output",
        ),
    ];
    for (args, message) in cases {
        let out = common::prism_cmd(dir.path())
            .args(args)
            .stdout(fs::File::options().write(true).open(full).unwrap())
            .output()
            .unwrap();
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(message) && err.contains("No space left"), "{args:?}: {err}");
    }
    // The statistics file fails after the image is written: both said.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "b.png", "-q", "--stats-json", "/dev/full"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr)
            .contains("--stats-json: b.png was written, but not the statistics: cannot write /dev/full"),
        "{}",
        text(&out.stderr)
    );
    assert!(dir.path().join("b.png").is_file());
}
