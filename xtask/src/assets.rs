//! `cargo xtask assets [--check]`: regenerate (or check) what `assets/`
//! holds. Everything there is made by this file, deterministically:
//!
//! - `gas-giant.png`: a banded gas-giant texture (1024×512, equirectangular,
//!   seamless in longitude) with turbulent bands and a great red spot, for
//!   the report's textured planet;
//! - `gem.obj` + `gem.mtl`: a faceted gem (flat normals, a glass MTL
//!   material), a few KB;
//! - `torus.obj`: a low-poly torus with uvs and no normals (prism computes
//!   smooth ones).
//!
//! `--check` regenerates in memory and compares with the committed files
//! (the OBJ/MTL text exactly, the PNG by decoded pixels within 2/255 so that
//! a different floating-point library cannot fail it).

use anyhow::{Context, Result, bail};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

const TEX_W: u32 = 1024;
const TEX_H: u32 = 512;

pub fn run(args: &[String]) -> Result<()> {
    let check = match args {
        [] => false,
        [a] if a == "--check" => true,
        _ => bail!("usage: cargo xtask assets [--check]"),
    };
    let dir = Path::new("assets");
    let texts = [("gem.obj", gem_obj()), ("gem.mtl", gem_mtl()), ("torus.obj", torus_obj())];
    let pixels = gas_giant();
    if check {
        let mut stale = Vec::new();
        for (name, text) in &texts {
            match std::fs::read_to_string(dir.join(name)) {
                Ok(old) if old == *text => {}
                _ => stale.push(name.to_string()),
            }
        }
        let png = dir.join("gas-giant.png");
        match image::open(&png) {
            Ok(img) => {
                let img = img.to_rgb8();
                let same = img.width() == TEX_W
                    && img.height() == TEX_H
                    && img.as_raw().iter().zip(&pixels).all(|(a, b)| a.abs_diff(*b) <= 2);
                if !same {
                    stale.push("gas-giant.png".into());
                }
            }
            Err(_) => stale.push("gas-giant.png".into()),
        }
        if !stale.is_empty() {
            bail!("assets/ is not what `cargo xtask assets` makes: {} (run it and commit)", stale.join(", "));
        }
        eprintln!("assets/ is up to date");
        return Ok(());
    }
    std::fs::create_dir_all(dir)?;
    for (name, text) in &texts {
        std::fs::write(dir.join(name), text).with_context(|| format!("writing assets/{name}"))?;
        println!("assets/{name} ({} bytes)", text.len());
    }
    let img = image::RgbImage::from_raw(TEX_W, TEX_H, pixels).context("texture size")?;
    img.save(dir.join("gas-giant.png")).context("writing assets/gas-giant.png")?;
    println!("assets/gas-giant.png ({TEX_W}×{TEX_H})");
    Ok(())
}

// ----- the gas giant ----------------------------------------------------

