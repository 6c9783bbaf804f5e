//! Linear fog by eye-space depth (the report's law, the default) and by
//! distance along the ray (`measure = "distance"`), checked against their
//! analytic values on a wall facing the camera.

use prism_geometry::glam::Vec3;
use prism_scene::parse_scene_str;
use prism_shade::{RenderHooks, render};
use std::path::Path;

const W: u32 = 48;
const H: u32 = 32;

/// A white, flat-lit wall at z = 0 facing a camera 10 units away on +Z,
/// linear black fog from 0 to 20 with `fog_extra` keys, and `more` objects.
fn wall(fog_extra: &str, more: &str) -> (Vec<Vec3>, prism_shade::Camera) {
    let text = format!(
        r#"
[render]
width = {W}
height = {H}
spp = 1
ambient = [1, 1, 1]

[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]
fov = 60

[fog]
start = 0
end = 20
color = [0, 0, 0]
{fog_extra}

[materials.white]
color = [1, 1, 1]
ambient = 1
diffuse = 0
specular = 0

[materials.pane]
transparency = 1

[[objects]]
type = "plane"
normal = [0, 0, 1]
material = "white"
{more}
"#
    );
    let loaded = parse_scene_str(&text, Path::new("."), Path::new("fog.toml")).expect("scene loads");
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    (image.pixels, loaded.settings.camera)
}

#[test]
fn linear_fog_by_depth_is_even_across_a_wall_facing_the_camera() {
    let (pixels, _) = wall("", "");
    // Every point of the wall is at depth 10: weight 10 / 20 everywhere.
    for (i, p) in pixels.iter().enumerate() {
        assert!((*p - Vec3::splat(0.5)).abs().max_element() < 1e-4, "pixel {i}: {p}");
    }
    // Seen through an unbent transparent pane, the wall keeps its depth.
    let pane = "[[objects]]\ntype = \"plane\"\npoint = [0, 0, 5]\nnormal = [0, 0, 1]\nmaterial = \"pane\"";
    let (pixels, _) = wall("", pane);
    for (i, p) in pixels.iter().enumerate() {
        assert!((*p - Vec3::splat(0.5)).abs().max_element() < 1e-4, "through the pane, pixel {i}: {p}");
    }
}

#[test]
fn linear_fog_by_distance_follows_the_path_length() {
    let (pixels, cam) = wall("measure = \"distance\"", "");
    let mut corner = 0.0;
    for j in 0..H {
        for i in 0..W {
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            // The wall is 10 units away along the axis: distance 10 / cos.
            let d = 10.0 / -ray.dir.z;
            let want = 1.0 - d / 20.0;
            let got = pixels[(j * W + i) as usize];
            assert!((got - Vec3::splat(want)).abs().max_element() < 1e-4, "({i}, {j}): {got}, want {want}");
            if (i, j) == (0, 0) {
                corner = got.x;
            }
        }
    }
    // The corners are foggier (darker here) than the centre.
    assert!(corner < 0.45, "{corner}");
}

#[test]
fn measure_belongs_to_linear_fog() {
    let cam = "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\n";
    let text = format!("[fog]\nmode = \"exponential\"\ndensity = 0.1\nmeasure = \"depth\"\n{cam}");
    let Err(e) = parse_scene_str(&text, Path::new("."), Path::new("fog.toml")) else { panic!("accepted") };
    assert!(e.to_string().starts_with("fog.toml:4:"), "{e}");
    let text = format!("[fog]\nend = 5\nmeasure = \"sideways\"\n{cam}");
    let Err(e) = parse_scene_str(&text, Path::new("."), Path::new("fog.toml")) else { panic!("accepted") };
    assert!(e.to_string().starts_with("fog.toml:3:") && e.to_string().contains("distance"), "{e}");
}
