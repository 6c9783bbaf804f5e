//! Texture orientation on every analytic shape: a labelled image (top-left
//! red, top-right green, bottom-left blue, bottom-right yellow) is rendered
//! on each shape, seen from outside, and the four quadrants of the rendered
//! face must show the four labels where an image viewer would
//! (docs/scene-format.md, "Texture coordinates").

use prism_geometry::glam::Vec3;
use prism_scene::parse_scene_str;
use prism_shade::{RenderHooks, render};
use std::path::Path;

const TL: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const TR: Vec3 = Vec3::new(0.0, 1.0, 0.0);
const BL: Vec3 = Vec3::new(0.0, 0.0, 1.0);
const BR: Vec3 = Vec3::new(1.0, 1.0, 0.0);
const SIZE: u32 = 64;

/// Writes the labelled 32×32 image: each quadrant one label colour.
fn write_labelled(dir: &Path) {
    let img = image::RgbImage::from_fn(32, 32, |x, y| {
        let c = match (x < 16, y < 16) {
            (true, true) => TL,
            (false, true) => TR,
            (true, false) => BL,
            (false, false) => BR,
        };
        image::Rgb(c.to_array().map(|v| (v * 255.0) as u8))
    });
    img.save(dir.join("labels.png")).expect("can write the labelled texture");
}

/// Renders `object` (TOML keys of one `[[objects]]`, using material
/// `labels`, whose `mapping` is `mapping`) seen from `eye` toward `at` with
/// `up`, flat-lit so that each pixel is the texture's colour.
fn render_view(
    dir: &Path,
    object: &str,
    mapping: &str,
    eye: [f32; 3],
    at: [f32; 3],
    up: [f32; 3],
) -> Vec<Vec3> {
    let text = format!(
        r#"
[render]
width = {SIZE}
height = {SIZE}
spp = 1
ambient = [1, 1, 1]

[camera]
position = {eye:?}
look_at = {at:?}
up = {up:?}
fov = 30

[materials.labels]
ambient = 1
diffuse = 0
specular = 0
texture = {{ type = "image", path = "labels.png", mapping = "{mapping}", wrap = "clamp" }}

[[objects]]
material = "labels"
{object}
"#
    );
    let loaded = parse_scene_str(&text, dir, Path::new("orientation.toml")).expect("scene loads");
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    image.pixels
}

/// Asserts that pixels `k` away from the centre, diagonally, show the four
/// labels in image-viewer order.
fn assert_quadrants(what: &str, pixels: &[Vec3], k: u32) {
    let c = SIZE / 2;
    let at = |x: u32, y: u32| pixels[(y * SIZE + x) as usize];
    let cases = [
        ("top-left", c - k, c - k, TL),
        ("top-right", c + k, c - k, TR),
        ("bottom-left", c - k, c + k, BL),
        ("bottom-right", c + k, c + k, BR),
    ];
    for (corner, x, y, want) in cases {
        let got = at(x, y);
        assert!((got - want).abs().max_element() < 0.05, "{what}: {corner} quadrant is {got}, want {want}");
    }
}

/// (what, object, mapping, eye, look at, up, pixel offset)
type View<'a> = (&'a str, &'a str, &'a str, [f32; 3], [f32; 3], [f32; 3], u32);

