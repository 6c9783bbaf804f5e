//! Output safety: Ctrl-C, SIGTERM and SIGHUP stop a render promptly and
//! write nothing (or, with `--partial`, a valid image of the rows done),
//! and one during the write lets it finish; SIGKILL mid-render leaves
//! nothing at the output path and no temporary file; no input of
//! any kind is overwritten; the same settings give the same image bit for
//! bit, with 1 and 2 threads and from run to run.

mod common;

use common::{GOOD, assert_clean_failure, listing, png_bytes, prism, text};
use std::fs;
use std::path::Path;

/// A render that would take far longer than any test (8×16384 pixels at
/// 65536 samples), in rows short enough that a cancel is seen at once.
#[cfg(unix)]
fn endless_scene() -> String {
    GOOD.replace("width = 32\nheight = 18\nspp = 1", "width = 8\nheight = 16384\nspp = 65536")
}

#[cfg(unix)]
mod signals {
    use super::*;
    use std::io::{BufRead, BufReader, Read};
    use std::process::{Child, ChildStderr, ExitStatus, Stdio};
    use std::time::{Duration, Instant};

    /// Starts `prism render s.toml -o img.png ARGS` in `dir` and returns once
    /// it has said that the render started (its SIGINT handler is in place).
    fn start(dir: &Path, args: &[&str]) -> (Child, BufReader<ChildStderr>, String) {
        start_scene(dir, &endless_scene(), args)
    }

    /// [`start`] with the scene `scene`.
    fn start_scene(dir: &Path, scene: &str, args: &[&str]) -> (Child, BufReader<ChildStderr>, String) {
        start_to(dir, scene, "img.png", args)
    }

    /// [`start_scene`] writing to `output`.
    fn start_to(
        dir: &Path,
        scene: &str,
        output: &str,
        args: &[&str],
    ) -> (Child, BufReader<ChildStderr>, String) {
        fs::write(dir.join("s.toml"), scene).unwrap();
        // SIGHUP at its default, whatever the test runs under: under
        // `nohup` it is inherited ignored, and prism then keeps ignoring it
        // (`a_sighup_ignored_at_start_stays_ignored`). GNU env execs prism,
        // so the child's id is prism's.
        let mut child = std::process::Command::new("env")
            .current_dir(dir)
            .arg("--default-signal=HUP")
            .arg(env!("CARGO_BIN_EXE_prism"))
            .args(["render", "s.toml", "-o", output, "--threads", "1"])
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start prism");
        let mut err = BufReader::new(child.stderr.take().expect("stderr"));
        let mut seen = String::new();
        if !read_until_started(&mut err, &mut seen) {
            let status = child.wait();
            panic!("prism ended ({status:?}) before rendering: {seen}");
        }
        (child, err, seen)
    }

    /// Reads stderr lines into `seen` until the `rendering …` line (true)
    /// or the end (false).
    fn read_until_started(err: &mut BufReader<ChildStderr>, seen: &mut String) -> bool {
        loop {
            let mut line = String::new();
            match err.read_line(&mut line) {
                Ok(0) | Err(_) => return false,
                Ok(_) => {}
            }
            seen.push_str(&line);
            if line.starts_with("rendering ") {
                return true;
            }
        }
    }

    /// Waits for `child`, failing (and killing it) if it runs 30 s more: a
    /// guard against a hang, not a timing requirement.
    fn wait(child: &mut Child) -> ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = child.try_wait().expect("wait") {
                return status;
            }
            if start.elapsed() > Duration::from_secs(30) {
                let _ = child.kill();
                panic!("prism did not stop within 30 s of the signal");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn signal(child: &Child, sig: &str) {
        let ok = std::process::Command::new("kill").args([sig, &child.id().to_string()]).status();
        assert!(ok.expect("run kill").success(), "kill {sig}");
    }

    fn rest(mut err: BufReader<ChildStderr>, seen: String) -> String {
        let mut s = seen;
        err.read_to_string(&mut s).expect("read stderr");
        s
    }

    #[test]
    fn sigint_stops_the_render_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, err, seen) = start(dir.path(), &[]);
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("error: interrupted (Ctrl-C)") && err.contains("nothing was written"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(listing(dir.path()), ["s.toml"], "no image and no temporary file");
    }

