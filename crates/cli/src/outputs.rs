//! What `prism render` writes besides the statistics, decided once before
//! the render (so that every file is checked against the inputs first) and
//! written after it: the image (PNG through the exposure, tone mapping and
//! bit depth flags; EXR linear), its alpha, and the AOV passes, as layers
//! of one multi-layer EXR or, with `--aov-files`, as separate files.

use anyhow::{Result, anyhow};
use clap::Args;
use prism_shade::{
    AovImages, BitDepth, Image, OutputError, OutputFormat, PngOptions, Tonemap, aov_path, write_aov_files,
    write_aov_preview_png, write_image, write_png, write_render_exr,
};
use std::path::PathBuf;

/// `--alpha`, apart from [`ImageArgs`]: `prism merge` takes those but not
/// this (tiles hold no alpha).
#[derive(Args)]
pub struct AlphaArgs {
    /// Make the background transparent: RGBA output (PNG with straight alpha, EXR premultiplied).
    #[arg(long)]
    pub alpha: bool,
}

/// The image flags of `prism render` and `prism merge`.
#[derive(Args)]
pub struct ImageArgs {
    /// Bits per channel of a PNG: 8 or 16.
    #[arg(long, value_name = "BITS", default_value = "8", value_parser = ["8", "16"])]
    bit_depth: String,
    /// Exposure in stops for PNG output (the linear values times 2^EV); EXR stays linear.
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Tone mapping for PNG output: clamp (default), reinhard, aces; EXR stays linear.
    #[arg(long, value_name = "OP", default_value = "clamp", hide_possible_values = true, value_parser = prism_scene::Named {
        parser: parse_tonemap,
        names: Tonemap::ALL.map(Tonemap::name).to_vec(),
    })]
    tonemap: Tonemap,
    /// Write each AOV pass to its own file (OUT-stem.PASS.exr, RGB) instead of as layers of one EXR.
    #[arg(long)]
    aov_files: bool,
}

fn parse_tonemap(s: &str) -> Result<Tonemap, String> {
    s.parse().map_err(|e: prism_shade::TonemapParseError| e.to_string())
}

/// The files of one render and how to write them.
#[derive(Clone)]
pub struct Plan {
    /// The image.
    pub output: PathBuf,
    format: OutputFormat,
    png: PngOptions,
    /// Whether the background is transparent.
    pub alpha: bool,
    /// AOV passes go to separate files (the old layout).
    aov_files: bool,
    previews: bool,
    /// Whether passes were asked for.
    has_aovs: bool,
}

impl Plan {
    /// The same plan for another image (one frame of a turntable).
    pub fn for_output(&self, output: PathBuf) -> Plan {
        Plan { output, ..self.clone() }
    }

    /// The image's format.
    pub fn format(&self) -> OutputFormat {
        self.format
    }

    /// Whether 8-bit previews of the passes are written.
    pub fn previews(&self) -> bool {
        self.previews
    }

    /// Whether the passes go to files of their own (`--aov-files`).
    pub fn aov_files(&self) -> bool {
        self.aov_files
    }

    /// The size in bytes of every file of a `width × height` render with
    /// `aovs`, uncompressed: an upper bound for the free-space check.
    pub fn uncompressed_bytes(&self, width: u32, height: u32, aovs: &[prism_shade::Aov]) -> u64 {
        let pixels = u64::from(width) * u64::from(height);
        let colour = 3 + u64::from(self.alpha);
        let image = match self.format {
            OutputFormat::Png => colour * if self.png.bit_depth == BitDepth::Sixteen { 2 } else { 1 },
            OutputFormat::Exr => colour * 4,
        };
        let passes: u64 = aovs.iter().map(|a| a.channels() as u64 * 4).sum();
        // Beside a PNG the passes' EXR repeats the colour as floats; previews are 8-bit RGB.
        let beside = if self.has_aovs && self.format == OutputFormat::Png { colour * 4 } else { 0 };
        let previews = if self.previews { 3 * aovs.len() as u64 } else { 0 };
        pixels * (image + passes + beside + previews)
    }

