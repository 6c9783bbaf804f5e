//! `prism render model.obj` with `--view`, `--light` and `--floor`: the
//! floor catches the mesh's shadow where the light puts it.

mod common;

use common::{prism, text};
use std::fs;

const CUBE: &str = "v -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

fn luma(p: image::Rgb<u8>) -> u32 {
    p.0.iter().map(|&c| u32::from(c)).sum()
}

#[test]
fn the_floor_catches_the_shadow_on_the_side_away_from_the_light() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("cube.obj"), CUBE).unwrap();
    let render = |name: &str, extra: &[&str]| {
        let mut args =
            vec!["render", "cube.obj", "-o", name, "--width", "64", "--view", "top", "--light", "4,2,0"];
        args.extend_from_slice(extra);
        let out = prism(dir.path(), &args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        image::open(dir.path().join(name)).unwrap().to_rgb8()
    };
    let floor = render("floor.png", &["--floor"]);
    let bare = render("bare.png", &[]);
    assert_eq!((floor.width(), floor.height()), (64, 48));
    // Seen from above (+X to the right), 2 units left and right of the
    // cube's centre: without the floor both are background; with it, the
    // left (away from the light at +X) is in the cube's shadow, the right lit.
    let (left, right) = ((10, 24), (54, 24));
    assert_eq!(bare.get_pixel(left.0, left.1), bare.get_pixel(right.0, right.1));
    let (l, r) = (luma(*floor.get_pixel(left.0, left.1)), luma(*floor.get_pixel(right.0, right.1)));
    assert!(
        r > luma(*bare.get_pixel(right.0, right.1)) + 60,
        "the lit floor {r} is brighter than the background"
    );
    assert!(l * 2 < r, "shadowed {l} vs lit {r}");
}

#[test]
fn obj_flags_on_a_scene_file_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), common::GOOD).unwrap();
    let out = prism(dir.path(), &["render", "s.toml", "-o", "x.png", "--floor"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).starts_with("error: --floor: applies to an OBJ file as a scene"),
        "{}",
        text(&out.stderr)
    );
    let out = prism(dir.path(), &["render", "s.toml", "-o", "x.png", "--view", "sideways"]);
    assert_eq!(out.status.code(), Some(2), "clap lists the views");
    assert!(
        text(&out.stderr).contains("front") && text(&out.stderr).contains("iso"),
        "{}",
        text(&out.stderr)
    );
}
