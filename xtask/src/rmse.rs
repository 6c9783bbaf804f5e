//! `cargo xtask rmse A.png B.png`: the root-mean-square difference of two
//! images of one size, over their 8-bit sRGB values scaled to `[0, 1]`
//! (every channel of every pixel), for the whole image and for its top,
//! middle and bottom thirds (issue 12's measure: a few-sample render
//! against a many-sample one of the same build; see docs/benchmarks.md).
//! `--diff OUT.png` also writes the absolute difference, times 8.

use anyhow::{Context, Result, bail};

pub fn run(args: &[String]) -> Result<()> {
    let (a, b, diff) = match args {
        [a, b] => (a, b, None),
        [a, b, flag, out] if flag == "--diff" => (a, b, Some(out)),
        _ => bail!("usage: cargo xtask rmse A.png B.png [--diff OUT.png]"),
    };
    let load = |p: &String| -> Result<image::RgbImage> {
        Ok(image::open(p).with_context(|| format!("cannot read {p}"))?.to_rgb8())
    };
    let (a, b) = (load(a)?, load(b)?);
    if a.dimensions() != b.dimensions() {
        bail!("the images differ in size: {:?} and {:?}", a.dimensions(), b.dimensions());
    }
    let (w, h) = a.dimensions();
    if let Some(out) = diff {
        let d: Vec<u8> =
            a.as_raw().iter().zip(b.as_raw()).map(|(&x, &y)| x.abs_diff(y).saturating_mul(8)).collect();
        image::save_buffer(out, &d, w, h, image::ExtendedColorType::Rgb8)
            .with_context(|| format!("cannot write {out}"))?;
    }
    let row = |y: u32| (y * w * 3) as usize;
    let part = |from: u32, to: u32| rmse(&a.as_raw()[row(from)..row(to)], &b.as_raw()[row(from)..row(to)]);
    println!(
        "rmse {:.5} (top third {:.5}, middle {:.5}, bottom {:.5}) over {w}x{h}",
        part(0, h),
        part(0, h / 3),
        part(h / 3, 2 * h / 3),
        part(2 * h / 3, h)
    );
    Ok(())
}

/// RMSE of two equally long byte slices, each byte read as `b / 255`.
fn rmse(a: &[u8], b: &[u8]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    let sum: f64 = a.iter().zip(b).map(|(&x, &y)| ((f64::from(x) - f64::from(y)) / 255.0).powi(2)).sum();
    (sum / a.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::rmse;

    #[test]
    fn rmse_of_known_differences() {
        assert_eq!(rmse(&[10, 20, 30], &[10, 20, 30]), 0.0);
        // Every value off by 51 = 0.2.
        assert!((rmse(&[0, 51, 100], &[51, 0, 151]) - 0.2).abs() < 1e-12);
        // One of four off by 255: sqrt(1/4).
        assert!((rmse(&[0, 0, 0, 0], &[255, 0, 0, 0]) - 0.5).abs() < 1e-12);
        assert_eq!(rmse(&[], &[]), 0.0);
    }
}