    /// The bytes the writers of a `width × height` render with `aovs`
    /// allocate besides the render's own buffers, the most of those that
    /// run one after another (the image, then the passes' files, then the
    /// previews; each frees its buffers before the next starts), for
    /// `crate::memory::RenderMemory::writers`. `tile`: the part of an image
    /// written as a tile file. A render holds no NaN (a non-finite sample
    /// counts as black; a pass has none), so the EXR writers' NaN-free
    /// copies are not made.
    pub fn writer_bytes(&self, width: u32, height: u32, aovs: &[prism_shade::Aov], tile: bool) -> u64 {
        // In u128: no product of these overflows it.
        let (w, h) = (u128::from(width), u128::from(height));
        let n = w * h;
        let alpha = u128::from(self.alpha);
        let channels: u128 = aovs.iter().map(|a| a.channels() as u128).sum();
        // A zlib stream of `raw` bytes: no longer than them and deflate's
        // block headers (5 bytes in 64 KiB; 1 in 1024 is ample), in a
        // growing Vec that may reserve up to twice that.
        let zlib = |raw: u128| 2 * (raw + raw / 1024 + 64);
        // A PNG of `k` bytes a pixel (`write_png`): the encoded pixels,
        // their big-endian copy at 16 bits (the image crate's), the zlib
        // stream of the rows with a filter byte each, and png's previous
        // and current row.
        let png = |k: u128, sixteen: bool| n * k * (1 + u128::from(sixteen)) + zlib(n * k + h) + 2 * w * k;
        // A layered EXR of `floats` a pixel (`render_layers`, then
        // `write_layered_exr`): the layers' planar copy and the writer's
        // copy of it (render_layers' interleaved colour, freed before that
        // copy is made, is no larger), and five blocks of 16 rows (ZIP16: the
        // block, the buffer its bytes are split into, the compressed
        // block reserving up to twice, the chunk written).
        let layered = |floats: u128| 2 * n * floats * 4 + 5 * 16 * w * floats * 4;
        let image = if tile {
            layered(3 + channels)
        } else {
            match self.format {
                OutputFormat::Png => {
                    let sixteen = self.png.bit_depth == BitDepth::Sixteen;
                    png((3 + alpha) * if sixteen { 2 } else { 1 }, sixteen)
                }
                // The colour, alpha and passes in one file; or
                // (`write_image_exr`) the colour alone, interleaved (the
                // image crate's encoder reads it a 64 × 64 tile at a time).
                OutputFormat::Exr if self.alpha || (self.has_aovs && !self.aov_files) => {
                    layered(3 + alpha + if self.aov_files { 0 } else { channels })
                }
                OutputFormat::Exr => n * 12,
            }
        };
        let bytes = if tile || aovs.is_empty() {
            image
        } else {
            // The passes each in a file of their own (`write_aov_exr`: its
            // RGB floats), or beside a PNG in one layered file.
            let files = if self.aov_files {
                n * 12
            } else if self.format == OutputFormat::Png {
                layered(3 + alpha + channels)
            } else {
                0
            };
            // A pass's preview: its 8-bit RGB, and the finite depths (a Vec
            // that may reserve up to twice their 4 bytes) or the PNG's
            // stream and rows.
            let previews = if self.previews { n * 3 + (8 * n).max(zlib(n * 3 + h) + 6 * w) } else { 0 };
            image.max(files).max(previews)
        };
        u64::try_from(bytes).unwrap_or(u64::MAX)
    }
}

impl ImageArgs {
    /// The flags that give another `prism render` or `prism merge` these
    /// choices (the defaults are left out).
    pub fn flags(&self) -> Vec<String> {
        let mut v = Vec::new();
        if self.bit_depth != "8" {
            v.extend(["--bit-depth".to_owned(), self.bit_depth.clone()]);
        }
        if self.exposure != 0.0 {
            v.extend(["--exposure".to_owned(), self.exposure.to_string()]);
        }
        if self.tonemap != Tonemap::Clamp {
            v.extend(["--tonemap".to_owned(), self.tonemap.name().to_owned()]);
        }
        if self.aov_files {
            v.push("--aov-files".to_owned());
        }
        v
    }

    /// The plan for `output` (format known), with or without a transparent
    /// background (`alpha`) and passes; warns
    /// (returned as text) about flags that do not apply.
    ///
    /// # Errors
    /// An `--exposure` that is not a number in [-64, 64].
    pub fn plan(
        &self,
        output: PathBuf,
        format: OutputFormat,
        alpha: bool,
        has_aovs: bool,
        previews: bool,
    ) -> Result<(Plan, Vec<String>)> {
        if !self.exposure.is_finite() || self.exposure.abs() > 64.0 {
            return Err(anyhow!("--exposure: must be a number of stops in [-64, 64], got {}", self.exposure));
        }
        let png = PngOptions {
            exposure: self.exposure,
            tonemap: self.tonemap,
            bit_depth: if self.bit_depth == "16" { BitDepth::Sixteen } else { BitDepth::Eight },
        };
        let mut warnings = Vec::new();
        if format == OutputFormat::Exr && png != PngOptions::default() {
            warnings.push(
                "--exposure, --tonemap and --bit-depth apply to PNG output only; the EXR stays linear float"
                    .to_owned(),
            );
        }
        if self.aov_files && !has_aovs {
            warnings.push(
                "--aov-files without AOV passes (--aov or the scene's `aov`) writes no pass files".into(),
            );
        }
        let plan = Plan { output, format, png, alpha, aov_files: self.aov_files, previews, has_aovs };
        Ok((plan, warnings))
    }
}

impl Plan {
    /// The multi-layer EXR holding the passes when the image is a PNG:
    /// `<stem>.aov.exr` beside it.
    fn layered_beside(&self) -> Result<Option<PathBuf>, OutputError> {
        if !self.has_aovs || self.aov_files || self.format == OutputFormat::Exr {
            return Ok(None);
        }
        let stem = self.output.file_stem().ok_or_else(|| OutputError::Invalid {
            path: self.output.clone(),
            reason: "the output path has no file name".into(),
        })?;
        let mut name = stem.to_os_string();
        name.push(".aov.exr");
        Ok(Some(self.output.with_file_name(name)))
    }

