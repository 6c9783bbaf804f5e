//! Golden images: every scene in `scenes/` rendered small (160×90, 2
//! samples per pixel) and compared with its committed reference in
//! `tests/golden/<scene>.png`.
//!
//! The metric, over 8-bit sRGB channels, with a pixel's error the largest
//! of its channel differences: the mean absolute error must be at most
//! [`MAX_MEAN`], the 99.5th percentile of the pixel errors at most
//! [`MAX_P995`], and the mean pixel error over every 8×8 tile at most
//! [`MAX_TILE`]. Renders are deterministic, so the bounds only leave room
//! for floating-point differences between machines on a few scattered
//! pixels; a change confined to one small object (a texture turned or
//! mirrored on a sphere, a cone 30% smaller) fails, as
//! `the_metric_catches_a_turned_or_mirrored_texture_and_a_smaller_cone`
//! shows. On failure the render and an amplified difference
//! image are written under `target/tmp/golden/`.
//!
//! After an intended change: `cargo xtask bless` (which sets
//! `PRISM_BLESS=1`) rewrites the references; review them before committing.
//! Only `PRISM_BLESS=1` writes; unset, empty or `0` compares, and any other
//! value fails the test (see [`bless_requested`]).

use prism_scene::{LoadOptions, Overrides, load_scene_with, parse_scene_str_with};
use prism_shade::{RenderHooks, render};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 90;
const SPP: u32 = 2;
/// Mean absolute error, in 8-bit levels.
const MAX_MEAN: f64 = 0.5;
/// 99.5th percentile of the per-pixel maximum channel error, in levels.
const MAX_P995: u8 = 4;
/// Largest mean pixel error over an 8×8 tile, in levels.
const MAX_TILE: f64 = 3.0;
/// Edge of a tile, in pixels.
const TILE: usize = 8;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

fn scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .expect("scenes/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

fn small() -> LoadOptions {
    LoadOptions {
        overrides: Overrides {
            width: Some(WIDTH),
            height: Some(HEIGHT),
            spp: Some(SPP),
            ..Overrides::default()
        },
        ..LoadOptions::default()
    }
}

fn render_small(scene: &Path) -> (u32, u32, Vec<u8>) {
    let loaded = load_scene_with(scene, &small()).unwrap_or_else(|e| panic!("{e}"));
    render_loaded(&loaded)
}

/// The scene `text`, as if it were the file `scenes/<name>`, rendered small.
fn render_text(text: &str, name: &str) -> Vec<u8> {
    let dir = root().join("scenes");
    let loaded =
        parse_scene_str_with(text, &dir, &dir.join(name), &small()).unwrap_or_else(|e| panic!("{e}"));
    render_loaded(&loaded).2
}

fn render_loaded(loaded: &prism_scene::LoadedScene) -> (u32, u32, Vec<u8>) {
    let mut settings = loaded.settings.clone();
    settings.threads = Some(2);
    let (image, _) = render(&loaded.scene, &settings, RenderHooks::default());
    (image.width, image.height, image.to_srgb8())
}

struct Diff {
    mean: f64,
    p995: u8,
    max: u8,
    tile: f64,
    per_pixel: Vec<u8>,
}

impl Diff {
    fn passes(&self) -> bool {
        self.mean <= MAX_MEAN && self.p995 <= MAX_P995 && self.tile <= MAX_TILE
    }
}

/// Compares two RGB8 images `width` pixels wide.
fn compare(a: &[u8], b: &[u8], width: usize) -> Diff {
    let per_pixel: Vec<u8> = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0))
        .collect();
    let sum: u64 = a.iter().zip(b).map(|(x, y)| u64::from(x.abs_diff(*y))).sum();
    let mean = sum as f64 / a.len().max(1) as f64;
    let mut sorted = per_pixel.clone();
    sorted.sort_unstable();
    let idx =
        ((sorted.len() as f64 * 0.995).ceil() as usize).saturating_sub(1).min(sorted.len().saturating_sub(1));
    let p995 = sorted.get(idx).copied().unwrap_or(0);
    let max = sorted.last().copied().unwrap_or(0);
    let width = width.max(1);
    let height = per_pixel.len() / width;
    let mut tile = 0.0f64;
    for ty in (0..height).step_by(TILE) {
        for tx in (0..width).step_by(TILE) {
            let (mut sum, mut n) = (0u64, 0u64);
            for y in ty..(ty + TILE).min(height) {
                for x in tx..(tx + TILE).min(width) {
                    sum += u64::from(per_pixel[y * width + x]);
                    n += 1;
                }
            }
            tile = tile.max(sum as f64 / n.max(1) as f64);
        }
    }
    Diff { mean, p995, max, tile, per_pixel }
}

