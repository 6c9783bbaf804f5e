//! Partial renders, tile files and `prism merge`, and turntable frames:
//! the pieces of a farm job, run locally. The merged image must be the
//! one-machine render bit for bit; every refusal names its flag or files
//! and writes nothing.

mod common;
use common::*;
use std::fs;
use std::path::{Path, PathBuf};

fn seed() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml").canonicalize().expect("seed scene")
}

/// Small and quick, with jittered samples, fog, a texture and AOVs.
const SMALL: [&str; 6] = ["--width", "61", "--height", "37", "--spp", "3"];

fn ok(dir: &Path, args: &[&str]) -> String {
    let out = prism(dir, args);
    assert!(out.status.success(), "prism {args:?}: {}", text(&out.stderr));
    text(&out.stdout)
}

fn fails(dir: &Path, args: &[&str]) -> String {
    let out = prism(dir, args);
    assert!(!out.status.success(), "prism {args:?} should fail");
    text(&out.stderr)
}

fn rgb8(p: &Path) -> Vec<u8> {
    image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())).to_rgb8().into_raw()
}

fn render_full(dir: &Path, scene: &str) {
    ok(
        dir,
        &[&["render", scene, "-q", "-o", "full.png"][..], &SMALL, &["--aov", "depth,normal,object_id"]]
            .concat(),
    );
    ok(dir, &[&["render", scene, "-q", "-o", "full.exr"][..], &SMALL].concat());
}

/// The bits of a multi-layer render file: the beauty, then each pass.
fn layered_bits(p: &Path) -> (Vec<u32>, Vec<(prism_shade::Aov, Vec<u32>)>) {
    let r = prism_shade::read_render_exr(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let image = r.image.pixels.iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect();
    let passes =
        r.passes.passes.iter().map(|a| (a.aov, a.data.iter().map(|v| v.to_bits()).collect())).collect();
    (image, passes)
}

fn assert_same_as_full(dir: &Path, merged: &str) {
    assert_eq!(rgb8(&dir.join(format!("{merged}.png"))), rgb8(&dir.join("full.png")), "PNG pixels");
    let (merged_exr, merged_passes) = layered_bits(&dir.join(format!("{merged}.exr")));
    let (full_exr, no_passes) = layered_bits(&dir.join("full.exr"));
    assert_eq!(merged_exr, full_exr, "EXR floats");
    assert!(no_passes.is_empty());
    // The passes: in the merged EXR's layers and beside the merged PNG, as beside the full PNG.
    let (_, full_passes) = layered_bits(&dir.join("full.aov.exr"));
    assert_eq!(full_passes.len(), 3);
    assert_eq!(merged_passes, full_passes, "passes in {merged}.exr");
    assert_eq!(layered_bits(&dir.join(format!("{merged}.aov.exr"))).1, full_passes, "{merged}.aov.exr");
}

#[test]
fn tiles_on_any_thread_count_merge_to_the_one_machine_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = seed();
    let scene = scene.to_str().unwrap();
    render_full(d, scene);
    let n = 5;
    let mut tiles = Vec::new();
    for i in 0..n {
        let name = format!("t{i}.exr");
        let threads = (1 + i % 3).to_string();
        let tile = format!("{i}/{n}");
        let args = [
            &["render", scene, "-q", "--tile", &tile, "--threads", &threads, "-o", &name][..],
            &SMALL,
            &["--aov", "depth,normal,object_id"],
        ]
        .concat();
        ok(d, &args);
        tiles.push(name);
    }
    // A tile is an OpenEXR file whose data window lies in the full display window.
    let t = prism_shade::read_layered_exr(&d.join("t2.exr")).unwrap();
    assert_eq!((t.width, t.height), (61, 37));
    assert_eq!(t.data_window, prism_shade::PixelBounds::tile(61, 37, 2, 5).unwrap());
    assert_eq!((t.int("prism:tile"), t.int("prism:tiles"), t.int("prism:spp")), (Some(2), Some(5), Some(3)));
    // The version and the commit `prism --version` shows.
    let version = ok(d, &["--version"]);
    let commit = version.lines().find_map(|l| l.strip_prefix("commit: ")).unwrap().trim();
    assert_eq!(
        t.text("prism:version"),
        Some(format!("{} (commit {commit})", env!("CARGO_PKG_VERSION")).as_str())
    );
    assert!(t.channel("", "Z").is_some() && t.channel("N", "Y").is_some() && t.channel("", "id").is_some());
    // Merged in any order, to PNG and EXR.
    let rev: Vec<&str> = tiles.iter().rev().map(String::as_str).collect();
    ok(d, &[&["merge"][..], &rev, &["-o", "merged.png"]].concat());
    ok(d, &[&["merge", "-q"][..], &rev, &["-o", "merged.exr"]].concat());
    assert_same_as_full(d, "merged");

    // Missing tiles: named, nothing written.
    let some: Vec<&str> = vec!["t0.exr", "t2.exr", "t4.exr"];
    let e = fails(d, &[&["merge"][..], &some, &["-o", "gap.png"]].concat());
    assert!(e.contains("tiles missing: 2 of 5 (indices 1, 3); nothing written"), "{e}");
    assert!(!d.join("gap.png").exists() && !d.join("gap.aov.exr").exists());
    // The same tile twice overlaps itself.
    let e = fails(d, &["merge", "t0.exr", "t1.exr", "t1.exr", "-o", "dup.png"]);
    assert!(e.contains("t1.exr and t1.exr overlap"), "{e}");
    // Tiles of other settings are named.
    ok(
        d,
        &[
            &["render", scene, "-q", "--tile", "1/5", "-o", "spp.exr", "--aov", "depth,normal,object_id"][..],
            &SMALL[..4],
            &["--spp", "2"],
        ]
        .concat(),
    );
    let e = fails(d, &["merge", "t0.exr", "spp.exr", "t2.exr", "t3.exr", "t4.exr", "-o", "mixed.png"]);
    assert!(
        e.contains("t0.exr and spp.exr were rendered with different settings (`spp: 3` and `spp: 2`)"),
        "{e}"
    );
    assert!(!d.join("mixed.png").exists());
}

