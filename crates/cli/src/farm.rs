//! `prism farm slurm`: a render split over a Slurm cluster. Slurm does the
//! scheduling, retries and accounting; prism splits the work and
//! assembles the result. One job array renders the tiles (`prism render
//! --tile-from-env N`) or the frames (`--frame-from-env`); for tiles, a
//! merge job that depends on it (`--dependency=afterok`) runs `prism
//! merge`. Every task writes its exit status to the work directory, so
//! that `--wait` can name failed tasks without Slurm's accounting
//! database. See `docs/farm.md`.

use crate::overwrite::{Output, check_not_an_input};
use crate::tile::INDEX_VARIABLES;
use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand};
use prism_scene::{LoadOptions, Overrides, load_path};
use prism_shade::{Aov, PixelBounds};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

#[derive(Args)]
pub struct FarmArgs {
    #[command(subcommand)]
    pub scheduler: Scheduler,
}

#[derive(Subcommand)]
pub enum Scheduler {
    /// Submit a Slurm job array (one task per tile or frame) and, for tiles, a merge job.
    Slurm(SlurmArgs),
}

#[derive(Args)]
pub struct SlurmArgs {
    /// The scene file; it and every file it reads must be on a filesystem the nodes share.
    scene: PathBuf,
    /// Split the image into N tiles (bands of rows), one task each, then merge them.
    #[arg(long, value_name = "N", required_unless_present = "frames", conflicts_with = "frames")]
    tiles: Option<u32>,
    /// Render an N-frame turntable, one task per frame, to OUT.####.png.
    #[arg(long, value_name = "N")]
    frames: Option<u32>,
    /// Degrees the camera turns over the --frames sequence [default: 360].
    #[arg(long, value_name = "DEGREES", requires = "frames", allow_hyphen_values = true)]
    orbit: Option<f32>,
    /// The merged image (.png or .exr), or the frames' name pattern.
    #[arg(short, long, value_name = "OUT")]
    output: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// AOV passes, as for `prism render --aov` (written next to the merged image).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Also write an 8-bit PNG preview of each AOV pass (OUT-stem.PASS.png), as for
    /// `prism render --aov-preview`: by the merge job for tiles, by each task for frames.
    #[arg(long)]
    aov_preview: bool,
    /// Replace a scene value by its dotted path, as for `prism render --set` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    #[command(flatten)]
    obj: crate::ObjArgs,
    #[command(flatten)]
    limits: crate::LimitArgs,
    #[command(flatten)]
    alpha: crate::outputs::AlphaArgs,
    #[command(flatten)]
    image: crate::outputs::ImageArgs,
    /// Where the scripts, tiles, logs and task statuses go (shared by the nodes)
    /// [default: OUT-stem.farm next to OUT].
    #[arg(long, value_name = "DIR")]
    work_dir: Option<PathBuf>,
    /// Block until the job has finished; exit non-zero naming failed tasks.
    #[arg(long)]
    wait: bool,
    /// Print the scripts and the sbatch commands; submit nothing, write nothing.
    #[arg(long)]
    dry_run: bool,
    /// Skip the check that the files are on a shared filesystem.
    #[arg(long)]
    no_shared_check: bool,
    /// Arguments for sbatch (partition, time, account...), after `--`.
    #[arg(last = true, value_name = "SBATCH_ARGS")]
    sbatch_args: Vec<String>,
}

/// Runs `prism farm`.
pub fn farm_command(args: &FarmArgs) -> Result<()> {
    match &args.scheduler {
        Scheduler::Slurm(a) => slurm(a),
    }
}

