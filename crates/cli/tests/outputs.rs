//! Images ready for compositing: `--alpha` (RGBA PNG and EXR, transparent
//! where the background was), `--bit-depth 16`, `--exposure`/`--tonemap`
//! (PNG only), and the AOV passes as layers of one multi-layer EXR with
//! standard channel names, read back with the `exr` crate.

mod common;

use common::{listing, prism, text};
use prism_shade::{PngOptions, Tonemap, read_exr_rgb};
use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

/// A unit sphere at the origin seen from (0, 0, 5) over a blue background
/// (no floor): the corners are background, the centre pixel (16, 12) sees
/// the sphere at depth 4.
const SPHERE: &str = r#"[render]
width = 33
height = 25
spp = 1
background = [0.2, 0.3, 0.9]

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 30

[[lights]]
position = [3, 5, 4]
intensity = 3

[materials.white]
color = [0.9, 0.9, 0.9]
specular = 0.8

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "white"
"#;

fn scene_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), SPHERE).unwrap();
    dir
}

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = prism(dir, args);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    text(&out.stderr)
}

/// Every channel of a (single-part) EXR file, read with the `exr` crate,
/// by full name.
fn exr_channels(path: &Path) -> BTreeMap<String, exr::prelude::FlatSamples> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(image.layer_data.len(), 1, "one part");
    let layer = &image.layer_data[0];
    assert_eq!((layer.size.x(), layer.size.y()), (33, 25));
    layer.channel_data.list.iter().map(|c| (c.name.to_string(), c.sample_data.clone())).collect()
}

