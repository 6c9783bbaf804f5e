//! Partial renders and tile files: `prism render --pixel-bounds X0,X1,Y0,Y1`,
//! `--tile I/N` and `--tile-from-env N` choose the pixels; a partial render
//! written as `.exr` is a tile file, an OpenEXR file whose data window
//! places it in the full image and whose header records what
//! `prism merge` checks (see `docs/farm.md`).

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use prism_shade::{
    Aov, AovImages, ExrAttribute, Image, LayeredExr, PixelBounds, RenderSettings, read_layered_exr,
    render_from_exr, render_layers, write_layered_exr,
};
use std::collections::BTreeMap;
use std::path::Path;

/// The environment variables a farm task reads its index from, in order:
/// Slurm job arrays, then Kubernetes Indexed Jobs.
pub const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// The pixels of a partial render and, for `--tile`, `(index, count)`.
pub type Part = (PixelBounds, Option<(u32, u32)>);

/// The flags of `prism render` that choose part of the image.
#[derive(Args, Clone, Debug, Default)]
pub struct PartArgs {
    /// Render only the pixels [X0, X1) × [Y0, Y1) (columns X, rows Y from the top); written
    /// as .exr, the file is a tile for `prism merge`.
    #[arg(long, value_name = "X0,X1,Y0,Y1", conflicts_with_all = ["tile", "tile_from_env"])]
    pub pixel_bounds: Option<String>,
    /// Render tile I of N (0-based): N bands of whole rows, tile 0 at the top.
    #[arg(long, value_name = "I/N", conflicts_with = "tile_from_env")]
    pub tile: Option<String>,
    /// Render tile I of N, with I from $SLURM_ARRAY_TASK_ID or else $JOB_COMPLETION_INDEX.
    #[arg(long, value_name = "N")]
    pub tile_from_env: Option<u32>,
}

impl PartArgs {
    /// The pixels to render in a `width × height` image and, for a tile,
    /// `(index, count)`; `None` for the whole image.
    ///
    /// # Errors
    /// Malformed, empty or out-of-range bounds, `I ≥ N`, more tiles than
    /// rows, or no index in the environment, naming the flag.
    pub fn region(&self, width: u32, height: u32) -> Result<Option<Part>> {
        if let Some(s) = &self.pixel_bounds {
            let b = parse_bounds(s)
                .and_then(|b| b.within(width, height).map_err(|e| e.to_string()))
                .map_err(|e| anyhow!("--pixel-bounds {s}: {e}"))?;
            return Ok(Some((b, None)));
        }
        let (flag, index, count) = match (&self.tile, self.tile_from_env) {
            (Some(s), _) => {
                let (i, n) = parse_tile(s).map_err(|e| anyhow!("--tile {s}: {e}"))?;
                (format!("--tile {s}"), i, n)
            }
            (None, Some(n)) => (format!("--tile-from-env {n}"), task_index("--tile-from-env")?, n),
            (None, None) => return Ok(None),
        };
        let b = PixelBounds::tile(width, height, index, count).map_err(|e| anyhow!("{flag}: {e}"))?;
        Ok(Some((b, Some((index, count)))))
    }
}

/// `X0,X1,Y0,Y1`.
fn parse_bounds(s: &str) -> Result<PixelBounds, String> {
    let v: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x0, x1, y0, y1] = v.as_slice() else {
        return Err(format!(
            "expected four comma-separated pixel numbers X0,X1,Y0,Y1, got {} values",
            v.len()
        ));
    };
    let n = |t: &str| {
        whole(t).map_err(|too_large| match too_large {
            true => format!("`{t}` is too large for a pixel number (at most {})", u32::MAX),
            false => format!("`{t}` is not a pixel number (0 or more)"),
        })
    };
    PixelBounds::new(n(x0)?, n(x1)?, n(y0)?, n(y1)?).map_err(|e| e.to_string())
}

/// `I/N`.
fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 0/8 for the first of 8 tiles")?;
    let num = |t: &str| {
        whole(t.trim()).map_err(|too_large| match too_large {
            true => format!("`{t}` is too large (at most {}; expected I/N)", u32::MAX),
            false => format!("`{t}` is not a whole number (expected I/N)"),
        })
    };
    Ok((num(i)?, num(n)?))
}

/// `t` as a `u32`; `Err(true)` where it is a whole number too large for
/// one, `Err(false)` where it is not a whole number.
fn whole(t: &str) -> Result<u32, bool> {
    t.parse::<u32>().map_err(|_| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()))
}

