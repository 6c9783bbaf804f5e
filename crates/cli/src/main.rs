//! `prism`: render scene files to PNG or EXR, and describe them.
//!
//! ```text
//! prism render SCENE [-o OUT] [--width W] [--height H] [--spp N] [--fog | --no-fog]
//!                    [--threads N] [--max-depth N] [--quiet]
//!                    [--aov LIST] [--aov-preview]
//!                    [--camera-pos X,Y,Z] [--look-at X,Y,Z] [--up X,Y,Z] [--fov DEGREES]
//! prism info SCENE [the same overrides as render]
//! prism view SCENE [the same overrides as render] [--save-dir DIR] [--verbose]
//! prism render SCENE (--pixel-bounds X0,X1,Y0,Y1 | --tile I/N | --tile-from-env N) -o TILE.exr
//! prism render SCENE --frames N [--orbit DEGREES] [--frame I | --frame-from-env] -o OUT.png
//! prism merge TILE... -o OUT
//! prism farm slurm SCENE (--tiles N | --frames N [--orbit DEG]) [RENDER OPTIONS] -o OUT
//!                  [--wait] [--dry-run] [--work-dir DIR] [-- SBATCH_ARGS...]
//! ```
//!
//! The overrides (`--width` … `--fov`) are one type, `prism_scene::Overrides`,
//! flattened into each command; the loader applies them once.
//!
//! A SCENE is a TOML scene file or an OBJ mesh (`.obj`), which becomes a
//! scene of its own (`prism_scene::load_obj_scene`: a camera framing it,
//! one light, its MTL materials).
//!
//! Errors are printed as `error: FILE:LINE:COLUMN: what` with a non-zero
//! exit status; no output file is created or changed then.

#![forbid(unsafe_code)]

mod farm;
mod frames;
mod info;
mod interrupt;
mod merge;
mod overwrite;
mod tile;

use anyhow::{Context, Result, anyhow};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use prism_scene::{Limits, LoadOptions, LoadedScene, Overrides, load_path};
use prism_shade::{
    Aov, OutputFormat, RenderHooks, RenderSettings, render, render_region, render_with_aovs, write_image,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// prism: a fast, exact, Whitted-style CPU ray tracer.
#[derive(Parser)]
#[command(name = "prism", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to a PNG (8-bit sRGB) or EXR (linear float) image.
    Render(RenderArgs),
    /// Describe a scene: objects, triangles, materials, lights, bounds.
    Info(InfoArgs),
    /// Open a window that renders a scene progressively: f/c fog on/off, s save PNG,
    /// r reload, arrows or drag orbit, w/a/d/x move, Home reset, Esc/q quit.
    View(ViewArgs),
    /// Assemble tiles (`prism render --tile I/N -o TILE.exr`) into the full image.
    Merge(merge::MergeArgs),
    /// Render on a cluster: tiles or turntable frames as a job array, merged (see docs/farm.md).
    Farm(farm::FarmArgs),
}

#[derive(Args)]
struct ViewArgs {
    /// The scene file, or an OBJ mesh to look at.
    scene: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// Where `s` saves snapshots [default: the current directory].
    #[arg(long, value_name = "DIR")]
    save_dir: Option<PathBuf>,
    /// Print frame timings and the key-to-frame latency to stderr.
    #[arg(short, long)]
    verbose: bool,
}

#[derive(Args)]
struct RenderArgs {
    /// The scene file (TOML, see docs/scene-format.md), or an OBJ mesh to look at.
    scene: PathBuf,
    /// Output image, .png or .exr [default: out/NAME.png for a scene NAME.toml].
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    overrides: Overrides,
    /// No progress bar and no closing statistics line.
    #[arg(short, long)]
    quiet: bool,
    /// On Ctrl-C, write the rows rendered so far (the rest black) instead of nothing.
    #[arg(long)]
    partial: bool,
    /// AOV passes to write next to the image as OUT-stem.PASS.exr, comma-separated:
    /// depth, normal, geo_normal, albedo, object_id, or all (replaces the scene's `aov`).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Also write an 8-bit PNG preview of each AOV pass (OUT-stem.PASS.png).
    #[arg(long)]
    aov_preview: bool,
    #[command(flatten)]
    limits: LimitArgs,
    #[command(flatten)]
    part: tile::PartArgs,
    #[command(flatten)]
    frames: frames::FrameArgs,
}

#[derive(Args)]
struct InfoArgs {
    /// The scene file, or an OBJ mesh.
    scene: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    #[command(flatten)]
    limits: LimitArgs,
}

#[derive(Args)]
struct LimitArgs {
    /// Largest image width or height accepted.
    #[arg(long, value_name = "PIXELS", default_value_t = Limits::default().max_side)]
    max_side: u32,
    /// Largest number of pixels accepted.
    #[arg(long, value_name = "PIXELS", default_value_t = Limits::default().max_pixels)]
    max_pixels: u64,
    /// Largest number of samples per pixel accepted.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_spp)]
    max_spp: u32,
}