#[test]
fn pixel_bounds_tiles_of_one_scene_only_merge() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    let full = ["render", "a.toml", "-q", "--spp", "4", "-o"];
    ok(d, &[&full[..], &["full.png"]].concat());
    // Rectangles that cover the 32×18 image once.
    let parts = ["0,32,0,5", "0,7,5,18", "7,32,5,11", "7,32,11,18"];
    for (k, b) in parts.iter().enumerate() {
        let name = format!("p{k}.exr");
        ok(d, &["render", "a.toml", "-q", "--spp", "4", "--pixel-bounds", b, "--threads", "2", "-o", &name]);
    }
    let e = fails(d, &["merge", "p3.exr", "p1.exr", "p0.exr", "p2.exr", "-o", "p0.exr"]);
    assert!(e.contains("p0.exr: refusing to write the image over an input of this command"), "{e}");
    ok(d, &["merge", "-q", "p3.exr", "p1.exr", "p0.exr", "p2.exr", "-o", "m.png"]);
    assert_eq!(rgb8(&d.join("m.png")), rgb8(&d.join("full.png")));
    let e = fails(d, &["merge", "p0.exr", "p1.exr", "p3.exr", "-o", "m2.png"]);
    assert!(e.contains("150 of 32×18 pixels are in no tile (6 rows between row 5 and row 10)"), "{e}");
    // A PNG of a part holds its pixels only.
    ok(d, &["render", "a.toml", "-q", "--spp", "4", "--pixel-bounds", "7,32,5,11", "-o", "part.png"]);
    let part = image::open(d.join("part.png")).unwrap().to_rgb8();
    assert_eq!(part.dimensions(), (25, 6));
    let whole = image::open(d.join("full.png")).unwrap().to_rgb8();
    assert_eq!(part.get_pixel(3, 2), whole.get_pixel(10, 7));
    // The same file with a --set is another scene, refused by name.
    let set = ["--set", "materials.red.color=[0.1, 0.8, 0.1]"];
    ok(
        d,
        &[&["render", "a.toml", "-q", "--spp", "4", "--pixel-bounds", "0,7,5,18", "-o", "set.exr"][..], &set]
            .concat(),
    );
    let e = fails(d, &["merge", "p0.exr", "set.exr", "p2.exr", "p3.exr", "-o", "m3.png"]);
    assert!(e.contains("p0.exr and set.exr are tiles of different scenes"), "{e}");
    // Another scene (a changed file) is refused by name.
    fs::write(d.join("a.toml"), GOOD.replace("0.8, 0.1, 0.1", "0.1, 0.8, 0.1")).unwrap();
    ok(d, &["render", "a.toml", "-q", "--spp", "4", "--pixel-bounds", "0,7,5,18", "-o", "other.exr"]);
    let e = fails(d, &["merge", "p0.exr", "other.exr", "p2.exr", "p3.exr", "-o", "m3.png"]);
    assert!(e.contains("p0.exr and other.exr are tiles of different scenes"), "{e}");
    // Not a tile at all.
    let e = fails(d, &["merge", "p0.exr", "full.png", "-o", "m4.png"]);
    assert!(e.contains("full.png"), "{e}");
    assert!(!d.join("m3.png").exists() && !d.join("m4.png").exists());
}

