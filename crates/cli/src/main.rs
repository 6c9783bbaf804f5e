//! `prism`: render scene files to PNG or EXR, and describe them.
//!
//! ```text
//! prism render SCENE [-o OUT] [--width W] [--height H] [--spp N] [--fog | --no-fog]
//!                    [--threads N] [--max-depth N] [--quiet]
//!                    [--aov LIST] [--aov-preview] [--aov-files] [--stats-json FILE]
//!                    [--alpha] [--bit-depth 8|16] [--exposure EV] [--tonemap clamp|reinhard|aces]
//!                    [--camera NAME] [--camera-pos X,Y,Z] [--look-at X,Y,Z] [--up X,Y,Z] [--fov DEGREES]
//!                    [--filter box|gaussian|blackman-harris] [--adaptive THRESHOLD] [--partial]
//!                    [--set KEY=VALUE]... [--view VIEW] [--light X,Y,Z] [--floor]
//! prism info SCENE [the same overrides as render] [--set KEY=VALUE]... [--json]
//! prism view SCENE [the same overrides as render] [--set KEY=VALUE]... [--view VIEW] [--light X,Y,Z] [--floor]
//!                  [--max-side N] [--max-pixels N] [--max-spp N] [--save-dir DIR] [--verbose]
//! prism render SCENE (--pixel-bounds X0,X1,Y0,Y1 | --tile I/N | --tile-from-env N) -o TILE.exr
//! prism render SCENE --frames N [--orbit DEGREES] [--frame I | --frame-from-env] -o OUT.png
//! prism merge TILE... -o OUT
//! prism farm slurm SCENE (--tiles N | --frames N [--orbit DEG]) [RENDER OPTIONS] -o OUT
//!                  [--wait] [--dry-run] [--work-dir DIR] [-- SBATCH_ARGS...]
//! prism completions bash|zsh|fish
//! prism --version
//! ```
//!
//! The overrides (`--width` … `--fov`) are one type, `prism_scene::Overrides`,
//! flattened into each command; the loader applies them once.
//!
//! A SCENE is a TOML scene file, `-` for one on standard input (its
//! relative paths then relative to the current directory), or an OBJ mesh
//! (`.obj`), which becomes a scene of its own
//! (`prism_scene::load_obj_scene`: a camera framing it from `--view`, one
//! light, its MTL materials, `--floor`). `--set KEY=VALUE` replaces any
//! value of a scene file by its dotted path (`prism_scene::LoadOptions::sets`).
//! An output that cannot be written is refused before the scene is loaded
//! (`writable.rs`).
//!
//! Errors are printed as `error: FILE:LINE:COLUMN: what` with a non-zero
//! exit status; no output file is created or changed then.

#![forbid(unsafe_code)]

// `outln!` and `errln!`: `println!` and `eprintln!` that never panic on a
// closed standard output or error (prism-view's, shared with the viewer).
#[macro_use]
extern crate prism_view;

mod completions;
mod env;
mod farm;
mod frames;
mod info;
mod interrupt;
mod memory;
mod merge;
mod outputs;
mod overwrite;
mod stats;
mod tile;
mod version;
mod writable;

