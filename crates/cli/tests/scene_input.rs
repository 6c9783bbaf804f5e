//! Where a render's scene comes from and how the command line changes it:
//! `--set KEY=VALUE` reaching the render, and a scene read from standard
//! input (`prism render -`), its relative paths taken from the current
//! directory.

mod common;

use common::{GOOD, listing, png_bytes, prism, prism_cmd, text};
use std::fs;
use std::io::Write;
use std::process::Stdio;

fn rgb(path: &std::path::Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn set_overrides_reach_the_render() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let out = prism(
        dir.path(),
        &[
            "render",
            "s.toml",
            "-o",
            "set.png",
            "--set",
            "render.width=20",
            "--set",
            "render.spp=3",
            "--set",
            "materials.red.color=[0, 0, 0.9]",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    // The closing line reports the size and samples the sets gave.
    assert!(text(&out.stdout).contains("set.png: 20×18, 3 spp"), "{}", text(&out.stdout));
    let img = rgb(&dir.path().join("set.png"));
    assert_eq!((img.width(), img.height()), (20, 18));
    // The sphere in the middle is blue now, not red.
    let p = img.get_pixel(10, 8).0;
    assert!(p[2] > p[0] && p[2] > p[1], "{p:?}");
    // The same render with the values written in the file is the same image.
    let edited = GOOD
        .replace("width = 32", "width = 20")
        .replace("spp = 1", "spp = 3")
        .replace("[0.8, 0.1, 0.1]", "[0, 0, 0.9]");
    fs::write(dir.path().join("e.toml"), edited).unwrap();
    let out = prism(dir.path(), &["render", "e.toml", "-o", "edited.png"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(rgb(&dir.path().join("edited.png")), img);
    // info sees them too.
    let out = prism(dir.path(), &["info", "s.toml", "--set", "render.spp=5"]);
    assert!(out.status.success() && text(&out.stdout).contains("5 spp"), "{}", text(&out.stdout));
}

#[test]
fn set_errors_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    for (set, words) in [
        ("render.spp=0", "error: --set: render.spp=0: spp (samples per pixel) must be at least 1"),
        ("render.sp=3", "error: --set: render.sp=3: unknown key `sp`; did you mean `spp`?"),
        ("objects.5.radius=1", "error: --set: objects.5.radius=1: `objects` has 2 entries"),
        ("spp", "error: --set: spp: expected KEY=VALUE"),
    ] {
        let out = prism(dir.path(), &["render", "s.toml", "-o", "x.png", "--set", set]);
        assert_eq!(out.status.code(), Some(1), "{set}");
        assert!(text(&out.stderr).starts_with(words), "{set}: {}", text(&out.stderr));
    }
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

#[test]
fn a_scene_on_standard_input_renders_with_paths_from_the_current_directory() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("tex")).unwrap();
    fs::write(dir.path().join("tex/t.png"), png_bytes()).unwrap();
    let scene =
        GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"tex/t.png\" }");
    let run = |args: &[&str], input: &str| {
        let mut child = prism_cmd(dir.path())
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(input.as_bytes()).unwrap();
        child.wait_with_output().unwrap()
    };
    let out = run(&["render", "-", "-o", "piped.png", "--stats-json", "piped.json"], &scene);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stats = fs::read_to_string(dir.path().join("piped.json")).unwrap();
    assert!(stats.contains("\"scene\": \"<stdin>\""), "{stats}");
    fs::write(dir.path().join("s.toml"), &scene).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "file.png"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(rgb(&dir.path().join("piped.png")), rgb(&dir.path().join("file.png")));
    // Without -o: out/stdin.png.
    let out = run(&["render", "-", "--quiet"], &scene);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("out/stdin.png").is_file());
    // Errors name <stdin> with the line and column.
    let out = run(&["render", "-", "-o", "bad.png"], &GOOD.replace("radius = 1", "radius = -1"));
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).starts_with("error: <stdin>:22:10: sphere radius must be greater than 0"),
        "{}",
        text(&out.stderr)
    );
    // --set works on it too.
    let out = run(&["info", "-", "--set", "render.spp=6"], &scene);
    assert!(out.status.success() && text(&out.stdout).contains("6 spp"), "{}", text(&out.stdout));
    // Named as messages name it.
    assert!(text(&out.stdout).starts_with("scene      <stdin>\n"), "{}", text(&out.stdout));
    let out = run(&["info", "-", "--json"], &scene);
    assert!(text(&out.stdout).contains("\"scene\": \"<stdin>\""), "{}", text(&out.stdout));
}