fn f32s(ch: &BTreeMap<String, exr::prelude::FlatSamples>, name: &str) -> Vec<f32> {
    match ch.get(name) {
        Some(exr::prelude::FlatSamples::F32(v)) => v.clone(),
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn alpha_is_transparent_where_the_background_was() {
    let dir = scene_dir();
    run_ok(dir.path(), &["render", "s.toml", "-o", "plain.png"]);
    run_ok(dir.path(), &["render", "s.toml", "-o", "a.png", "--alpha"]);
    let plain = image::open(dir.path().join("plain.png")).unwrap();
    let a = image::open(dir.path().join("a.png")).unwrap();
    assert_eq!(a.color(), image::ColorType::Rgba8);
    let (plain, a) = (plain.to_rgb8(), a.to_rgba8());
    // Background: fully transparent (and black); the plain render shows blue there.
    for (i, j) in [(0, 0), (32, 0), (0, 24), (32, 24)] {
        assert_eq!(a.get_pixel(i, j).0, [0, 0, 0, 0], "({i}, {j})");
        assert!(plain.get_pixel(i, j).0[2] > 200);
    }
    // On the sphere: opaque, and the same colour as without --alpha.
    let c = a.get_pixel(16, 12).0;
    assert_eq!(c[3], 255);
    assert_eq!(c[..3], plain.get_pixel(16, 12).0);
    let opaque = a.pixels().filter(|p| p.0[3] == 255).count();
    let clear = a.pixels().filter(|p| p.0[3] == 0).count();
    assert!(opaque > 50 && clear > 300 && opaque + clear == 33 * 25, "{opaque} {clear}");
}

#[test]
fn alpha_exr_is_premultiplied_with_an_a_channel() {
    let dir = scene_dir();
    run_ok(dir.path(), &["render", "s.toml", "-o", "plain.exr", "--spp", "4"]);
    run_ok(dir.path(), &["render", "s.toml", "-o", "a.exr", "--spp", "4", "--alpha"]);
    let ch = exr_channels(&dir.path().join("a.exr"));
    assert_eq!(ch.keys().collect::<Vec<_>>(), ["A", "B", "G", "R"]);
    let alpha = f32s(&ch, "A");
    let (_, _, plain) = read_exr_rgb(&dir.path().join("plain.exr")).unwrap();
    let rgb = [f32s(&ch, "R"), f32s(&ch, "G"), f32s(&ch, "B")];
    let mut edge = 0;
    for (k, &a) in alpha.iter().enumerate() {
        let px = [rgb[0][k], rgb[1][k], rgb[2][k]];
        match a {
            // Fully covered: bit for bit the plain render.
            1.0 => assert_eq!(px[..], plain[3 * k..3 * k + 3], "pixel {k}"),
            // Background: nothing.
            0.0 => assert_eq!(px, [0.0; 3], "pixel {k}"),
            // Silhouette: coverage in quarters (4 samples), colour without
            // the background's share.
            _ => {
                edge += 1;
                assert!([0.25, 0.5, 0.75].contains(&a), "{a}");
                assert!(px[2] < plain[3 * k + 2], "pixel {k}: the blue background is taken out");
            }
        }
    }
    assert!(edge > 0, "the silhouette is antialiased");
    assert_eq!(alpha[12 * 33 + 16], 1.0);
    assert_eq!(alpha[0], 0.0);
}

#[test]
fn aovs_are_layers_of_one_exr_with_standard_names() {
    let dir = scene_dir();
    let stdout =
        text(&prism(dir.path(), &["render", "s.toml", "-o", "out.exr", "--aov", "all", "--alpha"]).stdout);
    assert!(!stdout.contains("wrote"), "one file: {stdout}");
    assert_eq!(listing(dir.path()), ["out.exr", "s.toml"]);
    let ch = exr_channels(&dir.path().join("out.exr"));
    let names: Vec<&str> = ch.keys().map(String::as_str).collect();
    let mut want = [
        "R", "G", "B", "A", "Z", "id", "N.X", "N.Y", "N.Z", "Ng.X", "Ng.Y", "Ng.Z", "albedo.R", "albedo.G",
        "albedo.B",
    ];
    want.sort_unstable();
    assert_eq!(names, want);
    let centre = 12 * 33 + 16;
    // Depth: d − r = 4 at the centre; +inf where nothing is hit.
    let z = f32s(&ch, "Z");
    assert!((z[centre] - 4.0).abs() < 4e-4, "{}", z[centre]);
    assert_eq!(z[0], f32::INFINITY);
    // The id is stored as UINT: object 0, u32::MAX for nothing.
    match &ch["id"] {
        exr::prelude::FlatSamples::U32(ids) => {
            assert_eq!((ids[centre], ids[0]), (0, u32::MAX));
        }
        other => panic!("id is not UINT: {other:?}"),
    }
    let n = [f32s(&ch, "N.X")[centre], f32s(&ch, "N.Y")[centre], f32s(&ch, "N.Z")[centre]];
    assert!(n[0].abs() < 1e-4 && n[1].abs() < 1e-4 && (n[2] - 1.0).abs() < 1e-4, "{n:?}");
    assert_eq!(f32s(&ch, "albedo.G")[centre], 0.9);
    assert_eq!(f32s(&ch, "Ng.Z")[0], 0.0);
    // prism reads its own file back: the same passes.
    let back = prism_shade::read_render_exr(&dir.path().join("out.exr")).unwrap();
    assert_eq!(back.passes.passes.len(), 5);
    assert_eq!(back.alpha.as_deref().map(<[f32]>::len), Some(33 * 25));
}

#[test]
fn a_png_gets_its_passes_in_one_exr_beside_it() {
    let dir = scene_dir();
    let out = prism(
        dir.path(),
        &["render", "s.toml", "-o", "img.png", "--aov", "depth,object_id", "--aov-preview"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("wrote img.aov.exr"), "{}", text(&out.stdout));
    assert_eq!(
        listing(dir.path()),
        ["img.aov.exr", "img.depth.png", "img.object_id.png", "img.png", "s.toml"]
    );
    let ch = exr_channels(&dir.path().join("img.aov.exr"));
    assert_eq!(ch.keys().collect::<Vec<_>>(), ["B", "G", "R", "Z", "id"]);
    // The beauty in it is the linear render.
    run_ok(dir.path(), &["render", "s.toml", "-o", "lin.exr"]);
    let (_, _, lin) = read_exr_rgb(&dir.path().join("lin.exr")).unwrap();
    assert_eq!(f32s(&ch, "G"), lin.iter().skip(1).step_by(3).copied().collect::<Vec<_>>());
}

#[test]
fn sixteen_bit_png_refines_the_eight_bit_one() {
    let dir = scene_dir();
    run_ok(dir.path(), &["render", "s.toml", "-o", "a8.png"]);
    run_ok(dir.path(), &["render", "s.toml", "-o", "a16.png", "--bit-depth", "16"]);
    run_ok(dir.path(), &["render", "s.toml", "-o", "b16.png", "--bit-depth", "16", "--alpha"]);
    let a8 = image::open(dir.path().join("a8.png")).unwrap();
    let a16 = image::open(dir.path().join("a16.png")).unwrap();
    assert_eq!(a16.color(), image::ColorType::Rgb16);
    assert_eq!(image::open(dir.path().join("b16.png")).unwrap().color(), image::ColorType::Rgba16);
    let (a8, a16) = (a8.to_rgb8(), a16.to_rgb16());
    let mut finer = false;
    for (p8, p16) in a8.pixels().zip(a16.pixels()) {
        for (v8, v16) in p8.0.iter().zip(p16.0) {
            // Both round the same display value: 16 bits / 257 is within half a step of 8 bits.
            let scaled = f64::from(v16) / 257.0;
            assert!((scaled - f64::from(*v8)).abs() <= 0.5 + 1e-3, "{v8} vs {v16}");
            finer |= v16 % 257 != 0;
        }
    }
    assert!(finer, "16 bits carry more than 8");
}

#[test]
fn exposure_and_tonemap_shape_the_png_and_leave_the_exr_linear() {
    let dir = scene_dir();
    run_ok(dir.path(), &["render", "s.toml", "-o", "lin.exr"]);
    let (_, _, lin) = read_exr_rgb(&dir.path().join("lin.exr")).unwrap();
    for (ev, op) in [("1.5", Tonemap::Aces), ("-1", Tonemap::Reinhard), ("0.5", Tonemap::Clamp)] {
        run_ok(dir.path(), &["render", "s.toml", "-o", "t.png", "--exposure", ev, "--tonemap", op.name()]);
        let png = image::open(dir.path().join("t.png")).unwrap().to_rgb8();
        let o = PngOptions { exposure: ev.parse().unwrap(), tonemap: op, ..PngOptions::default() };
        let want: Vec<u8> = lin.iter().map(|&x| o.encode8(x)).collect();
        assert_eq!(png.as_raw(), &want, "{ev} {op}");
    }
    // The sphere's highlight saturates under clamp, not under Reinhard.
    run_ok(dir.path(), &["render", "s.toml", "-o", "c.png", "--exposure", "3"]);
    run_ok(dir.path(), &["render", "s.toml", "-o", "r.png", "--exposure", "3", "--tonemap", "reinhard"]);
    let white = |f: &str| {
        image::open(dir.path().join(f)).unwrap().to_rgb8().pixels().filter(|p| p.0 == [255; 3]).count()
    };
    assert!(white("c.png") > 0 && white("r.png") == 0);
    // An EXR stays linear, bit for bit, and says so.
    let err =
        run_ok(dir.path(), &["render", "s.toml", "-o", "e.exr", "--exposure", "2", "--tonemap", "aces"]);
    assert!(err.contains("apply to PNG output only"), "{err}");
    assert_eq!(read_exr_rgb(&dir.path().join("e.exr")).unwrap().2, lin);
}

#[test]
fn bad_image_flags_are_refused_naming_the_flag() {
    let dir = scene_dir();
    let cases: [(&[&str], &str, i32); 4] = [
        (&["--tonemap", "filmic"], "--tonemap", 2),
        (&["--bit-depth", "12"], "--bit-depth", 2),
        (&["--exposure", "nan"], "--exposure", 1),
        (&["--exposure", "1e9"], "--exposure", 1),
    ];
    for (flags, words, code) in cases {
        let mut args = vec!["render", "s.toml", "-o", "x.png"];
        args.extend(flags);
        let out = prism(dir.path(), &args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{flags:?}: {err}");
        assert!(err.contains(words) && !err.contains("panicked"), "{flags:?}: {err}");
    }
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

#[cfg(unix)]
#[test]
fn outputs_go_through_links_and_into_pipes_and_devices() {
    use std::os::unix::fs::{FileTypeExt, symlink};
    let dir = scene_dir();
    let p = dir.path();
    fs::create_dir(p.join("real")).unwrap();
    symlink("real/target.png", p.join("link.png")).unwrap();
    symlink("/dev/null", p.join("null.json")).unwrap();
    run_ok(p, &["render", "s.toml", "-o", "link.png", "--stats-json", "null.json", "--quiet"]);
    // The links stay links; the image is where the link points.
    for link in ["link.png", "null.json"] {
        assert!(fs::symlink_metadata(p.join(link)).unwrap().file_type().is_symlink(), "{link}");
    }
    assert_eq!(image::open(p.join("real/target.png")).unwrap().width(), 33);
    assert!(fs::metadata("/dev/null").unwrap().file_type().is_char_device());
    // A named pipe is written into, not replaced by a file.
    let fifo = p.join("pipe.json");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let reader = std::thread::spawn({
        let fifo = fifo.clone();
        move || fs::read_to_string(fifo).unwrap()
    });
    run_ok(p, &["render", "s.toml", "-o", "b.png", "--stats-json", "pipe.json", "--quiet"]);
    if !reader.is_finished() {
        // prism did not write into the pipe (it replaced it?): open its
        // other end so that the reader ends, and the checks below fail.
        std::thread::sleep(std::time::Duration::from_millis(200));
        if !reader.is_finished() {
            let _ = fs::OpenOptions::new().write(true).open(&fifo);
        }
    }
    let json = reader.join().unwrap();
    assert!(json.starts_with('{') && json.contains("\"rays\""), "{json}");
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(
        listing(p),
        ["b.png", "link.png", "null.json", "pipe.json", "real", "s.toml"],
        "no temporary file left"
    );
    // Standard output, as a path: the statistics go down the pipe.
    let out = common::prism_cmd(p)
        .args(["render", "s.toml", "-o", "c.png", "--stats-json", "/dev/stdout", "--quiet"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).trim_start().starts_with('{') && text(&out.stdout).contains("\"rays\""));
    // An EXR, whose writer seeks back to its table of offsets, down a
    // pipe (a link to standard output): whole files, plain and layered.
    symlink("/dev/stdout", p.join("piped.exr")).unwrap();
    for flags in [&[][..], &["--aov", "depth,object_id"]] {
        let out = common::prism_cmd(p)
            .args(["render", "s.toml", "-o", "piped.exr", "--quiet"])
            .args(flags)
            .output()
            .unwrap();
        assert!(out.status.success(), "{flags:?}: {}", text(&out.stderr));
        let exr = {
            use exr::prelude::*;
            read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .all_layers()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(&out.stdout))
        }
        .unwrap_or_else(|e| panic!("{flags:?}: not a whole EXR ({e}), {} bytes", out.stdout.len()));
        let channels = exr.layer_data[0].channel_data.list.len();
        assert_eq!(channels, if flags.is_empty() { 3 } else { 5 }, "{flags:?}");
    }
    assert!(fs::symlink_metadata(p.join("piped.exr")).unwrap().file_type().is_symlink());
    // A loop of links is refused before the render, and left as it was.
    symlink("loop.png", p.join("loop.png")).unwrap();
    let out = prism(p, &["render", "s.toml", "-o", "loop.png"]);
    common::assert_clean_failure("loop", &out);
    let err = text(&out.stderr);
    assert!(err.contains("loop.png") && err.contains("symbolic links"), "{err}");
    assert!(fs::symlink_metadata(p.join("loop.png")).unwrap().file_type().is_symlink());
    // A link to an image of the render, not made yet, is that image.
    symlink("d.png", p.join("d.json")).unwrap();
    let out = prism(p, &["render", "s.toml", "-o", "d.png", "--stats-json", "d.json"]);
    common::assert_clean_failure("stats through a link", &out);
    assert!(!p.join("d.png").exists());
}

/// As another user (nobody, through `setpriv`, which needs root): in a
/// shared sticky folder (as /tmp), a file of someone else's at an output's
/// name cannot be replaced; that is said before the render, not after it.
#[cfg(unix)]
#[test]
fn another_users_file_in_a_sticky_folder_is_refused_before_the_render() {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let dir = scene_dir();
    let p = dir.path();
    fs::write(p.join("b.png"), "someone's").unwrap();
    fs::write(p.join("c.aov.exr"), "someone's").unwrap();
    if fs::metadata(p.join("b.png")).unwrap().uid() != 0 {
        return prism_testkit::skip("running as another user needs root (setpriv)");
    }
    fs::set_permissions(p, fs::Permissions::from_mode(0o1777)).unwrap();
    let as_nobody = |args: &[&str]| {
        std::process::Command::new("setpriv")
            .current_dir(p)
            .args(["--reuid=65534", "--regid=65534", "--clear-groups", env!("CARGO_BIN_EXE_prism")])
            .args(["render", "s.toml", "--threads", "1"])
            .args(args)
            .output()
    };
    let Ok(out) = as_nobody(&["-o", "b.png"]) else {
        return prism_testkit::skip("setpriv is not installed (util-linux)");
    };
    for (out, name) in [(out, "b.png"), (as_nobody(&["-o", "c.png", "--aov", "depth"]).unwrap(), "c.aov.exr")]
    {
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(&format!("{name} belongs to another user (uid 0)")) && !err.contains("rendering"),
            "{name}: {err}"
        );
    }
    // Nothing was written beside them; a new name is written.
    assert_eq!(listing(p), ["b.png", "c.aov.exr", "s.toml"]);
    let out = as_nobody(&["-o", "d.png", "-q"]).unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(p.join("d.png").is_file());
}

#[test]
fn statistics_never_replace_an_image_of_the_render() {
    for (flags, stats) in [
        (&[][..], "a.png"),
        (&["--aov", "depth", "--aov-files"], "a.depth.exr"),
        (&["--aov", "depth", "--aov-preview"], "a.depth.png"),
        (&["--aov", "depth"], "a.aov.exr"),
    ] {
        let dir = scene_dir();
        let mut args = vec!["render", "s.toml", "-o", "a.png", "--stats-json", stats];
        args.extend(flags);
        let out = prism(dir.path(), &args);
        common::assert_clean_failure(stats, &out);
        let err = text(&out.stderr);
        assert!(
            err.contains(&format!("--stats-json {stats}: that is also where this render writes")),
            "{err}"
        );
        assert_eq!(listing(dir.path()), ["s.toml"], "{args:?}: nothing written");
    }
}

#[test]
fn statistics_to_standard_output_come_alone_there() {
    let dir = scene_dir();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "a.png", "--aov", "depth", "--stats-json", "-"]);
    let (stdout, err) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{err}");
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("standard output is the JSON alone");
    assert_eq!(json["outputs"], serde_json::json!(["a.png", "a.aov.exr"]), "{stdout}");
    // The closing line and the files written are on standard error instead.
    assert!(err.contains("a.png: ") && err.contains("M rays/s") && err.contains("wrote a.aov.exr"), "{err}");
    assert_eq!(listing(dir.path()), ["a.aov.exr", "a.png", "s.toml"], "no file named -");
    // `./-` is a file of that name.
    let out = prism(dir.path(), &["render", "s.toml", "-o", "a.png", "--quiet", "--stats-json", "./-"]);
    assert!(out.status.success() && out.stdout.is_empty(), "{}", text(&out.stderr));
    assert!(fs::read_to_string(dir.path().join("-")).unwrap().contains("\"rays\""));
}

/// A full disk, by a link to `/dev/full` (which every write fills): both
/// encoders report the file system's error, not an encoding one.
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_is_reported_as_such_for_png_and_exr() {
    use std::os::unix::fs::{FileTypeExt, symlink};
    for name in ["full.png", "full.exr"] {
        let dir = scene_dir();
        symlink("/dev/full", dir.path().join(name)).unwrap();
        let out = prism(dir.path(), &["render", "s.toml", "-o", name, "--quiet"]);
        common::assert_clean_failure(name, &out);
        let err = text(&out.stderr);
        assert!(err.starts_with(&format!("error: cannot write {name}: No space left on device")), "{err}");
        assert_eq!(listing(dir.path()), [name, "s.toml"], "no temporary file");
    }
    assert!(fs::metadata("/dev/full").unwrap().file_type().is_char_device());
}