/// The `prism render` flags that carry `o`, `aov` and `limits` to a task,
/// so that it renders what this process loaded: every field of
/// [`Overrides`] that is set, and the limits.
pub fn render_flags(o: &Overrides, aov: Option<&str>, limits: &crate::LimitArgs) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    let mut push = |flag: &str, value: Option<String>| {
        if let Some(value) = value {
            v.push(flag.to_owned());
            v.push(value);
        }
    };
    let vec3 = |p: Option<prism_geometry::glam::Vec3>| p.map(vec3_flag);
    push("--width", o.width.map(|x| x.to_string()));
    push("--height", o.height.map(|x| x.to_string()));
    push("--spp", o.spp.map(|x| x.to_string()));
    push("--max-depth", o.max_depth.map(|x| x.to_string()));
    push("--threads", o.threads.map(|x| x.to_string()));
    push("--camera-pos", vec3(o.camera_pos));
    push("--look-at", vec3(o.look_at));
    push("--up", vec3(o.up));
    push("--fov", o.fov.map(|x| x.to_string()));
    push("--filter", o.filter.map(|f| f.name().to_owned()));
    push("--adaptive", o.adaptive.map(|x| x.to_string()));
    push("--camera", o.camera.map(|c| c.to_string()));
    push("--aov", aov.map(str::to_owned));
    push("--max-side", Some(limits.max_side.to_string()));
    push("--max-pixels", Some(limits.max_pixels.to_string()));
    push("--max-spp", Some(limits.max_spp.to_string()));
    match o.fog {
        Some(true) => v.push("--fog".into()),
        Some(false) => v.push("--no-fog".into()),
        None => {}
    }
    v
}

/// `X,Y,Z` as a vector flag takes it (shortest round-trip forms).
fn vec3_flag(p: prism_geometry::glam::Vec3) -> String {
    format!("{},{},{}", p.x, p.y, p.z)
}

/// The `prism render` flags that carry `--set` and OBJ mode's choices to a task.
fn scene_flags(sets: &[String], obj: &crate::ObjArgs) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for s in sets {
        v.push("--set".into());
        v.push(s.clone());
    }
    if let Some(view) = obj.view.and_then(|view| clap::ValueEnum::to_possible_value(&view)) {
        v.push("--view".into());
        v.push(view.get_name().to_owned());
    }
    if let Some(p) = obj.light {
        v.push("--light".into());
        v.push(vec3_flag(p));
    }
    if obj.floor {
        v.push("--floor".into());
    }
    v
}