#[test]
fn every_shape_reads_like_the_image_from_outside() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_labelled(d);
    let y = [0.0, 1.0, 0.0];
    let front = [0.0, 0.0, 6.0];
    let o = [0.0, 0.0, 0.0];
    let sphere = "type = \"sphere\"\nradius = 1";
    let cylinder = "type = \"cylinder\"\nbase = [0, -1, 0]\nradius = 1\nheight = 2";
    let cone = "type = \"cone\"\nbase = [0, -1, 0]\nradius = 1\nheight = 2";
    let cuboid = "type = \"cuboid\"\nsize = 2";
    // (what, object, mapping, eye, look at, up, pixel offset)
    let views: [View; 16] = [
        ("sphere uv", sphere, "uv", front, o, y, 6),
        ("sphere spherical", sphere, "spherical", front, o, y, 6),
        // Turned a quarter to the left, the sphere shows the image's right
        // half; the east side comes to face the camera.
        ("sphere from +X", sphere, "uv", [6.0, 0.0, 0.0], o, y, 3),
        ("cylinder side", cylinder, "uv", front, o, y, 6),
        ("cylinder cylindrical", cylinder, "cylindrical", front, o, y, 6),
        ("cylinder top cap", cylinder, "uv", [0.0, 6.0, 0.0], o, [0.0, 0.0, -1.0], 6),
        ("cylinder bottom cap", cylinder, "uv", [0.0, -6.0, 0.0], o, [0.0, 0.0, 1.0], 6),
        ("cone side", cone, "uv", front, o, y, 2),
        ("cone cylindrical", cone, "cylindrical", front, o, y, 2),
        ("cone base", cone, "uv", [0.0, -6.0, 0.0], o, [0.0, 0.0, 1.0], 6),
        ("box front", cuboid, "uv", front, o, y, 6),
        ("box back", cuboid, "uv", [0.0, 0.0, -6.0], o, y, 6),
        ("box right", cuboid, "uv", [6.0, 0.0, 0.0], o, y, 6),
        ("box left", cuboid, "uv", [-6.0, 0.0, 0.0], o, y, 6),
        ("box top", cuboid, "uv", [0.0, 6.0, 0.0], o, [0.0, 0.0, -1.0], 6),
        ("box bottom", cuboid, "uv", [0.0, -6.0, 0.0], o, [0.0, 0.0, 1.0], 6),
    ];
    for (what, object, mapping, eye, at, up, k) in views {
        let pixels = render_view(d, object, mapping, eye, at, up);
        if what == "sphere from +X" {
            // u from 0.5 (left edge of the view, +Z) to 1 (right, −Z): the
            // image's right half, its top above.
            let c = SIZE / 2;
            let px = |x: u32, y: u32| pixels[(y * SIZE + x) as usize];
            assert!((px(c, c - 6) - TR).abs().max_element() < 0.05, "{what}: top is {}", px(c, c - 6));
            assert!((px(c, c + 6) - BR).abs().max_element() < 0.05, "{what}: bottom is {}", px(c, c + 6));
            continue;
        }
        assert_quadrants(what, &pixels, k);
    }
    // Wall planes facing each way: world-unit uv from the point, so the
    // image fills one unit square of the wall right of and below the point
    // (seen from the front), upright.
    let walls = [
        ("wall plane facing +Z", [0.0, 0.0, 1.0], [0.5, -0.5, 0.0]),
        ("wall plane facing −Z", [0.0, 0.0, -1.0], [-0.5, -0.5, 0.0]),
        ("wall plane facing +X", [1.0, 0.0, 0.0], [0.0, -0.5, -0.5]),
        ("wall plane facing −X", [-1.0, 0.0, 0.0], [0.0, -0.5, 0.5]),
    ];
    for (what, n, centre) in walls {
        let wall = format!("type = \"plane\"\nnormal = {n:?}");
        let eye = Vec3::from_array(centre) + 4.0 * Vec3::from_array(n);
        let pixels = render_view(d, &wall, "uv", eye.to_array(), centre, y);
        assert_quadrants(what, &pixels, 6);
    }
    // A triangle without uvs: (b1, 1 − b2), upright with the first corner
    // at the image's bottom-left, the second along its bottom edge and the
    // third at its top-left; the image's lower-left half shows. Three
    // points of the face, by their world position on z = 0.
    let tri = "type = \"triangle\"\nvertices = [[-1, -1, 0], [1, -1, 0], [-1, 1, 0]]";
    let pixels = render_view(d, tri, "uv", front, o, y);
    // Pixels per world unit at the face: fov 30° over SIZE pixels from 6 away.
    let scale = SIZE as f32 / 2.0 / (6.0 * 15f32.to_radians().tan());
    for (corner, x, y, want) in
        [("top-left", -0.7, 0.3, TL), ("bottom-left", -0.7, -0.7, BL), ("bottom-right", 0.3, -0.7, BR)]
    {
        let (px, py) = ((SIZE as f32 / 2.0 + x * scale) as u32, (SIZE as f32 / 2.0 - y * scale) as u32);
        let got = pixels[(py * SIZE + px) as usize];
        assert!((got - want).abs().max_element() < 0.05, "triangle: {corner} is {got}, want {want}");
    }
    // A floor plane seen from above, the image's top toward −Z.
    let floor = "type = \"plane\"";
    let pixels = render_view(d, floor, "uv", [0.5, 4.0, 0.5], [0.5, 0.0, 0.5], [0.0, 0.0, -1.0]);
    assert_quadrants("floor plane", &pixels, 6);
}

#[test]
fn cylindrical_mapping_covers_the_whole_height() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_labelled(d);
    // A tall cylinder from y = 2 to y = 8: the image's top row near the top
    // of the side, its bottom row near the bottom, whatever the placement.
    let tall = "type = \"cylinder\"\nbase = [0, 2, 0]\nradius = 1\nheight = 6";
    let pixels = render_view(d, tall, "cylindrical", [0.0, 5.0, 30.0], [0.0, 5.0, 0.0], [0.0, 1.0, 0.0]);
    // 30 units away with a 30° field of view, one pixel is ~0.25 units:
    // the side spans rows 20..44; sample just inside its ends.
    let c = SIZE / 2;
    let px = |x: u32, y: u32| pixels[(y * SIZE + x) as usize];
    assert!((px(c - 2, 21) - TL).abs().max_element() < 0.05, "near the top: {}", px(c - 2, 21));
    assert!((px(c + 2, 42) - BR).abs().max_element() < 0.05, "near the bottom: {}", px(c + 2, 42));
}

#[test]
fn a_texture_with_transparent_texels_is_warned_about() {
    // Alpha is ignored: a decal's transparent surround shows whatever
    // colour it holds (often black), which the user is told.
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let rgba = |a: u8| {
        image::RgbaImage::from_fn(4, 4, move |x, _| image::Rgba([200, 10, 10, if x == 0 { a } else { 255 }]))
    };
    rgba(0).save(d.join("decal.png")).expect("can write");
    rgba(255).save(d.join("opaque.png")).expect("can write");
    for (file, warned) in [("decal.png", true), ("opaque.png", false), ("labels.png", false)] {
        write_labelled(d);
        let text = format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
             [materials.m]\ntexture = {{ type = \"image\", path = \"{file}\" }}\n\
             [[objects]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"m\"\n"
        );
        let loaded = parse_scene_str(&text, d, Path::new("t.toml")).expect("scene loads");
        let found =
            loaded.warnings.iter().any(|w| w.starts_with("t.toml:5:") && w.contains("alpha is ignored"));
        assert_eq!(found, warned, "{file}: {:?}", loaded.warnings);
    }
}
