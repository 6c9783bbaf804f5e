//! An MTL material's `map_Kd` options, rendered: `-s` scales an OBJ
//! quad's texture coordinates, `-o` offsets them, `-clamp on` clamps them,
//! and options prism does not apply are named in a warning. The expected
//! pictures are those of three.js's MTL loader and Blender's OBJ
//! importer: `uv × s + o` in the file's own coordinates, `v` up from the
//! image's bottom.
//!
//! The texture is a labelled image (top-left red, top-right green,
//! bottom-left blue, bottom-right yellow) on a unit quad whose corners
//! carry uv `(0, 0)` to `(1, 1)`, seen face on. Each render is read at the
//! centres of a 4 × 4 grid of the quad's cells (u and v at 1/8, 3/8, 5/8,
//! 7/8), where no label's edge lies under any of the options below.

use prism_geometry::glam::Vec3;
use prism_scene::{LoadedScene, parse_scene_str};
use prism_shade::{RenderHooks, render};
use std::path::Path;

const LABELS: [(char, Vec3); 4] = [
    ('R', Vec3::new(1.0, 0.0, 0.0)),
    ('G', Vec3::new(0.0, 1.0, 0.0)),
    ('B', Vec3::new(0.0, 0.0, 1.0)),
    ('Y', Vec3::new(1.0, 1.0, 0.0)),
];
const SIZE: u32 = 64;

fn write_files(dir: &Path, map_kd: &str, more: &str) {
    let img = image::RgbImage::from_fn(32, 32, |x, y| {
        let c = LABELS[usize::from(x >= 16) + 2 * usize::from(y >= 16)].1;
        image::Rgb(c.to_array().map(|v| (v * 255.0) as u8))
    });
    img.save(dir.join("labels.png")).expect("can write the texture");
    let obj = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               usemtl labels\nf 1/1 2/2 3/3 4/4\n";
    std::fs::write(dir.join("quad.obj"), obj).expect("can write the OBJ");
    let mtl = format!("newmtl labels\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nmap_Kd {map_kd}\n{more}");
    std::fs::write(dir.join("quad.mtl"), mtl).expect("can write the MTL");
}

/// The scene, loaded with the quad's material's `map_Kd` value `map_kd`.
fn load(dir: &Path, map_kd: &str) -> LoadedScene {
    load_with(dir, map_kd, "")
}

/// [`load`] with the lines `more` at the end of the material.
fn load_with(dir: &Path, map_kd: &str, more: &str) -> LoadedScene {
    write_files(dir, map_kd, more);
    let text = format!(
        "[render]\nwidth = {SIZE}\nheight = {SIZE}\nspp = 1\nambient = [1, 1, 1]\n\
         [camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 30\n\
         [[lights]]\nposition = [0, 0, 6]\n\
         [[objects]]\ntype = \"mesh\"\npath = \"quad.obj\"\n"
    );
    parse_scene_str(&text, dir, Path::new("quad.toml")).expect("scene loads")
}

/// The label seen at the centre of each of the quad's 4 × 4 cells, rows
/// from the top, as four strings of `R`, `G`, `B`, `Y` (`?` where the
/// colour is none of them).
fn cells(loaded: &LoadedScene) -> [String; 4] {
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    // The quad spans ±1 at distance 6 under a 30° field of view.
    let half = SIZE as f32 / 2.0 / (6.0 * 15f32.to_radians().tan());
    let at = |f: f32| (SIZE as f32 / 2.0 + (f - 0.5) * 2.0 * half) as u32;
    [0, 1, 2, 3].map(|row| {
        (0..4)
            .map(|col| {
                let (x, y) = (at((col as f32 + 0.5) / 4.0), at((row as f32 + 0.5) / 4.0));
                let c = image.pixels[(y * SIZE + x) as usize];
                let c = c / c.max_element().max(1e-6);
                LABELS.iter().find(|(_, l)| (c - *l).abs().max_element() < 0.1).map_or('?', |(n, _)| *n)
            })
            .collect()
    })
}