/// The task index of a farm job, from the first of [`INDEX_VARIABLES`]
/// that is set; `flag` names the flag that asked, in messages.
///
/// # Errors
/// Neither variable set, or not a whole number.
pub fn task_index(flag: &str) -> Result<u32> {
    // An empty variable is unset, as the job script's `${VAR:-…}` reads it.
    for var in INDEX_VARIABLES {
        if let Ok(v) = std::env::var(var)
            && !v.is_empty()
        {
            return v
                .trim()
                .parse()
                .map_err(|_| anyhow!("{flag}: ${var} is `{v}`, not a task index (a whole number)"));
        }
    }
    bail!(
        "{flag}: neither $SLURM_ARRAY_TASK_ID nor $JOB_COMPLETION_INDEX is set; run it as a task of a job array"
    )
}

/// What a tile file's header records, for `prism merge` to check.
#[derive(Clone, Debug, PartialEq)]
pub struct TileHeader {
    /// The prism version and git commit that rendered it.
    pub version: String,
    /// The scene, as named on the command line (for messages only).
    pub scene: String,
    /// [`prism_scene::inputs_digest`] of every file the scene read.
    pub inputs: String,
    /// The render settings (camera, size, fog, spp, depth, cut-off) and
    /// the AOV passes, as text; equal for tiles of one render.
    pub settings: String,
    /// Samples per pixel.
    pub spp: u32,
    /// `(index, count)` of a `--tile` render; `None` for `--pixel-bounds`.
    pub tile: Option<(u32, u32)>,
}

impl TileHeader {
    /// The header of a tile of `settings` with `aovs`.
    pub fn new(
        scene: &Path,
        inputs: String,
        settings: &RenderSettings,
        aovs: &[Aov],
        tile: Option<(u32, u32)>,
    ) -> Self {
        let settings_text = format!(
            "{:?}; aov {:?}",
            RenderSettings { threads: None, ..settings.clone() },
            aovs.iter().map(|a| a.name()).collect::<Vec<_>>()
        );
        Self {
            // The commit too: two builds of one version may render differently.
            version: format!("{} (commit {})", env!("CARGO_PKG_VERSION"), crate::version::COMMIT),
            scene: scene.display().to_string(),
            inputs,
            settings: settings_text,
            spp: settings.spp,
            tile,
        }
    }

    fn attributes(&self) -> BTreeMap<String, ExrAttribute> {
        let mut a = BTreeMap::new();
        let text = |s: &str| ExrAttribute::Text(s.to_owned());
        a.insert("prism:version".into(), text(&self.version));
        a.insert("prism:scene".into(), text(&self.scene));
        a.insert("prism:inputs".into(), text(&self.inputs));
        a.insert("prism:settings".into(), text(&self.settings));
        a.insert("prism:spp".into(), ExrAttribute::Int(self.spp as i32));
        if let Some((i, n)) = self.tile {
            a.insert("prism:tile".into(), ExrAttribute::Int(i as i32));
            a.insert("prism:tiles".into(), ExrAttribute::Int(n as i32));
        }
        a
    }

    fn from_exr(exr: &LayeredExr, path: &Path) -> Result<Self> {
        let text = |k: &str| {
            exr.text(k).map(str::to_owned).with_context(|| {
                format!(
                    "{}: not a prism tile (no `{k}` in its header); render tiles with `prism render --tile`",
                    path.display()
                )
            })
        };
        let int = |k: &str| exr.int(k).and_then(|v| u32::try_from(v).ok());
        let tile = match (int("prism:tile"), int("prism:tiles")) {
            (Some(i), Some(n)) => Some((i, n)),
            _ => None,
        };
        Ok(Self {
            version: text("prism:version")?,
            scene: text("prism:scene")?,
            inputs: text("prism:inputs")?,
            settings: text("prism:settings")?,
            spp: int("prism:spp")
                .with_context(|| format!("{}: not a prism tile (no spp)", path.display()))?,
            tile,
        })
    }
}

/// A tile: where it lies, its beauty and passes, and its header.
#[derive(Debug)]
pub struct Tile {
    /// Full image width.
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// Its pixels in the full image.
    pub bounds: PixelBounds,
    /// The beauty, `bounds`' size, linear.
    pub image: Image,
    /// The passes, `bounds`' size.
    pub aovs: AovImages,
    /// The header.
    pub header: TileHeader,
}

/// Writes a tile file (atomically): the beauty and each pass under the
/// channel names of a full render (`prism_shade::render_layers`), the
/// data window `bounds` of the full `width × height` display window, the
/// header's attributes.
///
/// # Errors
/// If the file cannot be written.
pub fn write_tile(path: &Path, tile: &Tile) -> Result<()> {
    let exr = LayeredExr {
        width: tile.width,
        height: tile.height,
        data_window: tile.bounds,
        layers: render_layers(&tile.image, None, &tile.aovs),
        attributes: tile.header.attributes(),
    };
    write_layered_exr(path, &exr)?;
    Ok(())
}

