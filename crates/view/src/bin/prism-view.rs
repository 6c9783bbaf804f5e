//! `prism-view`: the viewer on its own (the `prism view` subcommand of the
//! CLI runs the same code). `prism-view --help` lists the options.

use prism_view::{SceneLoader, ViewOptions, demo};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

const USAGE: &str =
    "usage: prism-view (SCENE | --demo) [--width N] [--height N] [--spp N] [--threads N] [--max-depth N] \
[--fog | --no-fog] [--save-dir DIR] [--verbose]

Opens a window that renders SCENE progressively.
Keys: f fog on, c fog off, s save PNG, r reload, arrows/drag orbit,
w/x a/d PgUp/PgDn move, wheel dolly, Home reset camera, Esc/q quit.
--demo views a small built-in scene instead of a file.";

fn parse() -> Result<(ViewOptions, bool), String> {
    let mut opts = ViewOptions::default();
    let mut demo = false;
    let mut scene = None;
    let mut args = std::env::args().skip(1);
    fn num<T: std::str::FromStr>(flag: &str, v: Option<String>) -> Result<T, String> {
        let v = v.ok_or_else(|| format!("{flag} needs a value"))?;
        v.parse().map_err(|_| format!("{flag}: not a valid number: {v}"))
    }
    while let Some(a) = args.next() {
        match a.as_str() {
            "-h" | "--help" => return Err(String::new()),
            "--demo" => demo = true,
            "--width" => opts.width = Some(num(&a, args.next())?),
            "--height" => opts.height = Some(num(&a, args.next())?),
            "--spp" => opts.spp = Some(num(&a, args.next())?),
            "--threads" => opts.threads = Some(num(&a, args.next())?),
            "--max-depth" => opts.max_depth = Some(num(&a, args.next())?),
            "--fog" => opts.fog = Some(true),
            "--no-fog" => opts.fog = Some(false),
            "--save-dir" => {
                opts.save_dir = Some(PathBuf::from(args.next().ok_or("--save-dir needs a value")?))
            }
            "--verbose" | "-v" => opts.verbose = true,
            s if s.starts_with('-') => return Err(format!("unknown option {s}")),
            _ if scene.is_some() => return Err(format!("unexpected argument {a}")),
            _ => scene = Some(PathBuf::from(a)),
        }
    }
    if opts.width == Some(0) || opts.height == Some(0) || opts.spp == Some(0) || opts.threads == Some(0) {
        return Err("--width, --height, --spp and --threads must be at least 1".into());
    }
    match (scene, demo) {
        (Some(s), false) => opts.scene = s,
        (None, true) => opts.scene = PathBuf::from("demo"),
        (Some(_), true) => return Err("give a SCENE or --demo, not both".into()),
        (None, false) => return Err("missing SCENE (or --demo)".into()),
    }
    Ok((opts, demo))
}

fn main() -> ExitCode {
    let (opts, demo) = match parse() {
        Ok(p) => p,
        Err(msg) if msg.is_empty() => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(msg) => {
            eprintln!("prism-view: {msg}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let loader: Arc<SceneLoader> = if demo {
        Arc::new(|_: &std::path::Path| demo::demo_scene(800, 600).map_err(|e| e.to_string()))
    } else {
        prism_view::file_loader(&opts)
    };
    match prism_view::run_with_loader(opts, loader) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("prism-view: {e}");
            ExitCode::FAILURE
        }
    }
}