/// Whether `PRISM_BLESS` (its value `value`) asks to write the golden
/// images: only `1`, as `cargo xtask bless` sets it. Unset, empty or `0`
/// compare; anything else is refused, so that neither `PRISM_BLESS=0` nor
/// a typo can overwrite the references, and a wrong value is not silently
/// read as "compare" either.
fn bless_requested(value: Option<&OsStr>) -> Result<bool, String> {
    match value.map(|v| v.to_str().map(str::trim)) {
        None | Some(Some("" | "0")) => Ok(false),
        Some(Some("1")) => Ok(true),
        Some(_) => Err(format!(
            "PRISM_BLESS={:?}: set it to 1 to write the golden images (`cargo xtask bless`), or to 0 or nothing to compare",
            value.unwrap_or_default()
        )),
    }
}

#[test]
fn only_prism_bless_1_writes_golden_images() {
    let parse = |v: &str| bless_requested(Some(OsStr::new(v)));
    assert_eq!(bless_requested(None), Ok(false));
    assert_eq!(parse("1"), Ok(true));
    assert_eq!(parse(" 1\n"), Ok(true));
    assert_eq!(parse("0"), Ok(false));
    assert_eq!(parse(""), Ok(false));
    for bad in ["true", "yes", "2", "01", "no", "false"] {
        let err = parse(bad).expect_err(bad);
        assert!(err.contains("PRISM_BLESS") && err.contains(bad), "{err}");
    }
}

#[test]
fn every_scene_matches_its_golden_image() {
    let bless = bless_requested(std::env::var_os("PRISM_BLESS").as_deref()).unwrap_or_else(|e| panic!("{e}"));
    // PRISM_BLESS_ONLY narrows a bless; a comparison always covers every scene.
    let only: Option<Vec<String>> = std::env::var("PRISM_BLESS_ONLY")
        .ok()
        .filter(|_| bless)
        .map(|s| s.split(',').map(str::to_string).collect());
    let scenes = scenes();
    assert!(scenes.len() >= 10, "expected the seed, mesh and feature scenes, found {}", scenes.len());
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("golden");
    let mut failures = Vec::new();
    for scene in &scenes {
        let stem = scene.file_stem().and_then(|s| s.to_str()).expect("utf-8 scene names").to_string();
        if only.as_ref().is_some_and(|o| !o.contains(&stem)) {
            continue;
        }
        let (w, h, actual) = render_small(scene);
        let reference = golden_dir().join(format!("{stem}.png"));
        if bless {
            std::fs::create_dir_all(golden_dir()).expect("create tests/golden");
            image::RgbImage::from_raw(w, h, actual).expect("size").save(&reference).expect("write golden");
            eprintln!("blessed {}", reference.display());
            continue;
        }
        let expected = match image::open(&reference) {
            Ok(img) => img.to_rgb8(),
            Err(e) => {
                failures.push(format!(
                    "{stem}: no usable golden image at {} ({e}); run `cargo xtask bless`",
                    reference.display()
                ));
                continue;
            }
        };
        if (expected.width(), expected.height()) != (w, h) {
            failures.push(format!(
                "{stem}: golden image is {}×{}, render is {w}×{h}",
                expected.width(),
                expected.height()
            ));
            continue;
        }
        let d = compare(&actual, expected.as_raw(), w as usize);
        if !d.passes() {
            std::fs::create_dir_all(&out_dir).expect("create the diff directory");
            let actual_path = out_dir.join(format!("{stem}.actual.png"));
            let diff_path = out_dir.join(format!("{stem}.diff.png"));
            image::RgbImage::from_raw(w, h, actual).expect("size").save(&actual_path).expect("write");
            let amplified: Vec<u8> = d.per_pixel.iter().flat_map(|&e| [e.saturating_mul(4), 0, 0]).collect();
            image::RgbImage::from_raw(w, h, amplified).expect("size").save(&diff_path).expect("write");
            failures.push(format!(
                "{stem}: differs from {}: mean abs error {:.3} (limit {MAX_MEAN}), 99.5th percentile {} (limit {MAX_P995}), \
                 worst 8×8 tile {:.2} (limit {MAX_TILE}), max {}; \
                 render at {}, difference (×4) at {}. If the change is intended: cargo xtask bless",
                reference.display(),
                d.mean,
                d.p995,
                d.tile,
                d.max,
                actual_path.display(),
                diff_path.display()
            ));
        }
    }
    assert!(failures.is_empty(), "golden image mismatches:\n{}", failures.join("\n"));
}