/// An integer hash to [0, 1).
fn hash3(x: i64, y: i64, z: i64) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (z as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    h = h.wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^= h >> 32;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn smooth(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// Trilinear value noise in [-1, 1].
fn noise(p: [f64; 3]) -> f64 {
    let f = p.map(f64::floor);
    let i = f.map(|v| v as i64);
    let t = [smooth(p[0] - f[0]), smooth(p[1] - f[1]), smooth(p[2] - f[2])];
    let mut acc = 0.0;
    for c in 0..8 {
        let (dx, dy, dz) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
        let w = (if dx == 1 { t[0] } else { 1.0 - t[0] })
            * (if dy == 1 { t[1] } else { 1.0 - t[1] })
            * (if dz == 1 { t[2] } else { 1.0 - t[2] });
        acc += w * hash3(i[0] + dx, i[1] + dy, i[2] + dz);
    }
    2.0 * acc - 1.0
}

/// Fractal noise: `octaves` octaves of value noise.
fn fbm(p: [f64; 3], octaves: u32) -> f64 {
    let (mut sum, mut amp, mut freq, mut norm) = (0.0, 1.0, 1.0, 0.0);
    for _ in 0..octaves {
        sum += amp * noise([p[0] * freq, p[1] * freq, p[2] * freq]);
        norm += amp;
        amp *= 0.5;
        freq *= 2.03;
    }
    sum / norm
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// Band colours from north (v = 0) to south (v = 1), as (v, sRGB colour).
const BANDS: [(f64, [f64; 3]); 13] = [
    (0.00, [0.55, 0.50, 0.46]),
    (0.12, [0.70, 0.62, 0.52]),
    (0.22, [0.86, 0.78, 0.64]),
    (0.30, [0.70, 0.50, 0.35]),
    (0.36, [0.93, 0.88, 0.78]),
    (0.42, [0.62, 0.40, 0.26]),
    (0.50, [0.95, 0.92, 0.84]),
    (0.56, [0.74, 0.52, 0.36]),
    (0.63, [0.90, 0.82, 0.68]),
    (0.70, [0.66, 0.46, 0.32]),
    (0.78, [0.88, 0.80, 0.66]),
    (0.88, [0.68, 0.60, 0.52]),
    (1.00, [0.52, 0.48, 0.45]),
];

fn band_color(v: f64) -> [f64; 3] {
    let v = v.clamp(0.0, 1.0);
    for w in BANDS.windows(2) {
        let ((v0, c0), (v1, c1)) = (w[0], w[1]);
        if v <= v1 {
            return mix(c0, c1, smooth((v - v0) / (v1 - v0)));
        }
    }
    BANDS[BANDS.len() - 1].1
}

/// The texture as sRGB bytes, row 0 at the north pole.
fn gas_giant() -> Vec<u8> {
    // The great red spot: centre in (u, v) and radii.
    let (su, sv, sru, srv) = (0.66, 0.64, 0.055, 0.034);
    let mut out = Vec::with_capacity((TEX_W * TEX_H * 3) as usize);
    for y in 0..TEX_H {
        let v = (f64::from(y) + 0.5) / f64::from(TEX_H);
        for x in 0..TEX_W {
            let u = (f64::from(x) + 0.5) / f64::from(TEX_W);
            // Noise on a cylinder so that the texture wraps in longitude.
            let a = 2.0 * PI * u;
            let p = |r: f64, k: f64| [r * a.cos(), r * a.sin(), v * k];
            // Flow along the bands: strong east–west stretching.
            let warp = fbm(p(3.0, 40.0), 5);
            let fine = fbm(p(12.0, 160.0), 4);
            let mut vv = v + 0.018 * warp + 0.004 * fine;
            // Spot: a vortex that drags the bands around it.
            let du = (u - su) / sru;
            let dv = (v - sv) / srv;
            let r = (du * du + dv * dv).sqrt();
            let swirl = (-r * r * 1.5).exp();
            vv += 0.02 * swirl * (3.0 * dv.atan2(du) + 4.0 * r).sin();
            let mut c = band_color(vv);
            // Striations within the bands.
            let stria = (vv * 180.0 + 3.0 * warp).sin() * 0.035 + fine * 0.03;
            c = c.map(|k| k + stria);
            // The spot itself: a red oval with a paler rim and inner swirls.
            if r < 1.6 {
                let inner = 1.0 - smooth(((r - 0.75) / 0.3).clamp(0.0, 1.0));
                let rim = (-((r - 1.05) / 0.12).powi(2)).exp();
                let curl = (dv.atan2(du) * 2.0 + r * 9.0 + 2.0 * warp).sin();
                let red = mix([0.78, 0.38, 0.24], [0.66, 0.28, 0.18], 0.5 + 0.5 * curl);
                c = mix(c, red, inner);
                c = mix(c, [0.96, 0.92, 0.84], 0.6 * rim);
            }
            // Small white ovals in the southern bands.
            for k in 0..5 {
                let cu = 0.1 + 0.19 * f64::from(k);
                let (eu, ev) = ((u - cu) / 0.012, (v - 0.745) / 0.008);
                let e = (-(eu * eu + ev * ev)).exp();
                c = mix(c, [0.97, 0.95, 0.9], 0.8 * e);
            }
            // Limb-like darkening toward the poles.
            let lat = (v - 0.5) * 2.0;
            let dark = 1.0 - 0.25 * lat.powi(4);
            for k in c {
                out.push(((k * dark).clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
    }
    out
}

// ----- meshes -------------------------------------------------------------

fn num(x: f64) -> String {
    let s = format!("{x:.5}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn vec_line(kind: &str, v: [f64; 3]) -> String {
    format!("{kind} {} {} {}\n", num(v[0]), num(v[1]), num(v[2]))
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// A brilliant-cut-like gem: a flat table, a crown of kite and star facets,
/// a girdle, and a pavilion down to the culet. Faces are written with one
/// normal each (flat facets), counter-clockwise seen from outside.
fn gem_obj() -> String {
    const N: usize = 8;
    let ring = |r: f64, y: f64, phase: f64| -> Vec<[f64; 3]> {
        (0..N)
            .map(|i| {
                let a = 2.0 * PI * (i as f64 + phase) / N as f64;
                [r * a.cos(), y, r * a.sin()]
            })
            .collect()
    };
    let table = ring(0.55, 0.42, 0.0);
    let crown = ring(0.85, 0.22, 0.5);
    let girdle = ring(1.0, 0.0, 0.0);
    let culet = [0.0, -0.95, 0.0];
    let table_centre = [0.0, 0.42, 0.0];

    let mut verts: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<[usize; 3]> = Vec::new();
    let add = |v: [f64; 3], verts: &mut Vec<[f64; 3]>| -> usize {
        verts.push(v);
        verts.len()
    };
    let tc = add(table_centre, &mut verts);
    let t: Vec<usize> = table.iter().map(|&v| add(v, &mut verts)).collect();
    let c: Vec<usize> = crown.iter().map(|&v| add(v, &mut verts)).collect();
    let g: Vec<usize> = girdle.iter().map(|&v| add(v, &mut verts)).collect();
    let cu = add(culet, &mut verts);
    for i in 0..N {
        let j = (i + 1) % N;
        // Table: a fan, seen from above (normal +Y) counter-clockwise.
        faces.push([tc, t[j], t[i]]);
        // Star facet between two table corners and a crown point.
        faces.push([t[i], t[j], c[i]]);
        // Kite facets from the crown points down to the girdle.
        faces.push([t[j], c[j], c[i]]);
        faces.push([c[i], g[j], g[i]]);
        faces.push([c[i], c[j], g[j]]);
        // Pavilion.
        faces.push([g[i], g[j], cu]);
    }
    let mut s = String::from("# A faceted gem, generated by `cargo xtask assets`.\nmtllib gem.mtl\no gem\n");
    for v in &verts {
        s += &vec_line("v", *v);
    }
    // Orient every face outward (the gem is convex about its centre).
    let centre = [0.0, 0.0, 0.0];
    let mut normals = Vec::new();
    for f in &mut faces {
        let [a, b, cc] = f.map(|i| verts[i - 1]);
        let mut n = unit(cross(sub(b, a), sub(cc, a)));
        let mid = [(a[0] + b[0] + cc[0]) / 3.0, (a[1] + b[1] + cc[1]) / 3.0, (a[2] + b[2] + cc[2]) / 3.0];
        let out = sub(mid, centre);
        if n[0] * out[0] + n[1] * out[1] + n[2] * out[2] < 0.0 {
            f.swap(1, 2);
            n = n.map(|k| -k);
        }
        normals.push(n);
    }
    for n in &normals {
        s += &vec_line("vn", *n);
    }
    s += "usemtl gem\ns off\n";
    for (k, f) in faces.iter().enumerate() {
        let _ = writeln!(s, "f {}//{} {}//{} {}//{}", f[0], k + 1, f[1], k + 1, f[2], k + 1);
    }
    s
}

fn gem_mtl() -> String {
    "# The gem's glass, generated by `cargo xtask assets`.\n\
     newmtl gem\n\
     Kd 0.75 0.9 1.0\n\
     Ks 0.9 0.9 0.9\n\
     Ns 400\n\
     Ni 1.7\n\
     d 0.15\n\
     Tf 0.75 0.9 1.0\n\
     illum 7\n"
        .to_string()
}

/// A torus about +Y (major radius 1, minor 0.35), 16 × 8 quads, with uvs
/// (u around the ring, v around the tube) and no normals.
fn torus_obj() -> String {
    const NU: usize = 16;
    const NV: usize = 8;
    let (big, small) = (1.0, 0.35);
    let mut s = String::from(
        "# A torus, generated by `cargo xtask assets`; no normals (computed smooth).\no torus\n",
    );
    for i in 0..NU {
        let a = 2.0 * PI * i as f64 / NU as f64;
        for j in 0..NV {
            let b = 2.0 * PI * j as f64 / NV as f64;
            let r = big + small * b.cos();
            s += &vec_line("v", [r * a.cos(), small * b.sin(), -r * a.sin()]);
        }
    }
    // uv grid has one more row and column than the vertices (the seam).
    for i in 0..=NU {
        for j in 0..=NV {
            let _ = writeln!(s, "vt {} {}", num(i as f64 / NU as f64), num(j as f64 / NV as f64));
        }
    }
    let vid = |i: usize, j: usize| (i % NU) * NV + (j % NV) + 1;
    let tid = |i: usize, j: usize| i * (NV + 1) + j + 1;
    for i in 0..NU {
        for j in 0..NV {
            let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let corners: Vec<String> =
                c.iter().map(|&(a, b)| format!("{}/{}", vid(a, b), tid(a, b))).collect();
            let _ = writeln!(s, "f {}", corners.join(" "));
        }
    }
    s
}