    /// Every file the render may write besides the image, for the checks
    /// made before rendering.
    ///
    /// # Errors
    /// An output path without a file name.
    pub fn other_files(&self, aovs: &[prism_shade::Aov]) -> Result<Vec<PathBuf>, OutputError> {
        let mut v: Vec<PathBuf> = self.layered_beside()?.into_iter().collect();
        for &a in aovs {
            if self.aov_files {
                v.push(aov_path(&self.output, a, "exr")?);
            }
            if self.previews {
                v.push(aov_path(&self.output, a, "png")?);
            }
        }
        Ok(v)
    }

    /// Writes the image: `color` (premultiplied by `alpha` when given) as a
    /// PNG through the flags, or as a linear EXR whose base layer holds
    /// `A` too, and the passes as its layers unless they go elsewhere.
    ///
    /// # Errors
    /// As the writers.
    pub fn write_image(
        &self,
        color: &Image,
        alpha: Option<&[f32]>,
        passes: Option<&AovImages>,
    ) -> Result<(), OutputError> {
        match self.format {
            OutputFormat::Png => write_png(&self.output, color, alpha, &self.png),
            OutputFormat::Exr => {
                let layered = passes.filter(|_| !self.aov_files);
                if alpha.is_none() && layered.is_none() {
                    return write_image(&self.output, color, OutputFormat::Exr);
                }
                let empty = AovImages { width: color.width, height: color.height, passes: Vec::new() };
                write_render_exr(&self.output, color, alpha, layered.unwrap_or(&empty))
            }
        }
    }

    /// Writes the passes that do not live in the image (the multi-layer
    /// `<stem>.aov.exr` beside a PNG, or the separate files) and the
    /// previews; returns the files written, in order.
    ///
    /// # Errors
    /// As the writers; files written before an error stay, unless the
    /// call is inside `prism_shade::all_or_nothing` (as the render's and
    /// merge's are), which then removes them all.
    pub fn write_passes(
        &self,
        color: &Image,
        alpha: Option<&[f32]>,
        passes: &AovImages,
    ) -> Result<Vec<PathBuf>, OutputError> {
        if self.aov_files {
            return write_aov_files(&self.output, passes, self.previews);
        }
        let mut written = Vec::new();
        if let Some(beside) = self.layered_beside()? {
            write_render_exr(&beside, color, alpha, passes)?;
            written.push(beside);
        }
        if self.previews {
            for pass in &passes.passes {
                let png = aov_path(&self.output, pass.aov, "png")?;
                write_aov_preview_png(&png, pass)?;
                written.push(png);
            }
        }
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_shade::Aov;

    fn plan(
        output: &str,
        bit_depth: &str,
        alpha: bool,
        aov_files: bool,
        aovs: &[Aov],
        previews: bool,
    ) -> Plan {
        let args =
            ImageArgs { bit_depth: bit_depth.to_owned(), exposure: 0.0, tonemap: Tonemap::Clamp, aov_files };
        let format = OutputFormat::from_path(std::path::Path::new(output)).unwrap();
        args.plan(output.into(), format, alpha, !aovs.is_empty(), previews).unwrap().0
    }

    #[test]
    fn the_writers_bytes_hold_their_copies() {
        let (w, h) = (300, 200);
        let n = 300 * 200;
        // A 16-bit RGBA PNG: the encoded pixels, their big-endian copy, a
        // zlib stream at least as long (noise does not compress).
        let p = plan("a.png", "16", true, false, &[], false);
        assert!(p.writer_bytes(w, h, &[], false) >= 3 * n * 8);
        // A layered EXR: the layers and the writer's copy of them, twice
        // the file's floats.
        for (out, alpha) in [("a.exr", true), ("a.exr", false), ("a.png", true), ("a.png", false)] {
            let p = plan(out, "8", alpha, false, &Aov::ALL, false);
            let floats = 3 + u64::from(alpha) + 11;
            assert!(p.writer_bytes(w, h, &Aov::ALL, false) >= 2 * n * floats * 4, "{out} {alpha}");
            // As a tile (no alpha there).
            assert!(p.writer_bytes(w, h, &Aov::ALL, true) >= 2 * n * 14 * 4, "{out} {alpha}");
        }
        // The colour alone as EXR: its interleaved copy; each pass in its
        // own file: its RGB floats; previews: 3 bytes and up to 8 for the
        // finite depths.
        let p = plan("a.exr", "8", false, true, &[Aov::Depth], true);
        assert!(p.writer_bytes(w, h, &[Aov::Depth], false) >= n * 12);
        let p = plan("a.png", "8", false, false, &[Aov::Depth], true);
        assert!(p.writer_bytes(w, h, &[Aov::Depth], false) >= n * (3 + 8));
        // The largest image there can be does not overflow.
        let p = plan("a.exr", "8", true, false, &Aov::ALL, true);
        assert_eq!(p.writer_bytes(u32::MAX, u32::MAX, &Aov::ALL, false), u64::MAX);
    }
}