/// `s` quoted for a POSIX shell.
fn sh(s: &str) -> String {
    if !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b"-_./,=:+%@".contains(&b)) {
        s.to_owned()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// `p` as a part of a Slurm file name pattern (`--output`), where `%`
/// starts a replacement (`%j`, `%a`) and `%%` is a `%`. A name with a
/// backslash is no pattern to Slurm (nothing is replaced, `%a` stays as
/// written) and loses its single backslashes, so each is doubled there
/// (and doubled again on the `#SBATCH` line, [`sbatch_arg`]: checked
/// against Slurm 22.05).
fn slurm_literal(p: &Path) -> String {
    let p = p.to_string_lossy();
    if p.contains('\\') { p.replace('\\', r"\\") } else { p.replace('%', "%%") }
}

/// `arg` as the argument of an `#SBATCH` directive: quoted as for the
/// shell ([`sh`]), and each backslash doubled, since sbatch's directive
/// parser takes a backslash as an escape even inside quotes (`--chdir`
/// of `w\x` reached Slurm as `wx`, and no task ran).
fn sbatch_arg(arg: &str) -> String {
    sh(&arg.replace('\\', r"\\"))
}

/// Refuses a path with a line break (`\n` or `\r`), named `what` (the flag
/// or argument it came from). The job scripts hold paths on `#SBATCH`
/// comment lines, where no quoting can keep a line break: the rest of the
/// path would become a shell command of the job, and sbatch would stop
/// reading its directives there.
fn check_script_path(what: &str, p: &Path) -> Result<()> {
    if p.as_os_str().as_encoded_bytes().iter().any(|b| matches!(b, b'\n' | b'\r')) {
        bail!(
            "{what}: the path {:?} contains a line break, which a Slurm batch script cannot hold",
            p.as_os_str()
        );
    }
    Ok(())
}

fn absolute(p: &Path) -> Result<PathBuf> {
    Ok(if p.is_absolute() { p.to_path_buf() } else { std::env::current_dir()?.join(p) })
}

/// The job: what each task runs and where everything goes.
struct Job {
    /// Tiles (`true`) or frames.
    tiles: bool,
    count: u32,
    work: PathBuf,
    output: PathBuf,
    tile_files: Vec<PathBuf>,
}

impl Job {
    fn status(&self, name: &str) -> PathBuf {
        self.work.join("status").join(name)
    }
    fn task_status(&self, i: u32) -> PathBuf {
        self.status(&format!("task-{i}"))
    }
}

/// The script of the job array: each task runs `command` with its index
/// and records its exit status.
fn tasks_script(job: &Job, command: &str) -> String {
    let w = &job.work;
    let mut s = String::from("#!/bin/bash\n");
    let _ = writeln!(s, "#SBATCH --job-name=prism-{}", if job.tiles { "tiles" } else { "frames" });
    let _ = writeln!(s, "#SBATCH --array=0-{}", job.count - 1);
    let _ = writeln!(s, "#SBATCH --output={}", sbatch_arg(&format!("{}/logs/task-%a.log", slurm_literal(w))));
    let _ = writeln!(s, "#SBATCH --chdir={}", sbatch_arg(&w.to_string_lossy()));
    let _ = writeln!(s, "# The task index: Slurm's array index (or a Kubernetes Indexed Job's).");
    let _ = writeln!(s, "i=${{{}:-${}}}", INDEX_VARIABLES[0], INDEX_VARIABLES[1]);
    let _ = writeln!(s, "{command}");
    let _ = writeln!(s, "rc=$?");
    let _ = writeln!(s, "echo $rc > {}/task-$i", sh(&w.join("status").to_string_lossy()));
    s.push_str("exit $rc\n");
    s
}

fn merge_script(job: &Job, prism: &str, image_flags: &[String]) -> String {
    let w = &job.work;
    let mut s = String::from("#!/bin/bash\n#SBATCH --job-name=prism-merge\n");
    let _ = writeln!(s, "#SBATCH --output={}", sbatch_arg(&format!("{}/logs/merge.log", slurm_literal(w))));
    let _ = writeln!(s, "#SBATCH --chdir={}", sbatch_arg(&w.to_string_lossy()));
    let tiles: Vec<String> = job.tile_files.iter().map(|t| sh(&t.to_string_lossy())).collect();
    let _ = writeln!(
        s,
        "{} merge {} -o {}{}",
        sh(prism),
        tiles.join(" "),
        sh(&job.output.to_string_lossy()),
        image_flags.iter().map(|f| format!(" {f}")).collect::<String>()
    );
    let _ = writeln!(s, "rc=$?");
    let _ = writeln!(s, "echo $rc > {}", sh(&job.status("merge").to_string_lossy()));
    s.push_str("exit $rc\n");
    s
}

/// Filesystem types whose files only this machine sees.
const LOCAL_FS: [&str; 10] =
    ["tmpfs", "ramfs", "ext2/ext3", "xfs", "btrfs", "overlayfs", "zfs", "f2fs", "squashfs", "devtmpfs"];

/// The filesystem type of `path` (as `stat -f` names it), if it can be told.
fn fs_type(path: &Path) -> Option<String> {
    let out = Command::new("stat").args(["-f", "-c", "%T"]).arg(path).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// The number of nodes Slurm knows, if `sinfo` answers.
fn node_count() -> Option<u32> {
    let out = Command::new("sinfo").args(["-h", "-o", "%D"]).output().ok()?;
    out.status.success().then(|| {
        String::from_utf8_lossy(&out.stdout).lines().filter_map(|l| l.trim().parse::<u32>().ok()).sum()
    })
}

/// The cheap shared-filesystem check: on a cluster of several nodes, no
/// file a task reads or writes may lie on a filesystem local to this
/// machine (tmpfs, ext4, xfs...). Returns a note for the user.
fn shared_check(paths: &[PathBuf]) -> Result<String> {
    let nodes = node_count();
    let mut local = Vec::new();
    for p in paths {
        let existing = p.ancestors().find(|a| a.exists()).unwrap_or(p);
        if let Some(t) = fs_type(existing)
            && LOCAL_FS.contains(&t.as_str())
        {
            local.push(format!("{} ({t})", p.display()));
        }
    }
    match nodes {
        Some(n) if n > 1 && !local.is_empty() => bail!(
            "the cluster has {n} nodes, but these files are on a filesystem local to this machine, which other nodes cannot read: {}; \
             put the scene, its files, prism and the work directory on a shared filesystem (or pass --no-shared-check)",
            local.join(", ")
        ),
        Some(n) => Ok(format!("shared-filesystem check: {} paths, {n} node(s){}", paths.len(),
            if local.is_empty() { String::new() } else { format!("; local filesystem (fine on one node): {}", local.join(", ")) })),
        None => Ok("shared-filesystem check: sinfo did not answer, so the node count is unknown; the files must be visible to every node at the same paths".into()),
    }
}

fn slurm(a: &SlurmArgs) -> Result<()> {
    if prism_scene::is_stdin_path(&a.scene) {
        bail!("a farm job needs its scene in a file (every task reads it), not on standard input");
    }
    // Every path the scripts hold, as they will hold it (absolute: the
    // current directory is part of it), before the (possibly long) load.
    check_script_path("the scene", &absolute(&a.scene)?)?;
    check_script_path("-o", &absolute(&a.output)?)?;
    if let Some(d) = &a.work_dir {
        check_script_path("--work-dir", &absolute(d)?)?;
    }
    // Checked here so that a bad list fails before anything is submitted.
    let aov_flag = a.aov.as_deref().map(Aov::parse_list).transpose().map_err(|e| anyhow!("--aov: {e}"))?;
    let opts = LoadOptions {
        limits: a.limits.limits(),
        overrides: a.overrides,
        sets: a.set.clone(),
        obj: a.obj.options(),
    };
    let loaded = load_path(&a.scene, &opts)?;
    let (w, h) = loaded.settings.camera.size();
    let (tiles, count) = match (a.tiles, a.frames) {
        (Some(n), _) => {
            PixelBounds::tile(w, h, 0, n).map_err(|e| anyhow!("--tiles {n}: {e}"))?;
            (true, n)
        }
        (None, Some(n)) if n > 0 => (false, n),
        _ => bail!("--frames 0: a turntable needs at least 1 frame"),
    };
    if a.orbit.is_some() && a.frames.is_none() {
        // clap's `requires` lets it through beside --tiles.
        bail!("--orbit turns the camera over a turntable's frames; give --frames N (tiles do not orbit)");
    }
    crate::frames::check_orbit(a.orbit.unwrap_or(360.0))?;
    let output = absolute(&a.output)?;
    prism_shade::OutputFormat::from_path(&output)?;
    check_not_an_input(&output, &loaded.inputs)?;
    let scene = std::fs::canonicalize(&a.scene).with_context(|| format!("{}", a.scene.display()))?;
    let work = match &a.work_dir {
        Some(d) => absolute(d)?,
        None => {
            let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            output.with_file_name(format!("{stem}.farm"))
        }
    };
    let prism =
        std::env::current_exe().and_then(std::fs::canonicalize).context("cannot find the prism binary")?;
    // Reached through links: what the scripts hold.
    check_script_path("the scene", &scene)?;
    check_script_path("the prism binary", &prism)?;
    let prism = prism.to_string_lossy().into_owned();
    let tile_files = if tiles {
        (0..count).map(|i| work.join(format!("tiles/tile-{i:04}.exr"))).collect()
    } else {
        Vec::new()
    };
    let job = Job { tiles, count, work, output, tile_files };
    // The checks of a real run, made for a dry run too: where the image
    // (or the first frame) goes, and the work directory, can be written.
    let first = if tiles { job.output.clone() } else { crate::frames::frame_path(&job.output, 0, count) };
    crate::writable::check_writable(&first, Output::Image)?;
    // A later frame's name taken by an input or a folder would fail only
    // its own task, on the cluster.
    if !tiles {
        for f in crate::frames::existing_frames(&job.output, count) {
            check_not_an_input(&f, &loaded.inputs)?;
        }
    }
    let scripts = crate::writable::check_writable(&job.work.join("tasks.sbatch"), Output::Scripts);
    match &a.work_dir {
        Some(_) => scripts.context("--work-dir")?,
        None => scripts?,
    }

    if tiles && a.alpha.alpha {
        bail!("--alpha: tiles hold no alpha; render the whole image (--frames, or prism render) for it");
    }
    let mut flags = render_flags(&a.overrides, a.aov.as_deref(), &a.limits);
    flags.extend(scene_flags(&a.set, &a.obj));
    // The previews asked for by the flag or the scene's `aov_preview`; a
    // tile holds none, so for tiles the merge writes them.
    let previews = a.aov_preview || loaded.aov_preview;
    if previews && aov_flag.as_ref().unwrap_or(&loaded.aovs).is_empty() {
        let asked = if a.aov_preview {
            "--aov-preview".to_owned()
        } else {
            format!("{}: `aov_preview = true`", a.scene.display())
        };
        errln!("warning: {asked} without AOV passes (--aov or the scene's `aov`) writes no previews");
    }
    // The image flags go to whoever writes the image: each frame's task, or the merge.
    let mut image_flags: Vec<String> = a.image.flags().iter().map(|f| sh(f)).collect();
    if tiles && previews {
        image_flags.push("--aov-preview".to_owned());
    }
    if !tiles {
        if a.alpha.alpha {
            flags.push("--alpha".to_owned());
        }
        if a.aov_preview {
            flags.push("--aov-preview".to_owned());
        }
        flags.extend(a.image.flags());
    }
    let flags: Vec<String> = flags.iter().map(|f| sh(f)).collect();
    let command = if tiles {
        format!(
            "{} render {} -q --tile-from-env {count} -o {}/tile-$(printf %04d \"$i\").exr {}",
            sh(&prism),
            sh(&scene.to_string_lossy()),
            sh(&job.work.join("tiles").to_string_lossy()),
            flags.join(" ")
        )
    } else {
        format!(
            "{} render {} -q --frames {count} --orbit {} --frame-from-env -o {} {}",
            sh(&prism),
            sh(&scene.to_string_lossy()),
            a.orbit.unwrap_or(360.0),
            sh(&job.output.to_string_lossy()),
            flags.join(" ")
        )
    };
    let tasks = tasks_script(&job, &command);
    let merge = tiles.then(|| merge_script(&job, &prism, &image_flags));

    let mut shared: Vec<PathBuf> = loaded.inputs.clone();
    shared.push(PathBuf::from(&prism));
    shared.push(job.work.clone());
    shared.push(job.output.clone());
    let note = if a.no_shared_check {
        "shared-filesystem check skipped (--no-shared-check)".to_owned()
    } else {
        shared_check(&shared)?
    };
    let sbatch_extra: Vec<String> = a.sbatch_args.iter().map(|s| sh(s)).collect();
    if a.dry_run {
        outln!("# {note}");
        outln!("# {}:\n{tasks}", job.work.join("tasks.sbatch").display());
        if let Some(m) = &merge {
            outln!("# {}:\n{m}", job.work.join("merge.sbatch").display());
        }
        outln!("# submit with:");
        outln!(
            "sbatch --parsable {} {}",
            sbatch_extra.join(" "),
            sh(&job.work.join("tasks.sbatch").to_string_lossy())
        );
        if merge.is_some() {
            outln!(
                "sbatch --parsable --dependency=afterok:ARRAY_JOB_ID {} {}",
                sbatch_extra.join(" "),
                sh(&job.work.join("merge.sbatch").to_string_lossy())
            );
        }
        return Ok(());
    }
    // Before anything is written: a run that cannot submit leaves nothing.
    if find_program("sbatch").is_none() {
        bail!(
            "cannot submit: sbatch is not on the PATH (is Slurm installed here?); nothing was written \
             (--dry-run prints the scripts)"
        );
    }
    errln!("{note}");
    for d in ["tiles", "logs", "status"] {
        let dir = job.work.join(d);
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    if let Some(dir) = job.output.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    // Statuses of an earlier run of the same job would be read as this one's.
    for p in (0..count).map(|i| job.task_status(i)).chain([job.status("merge")]) {
        match std::fs::remove_file(&p) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("cannot remove the old status {}", p.display()));
            }
            _ => {}
        }
    }
    let tasks_path = job.work.join("tasks.sbatch");
    std::fs::write(&tasks_path, &tasks).with_context(|| format!("cannot write {}", tasks_path.display()))?;
    let array_id = sbatch(&a.sbatch_args, None, &tasks_path)?;
    let merge_id = match &merge {
        Some(m) => {
            let merge_path = job.work.join("merge.sbatch");
            let submitted = std::fs::write(&merge_path, m)
                .with_context(|| format!("cannot write {}", merge_path.display()))
                .and_then(|()| sbatch(&a.sbatch_args, Some(&array_id), &merge_path));
            match submitted {
                Ok(id) => Some(id),
                Err(e) => {
                    let _ = Command::new("scancel").arg(&array_id).status();
                    return Err(e.context(format!("job array {array_id} cancelled")));
                }
            }
        }
        None => None,
    };
    let what = if tiles { format!("{count} tiles") } else { format!("{count} frames") };
    outln!("submitted job array {array_id} ({what})");
    if let Some(m) = &merge_id {
        outln!("submitted merge job {m} (after {array_id} succeeds)");
    }
    let out_name = if tiles {
        job.output.clone()
    } else {
        job.output.with_file_name(format!("{}.####.{}", stem(&job.output), ext(&job.output)))
    };
    outln!("output: {}", out_name.display());
    if a.wait {
        wait(&job, &array_id, merge_id.as_deref())?;
        outln!("done: {}", out_name.display());
    }
    Ok(())
}

fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}
fn ext(p: &Path) -> String {
    p.extension().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The file `name` names on the `PATH`, as a shell would find it to run
/// it (on Unix, a file with an execute bit).
fn find_program(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| {
        let Ok(m) = std::fs::metadata(p) else { return false };
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            m.is_file() && m.permissions().mode() & 0o111 != 0
        }
        #[cfg(not(unix))]
        {
            m.is_file()
        }
    })
}

/// `sbatch --parsable [--dependency=afterok:AFTER] EXTRA SCRIPT`: the job id.
fn sbatch(extra: &[String], after: Option<&str>, script: &Path) -> Result<String> {
    let mut c = Command::new("sbatch");
    c.arg("--parsable");
    if let Some(id) = after {
        c.arg(format!("--dependency=afterok:{id}"));
    }
    c.args(extra).arg(script);
    let out = c.output().context("cannot run sbatch (is Slurm installed here?)")?;
    if !out.status.success() {
        bail!("sbatch {} failed: {}", script.display(), String::from_utf8_lossy(&out.stderr).trim());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_owned();
    if id.is_empty() {
        bail!("sbatch {} printed no job id", script.display());
    }
    Ok(id)
}

/// Whether Slurm still lists job `id` (pending, running or completing).
fn job_active(id: &str) -> Result<bool> {
    let mut last = String::new();
    for _ in 0..5 {
        let out = Command::new("squeue")
            .args(["-h", "-o", "%i", "-j", id])
            .output()
            .context("cannot run squeue")?;
        let err = String::from_utf8_lossy(&out.stderr);
        if out.status.success() {
            return Ok(!String::from_utf8_lossy(&out.stdout).trim().is_empty());
        }
        if err.contains("Invalid job id") {
            return Ok(false);
        }
        last = err.trim().to_owned();
        std::thread::sleep(Duration::from_secs(2));
    }
    bail!("squeue cannot tell the state of job {id}: {last}")
}

fn read_status(p: &Path) -> Option<i32> {
    std::fs::read_to_string(p).ok()?.trim().parse().ok()
}

/// Blocks until the job array (and the merge job) have finished; fails
/// naming the tasks that did not succeed (a non-zero status, or none:
/// killed, timed out, node lost), cancelling the merge job then.
fn wait(job: &Job, array_id: &str, merge_id: Option<&str>) -> Result<()> {
    let poll = Duration::from_millis(500);
    while job_active(array_id)? {
        std::thread::sleep(poll);
    }
    let failed: Vec<String> = (0..job.count)
        .filter_map(|i| match read_status(&job.task_status(i)) {
            Some(0) => None,
            Some(rc) => Some(format!("{i} (exit status {rc})")),
            None => Some(format!("{i} (no status: killed, timed out or never ran)")),
        })
        .collect();
    if !failed.is_empty() {
        if let Some(m) = merge_id {
            let _ = Command::new("scancel").arg(m).status();
        }
        let what = if job.tiles {
            "no merged output was written; merge job cancelled"
        } else {
            "the other frames were written"
        };
        bail!(
            "job {array_id}: {} of {} tasks failed: {}; logs in {}; {what}",
            failed.len(),
            job.count,
            failed.join(", "),
            job.work.join("logs").display()
        );
    }
    let Some(merge_id) = merge_id else { return Ok(()) };
    while job_active(merge_id)? {
        std::thread::sleep(poll);
    }
    match read_status(&job.status("merge")) {
        Some(0) => Ok(()),
        other => bail!(
            "merge job {merge_id} failed ({}); see {}",
            other.map_or("no status".to_owned(), |rc| format!("exit status {rc}")),
            job.work.join("logs/merge.log").display()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_quoting_keeps_every_byte() {
        assert_eq!(sh("a/b-c.exr"), "a/b-c.exr");
        assert_eq!(sh("it's here"), r"'it'\''s here'");
        assert_eq!(sh(""), "''");
        assert_eq!(sh("$HOME"), "'$HOME'");
        assert_eq!(slurm_literal(Path::new("/w/50%j.farm")), "/w/50%%j.farm");
    }

    /// sbatch's reading of one `#SBATCH` argument (`_get_argument` in its
    /// `opt.c`): a backslash escapes the next character anywhere, even
    /// inside quotes; quotes group; an unquoted space or `#` ends it.
    fn sbatch_reads(line: &str) -> String {
        let (mut out, mut quote, mut escape) = (String::new(), None, false);
        for c in line.chars() {
            if escape {
                escape = false;
            } else if c == '\\' {
                escape = true;
                continue;
            } else if let Some(q) = quote {
                if c == q {
                    quote = None;
                    continue;
                }
            } else if c == '"' || c == '\'' {
                quote = Some(c);
                continue;
            } else if c.is_whitespace() || c == '#' {
                break;
            }
            out.push(c);
        }
        out
    }

    #[test]
    fn sbatch_directives_keep_every_byte_of_a_path() {
        for p in [r"/w/a\x", r"/w/it's \ here", "/w/plain", r"/w/\\two", "/w/#hash", "/w/\"q\""] {
            assert_eq!(sbatch_reads(&sbatch_arg(p)), p, "{}", sbatch_arg(p));
        }
        let job = Job {
            tiles: true,
            count: 2,
            work: PathBuf::from(r"/w/a\x"),
            output: PathBuf::from("/w/o.png"),
            tile_files: Vec::new(),
        };
        let script = tasks_script(&job, "true");
        let chdir = script.lines().find_map(|l| l.strip_prefix("#SBATCH --chdir=")).unwrap();
        assert_eq!(sbatch_reads(chdir), r"/w/a\x");
        let output = script.lines().find_map(|l| l.strip_prefix("#SBATCH --output=")).unwrap();
        // Slurm's file name then loses one backslash of each pair (and
        // takes `%a` as written: every task logs to one file).
        assert_eq!(sbatch_reads(output), r"/w/a\\x/logs/task-%a.log");
        assert_eq!(slurm_literal(Path::new("/w/50%j.farm")), "/w/50%%j.farm");
        assert_eq!(slurm_literal(Path::new(r"/w/5%\j")), r"/w/5%\\j");
    }

    #[test]
    fn tasks_get_every_render_option_back() {
        use clap::Parser;
        use prism_geometry::glam::Vec3;
        let o = Overrides {
            width: Some(640),
            height: Some(360),
            spp: Some(9),
            max_depth: Some(3),
            threads: Some(2),
            fog: Some(false),
            camera_pos: Some(Vec3::new(0.1, -2.5, 1e-7)),
            look_at: Some(Vec3::new(1.0 / 3.0, 0.0, -0.0)),
            up: Some(Vec3::new(0.0, 1.0, 0.25)),
            fov: Some(33.3),
            filter: Some(prism_shade::PixelFilter::BlackmanHarris),
            adaptive: Some(0.05),
            camera: prism_scene::CameraName::new("top view").ok(),
        };
        let limits = crate::LimitArgs { max_side: 100, max_pixels: 5000, max_spp: 10 };
        let flags = render_flags(&o, Some("depth,albedo"), &limits);
        let cli = crate::Cli::try_parse_from(
            [&["prism", "render", "s.toml"][..], &flags.iter().map(String::as_str).collect::<Vec<_>>()]
                .concat(),
        )
        .unwrap();
        let crate::Command::Render(r) = cli.command else { panic!("not render") };
        assert_eq!(r.overrides, o);
        assert_eq!(r.aov.as_deref(), Some("depth,albedo"));
        assert_eq!(r.limits.limits(), limits.limits());
        let none = render_flags(&Overrides::default(), None, &limits);
        assert_eq!(none.len(), 6, "{none:?}");
        // --set and OBJ mode's choices come back too.
        let sets = vec!["render.spp=3".to_owned(), "objects.0.radius=0.1".to_owned()];
        let obj = crate::ObjArgs {
            view: Some(prism_scene::ObjView::Iso),
            light: Some(Vec3::new(-0.5, 1e-7, 3.25)),
            floor: true,
        };
        let flags = scene_flags(&sets, &obj);
        let cli = crate::Cli::try_parse_from(
            [&["prism", "render", "m.obj"][..], &flags.iter().map(String::as_str).collect::<Vec<_>>()]
                .concat(),
        )
        .unwrap();
        let crate::Command::Render(r) = cli.command else { panic!("not render") };
        assert_eq!(r.set, sets);
        assert_eq!(r.obj.options(), obj.options());
        assert!(scene_flags(&[], &crate::ObjArgs { view: None, light: None, floor: false }).is_empty());
    }
}