    #[test]
    fn sigint_takes_away_the_folders_the_render_made() {
        let dir = tempfile::tempdir().unwrap();
        fs::create_dir(dir.path().join("keep")).unwrap();
        let (mut child, err, seen) = start_to(dir.path(), &endless_scene(), "keep/new/deeper/img.png", &[]);
        assert!(dir.path().join("keep/new/deeper").is_dir(), "made before the render");
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("nothing was written"), "{err}");
        assert_eq!(listing(dir.path()), ["keep", "s.toml"], "{err}");
        assert!(listing(&dir.path().join("keep")).is_empty(), "a folder it did not make stays: {err}");
        // With --partial the image is written, and its folders stay.
        let (mut child, err, seen) = start_to(dir.path(), &endless_scene(), "new/img.png", &["--partial"]);
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert_eq!(listing(&dir.path().join("new")), ["img.png"], "{err}");
    }

    #[test]
    fn sigint_stops_a_render_of_one_pixel_with_many_samples() {
        // One row of one pixel with 2³² − 1 samples: a cancel checked only
        // between rows would not be seen for hours.
        let dir = tempfile::tempdir().unwrap();
        let one = GOOD.replace("width = 32\nheight = 18\nspp = 1", "width = 1\nheight = 1\nspp = 1");
        let many = ["-s", "4294967295", "--max-spp", "4294967295", "--partial"];
        let (mut child, err, seen) = start_scene(dir.path(), &one, &many);
        std::thread::sleep(Duration::from_millis(300));
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("after 0 of 1 rows") && err.contains("wrote the partial image"), "{err}");
        let img = image::open(dir.path().join("img.png")).expect("a valid PNG").to_rgb8();
        assert_eq!(img.as_raw(), &[0, 0, 0], "the pixel left midway is black, as rows not rendered are");
    }

    #[test]
    fn sigint_in_a_turntable_names_the_frame_and_the_frames_written() {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, mut err, mut seen) =
            start_scene(dir.path(), GOOD, &["--frames", "3", "-s", "20000", "--max-spp", "20000"]);
        // Frame 0 done: the second frame says it is rendering.
        assert!(read_until_started(&mut err, &mut seen), "{seen}");
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(
            err.contains("error: frame 1 (img.0001.png): interrupted (Ctrl-C) after")
                && err.contains(
                    "nothing was written (--partial writes the rows done); the frame before it was written"
                ),
            "{err}"
        );
        assert_eq!(listing(dir.path()), ["img.0000.png", "s.toml"]);
    }

    #[test]
    fn sigint_with_partial_writes_a_valid_image() {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, err, seen) = start(dir.path(), &["--partial"]);
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("wrote the partial image to img.png"), "{err}");
        let img = image::open(dir.path().join("img.png")).expect("a valid PNG").to_rgb8();
        assert_eq!((img.width(), img.height()), (8, 16384));
        assert_eq!(listing(dir.path()), ["img.png", "s.toml"], "no temporary file is left");
    }

    #[test]
    fn a_partial_exr_holds_the_image_alone_not_the_passes() {
        // The passes of rows not rendered would say "nothing hit" (depth
        // +inf, no object) where the scene has surfaces.
        let dir = tempfile::tempdir().unwrap();
        let (mut child, err, seen) = start_to(
            dir.path(),
            &endless_scene(),
            "img.exr",
            &["--partial", "--aov", "depth,object_id", "--alpha"],
        );
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("wrote the partial image to img.exr") && err.contains("no passes"), "{err}");
        let meta = exr::meta::MetaData::read_from_file(dir.path().join("img.exr"), false).expect("an EXR");
        let channels: Vec<String> =
            meta.headers[0].channels.list.iter().map(|c| c.name.to_string()).collect();
        assert_eq!(channels, ["A", "B", "G", "R"], "{err}");
        assert_eq!(listing(dir.path()), ["img.exr", "s.toml"], "no pass file and no temporary file");
    }

    #[test]
    fn sigterm_and_sighup_stop_the_render_as_sigint_does() {
        // What `kill`, `timeout`, Slurm and Kubernetes send, and what a
        // closing terminal sends: the render stops, nothing is written,
        // the folders it made go, and the status is 128 + the signal.
        for (sig, name, code) in [("-TERM", "SIGTERM", 143), ("-HUP", "SIGHUP", 129)] {
            let dir = tempfile::tempdir().unwrap();
            fs::create_dir(dir.path().join("keep")).unwrap();
            let (mut child, err, seen) =
                start_to(dir.path(), &endless_scene(), "keep/new/deeper/img.png", &[]);
            assert!(dir.path().join("keep/new/deeper").is_dir(), "made before the render");
            signal(&child, sig);
            let status = wait(&mut child);
            let err = rest(err, seen);
            assert_eq!(status.code(), Some(code), "{name}: {err}");
            assert!(
                err.contains(&format!("error: interrupted ({name}) after"))
                    && err.contains("nothing was written"),
                "{name}: {err}"
            );
            assert!(!err.contains("panicked"), "{err}");
            assert_eq!(listing(dir.path()), ["keep", "s.toml"], "{name}: {err}");
            assert!(listing(&dir.path().join("keep")).is_empty(), "{name}: no folder and no temporary file");
            // With --partial the rows done are written, under the same status.
            let (mut child, err, seen) = start(dir.path(), &["--partial"]);
            signal(&child, sig);
            let status = wait(&mut child);
            let err = rest(err, seen);
            assert_eq!(status.code(), Some(code), "{name}: {err}");
            assert!(err.contains("wrote the partial image to img.png"), "{name}: {err}");
            assert_eq!(listing(dir.path()), ["img.png", "keep", "s.toml"], "{name}: no temporary file");
        }
    }

    /// Sends `signals` (20 ms apart) to `child` once the temporary file of
    /// `img.exr` is in `folder` (the image is being written); whether it
    /// was seen within 30 s.
    fn signal_while_written(child: &mut Child, folder: &Path, signals: &[&str]) -> bool {
        let start = Instant::now();
        while child.try_wait().expect("wait").is_none() && start.elapsed() < Duration::from_secs(30) {
            if listing(folder).iter().any(|f| f.starts_with(".img.exr.") && f.ends_with(".tmp")) {
                for (k, sig) in signals.iter().enumerate() {
                    if k > 0 {
                        std::thread::sleep(Duration::from_millis(20));
                    }
                    signal(child, sig);
                }
                return true;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        false
    }

    #[test]
    fn sigterm_while_the_image_is_written_leaves_the_whole_image_and_no_temporary_file() {
        // A plain background at 2048×2048 renders in a moment and takes a
        // while to encode as EXR (48 MiB): the signal is sent once the
        // temporary file is there.
        let dir = tempfile::tempdir().unwrap();
        let scene = "[render]\nwidth = 2048\nheight = 2048\nspp = 1\nbackground = [0.2, 0.3, 0.4]\n\
                     [camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
        let (mut child, err, seen) = start_to(dir.path(), scene, "new/img.exr", &[]);
        let new = dir.path().join("new");
        let sent = signal_while_written(&mut child, &new, &["-TERM"]);
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert!(sent, "the temporary file was never seen: {err}");
        // The write is let finish, as for Ctrl-C.
        assert_eq!(status.code(), Some(0), "{err}");
        assert_eq!(listing(&new), ["img.exr"], "the image, and no temporary file: {err}");
        let img = image::open(new.join("img.exr")).expect("a whole EXR").to_rgb32f();
        assert_eq!((img.width(), img.height()), (2048, 2048));
    }

    #[test]
    fn a_second_signal_while_the_image_is_written_exits_and_leaves_the_old_image() {
        // As above, with the image there before: two signals while the
        // temporary file is written stop prism at once, and take the
        // temporary file away; the old image stays.
        let dir = tempfile::tempdir().unwrap();
        let scene = "[render]\nwidth = 2048\nheight = 2048\nspp = 1\nbackground = [0.2, 0.3, 0.4]\n\
                     [camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
        fs::create_dir(dir.path().join("new")).unwrap();
        let new = dir.path().join("new");
        fs::write(new.join("img.exr"), b"OLD").unwrap();
        let (mut child, err, seen) = start_to(dir.path(), scene, "new/img.exr", &[]);
        let sent = signal_while_written(&mut child, &new, &["-TERM", "-INT"]);
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert!(sent, "the temporary file was never seen: {err}");
        if status.code() == Some(0) {
            // The write finished between the two signals (a fast disk): the
            // new image, whole.
            let img = image::open(new.join("img.exr")).expect("a whole EXR").to_rgb32f();
            assert_eq!((img.width(), img.height()), (2048, 2048));
        } else {
            assert_eq!(status.code(), Some(130), "{err}");
            assert!(err.contains("Ctrl-C again: stopped at once"), "{err}");
            // The old file, or (the rename made before the second signal
            // came) the whole new one; never a part of it.
            let now = fs::read(new.join("img.exr")).unwrap();
            if now != b"OLD" {
                let img = image::open(new.join("img.exr")).expect("a whole EXR").to_rgb32f();
                assert_eq!((img.width(), img.height()), (2048, 2048), "{err}");
            }
        }
        assert_eq!(listing(&new), ["img.exr"], "no temporary file: {err}");
    }

    #[test]
    fn a_sighup_ignored_at_start_stays_ignored() {
        // `nohup prism render …`: the terminal closing does not stop it.
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("s.toml"), endless_scene()).unwrap();
        let mut child = std::process::Command::new("sh")
            .current_dir(dir.path())
            .args(["-c", "trap '' HUP; exec \"$0\" render s.toml -o img.png --threads 1"])
            .arg(env!("CARGO_BIN_EXE_prism"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start sh");
        let mut err = BufReader::new(child.stderr.take().expect("stderr"));
        let mut seen = String::new();
        assert!(read_until_started(&mut err, &mut seen), "{seen}");
        signal(&child, "-HUP");
        std::thread::sleep(Duration::from_millis(300));
        assert!(child.try_wait().expect("wait").is_none(), "SIGHUP stopped it: {seen}");
        signal(&child, "-INT");
        let status = wait(&mut child);
        let err = rest(err, seen);
        assert_eq!(status.code(), Some(130), "{err}");
        assert!(err.contains("interrupted (Ctrl-C)"), "{err}");
    }

    #[test]
    fn sigkill_mid_render_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, _err, _) = start(dir.path(), &["--partial"]);
        child.kill().expect("SIGKILL");
        let status = wait(&mut child);
        assert!(!status.success());
        // Nothing at the output path, and no `.img.png.<pid>.<n>.tmp` beside it.
        assert_eq!(listing(dir.path()), ["s.toml"]);
    }
}