#[test]
fn adaptive_tiles_merge_bit_for_bit() {
    // A tile's edge pixels compare with neighbours in other tiles (the
    // seed scene's chequered floor and textures refine at many of them).
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = seed();
    let scene = scene.to_str().unwrap();
    let opts = ["--width", "64", "--height", "36", "--spp", "9", "--adaptive", "0.02", "--threads", "2"];
    ok(d, &[&["render", scene, "-q", "-o", "full.exr"][..], &opts].concat());
    let mut names = Vec::new();
    for k in 0..5 {
        names.push(format!("t{k}.exr"));
        ok(d, &[&["render", scene, "-q", "--tile", &format!("{k}/5"), "-o", &names[k]][..], &opts].concat());
    }
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    ok(d, &[&["merge", "-q"][..], &names, &["-o", "m.exr"]].concat());
    let (merged, full) = (layered_bits(&d.join("m.exr")).0, layered_bits(&d.join("full.exr")).0);
    let differ = merged.iter().zip(&full).filter(|(a, b)| a != b).count();
    assert!(merged.len() == full.len() && differ == 0, "{differ} of {} values differ", full.len());
}

#[test]
fn bad_parts_are_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    let e = fails(d, &["render", "a.toml", "--pixel-bounds", "0,33,0,5", "-o", "x.exr"]);
    assert!(e.contains("--pixel-bounds 0,33,0,5: the bounds 0,33,0,5 reach past the 32×18 image"), "{e}");
    let e = fails(d, &["render", "a.toml", "--pixel-bounds", "4,4,0,5", "-o", "x.exr"]);
    assert!(e.contains("--pixel-bounds 4,4,0,5: the bounds 4,4,0,5 hold no pixel"), "{e}");
    let e = fails(d, &["render", "a.toml", "--tile", "4/4", "-o", "x.exr"]);
    assert!(e.contains("--tile 4/4: tile 4 of 4 does not exist"), "{e}");
    let e = fails(d, &["render", "a.toml", "--tile", "0/19", "-o", "x.exr"]);
    assert!(e.contains("--tile 0/19: 19 tiles are more than the image's 18 rows"), "{e}");
    let e = fails(d, &["render", "a.toml", "--tile", "0/2", "--pixel-bounds", "0,1,0,1", "-o", "x.exr"]);
    assert!(e.contains("--pixel-bounds") && e.contains("--tile"), "{e}");
    // A tile is whole or nothing, and names its scene file.
    let e = fails(d, &["render", "a.toml", "--tile", "0/2", "--partial", "-o", "x.exr"]);
    assert!(e.contains("--partial: a tile file is written whole"), "{e}");
    let mut cmd = prism_cmd(d);
    cmd.args(["render", "-", "--tile", "0/2", "-o", "x.exr"]).stdin(std::process::Stdio::piped());
    let mut child =
        cmd.stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    {
        use std::io::Write as _;
        child.stdin.take().unwrap().write_all(&fs::read(d.join("a.toml")).unwrap()).unwrap();
    }
    let out = child.wait_with_output().unwrap();
    assert!(
        !out.status.success() && text(&out.stderr).contains("not on standard input"),
        "{}",
        text(&out.stderr)
    );
    assert!(!d.join("x.exr").exists());
    let mut cmd = prism_cmd(d);
    cmd.args(["render", "a.toml", "--tile-from-env", "3", "-o", "x.exr"]);
    cmd.env_remove("SLURM_ARRAY_TASK_ID").env_remove("JOB_COMPLETION_INDEX");
    let e = text(&cmd.output().unwrap().stderr);
    assert!(
        e.contains("--tile-from-env: neither $SLURM_ARRAY_TASK_ID nor $JOB_COMPLETION_INDEX is set"),
        "{e}"
    );
    assert_eq!(listing(d), ["a.toml"], "nothing written");
    // Flags that a tile cannot honour, and the merge can, are warned of.
    let out = prism_cmd(d)
        .args(["render", "a.toml", "-q", "--tile", "0/2", "--aov", "depth", "--aov-files", "--aov-preview"])
        .args(["-o", "w.exr"])
        .output()
        .unwrap();
    let e = text(&out.stderr);
    assert!(out.status.success(), "{e}");
    assert!(e.contains("prism merge --aov-files writes them as files of their own"), "{e}");
    assert!(e.contains("prism merge --aov-preview writes them for the whole image"), "{e}");
}