/// Reads a tile file written by [`write_tile`].
///
/// # Errors
/// If it cannot be read, is not a prism tile, or lacks a channel.
pub fn read_tile(path: &Path) -> Result<Tile> {
    let exr = read_layered_exr(path)?;
    let header = TileHeader::from_exr(&exr, path)?;
    let render = render_from_exr(&exr, path)?;
    Ok(Tile {
        width: exr.width,
        height: exr.height,
        bounds: exr.data_window,
        image: render.image,
        aovs: render.passes,
        header,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_parse_and_are_refused_naming_the_flag() {
        let part = |b: Option<&str>, t: Option<&str>| PartArgs {
            pixel_bounds: b.map(str::to_owned),
            tile: t.map(str::to_owned),
            tile_from_env: None,
        };
        let r = part(Some("1,5,2,3"), None).region(8, 4).unwrap();
        assert_eq!(r, Some((PixelBounds::new(1, 5, 2, 3).unwrap(), None)));
        let r = part(None, Some("1/2")).region(8, 4).unwrap();
        assert_eq!(r, Some((PixelBounds::new(0, 8, 2, 4).unwrap(), Some((1, 2)))));
        assert_eq!(part(None, None).region(8, 4).unwrap(), None);
        let err = |p: PartArgs| p.region(8, 4).unwrap_err().to_string();
        // A whole number too large for one is called that, not "not a whole number".
        assert_eq!(
            err(part(None, Some("0/18446744073709551615"))),
            "--tile 0/18446744073709551615: `18446744073709551615` is too large (at most 4294967295; expected I/N)"
        );
        assert_eq!(err(part(None, Some("x/2"))), "--tile x/2: `x` is not a whole number (expected I/N)");
        assert!(
            err(part(Some("0,99999999999,0,1"), None))
                .ends_with("is too large for a pixel number (at most 4294967295)")
        );
        assert_eq!(
            err(part(Some("1,9,0,1"), None)),
            "--pixel-bounds 1,9,0,1: the bounds 1,9,0,1 reach past the 8×4 image"
        );
        assert!(
            err(part(Some("3,3,0,1"), None))
                .starts_with("--pixel-bounds 3,3,0,1: the bounds 3,3,0,1 hold no pixel")
        );
        assert!(err(part(Some("1,2,3"), None)).starts_with("--pixel-bounds 1,2,3: expected four"));
        assert!(err(part(Some("-1,2,0,1"), None)).contains("`-1` is not a pixel number"));
        assert!(err(part(None, Some("2/2"))).starts_with("--tile 2/2: tile 2 of 2 does not exist"));
        assert!(
            err(part(None, Some("0/5"))).starts_with("--tile 0/5: 5 tiles are more than the image's 4 rows")
        );
        assert!(err(part(None, Some("3"))).starts_with("--tile 3: expected I/N"));
    }

    #[test]
    fn tiles_round_trip_with_their_passes_and_header() {
        use prism_geometry::glam::Vec3;
        let dir = tempfile::tempdir().unwrap();
        let bounds = PixelBounds::new(2, 4, 1, 2).unwrap();
        let depth =
            prism_shade::AovImage { aov: Aov::Depth, width: 2, height: 1, data: vec![1.5, f32::INFINITY] };
        let normal = prism_shade::AovImage {
            aov: Aov::Normal,
            width: 2,
            height: 1,
            data: vec![0.0, 1.0, 0.0, 0.6, 0.0, 0.8],
        };
        let header = TileHeader {
            version: "0.1.0".into(),
            scene: "s.toml".into(),
            inputs: "0123456789abcdef".into(),
            settings: "x".into(),
            spp: 4,
            tile: Some((1, 3)),
        };
        let tile = Tile {
            width: 5,
            height: 3,
            bounds,
            image: Image {
                width: 2,
                height: 1,
                pixels: vec![Vec3::new(0.1, 0.2, 0.3), Vec3::new(4.0, 5.0, 6.0)],
            },
            aovs: AovImages { width: 2, height: 1, passes: vec![depth, normal] },
            header,
        };
        let p = dir.path().join("t.exr");
        write_tile(&p, &tile).unwrap();
        let back = read_tile(&p).unwrap();
        assert_eq!((back.width, back.height, back.bounds), (5, 3, bounds));
        assert_eq!(back.image, tile.image);
        assert_eq!(back.header, tile.header);
        assert_eq!(back.aovs.get(Aov::Depth), tile.aovs.get(Aov::Depth));
        assert_eq!(back.aovs.get(Aov::Normal), tile.aovs.get(Aov::Normal));
        let raw = read_layered_exr(&p).unwrap();
        assert_eq!(raw.channel("N", "Z"), Some(&prism_shade::ExrSamples::F32(vec![0.0, 0.8])));
    }
}