/// Every kind of input, each named `*.png` so that the output name is a
/// valid one: the scene, an OBJ mesh, its MTL library and its texture
/// (also reached through a symbolic link and a `./` path). prism refuses
/// each and leaves every file as it was.
#[test]
fn a_render_that_fails_takes_away_the_folders_it_made() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    // Refused once the folders are made: statistics describe one frame.
    let args = ["render", "s.toml", "-o", "a/b/img.png", "--frames", "3", "--stats-json", "st/s.json"];
    let out = prism(dir.path(), &args);
    assert_clean_failure("--frames with --stats-json", &out);
    assert!(text(&out.stderr).contains("--stats-json describes one render"), "{}", text(&out.stderr));
    // 6000 × 6000 into an EXR fits the colour buffer but not the EXR
    // writer's copies (it passed the check and then aborted).
    let out = std::process::Command::new("bash")
        .current_dir(dir.path())
        .arg("-c")
        .arg(format!(
            "ulimit -v 1000000 && exec {} render s.toml -o new/big.exr --width 6000 --height 6000 --threads 1",
            env!("CARGO_BIN_EXE_prism")
        ))
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap();
    assert_clean_failure("EXR copies", &out);
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

#[test]
fn no_kind_of_input_is_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj = "mtllib lib.png\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n";
    fs::write(d.join("mesh.png"), obj).unwrap();
    fs::write(d.join("lib.png"), "newmtl m\nKd 1 1 1\nmap_Kd tex.png\n").unwrap();
    fs::write(d.join("tex.png"), png_bytes()).unwrap();
    let scene = format!("{GOOD}[[objects]]\ntype = \"mesh\"\npath = \"mesh.png\"\n");
    fs::write(d.join("scene.png"), &scene).unwrap();
    let mut targets = vec!["scene.png", "mesh.png", "lib.png", "tex.png", "./tex.png"];
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("tex.png", d.join("link.png")).unwrap();
        targets.push("link.png");
    }
    let before: Vec<(String, Vec<u8>)> =
        listing(d).into_iter().map(|n| (n.clone(), fs::read(d.join(&n)).unwrap())).collect();
    // The scene renders (every input is in use).
    let ok = prism(d, &["render", "scene.png", "-o", "out/ok.png", "--quiet"]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    fs::remove_dir_all(d.join("out")).unwrap();
    for target in targets {
        let out = prism(d, &["render", "scene.png", "-o", target]);
        assert_clean_failure(target, &out);
        let err = text(&out.stderr);
        assert!(err.contains("refusing to write the image over an input"), "{target}: {err}");
        let after: Vec<(String, Vec<u8>)> =
            listing(d).into_iter().map(|n| (n.clone(), fs::read(d.join(&n)).unwrap())).collect();
        assert!(after == before, "{target}: the files changed");
    }
}

