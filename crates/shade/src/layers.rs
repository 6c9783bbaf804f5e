//! A render as one multi-layer OpenEXR file: the beauty, its alpha and
//! every AOV pass under the standard channel names compositors look for
//! (`docs/aov.md`), written and read through [`crate::exr`], the one
//! layered EXR writer.
//!
//! | what | layer | channels | type |
//! |---|---|---|---|
//! | beauty (linear; premultiplied with alpha) | base | `R`, `G`, `B` | float |
//! | alpha (with `--alpha`) | base | `A` | float |
//! | `depth` | base | `Z` | float |
//! | `normal` (shading) | `N` | `N.X`, `N.Y`, `N.Z` | float |
//! | `geo_normal` | `Ng` | `Ng.X`, `Ng.Y`, `Ng.Z` | float |
//! | `albedo` | `albedo` | `albedo.R`, `albedo.G`, `albedo.B` | float |
//! | `object_id` | base | `id` | unsigned int, [`NO_ID`] where nothing is hit |

use crate::exr::{ExrChannel, ExrLayer, LayeredExr, read_layered_exr, write_layered_exr};
use crate::output::invalid;
use crate::{Aov, AovImage, AovImages, Image, OutputError, PixelBounds};
use prism_geometry::glam::Vec3;
use std::collections::BTreeMap;
use std::path::Path;

/// The `id` channel's value where a pixel's centre ray hit nothing (the
/// float pass's −1).
pub const NO_ID: u32 = u32::MAX;

/// Where pass `aov` is stored: `(layer, channels)` (`""` is the base layer).
#[must_use]
pub fn aov_exr_channels(aov: Aov) -> (&'static str, &'static [&'static str]) {
    match aov {
        Aov::Depth => ("", &["Z"]),
        Aov::Normal => ("N", &["X", "Y", "Z"]),
        Aov::GeoNormal => ("Ng", &["X", "Y", "Z"]),
        Aov::Albedo => ("albedo", &["R", "G", "B"]),
        Aov::ObjectId => ("", &["id"]),
    }
}

/// Interleaved values split into `channels` planes.
fn planes(data: &[f32], channels: usize) -> Vec<Vec<f32>> {
    (0..channels).map(|c| data.iter().skip(c).step_by(channels).copied().collect()).collect()
}

/// The layers of a render (channel names in `docs/aov.md`): the beauty `image`, its
/// `alpha` if any (one value per pixel), and the passes.
#[must_use]
pub fn render_layers(image: &Image, alpha: Option<&[f32]>, passes: &AovImages) -> Vec<ExrLayer> {
    let rgb: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
    let mut base: Vec<ExrChannel> =
        planes(&rgb, 3).into_iter().zip(["R", "G", "B"]).map(|(v, n)| ExrChannel::f32(n, v)).collect();
    if let Some(a) = alpha {
        base.push(ExrChannel::f32("A", a.to_vec()));
    }
    let mut layers: Vec<ExrLayer> = Vec::new();
    for pass in &passes.passes {
        let (layer, names) = aov_exr_channels(pass.aov);
        let channels: Vec<ExrChannel> = if pass.aov == Aov::ObjectId {
            let ids = pass.data.iter().map(|&v| if v >= 0.0 { v as u32 } else { NO_ID }).collect();
            vec![ExrChannel::u32("id", ids)]
        } else {
            planes(&pass.data, names.len())
                .into_iter()
                .zip(names)
                .map(|(v, n)| ExrChannel::f32(*n, v))
                .collect()
        };
        if layer.is_empty() {
            base.extend(channels);
        } else {
            layers.push(ExrLayer { name: layer.to_owned(), channels });
        }
    }
    layers.insert(0, ExrLayer { name: String::new(), channels: base });
    layers
}

/// Writes a render as one multi-layer OpenEXR file ([`render_layers`]),
/// atomically.
///
/// # Errors
/// [`OutputError::Invalid`] if `alpha` or a pass does not match the
/// image's size; else as [`crate::write_layered_exr`].
pub fn write_render_exr(
    path: &Path,
    image: &Image,
    alpha: Option<&[f32]>,
    passes: &AovImages,
) -> Result<(), OutputError> {
    let (w, h) = (image.width, image.height);
    let n = w as usize * h as usize;
    let bad_alpha = alpha.is_some_and(|a| a.len() != n);
    let bad_pass =
        passes.passes.iter().any(|p| (p.width, p.height) != (w, h) || p.data.len() != n * p.channels());
    if bad_alpha || bad_pass || image.pixels.len() != n {
        return Err(invalid(path, format!("the alpha and AOV passes must all be {w}×{h}, as the image")));
    }
    let data_window = PixelBounds::full(w, h)
        .ok_or_else(|| invalid(path, format!("cannot write an empty {w}×{h} image")))?;
    let exr = LayeredExr {
        width: w,
        height: h,
        data_window,
        layers: render_layers(image, alpha, passes),
        attributes: BTreeMap::new(),
    };
    write_layered_exr(path, &exr)
}

/// A render read back from a multi-layer file written by
/// [`write_render_exr`]: the beauty, the alpha if stored, and every pass
/// found, in [`Aov::ALL`] order.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderExr {
    /// The beauty (`R`, `G`, `B`).
    pub image: Image,
    /// `A`, if present.
    pub alpha: Option<Vec<f32>>,
    /// The passes present.
    pub passes: AovImages,
}