impl LimitArgs {
    fn limits(&self) -> Limits {
        Limits {
            max_side: self.max_side,
            max_pixels: self.max_pixels,
            max_spp: self.max_spp,
            ..Limits::default()
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_command(&args),
        Command::Info(args) => info_command(&args),
        Command::View(args) => view_command(args),
        Command::Merge(args) => merge::merge_command(&args),
        Command::Farm(args) => farm::farm_command(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            interrupt::exit_code(&e)
        }
    }
}

fn view_command(args: ViewArgs) -> Result<()> {
    prism_view::run(prism_view::ViewOptions {
        scene: args.scene,
        overrides: args.overrides,
        save_dir: args.save_dir,
        verbose: args.verbose,
    })?;
    Ok(())
}

fn info_command(args: &InfoArgs) -> Result<()> {
    let opts = LoadOptions { limits: args.limits.limits(), overrides: args.overrides };
    let loaded = load_path(&args.scene, &opts)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    print!("{}", info::describe(&loaded, &args.scene));
    Ok(())
}

fn render_command(args: &RenderArgs) -> Result<()> {
    // An explicit output name is checked before the (possibly long) load.
    if let Some(o) = &args.output {
        OutputFormat::from_path(o)?;
    }
    let aov_flag = args.aov.as_deref().map(Aov::parse_list).transpose().map_err(|e| anyhow!("--aov: {e}"))?;

    let opts = LoadOptions { limits: args.limits.limits(), overrides: args.overrides };
    let loaded = load_path(&args.scene, &opts)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let output = match &args.output {
        Some(o) => o.clone(),
        None => default_output(&args.scene)?,
    };
    let format = OutputFormat::from_path(&output)?;
    overwrite::check_not_an_input(&output, &loaded.inputs)?;
    let aovs = aov_flag.unwrap_or_else(|| loaded.aovs.clone());
    let previews = args.aov_preview || loaded.aov_preview;
    if previews && aovs.is_empty() {
        eprintln!(
            "warning: --aov-preview without AOV passes (--aov or the scene's `aov`) writes no previews"
        );
    }
    for &a in &aovs {
        for ext in if previews { &["exr", "png"][..] } else { &["exr"][..] } {
            overwrite::check_not_an_input(&prism_shade::aov_path(&output, a, ext)?, &loaded.inputs)?;
        }
    }
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
    }

    let plan = frames::plan(&args.frames, &loaded.settings, &output)?;
    for (settings, output) in &plan {
        overwrite::check_not_an_input(output, &loaded.inputs)?;
        render_to(args, &loaded, settings, output, format, &aovs, previews)?;
    }
    Ok(())
}

/// Renders `settings` (the whole image, or the part `args` asks for) and
/// writes it to `output` (a part as `.exr`: a tile file).
fn render_to(
    args: &RenderArgs,
    loaded: &LoadedScene,
    settings: &RenderSettings,
    output: &Path,
    format: OutputFormat,
    aovs: &[Aov],
    previews: bool,
) -> Result<()> {
    let (w, h) = settings.camera.size();
    let region = args.part.region(w, h)?;

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
        eprintln!("rendering {w}×{h} at {} spp (Ctrl-C stops)", settings.spp);
    }
    let progress = |done: u32, _total: u32| {
        interrupt.note_rows(done);
        if let Some(b) = &bar {
            b.set_position(u64::from(done));
        }
    };
    let hooks = RenderHooks { progress: Some(&progress), cancel: Some(interrupt.flag()) };
    let start = Instant::now();
    let (image, passes, stats) = if let Some((b, _)) = region {
        let (image, passes, stats) = render_region(&loaded.scene, settings, b, aovs, hooks)?;
        (image, Some(passes), stats)
    } else if aovs.is_empty() {
        let (image, stats) = render(&loaded.scene, settings, hooks);
        (image, None, stats)
    } else {
        let (image, passes, stats) = render_with_aovs(&loaded.scene, settings, aovs, hooks);
        (image, Some(passes), stats)
    };
    let wall = start.elapsed().as_secs_f64();
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    if stats.cancelled {
        return Err(interrupt.finish(&image, output, format, args.partial));
    }
    let written = match (region, passes) {
        (Some((bounds, tile)), Some(passes)) if format == OutputFormat::Exr => {
            let inputs = prism_scene::inputs_digest(&loaded.inputs)?;
            let header = tile::TileHeader::new(&args.scene, inputs, settings, aovs, tile);
            let tile = tile::Tile { width: w, height: h, bounds, image, aovs: passes, header };
            tile::write_tile(output, &tile)?;
            Vec::new()
        }
        (_, passes) => {
            write_image(output, &image, format)?;
            match &passes {
                Some(p) => prism_shade::write_aov_files(output, p, previews)?,
                None => Vec::new(),
            }
        }
    };
    if !args.quiet {
        let mrays = stats.rays as f64 / 1e6;
        println!(
            "{}: {w}×{h}, {} spp, {wall:.2} s, {mrays:.2} M rays, {:.2} M rays/s",
            output.display(),
            settings.spp,
            if wall > 0.0 { mrays / wall } else { 0.0 }
        );
        for f in &written {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// `out/<scene stem>.png`, relative to the working directory.
fn default_output(scene: &Path) -> Result<PathBuf> {
    let stem = scene.file_stem().filter(|s| !s.is_empty()).with_context(|| {
        format!("cannot name an output image after {}; give one with -o", scene.display())
    })?;
    let mut name = stem.to_os_string();
    name.push(".png");
    Ok(Path::new("out").join(name))
}
