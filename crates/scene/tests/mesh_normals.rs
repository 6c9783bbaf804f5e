//! Computed mesh normals: welded by position, so that the shading normal
//! is continuous across uv seams (the torus asset, `spot.obj` from the
//! shared meshes); smoothing groups and the crease angle keep hard edges
//! hard.

use prism_geometry::TriangleMesh;
use prism_geometry::glam::Vec3;
use prism_scene::{LoadOptions, load_path, parse_scene_str};
use std::collections::HashMap;
use std::fs;
use std::path::Path;

/// `(positions with several vertices, of those where the normals differ)`.
fn seams(m: &TriangleMesh) -> (usize, usize) {
    let normals = m.normals().expect("computed normals");
    let mut by_pos: HashMap<[u32; 3], Vec<Vec3>> = HashMap::new();
    for (p, n) in m.positions().iter().zip(normals) {
        by_pos.entry(p.to_array().map(f32::to_bits)).or_default().push(*n);
    }
    let split: Vec<&Vec<Vec3>> = by_pos.values().filter(|v| v.len() > 1).collect();
    let differ = split.iter().filter(|v| v.iter().any(|n| (*n - v[0]).length() > 1e-6)).count();
    (split.len(), differ)
}

/// The meshes of the OBJ file `obj` used by a scene, with `keys` added to
/// its object.
fn meshes_of(obj: &Path, keys: &str) -> Vec<std::sync::Arc<TriangleMesh>> {
    let text = format!(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = {:?}\n{keys}\n",
        obj.display().to_string()
    );
    let loaded = parse_scene_str(&text, Path::new("."), Path::new("n.toml")).expect("loads");
    loaded.scene.accel.meshes().to_vec()
}

#[test]
fn the_torus_is_smooth_across_its_uv_seam() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/torus.obj");
    let loaded = load_path(&path, &LoadOptions::default()).expect("the torus loads");
    let m = &loaded.scene.accel.meshes()[0];
    let (split, differ) = seams(m);
    // The uv seam splits vertices (the file has uvs), yet every copy of a
    // position has the same normal: the shading normal is continuous.
    assert!(split > 10, "the torus has a uv seam ({split} split positions)");
    assert_eq!(differ, 0, "normals differ at {differ} of {split} seam positions");
}

#[test]
fn spot_is_smooth_across_its_uv_seams() {
    let Some(dir) = prism_testkit::shared_data() else { return };
    let spot = dir.join("spot.obj");
    if !spot.is_file() {
        prism_testkit::skip(&format!("{} is absent", spot.display()));
        return;
    }
    let meshes = meshes_of(&spot, "crease_angle = 180");
    let (split, differ) = seams(&meshes[0]);
    assert!(split > 100, "{split}");
    assert_eq!(differ, 0, "normals differ at {differ} of {split} seam positions");
}

/// A 12-sided prism side (neighbours meet at 30°) and a cube-like 90° edge
/// ring (4 sides), with the smoothing line `s`, faces split per quad.
fn ring_obj(sides: usize, s: &str) -> String {
    let mut text = String::from("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    for i in 0..sides {
        let t = i as f32 / sides as f32 * std::f32::consts::TAU;
        text += &format!("v {} 0 {}\nv {} 1 {}\n", t.sin(), t.cos(), t.sin(), t.cos());
    }
    text += s;
    text += "\n";
    for i in 0..sides {
        let (a, b) = (2 * i + 1, 2 * ((i + 1) % sides) + 1);
        text += &format!("f {a}/1 {b}/2 {}/3 {}/4\n", b + 1, a + 1);
    }
    text
}