#[test]
fn tile_from_env_reads_slurm_then_kubernetes_indices() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    ok(d, &["render", "a.toml", "-q", "--tile", "2/3", "-o", "flag.exr"]);
    for var in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"] {
        let mut cmd = prism_cmd(d);
        cmd.args(["render", "a.toml", "-q", "--tile-from-env", "3", "-o", "env.exr"]);
        cmd.env_remove("SLURM_ARRAY_TASK_ID").env_remove("JOB_COMPLETION_INDEX").env(var, "2");
        assert!(cmd.status().unwrap().success());
        let read = |f: &str| prism_shade::read_layered_exr(&d.join(f)).unwrap();
        assert!(read("env.exr") == read("flag.exr"), "{var}");
    }
    // An empty Slurm variable is unset, as the job script reads it.
    let mut cmd = prism_cmd(d);
    cmd.args(["render", "a.toml", "-q", "--tile-from-env", "3", "-o", "empty.exr"]);
    cmd.env("SLURM_ARRAY_TASK_ID", "").env("JOB_COMPLETION_INDEX", "2");
    assert!(cmd.status().unwrap().success());
    let read = |f: &str| prism_shade::read_layered_exr(&d.join(f)).unwrap();
    assert!(read("empty.exr") == read("flag.exr"));
}

#[test]
fn turntable_frames_orbit_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    ok(d, &["render", "a.toml", "-q", "-o", "still.png"]);
    ok(d, &["render", "a.toml", "-q", "--frames", "3", "--orbit", "90", "-o", "turn.png"]);
    assert_eq!(listing(d), ["a.toml", "still.png", "turn.0000.png", "turn.0001.png", "turn.0002.png"]);
    // Frame 0 is the scene's own camera; later frames differ.
    assert_eq!(rgb8(&d.join("turn.0000.png")), rgb8(&d.join("still.png")));
    assert_ne!(rgb8(&d.join("turn.0001.png")), rgb8(&d.join("still.png")));
    // One frame alone is the same frame, also with the camera given on the command line.
    ok(d, &["render", "a.toml", "-q", "--frames", "3", "--orbit", "90", "--frame", "1", "-o", "one.png"]);
    assert_eq!(rgb8(&d.join("one.0001.png")), rgb8(&d.join("turn.0001.png")));
    // A 30° turn of the camera at (0, 1, 5) about (0, 1, 0) is the camera at (5 sin 30°, 1, 5 cos 30°).
    let (s, c) = (5.0 * 0.5f32, 5.0 * 30f32.to_radians().cos());
    let pos = format!("{s},1,{c}");
    ok(d, &["render", "a.toml", "-q", "--camera-pos", &pos, "-o", "moved.png"]);
    let moved = rgb8(&d.join("moved.png"));
    let frame = rgb8(&d.join("turn.0001.png"));
    let differ = moved.iter().zip(&frame).filter(|(a, b)| a.abs_diff(**b) > 2).count();
    assert!(differ * 100 < moved.len(), "{differ} of {} values differ", moved.len());
    // A later frame's name taken by an input of the render (its texture)
    // stops the turntable before any frame is written.
    fs::copy(d.join("turn.0001.png"), d.join("tex.0002.png")).unwrap();
    let textured =
        GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"tex.0002.png\" }");
    fs::write(d.join("b.toml"), textured).unwrap();
    let e = fails(d, &["render", "b.toml", "-q", "--frames", "3", "-o", "tex.png"]);
    assert!(e.contains("tex.0002.png: refusing to write the image over an input of this command"), "{e}");
    assert!(!d.join("tex.0000.png").exists() && !d.join("tex.0001.png").exists());
    let e = fails(
        d,
        &["farm", "slurm", "b.toml", "--frames", "3", "-o", "tex.png", "--dry-run", "--no-shared-check"],
    );
    assert!(e.contains("tex.0002.png: refusing to write the image over an input of this command"), "{e}");
    let e = fails(d, &["render", "a.toml", "--frames", "3", "--frame", "3", "-o", "x.png"]);
    assert!(e.contains("--frame: frame 3 does not exist; --frames 3 numbers them 0 to 2"), "{e}");
    let e = fails(d, &["render", "a.toml", "--frame", "1", "-o", "x.png"]);
    assert!(e.contains("--frames"), "{e}");
}