/// Reads a file written by [`write_render_exr`] (or any OpenEXR file with
/// those channel names; the data window must be the whole image).
///
/// # Errors
/// [`OutputError::Read`]/[`OutputError::Image`] if it cannot be read,
/// [`OutputError::Invalid`] if it has no `R`, `G`, `B`, a channel of the
/// wrong type, or a partial data window.
pub fn read_render_exr(path: &Path) -> Result<RenderExr, OutputError> {
    let exr = read_layered_exr(path)?;
    if Some(exr.data_window) != PixelBounds::full(exr.width, exr.height) {
        return Err(invalid(path, "the data window is not the whole image (a tile? merge it first)"));
    }
    render_from_exr(&exr, path)
}

/// The beauty, alpha and passes of `exr`'s data window (a whole image, or
/// a farm tile), under the channel names of [`render_layers`]; `path`
/// names the file in errors.
///
/// # Errors
/// [`OutputError::Invalid`] if it has no `R`, `G`, `B`, or a channel of
/// the wrong type or length.
pub fn render_from_exr(exr: &LayeredExr, path: &Path) -> Result<RenderExr, OutputError> {
    let (w, h) = (exr.data_window.width(), exr.data_window.height());
    let n = w as usize * h as usize;
    let f32s = |layer: &str, ch: &str| -> Result<Option<&[f32]>, OutputError> {
        match exr.channel(layer, ch) {
            None => Ok(None),
            Some(s) => s
                .as_f32()
                .filter(|v| v.len() == n)
                .map(Some)
                .ok_or_else(|| invalid(path, format!("channel {layer}.{ch} is not {n} floats"))),
        }
    };
    let interleave = |layer: &str, names: &[&str]| -> Result<Option<Vec<f32>>, OutputError> {
        let mut chans = Vec::new();
        for n in names {
            match f32s(layer, n)? {
                Some(c) => chans.push(c),
                None => return Ok(None),
            }
        }
        let len = chans.first().map_or(0, |c| c.len());
        Ok(Some((0..len).flat_map(|k| chans.iter().map(move |c| c[k])).collect()))
    };
    let rgb = interleave("", &["R", "G", "B"])?.ok_or_else(|| invalid(path, "no R, G, B channels"))?;
    let pixels = rgb.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    let alpha = f32s("", "A")?.map(<[f32]>::to_vec);
    let mut found = Vec::new();
    for aov in Aov::ALL {
        let (layer, names) = aov_exr_channels(aov);
        let data = if aov == Aov::ObjectId {
            match exr.channel(layer, "id") {
                None => None,
                Some(s) => {
                    let ids = s
                        .as_u32()
                        .filter(|v| v.len() == n)
                        .ok_or_else(|| invalid(path, format!("channel id is not {n} unsigned ints")))?;
                    Some(ids.iter().map(|&i| if i == NO_ID { -1.0 } else { i as f32 }).collect())
                }
            }
        } else {
            interleave(layer, names)?
        };
        if let Some(data) = data {
            found.push(AovImage { aov, width: w, height: h, data });
        }
    }
    Ok(RenderExr {
        image: Image { width: w, height: h, pixels },
        alpha,
        passes: AovImages { width: w, height: h, passes: found },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn passes() -> AovImages {
        let (w, h) = (2, 1);
        let pass = |aov: Aov, data: Vec<f32>| AovImage { aov, width: w, height: h, data };
        AovImages {
            width: w,
            height: h,
            passes: vec![
                pass(Aov::ObjectId, vec![3.0, -1.0]),
                pass(Aov::Depth, vec![2.5, f32::INFINITY]),
                pass(Aov::Normal, vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
                pass(Aov::GeoNormal, vec![0.0, 0.6, 0.8, 0.0, 0.0, 0.0]),
                pass(Aov::Albedo, vec![0.5, 0.25, 0.125, 0.0, 0.0, 0.0]),
            ],
        }
    }

    #[test]
    fn a_render_round_trips_with_standard_names() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.exr");
        let image = Image { width: 2, height: 1, pixels: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO] };
        let alpha = [1.0, 0.0];
        write_render_exr(&p, &image, Some(&alpha), &passes()).unwrap();
        let raw = read_layered_exr(&p).unwrap();
        let names = |l: &str| -> Vec<&str> {
            let mut v: Vec<&str> = raw.layer(l).unwrap().channels.iter().map(|c| c.name.as_str()).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(names(""), ["A", "B", "G", "R", "Z", "id"]);
        assert_eq!(names("N"), ["X", "Y", "Z"]);
        assert_eq!(names("Ng"), ["X", "Y", "Z"]);
        assert_eq!(names("albedo"), ["B", "G", "R"]);
        assert_eq!(raw.channel("", "id").unwrap().as_u32(), Some(&[3, NO_ID][..]));
        let back = read_render_exr(&p).unwrap();
        assert_eq!(back.image, image);
        assert_eq!(back.alpha.as_deref(), Some(&alpha[..]));
        let mut want = passes();
        want.passes.sort_by_key(|p| Aov::ALL.iter().position(|a| *a == p.aov));
        assert_eq!(back.passes, want);
    }

    #[test]
    fn mismatched_sizes_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.exr");
        let image = Image { width: 1, height: 1, pixels: vec![Vec3::ZERO] };
        let e = write_render_exr(
            &p,
            &image,
            Some(&[1.0, 1.0]),
            &AovImages { width: 1, height: 1, passes: vec![] },
        );
        assert!(matches!(e, Err(OutputError::Invalid { .. })), "{e:?}");
        let e = write_render_exr(&p, &image, None, &passes());
        assert!(matches!(e, Err(OutputError::Invalid { .. })), "{e:?}");
        assert!(!p.exists());
    }
}