/// A scene with reflection, refraction, texture-free shading and several
/// samples per pixel: every path the threads could disagree on.
fn busy_scene() -> String {
    GOOD.replace("width = 32\nheight = 18\nspp = 1", "width = 40\nheight = 24\nspp = 5\nmax_depth = 6")
        .replace(
            "color = [0.8, 0.1, 0.1]",
            "color = [0.8, 0.1, 0.1]\nreflectivity = 0.3\ntransmission = 0.5\nior = 1.5",
        )
}

#[test]
fn images_are_bit_identical_across_threads_and_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    fs::write(d.join("s.toml"), busy_scene()).unwrap();
    let mut pngs = Vec::new();
    let mut exrs = Vec::new();
    for (i, threads) in ["1", "2", "1", "2"].into_iter().enumerate() {
        for ext in ["png", "exr"] {
            let name = format!("r{i}.{ext}");
            let out = prism(d, &["render", "s.toml", "-o", &name, "--threads", threads, "--quiet"]);
            assert!(out.status.success(), "{}", text(&out.stderr));
            let bytes = fs::read(d.join(&name)).unwrap();
            if ext == "png" {
                pngs.push(bytes);
            } else {
                let px = image::open(d.join(&name)).unwrap().to_rgb32f();
                exrs.push(px.as_raw().iter().map(|f| f.to_bits()).collect::<Vec<u32>>());
            }
        }
    }
    assert!(pngs.iter().all(|p| *p == pngs[0]), "PNG bytes differ between runs or thread counts");
    assert!(exrs.iter().all(|p| *p == exrs[0]), "float pixels differ between runs or thread counts");
    // The image is not trivially uniform.
    assert!(exrs[0].iter().any(|&b| b != exrs[0][0]));
}