#[test]
fn farm_dry_run_prints_the_job_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    let args = [
        "farm",
        "slurm",
        "a.toml",
        "--tiles",
        "3",
        "--spp",
        "2",
        "--no-fog",
        "--aov",
        "depth",
        "--bit-depth",
        "16",
        "--tonemap",
        "aces",
        "-o",
        "out/x.png",
        "--dry-run",
        "--no-shared-check",
        "--",
        "--partition=render",
        "--time=10",
    ];
    let out = ok(d, &args);
    for want in [
        "#SBATCH --array=0-2",
        "--tile-from-env 3",
        "--spp 2",
        "--no-fog",
        "--aov depth",
        "i=${SLURM_ARRAY_TASK_ID:-$JOB_COMPLETION_INDEX}",
        " merge ",
        "--dependency=afterok:ARRAY_JOB_ID --partition=render --time=10",
        "x.farm/tiles/tile-0002.exr",
    ] {
        assert!(out.contains(want), "`{want}` in\n{out}");
    }
    // The image flags go to the merge, which writes the image, not to the tiles.
    let merge = out.lines().find(|l| l.contains(" merge ")).unwrap_or_else(|| panic!("{out}"));
    assert!(merge.ends_with("--bit-depth 16 --tonemap aces"), "{merge}");
    let task = out.lines().find(|l| l.contains("--tile-from-env")).unwrap_or_else(|| panic!("{out}"));
    assert!(!task.contains("--bit-depth"), "{task}");
    assert_eq!(listing(d), ["a.toml"], "a dry run writes nothing");
    let frames = ok(
        d,
        &[
            "farm",
            "slurm",
            "a.toml",
            "--frames",
            "5",
            "--orbit",
            "45",
            "--exposure",
            "1.5",
            "-o",
            "t.png",
            "--dry-run",
            "--no-shared-check",
        ],
    );
    assert!(
        frames.contains("--frames 5 --orbit 45 --frame-from-env")
            && frames.contains("--exposure 1.5")
            && !frames.contains(" merge "),
        "{frames}"
    );
    let e = fails(d, &["farm", "slurm", "a.toml", "--tiles", "40", "-o", "x.png", "--dry-run"]);
    assert!(e.contains("--tiles 40: 40 tiles are more than the image's 18 rows"), "{e}");
    let e = fails(d, &["farm", "slurm", "a.toml", "--tiles", "2", "--alpha", "-o", "x.png", "--dry-run"]);
    assert!(e.contains("--alpha: tiles hold no alpha"), "{e}");
    let e = fails(d, &["farm", "slurm", "a.toml", "-o", "x.png", "--dry-run"]);
    assert!(e.contains("required arguments were not provided") && e.contains("--tiles"), "{e}");
    let e =
        fails(d, &["farm", "slurm", "a.toml", "--tiles", "2", "--orbit", "30", "-o", "x.png", "--dry-run"]);
    assert!(e.contains("--orbit turns the camera over a turntable's frames; give --frames N"), "{e}");
    let e = fails(
        d,
        &["farm", "slurm", "a.toml", "--frames", "2", "--orbit", "1e40", "-o", "x.png", "--dry-run"],
    );
    assert!(e.contains("--orbit: the angle must be a finite number of degrees, at most about 3.4e38"), "{e}");
    let e = fails(d, &["farm", "slurm", "-", "--tiles", "2", "-o", "x.png", "--dry-run"]);
    assert!(
        e.contains("a farm job needs its scene in a file (every task reads it), not on standard input"),
        "{e}"
    );
}