#[test]
fn map_kd_scale_offset_and_clamp_move_the_texture() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let cases: [(&str, [&str; 4]); 11] = [
        // The image as an image viewer shows it.
        ("labels.png", ["RRGG", "RRGG", "BBYY", "BBYY"]),
        // Half a repeat along u: the left and right halves swap.
        ("-o 0.5 0 0 labels.png", ["GGRR", "GGRR", "YYBB", "YYBB"]),
        // Half along v: the top and bottom halves swap.
        ("-o 0 0.5 labels.png", ["BBYY", "BBYY", "RRGG", "RRGG"]),
        // Twice across u, repeated.
        ("-s 2 1 1 labels.png", ["RGRG", "RGRG", "BYBY", "BYBY"]),
        // Twice across u, clamped: the right half holds the last column.
        ("-s 2 1 1 -clamp on labels.png", ["RGGG", "RGGG", "BYYY", "BYYY"]),
        // A negative scale mirrors.
        ("-s -1 1 1 labels.png", ["GGRR", "GGRR", "YYBB", "YYBB"]),
        // Scale, then offset: u' = 2u + 0.5.
        ("-s 2 1 -o 0.5 0 labels.png", ["GRGR", "GRGR", "YBYB", "YBYB"]),
        // A quarter along u: the image moves a quarter to the left.
        ("-o 0.25 0 labels.png", ["RGGR", "RGGR", "BYYB", "BYYB"]),
        // A quarter along v, which runs up from the image's bottom as the
        // file's own `vt` do: the image moves a quarter down.
        ("-o 0 0.25 labels.png", ["BBYY", "RRGG", "RRGG", "BBYY"]),
        // Half across v: the quad shows the image's bottom half.
        ("-s 1 0.5 labels.png", ["BBYY", "BBYY", "BBYY", "BBYY"]),
        // Twice across v, clamped: the top three quarters hold the top row.
        ("-s 1 2 -clamp on labels.png", ["RRGG", "RRGG", "RRGG", "BBYY"]),
    ];
    for (map_kd, want) in cases {
        let loaded = load(d, map_kd);
        assert_eq!(cells(&loaded), want.map(String::from), "map_Kd {map_kd}");
        assert!(
            !loaded.warnings.iter().any(|w| w.contains("map_Kd")),
            "map_Kd {map_kd}: {:?}",
            loaded.warnings
        );
    }
}

#[test]
fn map_kd_options_not_applied_are_named_in_a_warning() {
    let dir = tempfile::tempdir().expect("temp dir");
    let loaded = load(dir.path(), "-mm 0.2 1 -blendu on -s 0 1 labels.png");
    assert_eq!(cells(&loaded), ["RRGG", "RRGG", "BBYY", "BBYY"].map(String::from));
    let about: Vec<&String> = loaded.warnings.iter().filter(|w| w.contains("map_Kd option")).collect();
    assert_eq!(about.len(), 2, "{:?}", loaded.warnings);
    // The MTL file's map_Kd line, not the OBJ file.
    assert!(
        about[0].contains("quad.mtl:5: material `labels`") && about[0].contains("`-mm 0.2 1`"),
        "{}",
        about[0]
    );
    assert!(about[1].contains("`-s 0 1`") && about[1].contains("not 0"), "{}", about[1]);
}

/// Maps prism does not use are named with their MTL line, once each, and
/// change nothing.
#[test]
fn maps_prism_does_not_use_are_named_in_a_warning() {
    let dir = tempfile::tempdir().expect("temp dir");
    let more = "map_d alpha.png\nbump -bm 0.5 normal.png\nmap_Ks spec.png\nmap_d alpha2.png # again\n";
    let loaded = load_with(dir.path(), "labels.png", more);
    assert_eq!(cells(&loaded), ["RRGG", "RRGG", "BBYY", "BBYY"].map(String::from));
    let about: Vec<&String> = loaded.warnings.iter().filter(|w| w.contains("is not used by prism")).collect();
    assert_eq!(about.len(), 3, "{:?}", loaded.warnings);
    for (at, key, then) in [
        ("quad.mtl:9", "map_d", "nothing is cut out"),
        ("quad.mtl:7", "bump", "shaded without it"),
        ("quad.mtl:8", "map_Ks", "Ks applies all over"),
    ] {
        let w = format!("{at}: material `labels`: `{key}` is not used by prism");
        assert!(about.iter().any(|a| a.contains(&w) && a.contains(then)), "no {w:?} in {about:#?}");
    }
    assert!(!loaded.warnings.iter().any(|w| w.contains("map_Kd option")), "{:?}", loaded.warnings);
}