/// A render whose image buffers cannot fit is refused before it starts,
/// with what it needs and what limits it, not aborted by a failed
/// allocation ("memory allocation of N bytes failed", exit 134).
#[cfg(target_os = "linux")]
#[test]
fn a_render_too_large_for_memory_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    // Under `ulimit -v` (1 GB): 10000 × 10000 pixels with every pass need
    // about 20 GiB (their EXR's layers and the writer's copy of them, 11.2
    // GB, beside the colour and passes and the rows they came from).
    let out = std::process::Command::new("bash")
        .current_dir(dir.path())
        .arg("-c")
        .arg(format!(
            "ulimit -v 1000000 && exec {} render s.toml -o big.exr --width 10000 --height 10000 --aov all --threads 1",
            env!("CARGO_BIN_EXE_prism")
        ))
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap();
    assert_clean_failure("ulimit -v", &out);
    let err = text(&out.stderr);
    assert!(err.contains("needs about 19.8 GiB for its image buffers") && err.contains("ulimit -v"), "{err}");
    assert_eq!(out.status.code(), Some(1), "{err}");
    // More than any machine here holds in memory and swap (12 TB of
    // colour alone), limits raised to let it through.
    let out = prism(
        dir.path(),
        &[
            "render",
            "s.toml",
            "-o",
            "huge.png",
            "--width",
            "1000000",
            "--height",
            "1000000",
            "--max-side",
            "1000000",
            "--max-pixels",
            "1000000000000",
            "--threads",
            "1",
        ],
    );
    assert_clean_failure("machine", &out);
    let err = text(&out.stderr);
    assert!(err.contains("more than this machine's"), "{err}");
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

/// `prism render s.toml ARGS --threads 1` under `ulimit -v LIMIT_KIB` in `dir`.
#[cfg(target_os = "linux")]
fn render_under_ulimit(dir: &Path, limit_kib: u64, args: &str) -> std::process::Output {
    std::process::Command::new("bash")
        .current_dir(dir)
        .arg("-c")
        .arg(format!(
            "ulimit -v {limit_kib} && exec {} render s.toml {args} --threads 1 --quiet",
            env!("CARGO_BIN_EXE_prism")
        ))
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap()
}