/// `--aov-preview` (or the scene's `aov_preview = true`) goes to whoever
/// writes the image: the merge job for tiles (a tile holds no previews),
/// each task for frames; without AOV passes it warns, as `render` does.
#[test]
fn farm_aov_previews_go_to_whoever_writes_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    let with_previews = GOOD.replacen("[render]", "[render]\naov = [\"depth\"]\naov_preview = true", 1);
    assert_ne!(with_previews, GOOD);
    fs::write(d.join("p.toml"), with_previews).unwrap();
    let dry = ["-o", "x.png", "--dry-run", "--no-shared-check"];
    let line = |out: &str, what: &str| -> String {
        out.lines().find(|l| l.contains(what)).unwrap_or_else(|| panic!("{what} in\n{out}")).to_owned()
    };
    for args in [
        &["farm", "slurm", "a.toml", "--tiles", "2", "--aov", "depth", "--aov-preview"][..],
        &["farm", "slurm", "p.toml", "--tiles", "2"][..],
    ] {
        let out = ok(d, &[args, &dry[..]].concat());
        assert!(line(&out, " merge ").ends_with(" --aov-preview"), "{args:?}:\n{out}");
        assert!(!line(&out, "--tile-from-env").contains("--aov-preview"), "{args:?}:\n{out}");
    }
    let out = ok(
        d,
        &[&["farm", "slurm", "a.toml", "--frames", "2", "--aov", "depth", "--aov-preview"][..], &dry[..]]
            .concat(),
    );
    assert!(line(&out, "--frame-from-env").contains("--aov-preview"), "{out}");
    let out = ok(d, &[&["farm", "slurm", "a.toml", "--tiles", "2"][..], &dry[..]].concat());
    assert!(!out.contains("--aov-preview"), "{out}");
    let bare =
        prism(d, &[&["farm", "slurm", "a.toml", "--tiles", "2", "--aov-preview"][..], &dry[..]].concat());
    assert!(bare.status.success());
    let e = text(&bare.stderr);
    assert!(
        e.contains(
            "warning: --aov-preview without AOV passes (--aov or the scene's `aov`) writes no previews"
        ),
        "{e}"
    );
}

#[test]
fn help_lists_alpha_only_where_it_can_be_used() {
    let d = tempfile::tempdir().unwrap();
    let help = |args: &[&str]| text(&prism(d.path(), args).stdout);
    let merge = help(&["merge", "--help"]);
    assert!(merge.contains("--exposure") && !merge.contains("--alpha"), "{merge}");
    for cmd in [&["render", "--help"][..], &["farm", "slurm", "--help"]] {
        assert!(help(cmd).contains("--alpha"), "{cmd:?}");
    }
    // Given anyway, merge says why it cannot be.
    let e = fails(d.path(), &["merge", "t.exr", "--alpha", "-o", "x.png"]);
    assert!(e.contains("--alpha: tiles hold no alpha; render the whole image with --alpha instead"), "{e}");
}

