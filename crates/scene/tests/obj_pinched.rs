//! An OBJ face whose outline touches itself, rendered face on: a triangle
//! with a spike out of its long side and straight back (the outline
//! passes the spike's foot twice). The spike covers nothing, and no
//! triangle of the cut may reach past the long side; before the outline
//! was cut at the spike's foot, the ear clipping covered part of the
//! spike's side of that edge.

use prism_scene::parse_scene_str;
use prism_shade::{RenderHooks, render};
use std::path::Path;

const SIZE: u32 = 96;

#[test]
fn a_face_with_a_spike_covers_only_its_triangle() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    // The triangle x + y <= 0 within [-1.5, 1.5]², and a spike from its
    // long side's middle (0, 0) up to (0, 1.5) and back.
    let obj = "v -1.5 -1.5 0\nv 1.5 -1.5 0\nv 0 0 0\nv 0 1.5 0\nv -1.5 1.5 0\nf 1 2 3 4 3 5\n";
    std::fs::write(d.join("spike.obj"), obj).expect("can write the OBJ");
    let text = format!(
        "[render]\nwidth = {SIZE}\nheight = {SIZE}\nspp = 1\nambient = [1, 1, 1]\nbackground = [0, 0, 0]\n\
         [camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 30\n\
         [[lights]]\nposition = [0, 0, 6]\n\
         [materials.white]\ncolor = [1, 1, 1]\n\
         [[objects]]\ntype = \"mesh\"\npath = \"spike.obj\"\nmaterial = \"white\"\n"
    );
    let loaded = parse_scene_str(&text, d, Path::new("spike.toml")).expect("scene loads");
    let (image, _) = render(&loaded.scene, &loaded.settings, RenderHooks::default());
    // The plane z = 0 spans ±6·tan 15° across the image; y up.
    let half = 6.0 * 15f32.to_radians().tan();
    let lit = |x: f32, y: f32| {
        let px = ((x / half + 1.0) / 2.0 * SIZE as f32) as u32;
        let py = ((1.0 - y / half) / 2.0 * SIZE as f32) as u32;
        image.pixels[(py * SIZE + px) as usize].max_element() > 0.1
    };
    for (x, y) in [(-1.0, -1.0), (0.8, -1.2), (-1.2, 0.8), (-0.3, 0.1)] {
        assert!(lit(x, y), "({x}, {y}) is inside the triangle but not lit");
    }
    for (x, y) in [(-0.1, 1.0), (-0.2, 0.6), (0.3, 0.3), (1.0, 1.0), (0.1, 1.2)] {
        assert!(!lit(x, y), "({x}, {y}) is outside the triangle but lit");
    }
}
