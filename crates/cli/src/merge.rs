//! `prism merge TILE... -o OUT`: assembles tile files (`prism render
//! --tile` or `--pixel-bounds` to `.exr`) into the full image, the same bit
//! for bit as one machine's `prism render`, after checking that they belong
//! together: one scene (the same input bytes), one set of settings, one
//! prism version, no overlap, nothing missing. Otherwise nothing is written.

use crate::overwrite::check_not_an_input;
use crate::tile::{Tile, read_tile};
use anyhow::{Result, bail};
use clap::Args;
use prism_shade::{AovImage, AovImages, Image, OutputFormat};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct MergeArgs {
    /// The tile files (OpenEXR), in any order.
    #[arg(required = true, value_name = "TILE")]
    pub tiles: Vec<PathBuf>,
    /// The merged image, .png or .exr; AOV passes go in it as layers (.exr) or beside
    /// it as OUT-stem.aov.exr (.png), as for `prism render`.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub image: crate::outputs::ImageArgs,
    /// Refused: tiles hold no alpha (hidden from the help; kept to say so).
    #[arg(long, hide = true)]
    pub alpha: bool,
    /// Also write an 8-bit PNG preview of each AOV pass (OUT-stem.PASS.png).
    #[arg(long)]
    pub aov_preview: bool,
    /// No closing line.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `prism merge`.
pub fn merge_command(args: &MergeArgs) -> Result<()> {
    if args.alpha {
        bail!("--alpha: tiles hold no alpha; render the whole image with --alpha instead");
    }
    let format = OutputFormat::from_path(&args.output)?;
    let inputs: Vec<PathBuf> = args.tiles.iter().filter_map(|t| std::fs::canonicalize(t).ok()).collect();
    check_not_an_input(&args.output, &inputs)?;
    let tiles: Vec<(PathBuf, Tile)> =
        args.tiles.iter().map(|p| Ok((p.clone(), read_tile(p)?))).collect::<Result<_>>()?;
    let (image, aovs) = assemble(&tiles)?;
    let has_aovs = !aovs.passes.is_empty();
    if args.aov_preview && !has_aovs {
        errln!("warning: --aov-preview: the tiles hold no AOV passes, so no previews are written");
    }
    let (plan, warnings) = args.image.plan(args.output.clone(), format, false, has_aovs, args.aov_preview)?;
    for w in warnings {
        errln!("warning: {w}");
    }
    let kinds: Vec<prism_shade::Aov> = aovs.passes.iter().map(|p| p.aov).collect();
    for f in plan.other_files(&kinds)? {
        check_not_an_input(&f, &inputs)?;
    }
    // A folder made here goes again if nothing is written.
    let mut made = crate::writable::MadeDirs::default();
    let passes = has_aovs.then_some(&aovs);
    let result =
        made.make(args.output.parent().unwrap_or(Path::new("")), "the output directory").and_then(|()| {
            // The image and its AOV files together, or none of them.
            Ok(prism_shade::all_or_nothing(|| {
                plan.write_image(&image, None, passes)?;
                match passes {
                    Some(p) => plan.write_passes(&image, None, p),
                    None => Ok(Vec::new()),
                }
            })?)
        });
    if result.is_err() {
        made.remove_empty();
    }
    let written = result?;
    if !args.quiet {
        outln!("{}: {}×{} from {} tiles", args.output.display(), image.width, image.height, tiles.len());
        for f in &written {
            outln!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// The first item where two settings texts differ, for a message (`spp:
/// 4` against `spp: 16`): items are separated by `, ` or `; `, and shown
/// without the names and braces of the structures around them.
fn first_difference(a: &str, b: &str) -> (String, String) {
    // Items end at `, ` or `; ` outside parentheses and brackets (a
    // `Vec3(0.0, 2.0, 10.0)` is one item).
    let split = |s: &str| {
        let (mut items, mut depth, mut start) = (Vec::new(), 0i32, 0);
        let b = s.as_bytes();
        for (i, &c) in b.iter().enumerate() {
            match c {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth -= 1,
                b',' | b';' if depth == 0 && b.get(i + 1) == Some(&b' ') => {
                    items.push(&s[start..i]);
                    start = i + 2;
                }
                _ => {}
            }
        }
        items.push(&s[start.min(s.len())..]);
        // Each item named by the fields around it (`camera.position: …`):
        // `field: Type { ` opens a level, a trailing ` }` closes one.
        let mut path: Vec<&str> = Vec::new();
        let mut out = Vec::new();
        for item in items {
            let mut parts = item.split("{ ").collect::<Vec<_>>();
            let leaf = parts.pop().unwrap_or_default();
            for opened in parts {
                path.push(opened.split_once(':').map_or("", |(field, _)| field.trim()));
            }
            let mut leaf = leaf;
            let mut closes = 0;
            while let Some(rest) = leaf.strip_suffix(" }") {
                (leaf, closes) = (rest, closes + 1);
            }
            let named: Vec<&str> = path.iter().copied().filter(|f| !f.is_empty()).collect();
            out.push(if named.is_empty() { leaf.to_owned() } else { format!("{}.{leaf}", named.join(".")) });
            path.truncate(path.len().saturating_sub(closes));
        }
        out
    };
    let (sa, sb) = (split(a), split(b));
    for (x, y) in sa.iter().zip(&sb) {
        if x != y {
            return (x.clone(), y.clone());
        }
    }
    (a.to_owned(), b.to_owned())
}

/// What differs between two tiles' inputs (`DIGEST; set [...]; obj ...`,
/// as `render` records them): the files, the `--set` flags or the OBJ
/// options, for a message.
fn inputs_difference(a: &str, b: &str) -> String {
    // `DIGEST; set SETS; obj OBJ`; the digest is hex and OBJ's words hold
    // no `; obj `, so the parts split cleanly.
    let parts = |s: &str| -> (String, String, String) {
        let (digest, rest) = s.split_once("; set ").unwrap_or((s, ""));
        let (sets, obj) = rest.rsplit_once("; obj ").unwrap_or((rest, ""));
        (digest.to_owned(), sets.to_owned(), obj.to_owned())
    };
    let ((da, sa, oa), (db, sb, ob)) = (parts(a), parts(b));
    if da != db {
        "the files they read differ".to_owned()
    } else if sa != sb {
        format!("their --set flags differ: {sa} and {sb}")
    } else if oa != ob {
        format!("their OBJ options (--view, --light, --floor) differ: {oa} and {ob}")
    } else {
        "what they read differs".to_owned()
    }
}

/// Checks that `tiles` make one image, and makes it: the beauty and the
/// passes.
///
/// # Errors
/// Tiles of different scenes, settings, versions, image sizes or tile
/// counts (naming two files that differ), overlapping tiles (naming both
/// and the pixels), or missing tiles (naming their indices, or the pixels
/// no tile covers).
pub fn assemble(tiles: &[(PathBuf, Tile)]) -> Result<(Image, AovImages)> {
    let Some((first_path, first)) = tiles.first() else { bail!("no tiles to merge") };
    let f = first_path.display();
    for (path, t) in &tiles[1..] {
        let p = path.display();
        let (a, b) = (&first.header, &t.header);
        if a.inputs != b.inputs {
            bail!(
                "{f} and {p} are tiles of different scenes ({} and {}: {}); merge tiles of one render only",
                a.scene,
                b.scene,
                inputs_difference(&a.inputs, &b.inputs)
            );
        }
        if (first.width, first.height) != (t.width, t.height) {
            bail!(
                "{f} and {p} are tiles of different image sizes ({}×{} and {}×{})",
                first.width,
                first.height,
                t.width,
                t.height
            );
        }
        if a.settings != b.settings {
            let (x, y) = first_difference(&a.settings, &b.settings);
            bail!(
                "{f} and {p} were rendered with different settings (`{x}` and `{y}`); merge tiles of one render only"
            );
        }
        if a.version != b.version {
            bail!("{f} and {p} were rendered by different prism versions ({} and {})", a.version, b.version);
        }
        if a.tile.map(|t| t.1) != b.tile.map(|t| t.1) {
            let count =
                |t: Option<(u32, u32)>| t.map_or("--pixel-bounds".to_owned(), |(_, n)| format!("{n} tiles"));
            bail!("{f} and {p} come from different splits ({} and {})", count(a.tile), count(b.tile));
        }
        let passes = |t: &Tile| t.aovs.passes.iter().map(|p| p.aov).collect::<Vec<_>>();
        if passes(first) != passes(t) {
            bail!("{f} and {p} hold different AOV passes");
        }
    }
    for (k, (pa, a)) in tiles.iter().enumerate() {
        for (pb, b) in &tiles[k + 1..] {
            if let Some(o) = a.bounds.intersection(&b.bounds) {
                bail!(
                    "{} and {} overlap (pixels {o}, as X0,X1,Y0,Y1); each pixel must come from one tile",
                    pa.display(),
                    pb.display()
                );
            }
        }
    }
    let (w, h) = (first.width, first.height);
    let covered: u64 = tiles.iter().map(|(_, t)| t.bounds.area()).sum();
    if covered < u64::from(w) * u64::from(h) {
        // Every index there but pixels uncovered (tiles whose image size
        // was altered after the render): said by the pixels below.
        if let Some((_, n)) = first.header.tile {
            let have: Vec<u32> = tiles.iter().filter_map(|(_, t)| t.header.tile.map(|x| x.0)).collect();
            let missing: Vec<String> = (0..n).filter(|i| !have.contains(i)).map(|i| i.to_string()).collect();
            if missing.is_empty() {
                bail!(
                    "the {n} tiles are all here but cover {covered} of the {w}×{h} image's {} pixels: \
                     their image size does not match their split (files altered after the render?); nothing written",
                    u64::from(w) * u64::from(h)
                );
            }
            bail!(
                "tiles missing: {} of {n} (indices {}); nothing written",
                missing.len(),
                missing.join(", ")
            );
        }
        bail!(
            "tiles missing: {} of {w}×{h} pixels are in no tile ({}); nothing written",
            u64::from(w) * u64::from(h) - covered,
            missing_rows(tiles, w, h)
        );
    }
    let mut image = Image { width: w, height: h, pixels: vec![Default::default(); w as usize * h as usize] };
    let mut passes: Vec<AovImage> = first
        .aovs
        .passes
        .iter()
        .map(|p| AovImage {
            aov: p.aov,
            width: w,
            height: h,
            data: vec![0.0; w as usize * h as usize * p.channels()],
        })
        .collect();
    for (_, t) in tiles {
        let b = t.bounds;
        let tw = b.width() as usize;
        for y in 0..b.height() as usize {
            let at = (b.y0() as usize + y) * w as usize + b.x0() as usize;
            image.pixels[at..at + tw].copy_from_slice(&t.image.pixels[y * tw..(y + 1) * tw]);
            for (whole, part) in passes.iter_mut().zip(&t.aovs.passes) {
                let c = part.channels();
                whole.data[at * c..(at + tw) * c].copy_from_slice(&part.data[y * tw * c..(y + 1) * tw * c]);
            }
        }
    }
    Ok((image, AovImages { width: w, height: h, passes }))
}

/// The first rows with pixels in no tile, as `rows A..B`, for a message.
fn missing_rows(tiles: &[(PathBuf, Tile)], w: u32, h: u32) -> String {
    let full_row = |y: u32| {
        let mut spans: Vec<(u32, u32)> = tiles
            .iter()
            .filter(|(_, t)| y >= t.bounds.y0() && y < t.bounds.y1())
            .map(|(_, t)| (t.bounds.x0(), t.bounds.x1()))
            .collect();
        spans.sort_unstable();
        spans.iter().try_fold(0, |x, &(a, b)| (a <= x).then_some(x.max(b))).is_some_and(|x| x >= w)
    };
    let bad: Vec<u32> = (0..h).filter(|&y| !full_row(y)).collect();
    match (bad.first(), bad.last()) {
        (Some(a), Some(b)) if a == b => format!("row {a}"),
        (Some(a), Some(b)) => format!("{} rows between row {a} and row {b}", bad.len()),
        _ => "no row".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tile::TileHeader;
    use prism_geometry::glam::Vec3;
    use prism_shade::PixelBounds;

    /// Tile `i` of `n` of a 4×6 image; pixel `(x, y)` has value `x + 10 y`.
    fn tile(i: u32, n: u32) -> (PathBuf, Tile) {
        let b = PixelBounds::tile(4, 6, i, n).unwrap();
        bounds_tile(b, Some((i, n)))
    }

    fn bounds_tile(b: PixelBounds, tile: Option<(u32, u32)>) -> (PathBuf, Tile) {
        let pixels = (b.y0()..b.y1())
            .flat_map(|y| (b.x0()..b.x1()).map(move |x| Vec3::splat((x + 10 * y) as f32)))
            .collect::<Vec<_>>();
        let depth: Vec<f32> = pixels.iter().map(|p| p.x + 0.5).collect();
        let header = TileHeader {
            version: "0.1.0".into(),
            scene: "s.toml".into(),
            inputs: "00".into(),
            settings: "RenderSettings { spp: 4, fog: true }".into(),
            spp: 4,
            tile,
        };
        let name = format!("t{}-{}.exr", b.y0(), b.x0());
        let (w, h) = (b.width(), b.height());
        let aovs = AovImages {
            width: w,
            height: h,
            passes: vec![AovImage { aov: prism_shade::Aov::Depth, width: w, height: h, data: depth }],
        };
        (
            PathBuf::from(name),
            Tile {
                width: 4,
                height: 6,
                bounds: b,
                image: Image { width: w, height: h, pixels },
                aovs,
                header,
            },
        )
    }

    fn err(tiles: &[(PathBuf, Tile)]) -> String {
        assemble(tiles).unwrap_err().to_string()
    }

    #[test]
    fn tiles_in_any_order_make_the_image() {
        for n in 1..=6 {
            let mut tiles: Vec<_> = (0..n).map(|i| tile(i, n)).collect();
            tiles.reverse();
            let (img, aovs) = assemble(&tiles).unwrap();
            for y in 0..6 {
                for x in 0..4 {
                    let v = (x + 10 * y) as f32;
                    assert_eq!(img.pixels[(y * 4 + x) as usize], Vec3::splat(v));
                    assert_eq!(aovs.passes[0].scalar(x, y), Some(v + 0.5));
                }
            }
        }
        // Arbitrary rectangles that cover the image once.
        let parts = [(0, 4, 0, 2), (0, 1, 2, 6), (1, 4, 2, 6)];
        let tiles: Vec<_> = parts
            .iter()
            .map(|&(a, b, c, d)| bounds_tile(PixelBounds::new(a, b, c, d).unwrap(), None))
            .collect();
        assert_eq!(assemble(&tiles).unwrap().0.pixels[23], Vec3::splat(53.0));
    }

    #[test]
    fn mixed_overlapping_and_missing_tiles_are_refused_by_name() {
        let mut other_scene = tile(1, 3);
        other_scene.1.header.inputs = "01".into();
        other_scene.1.header.scene = "t.toml".into();
        let e = err(&[tile(0, 3), other_scene]);
        assert!(
            e.starts_with("t0-0.exr and t2-0.exr are tiles of different scenes (s.toml and t.toml"),
            "{e}"
        );
        // The same files with other sets or OBJ options: named as such.
        for (a, b, words) in [
            ("0a; set []; obj None", "0b; set []; obj None", "the files they read differ"),
            (
                r#"0a; set ["render.spp=1"]; obj None"#,
                "0a; set []; obj None",
                r#"their --set flags differ: ["render.spp=1"] and []"#,
            ),
            (
                "0a; set []; obj None",
                "0a; set []; obj Some(Floor)",
                "their OBJ options (--view, --light, --floor) differ",
            ),
        ] {
            let (mut x, mut y) = (tile(0, 3), tile(1, 3));
            (x.1.header.inputs, y.1.header.inputs) = (a.into(), b.into());
            let e = err(&[x, y]);
            assert!(e.contains(&format!("(s.toml and s.toml: {words}")), "{e}");
        }
        // A settings difference inside a nested structure, or in the AOVs,
        // is named by its fields' path, without the types' names; a
        // structure closed before it is left.
        assert_eq!(
            first_difference(
                "RenderSettings { spp: 4, antialias: Antialias { filter: Box, point_textures: false } }; aov [\"depth\"]",
                "RenderSettings { spp: 4, antialias: Antialias { filter: Box, point_textures: false } }; aov []"
            ),
            ("aov [\"depth\"]".to_owned(), "aov []".to_owned())
        );
        assert_eq!(
            first_difference("S { a: A { filter: Box, x: 1 } }", "S { a: A { filter: Gaussian, x: 1 } }"),
            ("a.filter: Box".to_owned(), "a.filter: Gaussian".to_owned())
        );
        assert_eq!(
            first_difference("S { a: A { x: 1 }, spp: 4 }", "S { a: A { x: 1 }, spp: 9 }"),
            ("spp: 4".to_owned(), "spp: 9".to_owned())
        );
        // A vector is one item, named.
        assert_eq!(
            first_difference(
                "S { c: C { position: Vec3(0.0, 2.0, 10.0), fov: 45.0 }, aov [\"depth\", \"normal\"] }",
                "S { c: C { position: Vec3(0.0, 3.0, 10.0), fov: 45.0 }, aov [\"depth\", \"normal\"] }"
            ),
            ("c.position: Vec3(0.0, 2.0, 10.0)".to_owned(), "c.position: Vec3(0.0, 3.0, 10.0)".to_owned())
        );
        let mut spp = tile(1, 3);
        spp.1.header.settings = "RenderSettings { spp: 16, fog: true }".into();
        let e = err(&[tile(0, 3), spp]);
        assert!(
            e.contains(
                "t0-0.exr and t2-0.exr were rendered with different settings (`spp: 4` and `spp: 16`)"
            ),
            "{e}"
        );
        let mut version = tile(2, 3);
        version.1.header.version = "9.9.9".into();
        assert!(err(&[tile(0, 3), version]).contains("different prism versions (0.1.0 and 9.9.9)"));
        let e = err(&[tile(0, 3), tile(1, 2)]);
        assert!(e.contains("different splits (3 tiles and 2 tiles)"), "{e}");
        let e = err(&[tile(0, 3), bounds_tile(PixelBounds::new(1, 3, 1, 3).unwrap(), Some((1, 3)))]);
        assert_eq!(
            e,
            "t0-0.exr and t1-1.exr overlap (pixels 1,3,1,2, as X0,X1,Y0,Y1); each pixel must come from one tile"
        );
        let e = err(&[tile(0, 5), tile(2, 5), tile(4, 5)]);
        assert_eq!(e, "tiles missing: 2 of 5 (indices 1, 3); nothing written");
        let e = err(&[
            bounds_tile(PixelBounds::new(0, 4, 0, 2).unwrap(), None),
            bounds_tile(PixelBounds::new(0, 3, 2, 6).unwrap(), None),
        ]);
        assert_eq!(
            e,
            "tiles missing: 4 of 4×6 pixels are in no tile (4 rows between row 2 and row 5); nothing written"
        );
        // Every index of the split, on an image size altered after the render.
        let taller = |i| {
            let mut t = tile(i, 3);
            t.1.height = 12;
            t
        };
        let e = err(&[taller(0), taller(1), taller(2)]);
        assert_eq!(
            e,
            "the 3 tiles are all here but cover 24 of the 4×12 image's 48 pixels: their image size does not match \
             their split (files altered after the render?); nothing written"
        );
    }
}