/// `--alpha` and AOV renders count every buffer they hold at once: the
/// per-row sinks their passes and coverage are gathered from, the beauty
/// beside them, the rows' memory while the files are written. Left out,
/// these two passed the check and, after rendering, aborted on a failed
/// allocation (exit 134, nothing written).
#[cfg(target_os = "linux")]
#[test]
fn alpha_and_aov_renders_are_refused_with_what_they_hold() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    for (limit_kib, args) in [
        // Needs about 1.4 GiB, and its threads' address space (the
        // estimate was 0.7 GiB).
        (1_030_000, "-o a16.png --width 6000 --height 4000 --alpha --bit-depth 16"),
        // Needs about 2.3 GiB, and its threads' address space (the
        // estimate was 1.9 GiB).
        (2_250_000, "-o dn.exr --width 6000 --height 4000 --aov depth,normal"),
    ] {
        let out = render_under_ulimit(dir.path(), limit_kib, args);
        assert_clean_failure(args, &out);
        let err = text(&out.stderr);
        assert!(err.contains("needs about") && err.contains("ulimit -v"), "{args}: {err}");
        assert_eq!(out.status.code(), Some(1), "{args}: {err}");
    }
    assert_eq!(listing(dir.path()), ["s.toml"]);
}

/// Under any address-space limit a render with every buffer (alpha, every
/// pass, a layered EXR) is either refused up front or finishes: no limit
/// lets it start and then abort (exit 134). The limits rise by 50 MB from
/// the least under which a 1 × 1 render of the scene finishes (what the
/// process and its threads take before any image, which depends on the
/// machine's cores) until the render has finished three times.
#[cfg(target_os = "linux")]
#[test]
fn under_any_limit_a_render_is_refused_or_finishes() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), GOOD).unwrap();
    let tiny = "-o one.exr --width 1 --height 1";
    let start = (2..=160)
        .map(|k| k * 100_000)
        .find(|&kib| render_under_ulimit(dir.path(), kib, tiny).status.success())
        .expect("a 1 × 1 render finishes under some limit up to 16 GB");
    let args = "-o all.exr --width 1200 --height 800 --alpha --aov all";
    let (mut refused, mut finished, mut kib) = (0, 0, start);
    while finished < 3 {
        let out = render_under_ulimit(dir.path(), kib, args);
        let err = text(&out.stderr);
        match out.status.code() {
            Some(0) => finished += 1,
            Some(1) if err.contains("needs about") => refused += 1,
            code => panic!("under ulimit -v {kib} KiB: exit {code:?}\n{err}"),
        }
        let _ = fs::remove_file(dir.path().join("all.exr"));
        kib += 50_000;
        assert!(kib < start + 4_000_000, "still refused 4 GB above the 1 × 1 render's limit: {err}");
    }
    // The render's buffers need more than the 1 × 1 render's.
    assert!(refused > 0, "{refused} refused, {finished} finished");
}

/// Image textures that cannot fit in the memory left are refused from
/// their headers, before their pixels are decoded, naming the file and the
/// limit; not aborted mid-load by a failed allocation (exit 134), nor
/// panicked on by the image decoder's conversions (exit 101).
#[cfg(target_os = "linux")]
#[test]
fn a_texture_too_large_for_memory_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    // 8192 × 4096 black texels: a 100 MB decode into 400 MB of linear
    // texels, and their mip-map; the file itself is small.
    image::RgbImage::new(8192, 4096).save(dir.path().join("big.png")).unwrap();
    let scene = GOOD.replace("color = [0.8, 0.1, 0.1]", "texture = { type = \"image\", path = \"big.png\" }");
    fs::write(dir.path().join("s.toml"), scene).unwrap();
    let run = |limit_kib: u64| {
        std::process::Command::new("bash")
            .current_dir(dir.path())
            .arg("-c")
            .arg(format!(
                "ulimit -v {limit_kib} && exec {} render s.toml -o out.png --threads 1",
                env!("CARGO_BIN_EXE_prism")
            ))
            .env_remove("RUST_BACKTRACE")
            .output()
            .unwrap()
    };
    // Under 300 MB of address space.
    let out = run(300_000);
    assert_clean_failure("ulimit -v", &out);
    let err = text(&out.stderr);
    assert!(
        err.contains("big.png") && err.contains("8192×4096 texels need about") && err.contains("ulimit -v"),
        "{err}"
    );
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!dir.path().join("out.png").exists());
    // With room for it, the same scene renders.
    let out = run(4_000_000);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("out.png").exists());
}