#[test]
fn smoothing_groups_and_the_crease_angle() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let write = |name: &str, text: String| {
        let p = d.join(name);
        fs::write(&p, text).expect("write");
        p
    };
    // No `s` lines: smooth at 30°, hard at 90° (the default crease, 60°).
    let (split, differ) = seams(&meshes_of(&write("r12.obj", ring_obj(12, "")), "")[0]);
    assert_eq!((split > 0, differ), (true, 0));
    let (_, differ) = seams(&meshes_of(&write("r4.obj", ring_obj(4, "")), "")[0]);
    assert_eq!(differ, 8, "every position of the square ring has a hard edge");
    // A smaller crease angle makes the 30° edges hard too.
    let (_, differ) = seams(&meshes_of(&d.join("r12.obj"), "crease_angle = 20")[0]);
    assert_eq!(differ, 24);
    // `s off`: flat, whatever the angle; `s 1`: smooth.
    let (_, differ) = seams(&meshes_of(&write("off.obj", ring_obj(12, "s off")), "")[0]);
    assert_eq!(differ, 24);
    let (_, differ) = seams(&meshes_of(&write("on.obj", ring_obj(12, "s 1")), "")[0]);
    assert_eq!(differ, 0);
    // `normals = "smooth"` joins everything, even 90° edges.
    let (_, differ) = seams(&meshes_of(&d.join("r4.obj"), "normals = \"smooth\"")[0]);
    assert_eq!(differ, 0);
    // Bad crease angles are refused at their place.
    for (keys, words) in [
        ("crease_angle = 200", "at most 180"),
        ("crease_angle = -1", "crease_angle"),
        ("normals = \"flat\"\ncrease_angle = 30", "applies to"),
    ] {
        let text = format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = \"r4.obj\"\n{keys}\n"
        );
        let Err(e) = parse_scene_str(&text, d, Path::new("n.toml")) else { panic!("{keys} accepted") };
        let e = e.to_string();
        assert!(e.contains(words) && e.starts_with("n.toml:"), "{keys}: {e}");
    }
}

/// A tent of two quads folded 40° at the edge x = 0, the halves in two
/// materials (tobj cuts them into two models) or in one.
fn tent(two_materials: bool, uvs: bool) -> String {
    let mut s = String::from(
        "mtllib two.mtl\nv -1 -1 0\nv 0 -1 0.36397\nv 0 1 0.36397\nv -1 1 0\nv 1 -1 0\nv 1 1 0\n",
    );
    if uvs {
        s.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    }
    let face = |c: [usize; 4]| {
        let corners: Vec<String> = c
            .iter()
            .enumerate()
            .map(|(k, v)| if uvs { format!("{v}/{}", k + 1) } else { v.to_string() })
            .collect();
        format!("f {}\n", corners.join(" "))
    };
    s.push_str("usemtl a\n");
    s.push_str(&face([1, 2, 3, 4]));
    if two_materials {
        s.push_str("usemtl b\n");
    }
    s.push_str(&face([2, 5, 6, 3]));
    s
}

/// The normals at the fold's positions (x = 0), over all the meshes.
fn fold_normals(meshes: &[std::sync::Arc<TriangleMesh>]) -> Vec<Vec3> {
    meshes
        .iter()
        .flat_map(|m| {
            let normals = m.normals().expect("computed").to_vec();
            m.positions().iter().zip(normals).filter(|(p, _)| p.x == 0.0).map(|(_, n)| n).collect::<Vec<_>>()
        })
        .collect()
}