#[test]
fn a_dry_run_checks_what_a_real_run_would_write() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    let base = ["farm", "slurm", "a.toml", "--tiles", "2", "--dry-run", "--no-shared-check"];
    for (extra, words) in [
        (
            &["-o", "/proc/prism-no-such-dir/f.png"][..],
            "/proc/prism-no-such-dir/f.png: cannot write the image",
        ),
        (&["-o", "a.toml/f.png"], "a.toml is a file, not a directory"),
        (
            &["-o", "f.png", "--work-dir", "a.toml"],
            "a.toml/tasks.sbatch: cannot write the job's scripts there: ",
        ),
        (&["-o", "f.png", "--work-dir", "/proc/prism-no-such-dir"], "cannot write the job's scripts"),
    ] {
        let out = prism(d, &[&base[..], extra].concat());
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.starts_with("error: ") && err.contains(words), "{extra:?}: {err}");
        assert!(out.stdout.is_empty(), "{extra:?}: no script printed");
        if extra.contains(&"--work-dir") {
            assert!(err.starts_with("error: --work-dir: "), "{err}");
        }
    }
    // A turntable's first frame is checked, as render checks it.
    fs::create_dir(d.join("t.0000.png")).unwrap();
    let e = fails(
        d,
        &["farm", "slurm", "a.toml", "--frames", "2", "-o", "t.png", "--dry-run", "--no-shared-check"],
    );
    assert!(e.contains("t.0000.png: the output is a directory"), "{e}");
    fs::remove_dir(d.join("t.0000.png")).unwrap();
    // So is every later one, whatever the count (found by listing the
    // folder, not by trying each name), as its task would fail on it.
    for (frames, name) in [("2", "t.0001.png"), ("4000000000", "t.3999999999.png")] {
        fs::create_dir(d.join(name)).unwrap();
        let e = fails(
            d,
            &["farm", "slurm", "a.toml", "--frames", frames, "-o", "t.png", "--dry-run", "--no-shared-check"],
        );
        assert!(e.contains(&format!("{name}: the output is a directory")), "{e}");
        fs::remove_dir(d.join(name)).unwrap();
    }
    // A real run with no sbatch to run writes nothing.
    let empty = d.join("empty-bin");
    fs::create_dir(&empty).unwrap();
    let out = prism_cmd(d)
        .args(["farm", "slurm", "a.toml", "--tiles", "2", "-o", "f.png", "--no-shared-check"])
        .env("PATH", &empty)
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("sbatch is not on the PATH") && err.contains("nothing was written"), "{err}");
    assert_eq!(listing(d), ["a.toml", "empty-bin"]);
}

#[test]
#[cfg(unix)]
fn a_line_break_in_a_path_the_job_scripts_hold_is_refused() {
    // In an `#SBATCH` line no quoting can hold a line break: what follows
    // it would run as a command of the job, and sbatch would stop reading
    // its directives there.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("a.toml"), GOOD).unwrap();
    fs::write(d.join("a\nb.toml"), GOOD).unwrap();
    // A real run would reach this sbatch, which leaves a mark.
    let bin = d.join("bin");
    fs::create_dir(&bin).unwrap();
    let sbatch = bin.join("sbatch");
    fs::write(&sbatch, format!("#!/bin/sh\ntouch '{}'\necho 1\n", d.join("SUBMITTED").display())).unwrap();
    let mut perms = fs::metadata(&sbatch).unwrap().permissions();
    std::os::unix::fs::PermissionsExt::set_mode(&mut perms, 0o755);
    fs::set_permissions(&sbatch, perms).unwrap();
    let before = listing(d);
    for (args, what) in [
        (&["a.toml", "-o", "f.png", "--work-dir", "wd\ntouch PWNED\n#"][..], "--work-dir"),
        (&["a.toml", "-o", "f.png", "--work-dir", "wd\rx"], "--work-dir"),
        (&["a.toml", "-o", "out/x\nid #.png"], "-o"),
        (&["a\nb.toml", "-o", "f.png"], "the scene"),
    ] {
        for dry in [true, false] {
            let mut cmd = prism_cmd(d);
            cmd.args(["farm", "slurm", "--tiles", "2", "--no-shared-check"]).args(args);
            if dry {
                cmd.arg("--dry-run");
            }
            let out = cmd.env("PATH", &bin).output().unwrap();
            let err = text(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
            assert!(
                err.starts_with(&format!("error: {what}: the path "))
                    && err.contains("contains a line break, which a Slurm batch script cannot hold"),
                "{args:?}: {err}"
            );
            assert_eq!(err.lines().count(), 1, "the line break is shown escaped: {err}");
            assert!(out.stdout.is_empty(), "{args:?}: no script printed");
            assert_eq!(listing(d), before, "{args:?}: nothing written, nothing submitted");
        }
    }
}
