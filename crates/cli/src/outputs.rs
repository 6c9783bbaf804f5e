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