use anyhow::{Context, Result, anyhow};
use clap::{Args, CommandFactory, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use prism_scene::{Limits, LoadOptions, LoadedScene, Overrides, load_path};
use prism_shade::{
    Aov, OutputFormat, RenderHooks, RenderSettings, render, render_region, render_with_alpha,
    render_with_aovs,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// prism: a fast, exact, Whitted-style CPU ray tracer.
#[derive(Parser)]
#[command(name = "prism", version, long_version = version::long(), about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The subcommands that take numeric flags read a negative number as the
/// flag's value (`allow_negative_numbers`), so that `--spp -1` is refused
/// naming `--spp`, not as an unknown argument `-1`.
#[derive(Subcommand)]
enum Command {
    /// Render a scene file to a PNG (8-bit sRGB) or EXR (linear float) image.
    #[command(allow_negative_numbers = true)]
    Render(RenderArgs),
    /// Describe a scene: objects, triangles, materials, lights, bounds.
    #[command(allow_negative_numbers = true)]
    Info(InfoArgs),
    /// Open a window that renders a scene progressively: f/c fog on/off, s save PNG,
    /// r reload, arrows or drag orbit, w/a/d/x move, Home reset, Esc/q quit.
    #[command(allow_negative_numbers = true)]
    View(ViewArgs),
    /// Print a shell completion script: `prism completions bash > ~/.local/share/bash-completion/completions/prism`.
    Completions(completions::CompletionsArgs),
    /// Write the man pages into a directory (run by `cargo xtask man`).
    #[command(hide = true)]
    Man(completions::ManArgs),
    /// Assemble tiles (`prism render --tile I/N -o TILE.exr`) into the full image.
    Merge(merge::MergeArgs),
    /// Render on a cluster: tiles or turntable frames as a job array, merged (see docs/farm.md).
    #[command(allow_negative_numbers = true)]
    Farm(farm::FarmArgs),
}

#[derive(Args)]
struct ViewArgs {
    /// The scene file, `-` for a scene on standard input (read once: `r` cannot reload it), or an OBJ mesh to look at.
    scene: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// Replace a scene value by its dotted path, on every load (repeatable):
    /// --set render.spp=16 --set fog.enabled=false.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    #[command(flatten)]
    obj: ObjArgs,
    #[command(flatten)]
    limits: LimitArgs,
    /// Where `s` saves snapshots [default: the current directory].
    #[arg(long, value_name = "DIR")]
    save_dir: Option<PathBuf>,
    /// Print frame timings and the key-to-frame latency to stderr.
    #[arg(short, long)]
    verbose: bool,
}

#[derive(Args)]
struct RenderArgs {
    /// The scene file (TOML, see docs/scene-format.md), `-` for a scene on standard input,
    /// or an OBJ mesh to look at.
    scene: PathBuf,
    /// Output image, .png or .exr [default: out/NAME.png for a scene NAME.toml].
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    overrides: Overrides,
    /// Replace a scene value by its dotted path, before the scene is checked (repeatable):
    /// --set render.spp=16 --set fog.enabled=false --set objects.0.radius=2.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// No start line, progress bar or closing statistics line (warnings
    /// and errors are still printed).
    #[arg(short, long)]
    quiet: bool,
    /// On Ctrl-C (or SIGTERM, SIGHUP), write the rows rendered so far (the rest black) instead of nothing:
    /// the image alone, without passes, previews or statistics.
    #[arg(long)]
    partial: bool,
    /// AOV passes, comma-separated: depth, normal, geo_normal, albedo, object_id, or all
    /// (replaces the scene's `aov`; none for no pass); layers of OUT.exr, or of OUT-stem.aov.exr beside a PNG
    /// (--aov-files: one OUT-stem.PASS.exr each).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Also write an 8-bit PNG preview of each AOV pass (OUT-stem.PASS.png).
    #[arg(long)]
    aov_preview: bool,
    /// Write the render's figures to FILE as JSON: seconds per phase, rays per kind,
    /// BVH size, peak memory. `-` writes them to standard output, and the closing
    /// statistics line and `wrote` lines go to standard error instead.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
    #[command(flatten)]
    obj: ObjArgs,
    #[command(flatten)]
    limits: LimitArgs,
    #[command(flatten)]
    alpha: outputs::AlphaArgs,
    #[command(flatten)]
    image: outputs::ImageArgs,
    #[command(flatten)]
    part: tile::PartArgs,
    #[command(flatten)]
    frames: frames::FrameArgs,
}

impl RenderArgs {
    /// Whether `--stats-json -` sends the statistics to standard output.
    fn stats_to_stdout(&self) -> bool {
        self.stats_json.as_deref() == Some(Path::new("-"))
    }

    /// The file `--stats-json` names (not `-`, standard output).
    fn stats_file(&self) -> Option<&Path> {
        self.stats_json.as_deref().filter(|_| !self.stats_to_stdout())
    }
}

#[derive(Args)]
struct InfoArgs {
    /// The scene file, `-` for standard input, or an OBJ mesh.
    scene: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// Replace a scene value by its dotted path, before the scene is checked (repeatable):
    /// --set render.spp=16 --set fog.enabled=false --set objects.0.radius=2.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    #[command(flatten)]
    obj: ObjArgs,
    #[command(flatten)]
    limits: LimitArgs,
    /// Print the description as one JSON object (for scripts; keys in the README).
    #[arg(long)]
    json: bool,
}

/// OBJ mode's choices (`prism render model.obj`); a TOML scene refuses them.
#[derive(Args)]
struct ObjArgs {
    /// For an OBJ file: where the camera looks from [default: auto, facing the mesh's larger side].
    #[arg(long, value_enum, value_name = "VIEW")]
    view: Option<prism_scene::ObjView>,
    /// For an OBJ file: the point light's position, replacing the one placed for the view.
    #[arg(long, value_name = "X,Y,Z", value_parser = prism_scene::parse_vec3, allow_hyphen_values = true)]
    light: Option<prism_geometry::glam::Vec3>,
    /// For an OBJ file: a ground plane under the mesh, which catches its shadow.
    #[arg(long)]
    floor: bool,
}

impl ObjArgs {
    fn options(&self) -> prism_scene::ObjOptions {
        prism_scene::ObjOptions { view: self.view, light: self.light, floor: self.floor }
    }
}

#[derive(Args)]
struct LimitArgs {
    /// Largest image width or height accepted.
    #[arg(long, value_name = "PIXELS", default_value_t = Limits::default().max_side, value_parser = |s: &str| prism_scene::whole_u32(s, 1))]
    max_side: u32,
    /// Largest number of pixels accepted.
    #[arg(long, value_name = "PIXELS", default_value_t = Limits::default().max_pixels, value_parser = |s: &str| prism_scene::whole_number(s, 1))]
    max_pixels: u64,
    /// Largest number of samples per pixel accepted.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_spp, value_parser = |s: &str| prism_scene::whole_u32(s, 1))]
    max_spp: u32,
}

impl LimitArgs {
    fn limits(&self) -> Limits {
        Limits {
            max_side: self.max_side,
            max_pixels: self.max_pixels,
            max_spp: self.max_spp,
            memory: memory::room(),
            ..Limits::default()
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if matches!(cli.command, Command::Render(_) | Command::Info(_) | Command::View(_)) {
        for w in env::warnings() {
            errln!("warning: {w}");
        }
    }
    let result = match cli.command {
        Command::Render(args) => render_command(&args),
        Command::Info(args) => info_command(&args),
        Command::View(args) => view_command(args),
        Command::Completions(args) => completions::completions_command(&args, Cli::command()),
        Command::Man(args) => completions::man_command(&args, Cli::command()),
        Command::Merge(args) => merge::merge_command(&args),
        Command::Farm(args) => farm::farm_command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("error: {}", report(&e));
            interrupt::exit_code(&e)
        }
    }
}

/// The error and its causes joined by `: ` (as `{e:#}`), leaving out a
/// cause whose words the message before it already ends with: a library
/// error that shows its source in its own message would otherwise say it
/// twice (`cannot write x.json: No such file…: No such file…`).
fn report(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !out.is_empty() && out.ends_with(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

fn view_command(args: ViewArgs) -> Result<()> {
    prism_view::run(prism_view::ViewOptions {
        scene: args.scene,
        overrides: args.overrides,
        sets: args.set,
        obj: args.obj.options(),
        limits: args.limits.limits(),
        memory: Some(memory::room),
        save_dir: args.save_dir,
        verbose: args.verbose,
    })?;
    Ok(())
}

fn info_command(args: &InfoArgs) -> Result<()> {
    let opts = LoadOptions {
        limits: args.limits.limits(),
        overrides: args.overrides,
        sets: args.set.clone(),
        obj: args.obj.options(),
    };
    let loaded = load_path(&args.scene, &opts)?;
    for w in &loaded.warnings {
        errln!("warning: {w}");
    }
    let text = if args.json {
        format!("{:#}\n", info::to_json(&loaded, &args.scene))
    } else {
        // Names as written in the file, escape sequences made harmless.
        prism_view::printable(&info::describe(&loaded, &args.scene)).into_owned()
    };
    write_stdout(text.as_bytes(), "the description")
}

/// Writes `bytes`, the command's data (`what`), to standard output. A
/// reader that stopped early (`prism info s.toml | head`) is not an error;
/// any other failure (a full disk) is, so that a script does not take a
/// cut-off file for a whole one.
fn write_stdout(bytes: &[u8], what: &str) -> Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(bytes).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(e).with_context(|| format!("cannot write {what} to standard output"))
        }
        _ => Ok(()),
    }
}

fn render_command(args: &RenderArgs) -> Result<()> {
    // The output (given, or `out/<stem>.png`) is checked before the
    // (possibly long) load. A scene path with no name to give the image
    // (`.`) is left to the load, which says what is wrong with it.
    let early = args.output.clone().or_else(|| default_output(&args.scene).ok());
    let aov_flag = args.aov.as_deref().map(Aov::parse_list).transpose().map_err(|e| anyhow!("--aov: {e}"))?;
    if let Some(o) = &early {
        let format = OutputFormat::from_path(o)?;
        // A turntable writes its frames beside OUT, not at OUT itself.
        let first = match args.frames.frames {
            Some(n) => frames::frame_path(o, args.frames.frame.unwrap_or(0), n),
            None => o.clone(),
        };
        writable::check_writable(&first, overwrite::Output::Image)?;
        // The passes' files that --aov alone decides (the scene's `aov`
        // and `aov_preview` are known only after the load).
        if let Some(aovs) = aov_flag.as_deref().filter(|a| !a.is_empty()) {
            let (plan, _) =
                args.image.plan(first.clone(), format, args.alpha.alpha, true, args.aov_preview)?;
            for f in plan.other_files(aovs)? {
                writable::check_writable(&f, overwrite::Output::Image)?;
            }
        }
    }
    if let Some(s) = args.stats_file() {
        writable::check_writable(s, overwrite::Output::Stats).context("--stats-json")?;
    }

    let opts = LoadOptions {
        limits: args.limits.limits(),
        overrides: args.overrides,
        sets: args.set.clone(),
        obj: args.obj.options(),
    };
    let load_start = Instant::now();
    let loaded = load_path(&args.scene, &opts)?;
    let load_seconds = load_start.elapsed().as_secs_f64();
    for w in &loaded.warnings {
        errln!("warning: {w}");
    }
    let output = match early {
        Some(o) => o,
        None => default_output(&args.scene)?,
    };
    let format = OutputFormat::from_path(&output)?;
    overwrite::check_not_an_input(&output, &loaded.inputs)?;
    let aovs = aov_flag.unwrap_or_else(|| loaded.aovs.clone());
    let previews = args.aov_preview || loaded.aov_preview;
    if previews && aovs.is_empty() {
        // Named as the user gave it: the flag, or the scene's key.
        let asked = if args.aov_preview {
            "--aov-preview".to_owned()
        } else if prism_scene::is_stdin_path(&args.scene) {
            format!("{}: `aov_preview = true`", prism_scene::STDIN_NAME)
        } else {
            format!("{}: `aov_preview = true`", args.scene.display())
        };
        errln!("warning: {asked} without AOV passes (--aov or the scene's `aov`) writes no previews");
    }
    let (plan, warnings) =
        args.image.plan(output.clone(), format, args.alpha.alpha, !aovs.is_empty(), previews)?;
    for w in warnings {
        errln!("warning: {w}");
    }
    if loaded.settings.antialias.adaptive.is_some() && (plan.alpha || !aovs.is_empty()) {
        errln!(
            "warning: adaptive supersampling is off for this render: with --alpha or AOV passes every pixel takes all {} samples",
            loaded.settings.spp
        );
    }
    if let Some(s) = args.stats_file() {
        overwrite::check_output(s, &loaded.inputs, overwrite::Output::Stats)?;
    }
    let (w, h) = loaded.settings.camera.size();
    if let Some(warning) = writable::check_space(&output, plan.uncompressed_bytes(w, h, &aovs))? {
        errln!("warning: {warning}");
    }
    // The folders are made now, before the render: a render never ends in
    // a missing folder. Those made here go again if nothing is written
    // (an error, or Ctrl-C without --partial).
    let mut made = writable::MadeDirs::default();
    // From here on SIGINT, SIGTERM and SIGHUP cancel the render (and so
    // let the folders be removed) rather than end prism at once.
    interrupt::Interrupt::install()?;
    let result = make_output_dirs(args, &output, &mut made)
        .and_then(|()| render_frames(args, &loaded, &plan, &output, &aovs, load_seconds));
    if result.is_err() {
        made.remove_empty();
    }
    result
}

/// Makes the missing folders of the image and of `--stats-json`, noting
/// them in `made`.
fn make_output_dirs(args: &RenderArgs, output: &Path, made: &mut writable::MadeDirs) -> Result<()> {
    if let Some(dir) = args.stats_file().and_then(Path::parent) {
        made.make(dir, "the directory").context("--stats-json")?;
    }
    if let Some(dir) = output.parent() {
        made.make(dir, "the output directory")?;
    }
    Ok(())
}

/// Renders the image, or each frame of a turntable, and writes its files.
fn render_frames(
    args: &RenderArgs,
    loaded: &LoadedScene,
    plan: &outputs::Plan,
    output: &Path,
    aovs: &[Aov],
    load_seconds: f64,
) -> Result<()> {
    let frames = frames::plan(&args.frames, &loaded.settings, output)?;
    if args.stats_json.is_some() && frames.len() > 1 {
        return Err(anyhow!(
            "--stats-json describes one render; with --frames, give --frame I (or --frame-from-env)"
        ));
    }
    let several = frames.len() > 1;
    // Every frame's files are checked before the first is rendered: a
    // name taken by an input of this render or by a folder stops the
    // sequence before it writes any of it.
    let mut files = Vec::with_capacity(frames.len());
    for (_, frame_output) in &frames {
        overwrite::check_not_an_input(frame_output, &loaded.inputs)?;
        let plan = plan.for_output(frame_output.clone());
        let written = plan.other_files(aovs)?;
        for f in &written {
            overwrite::check_not_an_input(f, &loaded.inputs)?;
        }
        files.push((plan, written));
    }
    for (k, ((settings, frame_output), (plan, mut written))) in frames.iter().zip(files).enumerate() {
        if let Some(s) = args.stats_file() {
            written.push(frame_output.clone());
            overwrite::check_stats_apart(s, &written)?;
        }
        render_to(args, loaded, settings, &plan, aovs, load_seconds)
            .map_err(|e| if several { interrupt::in_frame(e, k, frame_output, k) } else { e })?;
    }
    Ok(())
}

/// Renders `settings` (the whole image, or the part `args` asks for) and
/// writes the files of `plan` (a part as `.exr`: a tile file).
fn render_to(
    args: &RenderArgs,
    loaded: &LoadedScene,
    settings: &RenderSettings,
    plan: &outputs::Plan,
    aovs: &[Aov],
    load_seconds: f64,
) -> Result<()> {
    let output = &plan.output;
    let (w, h) = settings.camera.size();
    let region = args.part.region(w, h)?;
    if region.is_some() && plan.alpha {
        return Err(anyhow!(
            "--alpha is not available for part of an image (--pixel-bounds, --tile); render the whole image"
        ));
    }
    let tile_file = region.is_some() && plan.format() == OutputFormat::Exr;
    if tile_file && args.partial {
        return Err(anyhow!("--partial: a tile file is written whole or not at all; render the tile again"));
    }
    if tile_file && prism_scene::is_stdin_path(&args.scene) {
        return Err(anyhow!(
            "a tile needs its scene in a file (its header names and hashes it for prism merge), not on standard input"
        ));
    }
    if tile_file && plan.previews() {
        errln!(
            "warning: a tile holds no AOV previews; prism merge --aov-preview writes them for the whole image"
        );
    }
    if tile_file && plan.aov_files() {
        errln!(
            "warning: a tile holds its passes as layers; prism merge --aov-files writes them as files of their own"
        );
    }

    if let Some(warning) = memory::check(&render_memory(settings, region, plan, aovs), "this render")? {
        errln!("warning: {warning}");
    }

    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
        let bar = ProgressBar::new(u64::from(region.map_or(h, |r| r.0.height())));
        if let Ok(style) = ProgressStyle::with_template(
            "{spinner} rendering [{bar:40}] {pos}/{len} rows, {elapsed} (eta {eta})",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    });
    let interrupt = interrupt::Interrupt::install()?;
    if bar.is_none() && !args.quiet {
        errln!("rendering {w}×{h} at {} spp (Ctrl-C stops)", settings.spp);
    }
    let rows = region.map_or(h, |r| r.0.height());
    let progress = |done: u32, total: u32| {
        // Adaptive sampling counts its base pass's rows first: the image's
        // rows are finished in the refine pass, the last `rows` counted.
        interrupt.note_rows(done.saturating_sub(total.saturating_sub(rows)));
        if let Some(b) = &bar {
            b.set_length(u64::from(total));
            b.set_position(u64::from(done));
        }
    };
    let hooks = RenderHooks { progress: Some(&progress), cancel: Some(interrupt.flag()) };
    let start = Instant::now();
    let (image, alpha, passes, stats) = if let Some((b, _)) = region {
        let (image, passes, stats) = render_region(&loaded.scene, settings, b, aovs, hooks)?;
        (image, None, (!aovs.is_empty()).then_some(passes), stats)
    } else if plan.alpha {
        let (rgba, passes, stats) = render_with_alpha(&loaded.scene, settings, aovs, hooks);
        (rgba.color, Some(rgba.alpha), (!aovs.is_empty()).then_some(passes), stats)
    } else if aovs.is_empty() {
        let (image, stats) = render(&loaded.scene, settings, hooks);
        (image, None, None, stats)
    } else {
        let (image, passes, stats) = render_with_aovs(&loaded.scene, settings, aovs, hooks);
        (image, None, Some(passes), stats)
    };
    let wall = start.elapsed().as_secs_f64();
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if stats.cancelled {
        // The image alone, as the message says: passes of the rows not
        // rendered would read "nothing hit" there.
        let write = || plan.write_image(&image, alpha.as_deref(), None);
        return Err(interrupt.finish(image.height, output, args.partial, write));
    }
    if stats.nonfinite_samples > 0 {
        // Shown even with --quiet: the image is wrong where they fell.
        errln!(
            "warning: {} samples were not finite (a light's power times a material's coefficients overflowed, or NaN) and were counted as black; lower the lights' intensity",
            stats.nonfinite_samples
        );
    }
    let write_start = Instant::now();
    let written = match region {
        Some((bounds, tile)) if plan.format() == OutputFormat::Exr => {
            // What made the scene besides its files: a merge refuses tiles that differ in any.
            let inputs = format!(
                "{}; set {:?}; obj {:?}",
                prism_scene::inputs_digest(&loaded.inputs)?,
                args.set,
                args.obj.options()
            );
            let header = tile::TileHeader::new(&args.scene, inputs, settings, aovs, tile);
            let aovs = passes.unwrap_or(prism_shade::AovImages {
                width: image.width,
                height: image.height,
                passes: Vec::new(),
            });
            let tile = tile::Tile { width: w, height: h, bounds, image, aovs, header };
            tile::write_tile(output, &tile)?;
            Vec::new()
        }
        _ => {
            // On the render's threads (`--threads`): the PNG encoder is
            // parallel, by rows (no more workers than rows: idle ones cost).
            let threads = settings.threads.map(|n| n.min(image.height.max(1) as usize));
            // The image and its AOV files replace what was there together,
            // or (a full disk midway) none of them does.
            prism_shade::in_pool(threads, || {
                prism_shade::all_or_nothing(|| {
                    plan.write_image(&image, alpha.as_deref(), passes.as_ref())?;
                    match &passes {
                        Some(p) => plan.write_passes(&image, alpha.as_deref(), p),
                        None => Ok(Vec::new()),
                    }
                })
            })?
        }
    };
    if args.stats_json.is_some() {
        let phases =
            stats::Phases { load: load_seconds, render: wall, write: write_start.elapsed().as_secs_f64() };
        let outputs: Vec<&Path> =
            std::iter::once(output.as_path()).chain(written.iter().map(PathBuf::as_path)).collect();
        let json = stats::to_json(loaded, &args.scene, &outputs, phases, &stats);
        match args.stats_file() {
            Some(file) => prism_shade::write_bytes_atomic(file, format!("{json:#}\n").as_bytes())
                .with_context(|| {
                    format!("--stats-json: {} was written, but not the statistics", output.display())
                })?,
            None => write_stdout(format!("{json:#}\n").as_bytes(), "the statistics (--stats-json -)")?,
        }
    }
    if !args.quiet {
        let mrays = stats.rays as f64 / 1e6;
        let mut lines = vec![format!(
            "{}: {w}×{h}, {} spp, {wall:.2} s, {mrays:.2} M rays, {:.2} M rays/s",
            output.display(),
            settings.spp,
            if wall > 0.0 { mrays / wall } else { 0.0 }
        )];
        lines.extend(written.iter().map(|f| format!("wrote {}", f.display())));
        for line in lines {
            // Standard output holds the JSON alone with `--stats-json -`.
            if args.stats_to_stdout() {
                errln!("{line}");
            } else {
                outln!("{line}");
            }
        }
    }
    Ok(())
}

/// The image buffers of the render `render_to` runs: of the image, or of
/// `region` (written as a tile file if an EXR).
fn render_memory(
    settings: &RenderSettings,
    region: Option<tile::Part>,
    plan: &outputs::Plan,
    aovs: &[Aov],
) -> memory::RenderMemory {
    let (w, h) = settings.camera.size();
    let bounds = region.map_or_else(|| prism_shade::PixelBounds::full(w, h), |(b, _)| Some(b));
    let (rw, rh) = bounds.map_or((w, h), |b| (b.width(), b.height()));
    let tile = region.is_some() && plan.format() == OutputFormat::Exr;
    // As `render_pixels`: off with passes or alpha; its base pass takes a
    // border of one pixel (within the image) around a part.
    let adaptive = settings.antialias.adaptive.is_some()
        && aovs.is_empty()
        && !plan.alpha
        && settings.spp > prism_shade::ADAPTIVE_BASE_SAMPLES;
    let adaptive_base = adaptive.then(|| {
        let grown =
            |lo: u32, hi: u32, max: u32| u64::from(hi.saturating_add(1).min(max) - lo.saturating_sub(1));
        bounds.map_or(u64::from(w) * u64::from(h), |b| grown(b.x0(), b.x1(), w) * grown(b.y0(), b.y1(), h))
    });
    // A `--threads` pool for the render, another for the writers (a tile
    // is written on this thread); at most one thread a row.
    let pool = settings.threads.map_or(0, |n| n.min(rh.max(1) as usize) as u64);
    memory::RenderMemory {
        width: u64::from(rw),
        rows: u64::from(rh),
        alpha: plan.alpha,
        passes: aovs.len() as u64,
        pass_channels: aovs.iter().map(|a| a.channels() as u64).sum(),
        adaptive_base,
        writers: plan.writer_bytes(rw, rh, aovs, tile),
        threads: pool * if tile { 1 } else { 2 },
    }
}

/// `out/<scene stem>.png`, relative to the working directory
/// (`out/stdin.png` for a scene read from standard input).
fn default_output(scene: &Path) -> Result<PathBuf> {
    if prism_scene::is_stdin_path(scene) {
        return Ok(Path::new("out").join("stdin.png"));
    }
    let stem = scene.file_stem().filter(|s| !s.is_empty()).with_context(|| {
        format!("cannot name an output image after {}; give one with -o", scene.display())
    })?;
    let mut name = stem.to_os_string();
    name.push(".png");
    Ok(Path::new("out").join(name))
}

#[cfg(test)]
mod tests {
    use super::report;
    use anyhow::{Context, anyhow};

    #[test]
    fn a_cause_the_message_already_shows_is_said_once() {
        let source = std::io::Error::from(std::io::ErrorKind::NotFound);
        let words = source.to_string();
        let e = anyhow::Error::new(prism_shade::OutputError::Io { path: "x.json".into(), source })
            .context("--stats-json");
        assert_eq!(format!("{e:#}"), format!("--stats-json: cannot write x.json: {words}: {words}"));
        assert_eq!(report(&e), format!("--stats-json: cannot write x.json: {words}"));
        // Other chains read as `{e:#}` does.
        let e = Err::<(), _>(anyhow!("inner")).context("middle").context("outer").unwrap_err();
        assert_eq!(report(&e), format!("{e:#}"));
        assert_eq!(report(&e), "outer: middle: inner");
    }
}