/// A material boundary is no crease: the two halves of a smooth tent in
/// two materials get the normals of the tent in one (a probe found the
/// fold shaded flat).
#[test]
fn a_change_of_material_does_not_crease_computed_normals() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("two.mtl"), "newmtl a\nKd 1 1 1\nnewmtl b\nKd 1 1 1\n").unwrap();
    for uvs in [false, true] {
        for keys in ["normals = \"smooth\"", "", "crease_angle = 30"] {
            let one = dir.path().join("one.obj");
            let two = dir.path().join("two.obj");
            fs::write(&one, tent(false, uvs)).unwrap();
            fs::write(&two, tent(true, uvs)).unwrap();
            let (single, split) = (meshes_of(&one, keys), meshes_of(&two, keys));
            assert_eq!((single.len(), split.len()), (1, 2), "{keys}");
            let (a, b) = (fold_normals(&single), fold_normals(&split));
            assert_eq!(b.len(), 4, "{keys}: the fold's two positions in each half");
            let up = Vec3::Z;
            for n in &b {
                // The same normal as the one-material tent's at the fold.
                assert!(a.iter().any(|m| (*m - *n).length() < 1e-6), "{keys} {uvs}: {n} not among {a:?}");
                if keys == "crease_angle = 30" {
                    // 40° apart: a crease; each half keeps its own face normal.
                    assert!(n.dot(up) < 0.99, "{n}");
                } else {
                    assert!((n.dot(up) - 1.0).abs() < 1e-6, "{keys} {uvs}: {n} is not the fold's mean (+Z)");
                }
            }
            assert_eq!(split.iter().all(|m| m.uvs().is_some()), uvs);
        }
    }
}

/// A closed latitude–longitude sphere of radius 1: `rings` bands of
/// `sides` quads (triangle fans at the poles), wound counter-clockwise
/// seen from outside, without normals (prism computes smooth ones).
fn globe_obj(sides: usize, rings: usize) -> String {
    let mut s = String::from("v 0 1 0\n");
    for r in 1..rings {
        let lat = std::f32::consts::PI * r as f32 / rings as f32;
        for k in 0..sides {
            let lon = std::f32::consts::TAU * k as f32 / sides as f32;
            s += &format!("v {} {} {}\n", lat.sin() * lon.cos(), lat.cos(), -lat.sin() * lon.sin());
        }
    }
    s += "v 0 -1 0\n";
    let at = |r: usize, k: usize| 2 + (r - 1) * sides + k % sides;
    let south = 2 + (rings - 1) * sides;
    for k in 0..sides {
        s += &format!("f 1 {} {}\n", at(1, k), at(1, k + 1));
        for r in 1..rings - 1 {
            s += &format!("f {} {} {} {}\n", at(r, k), at(r + 1, k), at(r + 1, k + 1), at(r, k + 1));
        }
        s += &format!("f {} {south} {}\n", at(rings - 1, k), at(rings - 1, k + 1));
    }
    s
}

/// A convex mirror against a white sky shows only the sky: every pixel is
/// white. With smooth normals, grazing rays near the outline were
/// reflected about the shading normal into the mesh and lost there (black
/// samples), where the analytic sphere had none.
#[test]
fn a_smooth_mirror_mesh_reflects_the_sky_up_to_its_outline() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("globe.obj"), globe_obj(32, 16)).unwrap();
    let text = "[render]\nwidth = 160\nheight = 120\nspp = 16\nbackground = [1, 1, 1]\n\
                [camera]\nposition = [0.3, 0.4, 3.2]\nlook_at = [0, 0, 0]\nfov = 45\n\
                [materials.mirror]\ncolor = [1, 1, 1]\nreflectivity = 1\nambient = 0\ndiffuse = 0\nspecular = 0\n\
                [[objects]]\ntype = \"mesh\"\npath = \"globe.obj\"\nmaterial = \"mirror\"\n";
    let loaded = parse_scene_str(text, dir.path(), Path::new("m.toml")).expect("loads");
    assert!(loaded.warnings.iter().all(|w| !w.contains("inside out")), "{:?}", loaded.warnings);
    let (image, _) =
        prism_shade::render(&loaded.scene, &loaded.settings, prism_shade::RenderHooks::default());
    let dark: Vec<(usize, Vec3)> =
        image.pixels.iter().copied().enumerate().filter(|(_, p)| p.min_element() < 0.999).collect();
    assert!(
        dark.is_empty(),
        "{} pixels darker than the sky, e.g. {:?}",
        dark.len(),
        &dark[..dark.len().min(5)]
    );
}
