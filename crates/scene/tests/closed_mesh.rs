//! Closed meshes are solids: a transparent closed mesh is shaded once where
//! a ray passes through it and dims a shadow once, exactly as the analytic
//! box of the same shape does; `assets/gem.obj` is found closed.

use prism_geometry::glam::Vec3;
use prism_scene::{LoadOptions, load_path, parse_scene_str};
use prism_shade::{RenderHooks, render};
use std::fs;
use std::path::Path;

/// A cube of edge 0.6 about the origin, every face with its own uvs (so the
/// loader splits its corners), counter-clockwise from outside. With
/// `open`, the top face is left out.
fn cube_obj(open: bool) -> String {
    let mut s = String::from("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    for i in 0..8 {
        let c = |b: u32| if i >> b & 1 == 1 { 0.3 } else { -0.3 };
        s += &format!("v {} {} {}\n", c(0), c(1), c(2));
    }
    // Corner k is (x, y, z) = bits (0, 1, 2) of k - 1.
    let quads = [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]];
    for (f, q) in quads.iter().enumerate() {
        if open && f == 3 {
            continue;
        }
        s += &format!("f {}/1 {}/2 {}/3 {}/4\n", q[0], q[1], q[2], q[3]);
    }
    s
}

/// `occluder` (TOML keys of an object, material `tinted`) at (2, 2, 0);
/// returns the colour at the image centre seen from `eye` looking at `at`.
fn centre(dir: &Path, occluder: &str, eye: [f32; 3], at: [f32; 3], up: [f32; 3]) -> Vec3 {
    let text = format!(
        r#"
[render]
width = 33
height = 33
spp = 1
ambient = [1, 1, 1]
background = [0.3, 0.3, 0.3]

[camera]
position = {eye:?}
look_at = {at:?}
up = {up:?}
fov = 20

[[lights]]
position = [4, 4, 0]

[materials.floor]
color = [0.5, 0.7, 0.9]
ambient = 0.2
diffuse = 0.8
specular = 0

[materials.tinted]
color = [1, 0.5, 0.25]
transparency = 0.6
ambient = 0.2
diffuse = 0.8
specular = 0

[[objects]]
type = "plane"
material = "floor"

[[objects]]
material = "tinted"
transform = [{{ translate = [2, 2, 0] }}]
{occluder}
"#
    );
    let loaded = parse_scene_str(&text, dir, Path::new("closed.toml")).expect("scene loads");
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    image.pixels[16 * 33 + 16]
}

#[test]
fn a_closed_mesh_is_a_solid_like_the_analytic_box() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    fs::write(d.join("cube.obj"), cube_obj(false)).expect("cube.obj");
    fs::write(d.join("open.obj"), cube_obj(true)).expect("open.obj");
    // Flat normals, as the box has (smooth ones would shade differently).
    let mesh = "type = \"mesh\"\npath = \"cube.obj\"\nnormals = \"flat\"";
    let open = "type = \"mesh\"\npath = \"open.obj\"\nnormals = \"flat\"";
    let boxed = "type = \"cuboid\"\nsize = 0.6";
    let loaded = parse_scene_str(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n",
        d,
        Path::new("c.toml"),
    )
    .expect("loads");
    assert!(loaded.scene.accel.meshes()[0].is_closed(), "the split cube is closed");
    // The floor under the cube, seen from above: the shadow is dimmed once,
    // by 0.6 · colour, as under the analytic box.
    let above = ([0.0, 10.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]);
    let shadow_box = centre(d, boxed, above.0, above.1, above.2);
    let shadow_mesh = centre(d, mesh, above.0, above.1, above.2);
    assert!((shadow_box - shadow_mesh).abs().max_element() < 1e-5, "{shadow_box} vs {shadow_mesh}");
    let floor = Vec3::new(0.5, 0.7, 0.9);
    let direct = 0.8 * floor * Vec3::Y.dot(Vec3::new(4.0, 4.0, 0.0).normalize());
    let want = 0.2 * floor + 0.6 * Vec3::new(1.0, 0.5, 0.25) * direct;
    assert!((shadow_mesh - want).abs().max_element() < 1e-4, "{shadow_mesh}, want {want}");
    // Looking through the cube: its far side is not shaded a second time.
    let front = ([2.0, 2.0, 6.0], [2.0, 2.0, 0.0], [0.0, 1.0, 0.0]);
    let through_box = centre(d, boxed, front.0, front.1, front.2);
    let through_mesh = centre(d, mesh, front.0, front.1, front.2);
    assert!((through_box - through_mesh).abs().max_element() < 1e-5, "{through_box} vs {through_mesh}");
    // The open cube is a surface: the far side is shaded too, so it differs.
    let through_open = centre(d, open, front.0, front.1, front.2);
    assert!((through_open - through_box).abs().max_element() > 1e-3, "{through_open} vs {through_box}");
}

#[test]
fn the_gem_and_torus_assets_are_closed() {
    for name in ["gem.obj", "torus.obj"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(name);
        let loaded = load_path(&path, &LoadOptions::default()).expect("the asset loads");
        let meshes = loaded.scene.accel.meshes();
        assert!(!meshes.is_empty() && meshes.iter().all(|m| m.is_closed()), "{name} is closed");
    }
}
