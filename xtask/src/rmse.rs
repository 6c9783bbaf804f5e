//! `cargo xtask rmse A.png B.png`: the root-mean-square difference of two
//! images of one size, over their 8-bit sRGB values scaled to `[0, 1]`
//! (every channel of every pixel), for the whole image and for its top,
//! middle and bottom thirds (issue 12's measure: a few-sample render
//! against a many-sample one of the same build; see docs/benchmarks.md).
//! `--diff OUT.png` also writes the absolute difference, times 8.
//! `--worst-rows N` also lists the `N` rows holding the largest shares of
//! the squared error, and the RMSE with their error counted as zero (a
//! single horizontal edge, such as a horizon, can hold half of it).

use anyhow::{Context, Result, bail};

pub fn run(args: &[String]) -> Result<()> {
    let usage = "usage: cargo xtask rmse A.png B.png [--diff OUT.png] [--worst-rows N]";
    let [a, b, flags @ ..] = args else { bail!(usage) };
    let (mut diff, mut worst) = (None, 0usize);
    let mut rest = flags;
    while let [flag, value, tail @ ..] = rest {
        match flag.as_str() {
            "--diff" => diff = Some(value),
            "--worst-rows" => {
                worst = value.parse().with_context(|| format!("--worst-rows {value}: not a count"))?
            }
            _ => bail!(usage),
        }
        rest = tail;
    }
    if !rest.is_empty() {
        bail!(usage);
    }
    let load = |p: &String| -> Result<image::RgbImage> {
        Ok(image::open(crate::user_path(p)).with_context(|| format!("cannot read {p}"))?.to_rgb8())
    };
    let (a, b) = (load(a)?, load(b)?);
    if a.dimensions() != b.dimensions() {
        bail!("the images differ in size: {:?} and {:?}", a.dimensions(), b.dimensions());
    }
    let (w, h) = a.dimensions();
    if let Some(out) = diff {
        let d: Vec<u8> =
            a.as_raw().iter().zip(b.as_raw()).map(|(&x, &y)| x.abs_diff(y).saturating_mul(8)).collect();
        image::save_buffer(crate::user_path(out), &d, w, h, image::ExtendedColorType::Rgb8)
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
    if worst > 0 {
        let sums = row_squared_errors(a.as_raw(), b.as_raw(), w as usize * 3);
        let total: f64 = sums.iter().sum();
        let ranked = worst_rows(&sums, worst);
        for &y in &ranked {
            let share = if total > 0.0 { 100.0 * sums[y] / total } else { 0.0 };
            println!("row {y}: rmse {:.5}, {share:.1}% of the squared error", part(y as u32, y as u32 + 1));
        }
        let left: f64 = total - ranked.iter().map(|&y| sums[y]).sum::<f64>();
        let values = (w as usize * h as usize * 3).max(1) as f64;
        println!("rmse {:.5} with the error of those rows counted as zero", (left.max(0.0) / values).sqrt());
    }
    Ok(())
}

/// RMSE of two equally long byte slices, each byte read as `b / 255`.
fn rmse(a: &[u8], b: &[u8]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    (squared_error(a, b) / a.len() as f64).sqrt()
}

/// The summed squared difference of two equally long byte slices, each
/// byte read as `b / 255`.
fn squared_error(a: &[u8], b: &[u8]) -> f64 {
    a.iter().zip(b).map(|(&x, &y)| ((f64::from(x) - f64::from(y)) / 255.0).powi(2)).sum()
}

/// The summed squared error of each row of `row_len` bytes.
fn row_squared_errors(a: &[u8], b: &[u8], row_len: usize) -> Vec<f64> {
    a.chunks(row_len.max(1)).zip(b.chunks(row_len.max(1))).map(|(x, y)| squared_error(x, y)).collect()
}

/// The indices of the `n` largest of `sums`, largest first (ties: lower index first).
fn worst_rows(sums: &[f64], n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..sums.len()).collect();
    order.sort_by(|&i, &j| sums[j].total_cmp(&sums[i]).then(i.cmp(&j)));
    order.truncate(n);
    order
}

#[cfg(test)]
mod tests {
    use super::{rmse, row_squared_errors, worst_rows};

    #[test]
    fn rmse_of_known_differences() {
        assert_eq!(rmse(&[10, 20, 30], &[10, 20, 30]), 0.0);
        // Every value off by 51 = 0.2.
        assert!((rmse(&[0, 51, 100], &[51, 0, 151]) - 0.2).abs() < 1e-12);
        // One of four off by 255: sqrt(1/4).
        assert!((rmse(&[0, 0, 0, 0], &[255, 0, 0, 0]) - 0.5).abs() < 1e-12);
        assert_eq!(rmse(&[], &[]), 0.0);
    }

    #[test]
    fn rows_ranked_by_squared_error() {
        // Three rows of two values: row 1 off by 255 once, row 2 by 51 twice, row 0 exact.
        let a = [0, 0, 255, 0, 51, 51];
        let b = [0, 0, 0, 0, 0, 0];
        let sums = row_squared_errors(&a, &b, 2);
        assert_eq!(sums.len(), 3);
        assert_eq!(sums[0], 0.0);
        assert!((sums[1] - 1.0).abs() < 1e-12 && (sums[2] - 0.08).abs() < 1e-12);
        assert_eq!(worst_rows(&sums, 2), vec![1, 2]);
        assert_eq!(worst_rows(&sums, 9), vec![1, 2, 0]);
        assert_eq!(worst_rows(&sums, 0), Vec::<usize>::new());
    }
}
