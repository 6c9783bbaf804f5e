//! OBJ and MTL files as other tools write them (Windows paths, one-value
//! colours, empty material names, Latin-1 bytes, missing textures) load
//! with a warning for each guess; MTL errors name the MTL file and line.
//! Every file is generated in the test's temporary directory.

use prism_scene::{LoadOptions, load_path, parse_scene_str};
use prism_shade::Texture;
use std::fs;
use std::path::Path;

/// A one-triangle OBJ with uvs, `header` lines first and `usemtl` lines
/// (one face each) after.
fn obj(header: &[u8], usemtl: &[&[u8]]) -> Vec<u8> {
    let mut o = header.to_vec();
    o.extend_from_slice(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n");
    for u in usemtl {
        o.extend_from_slice(b"usemtl ");
        o.extend_from_slice(u);
        o.extend_from_slice(b"\nf 1/1 2/2 3/3\n");
    }
    o
}

fn has(warnings: &[String], words: &[&str]) -> bool {
    warnings.iter().any(|w| words.iter().all(|x| w.contains(x)))
}

#[test]
fn files_from_other_tools_load_with_warnings() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    fs::create_dir(d.join("mats")).expect("mats");
    image::RgbImage::from_pixel(2, 2, image::Rgb([0, 255, 0])).save(d.join("mats/tex.png")).expect("png");
    // MTL: an empty name with a Windows texture path, a one-value `Ks`,
    // a Latin-1 name whose texture is missing.
    let mut mtl = b"newmtl \nKd 1 1 1\nKs 0\nmap_Kd .\\tex.png\n\nnewmtl m\xe9tal\nKd 0.2 0.4 0.6\n".to_vec();
    mtl.extend_from_slice(b"map_Kd missing.png\n");
    fs::write(d.join("mats/m.mtl"), mtl).expect("mtl");
    let text = obj(b"# caf\xe9 \xa9 2024\nmtllib .\\mats\\m.mtl\n", &[b"", b"m\xe9tal"]);
    fs::write(d.join("wild.obj"), text).expect("obj");
    let loaded = load_path(&d.join("wild.obj"), &LoadOptions::default()).expect("loads");
    let w = &loaded.warnings;
    assert!(has(w, &["wild.obj:1:", "Latin-1"]), "{w:#?}");
    assert!(has(w, &["wild.obj:2:", "Windows"]), "{w:#?}");
    assert!(has(w, &["wild.obj:", "`usemtl` without a name"]), "{w:#?}");
    assert!(has(w, &["m.mtl:1:", "without a name"]), "{w:#?}");
    assert!(has(w, &["m.mtl:3:", "`Ks 0` has one value"]), "{w:#?}");
    assert!(has(w, &["m.mtl:4:", "Windows"]), "{w:#?}");
    assert!(has(w, &["m.mtl:6:", "Latin-1"]), "{w:#?}");
    assert!(has(w, &["métal", "missing.png", "using its colour"]), "{w:#?}");
    // The unnamed material has its texture; `métal` its colour.
    let mats = &loaded.scene.materials;
    let names = &loaded.info.materials;
    let at = |name: &str| {
        let i = names.iter().position(|n| n.ends_with(name)).unwrap_or_else(|| panic!("{name} in {names:?}"));
        &mats[i]
    };
    assert!(matches!(at("(unnamed)").texture, Texture::Image { .. }));
    assert_eq!(at("(unnamed)").specular, 0.0);
    assert_eq!(at("métal").texture, Texture::Solid(prism_geometry::glam::Vec3::new(0.2, 0.4, 0.6)));
}

#[test]
fn mtl_errors_name_the_mtl_file_and_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    fs::write(d.join("bad.mtl"), "newmtl a\n# colours\nKd 1 x 1\n").expect("mtl");
    fs::write(d.join("m.obj"), obj(b"mtllib bad.mtl\n", &[b"a"])).expect("obj");
    // As a scene's mesh without its own material: an error.
    let scene = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[objects]]\ntype = \"mesh\"\npath = \"m.obj\"\n";
    let Err(e) = parse_scene_str(scene, d, Path::new("s.toml")) else { panic!("accepted") };
    assert!(e.to_string().contains("bad.mtl:3:"), "{e}");
    // As an OBJ scene: a warning, and grey.
    let loaded = load_path(&d.join("m.obj"), &LoadOptions::default()).expect("loads");
    assert!(has(&loaded.warnings, &["bad.mtl:3:", "`x`"]), "{:#?}", loaded.warnings);
}