#[test]
fn every_golden_image_has_a_scene() {
    let names: Vec<String> =
        scenes().iter().filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string)).collect();
    let entries = std::fs::read_dir(golden_dir()).expect("tests/golden/ is readable");
    let mut count = 0;
    for e in entries {
        count += 1;
        let p = e.expect("entry").path();
        assert!(p.extension().is_some_and(|x| x == "png"), "{} is not a golden PNG; delete it", p.display());
        let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("").to_string();
        assert!(names.contains(&stem), "{} has no scene in scenes/; delete it", p.display());
    }
    assert_eq!(count, names.len(), "one golden image per scene");
}

#[test]
fn the_metric_tolerates_a_few_pixels_but_not_a_change() {
    // 40 × 25 pixels.
    let a = vec![100u8; 3 * 1000];
    let mut b = a.clone();
    // Four scattered pixels (0.4 %) changed a lot: within every bound.
    for px in [0, 10, 420, 860] {
        b[3 * px] = 250;
    }
    let d = compare(&a, &b, 40);
    assert!(d.passes() && d.max == 150, "mean {} p995 {} tile {}", d.mean, d.p995, d.tile);
    // The same four pixels side by side (a small object moved): one tile fails.
    let mut c = a.clone();
    for px in [0, 1, 40, 41] {
        c[3 * px] = 250;
    }
    let d = compare(&a, &c, 40);
    assert!(!d.passes() && d.tile > MAX_TILE && d.p995 <= MAX_P995);
    // A visible change everywhere fails.
    let c: Vec<u8> = a.iter().map(|x| x + 6).collect();
    assert!(!compare(&a, &c, 40).passes());
    // One level everywhere (rounding on another machine) fails on the mean,
    // one level on a few pixels passes.
    let c: Vec<u8> = a.iter().map(|x| x + 1).collect();
    let d = compare(&a, &c, 40);
    assert!(!d.passes() && d.mean > MAX_MEAN && d.p995 <= MAX_P995, "mean {} p995 {}", d.mean, d.p995);
    let mut c = a.clone();
    for px in (0..1000).step_by(50) {
        c[3 * px] += 1;
    }
    assert!(compare(&a, &c, 40).passes());
}

#[test]
fn the_metric_catches_a_turned_or_mirrored_texture_and_a_smaller_cone() {
    let path = root().join("scenes/textures.toml");
    let text = std::fs::read_to_string(&path).expect("scenes/textures.toml");
    let reference = render_text(&text, "textures.toml");
    let planet = "transform = [{ rotate_y = 180 }, { translate = [0, 1.3, 0] }]";
    let cone = "radius = 0.5\nheight = 1.1";
    let cone_at = "transform = [{ translate = [1.9, 0, 1.8] }]";
    assert!(
        text.contains(planet) && text.contains(cone) && text.contains(cone_at),
        "the scene changed; update this test"
    );
    for (what, from, to) in [
        ("sphere texture turned 180°", planet, "transform = [{ translate = [0, 1.3, 0] }]"),
        (
            "sphere texture mirrored",
            planet,
            "transform = [{ scale = [-1, 1, 1] }, { rotate_y = 180 }, { translate = [0, 1.3, 0] }]",
        ),
        ("cone 30% smaller", cone, "radius = 0.35\nheight = 0.77"),
        // A tenth of its radius.
        ("cone moved 0.05 along +X", cone_at, "transform = [{ translate = [1.95, 0, 1.8] }]"),
    ] {
        let changed = render_text(&text.replace(from, to), "textures.toml");
        let d = compare(&reference, &changed, WIDTH as usize);
        assert!(
            !d.passes(),
            "{what} passes the golden comparison: mean {:.3}, p99.5 {}, tile {:.2}",
            d.mean,
            d.p995,
            d.tile
        );
    }
    // And the unchanged scene, rendered again, is identical.
    let again = render_text(&text, "textures.toml");
    assert_eq!(compare(&reference, &again, WIDTH as usize).max, 0);
}
