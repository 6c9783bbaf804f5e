//! Files a scene names: paths resolved against the scene file, inputs,
//! meshes read once and instanced, MTL materials, textures, malformed files.

use super::*;
use prism_geometry::glam::{Vec2, Vec3};
use prism_shade::{Mapping, Texture};

#[test]
fn missing_files_are_named_with_the_resolved_path() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[[objects]]\ntype = \"mesh\"\npath = \"meshes/none.obj\"\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(
        err.contains("cannot read mesh") && err.contains("meshes/none.obj") && err.contains("no such file"),
        "{err}"
    );
    assert_at(&err, extra, "none.obj");
    let extra = "[materials.m]\ntexture = { type = \"image\", path = \"nope.png\" }\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("cannot read texture") && err.contains("nope.png"), "{err}");
    assert_at(&err, extra, "nope.png");
    // A directory where a file is expected.
    fs::create_dir(dir.path().join("d.obj")).unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"d.obj\"\n");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
}

#[test]
fn load_scene_resolves_paths_against_the_scene_file_and_lists_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("scenes");
    fs::create_dir_all(sub.join("m")).unwrap();
    fs::write(sub.join("m/tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"m/tri.obj\"\nmaterial = \"red\"\n");
    fs::write(sub.join("s.toml"), text).unwrap();
    // Loaded from elsewhere: the mesh is found next to the scene, not the cwd.
    let loaded = load_scene(&sub.join("s.toml")).unwrap();
    assert_eq!(loaded.info.stored_triangles, 1);
    let canon = |p: &Path| fs::canonicalize(p).unwrap();
    assert_eq!(loaded.inputs, vec![canon(&sub.join("s.toml")), canon(&sub.join("m/tri.obj"))]);
}

#[test]
fn scene_files_that_are_not_text_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bin.toml");
    fs::write(&p, b"[camera]\nposition = [0, 0, 1]\n\xff\xfe\x00garbage").unwrap();
    let err = load_scene(&p).unwrap_err().to_string();
    assert!(err.contains(":3:1:") && err.contains("UTF-8"), "{err}");
    let p16 = dir.path().join("u16.toml");
    fs::write(&p16, [0xFF, 0xFE, b'[', 0]).unwrap();
    assert!(load_scene(&p16).unwrap_err().to_string().contains("UTF-16"));
    let err = load_scene(dir.path()).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
    let err = load_scene(&dir.path().join("none.toml")).unwrap_err().to_string();
    assert!(err.contains("no such file"), "{err}");
    let empty = dir.path().join("empty.toml");
    fs::write(&empty, "").unwrap();
    assert!(load_scene(&empty).unwrap_err().to_string().contains("missing [camera]"));
}

#[test]
fn mtl_materials_are_mapped() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n");
    fs::write(dir.path().join("s.toml"), &text).unwrap();
    let loaded = load_scene(&dir.path().join("s.toml")).unwrap();
    let info = &loaded.info;
    assert_eq!(info.stored_triangles, 12);
    assert_eq!(info.meshes.len(), 1);
    assert_eq!(info.meshes[0].models, 3);
    assert_eq!(info.materials, ["red", "cube.obj/glass", "cube.obj/mirror", "cube.obj/painted"]);
    let m = &loaded.scene.materials;
    let glass = &m[1];
    assert!((glass.transmission - 0.75).abs() < 1e-6 && glass.transparency == 0.0);
    assert!((glass.ior - 1.45).abs() < 1e-6 && (glass.shininess - 200.0).abs() < 1e-6);
    assert!((glass.specular - 0.5).abs() < 1e-6);
    assert_eq!(glass.texture, Texture::Solid(Vec3::new(0.9, 0.9, 1.0)));
    let mirror = &m[2];
    assert!((mirror.reflectivity - 0.8).abs() < 1e-6);
    let painted = &m[3];
    assert!((painted.transparency - 0.5).abs() < 1e-6 && painted.transmission == 0.0);
    assert_eq!(painted.emission, Vec3::new(0.25, 0.5, 0.0), "Ke");
    assert_eq!(glass.emission, Vec3::ZERO);
    let Texture::Image { mapping, tint, image, .. } = &painted.texture else {
        panic!("map_Kd gives an image")
    };
    assert_eq!(*mapping, Mapping::Uv);
    assert_eq!(*tint, Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(image.width(), 2);
    // Inputs: the scene, the OBJ, the MTL and the texture.
    assert_eq!(loaded.inputs.len(), 4, "{:?}", loaded.inputs);
    let mesh = &loaded.scene.accel.meshes()[0];
    assert!(mesh.uvs().is_some());
    assert!(mesh.normals().is_some(), "smooth normals are computed when the file has none");
}

#[test]
fn a_named_material_overrides_the_mtl() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    // Even a missing MTL file does not matter then.
    fs::remove_file(dir.path().join("cube.mtl")).unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\nmaterial = \"red\"\n");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    assert_eq!(loaded.info.materials, ["red"]);
    assert!(loaded.scene.object_materials.iter().all(|&m| m == 0));
    // Without the override, the missing MTL is an error naming it.
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n");
    let err = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap_err().to_string();
    assert!(err.contains("cube.mtl") && err.contains("used at s.toml:"), "{err}");
}

#[test]
fn a_usemtl_missing_from_the_library_is_a_warning_where_the_mtl_is_used() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let obj = fs::read_to_string(dir.path().join("cube.obj")).unwrap();
    fs::write(dir.path().join("cube.obj"), obj.replace("usemtl mirror", "usemtl miror")).unwrap();
    let line = obj.lines().position(|l| l == "usemtl mirror").unwrap() + 1;
    let mesh = "[[objects]]\ntype = \"mesh\"\npath = \"cube.obj\"\n";
    // Two instances: one warning.
    let text = format!("{BASE}{mesh}{mesh}");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    let about: Vec<&String> = loaded.warnings.iter().filter(|w| w.contains("miror")).collect();
    assert_eq!(about.len(), 1, "{:?}", loaded.warnings);
    assert!(
        about[0].ends_with(&format!(
            "cube.obj:{line}: `usemtl miror` names no material of cube.mtl; did you mean `mirror`? (it defines: glass, mirror, painted); those faces get the default material"
        )),
        "{}",
        about[0]
    );
    assert!(loaded.info.materials.iter().any(|m| m == "(default)"), "{:?}", loaded.info.materials);
    // A material named by the object replaces the MTL's: nothing to say.
    let text = format!("{BASE}{mesh}material = \"red\"\n");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    assert!(!loaded.warnings.iter().any(|w| w.contains("miror")), "{:?}", loaded.warnings);
}

#[test]
fn meshes_are_loaded_once_and_instanced() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    fs::create_dir(dir.path().join("sub")).unwrap();
    let mut text = BASE.to_string();
    for (i, p) in ["cube.obj", "./cube.obj", "sub/../cube.obj"].iter().enumerate() {
        text += &format!(
            "[[objects]]\ntype = \"mesh\"\npath = \"{p}\"\ntransform = [{{ translate = [{}, 0, 0] }}]\n",
            3 * i
        );
    }
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    let info = &loaded.info;
    assert_eq!(info.meshes.len(), 1);
    assert_eq!(info.meshes[0].instances, 3);
    assert_eq!(loaded.scene.accel.meshes().len(), 3, "three models, stored once");
    assert_eq!(info.objects, 9);
    assert_eq!(info.stored_triangles, 12);
    assert_eq!(info.instanced_triangles, 36);
    // MTL materials converted once, shared by the instances.
    assert_eq!(info.materials.len(), 4);
    assert!((info.bounds.max.x - 7.0).abs() < 1e-5, "{:?}", info.bounds);
}

#[test]
fn malformed_objs_are_reported_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], &str); 14] = [
        (
            "range.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "range.obj:4: face corner `9`: vertex index 9 is out of range",
        ),
        (
            "zero.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "zero.obj:4: face corner `0`: vertex index 0 is invalid",
        ),
        ("two.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n", "two.obj:3: a face needs at least 3 corners"),
        ("lines.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n", "no faces"),
        ("empty.obj", b"", "no faces"),
        ("garbage.obj", b"\x00\xff\xfe\x80binary", "garbage.obj:1: a NUL byte"),
        (
            "nul.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\x00\x01\n",
            "nul.obj:4: a NUL byte: is it a binary file?",
        ),
        (
            "five.obj",
            b"v 0 0 0\nv 1 0 0 1 1\n",
            "five.obj:2: `v` needs 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b), found 5",
        ),
        ("w.obj", b"v 0 0 0 0\n", "w.obj:1: `v` weight w is 0"),
        ("rgb.obj", b"v 0 0 0 1 red 0\n", "rgb.obj:1: `v` value `red` is not a number"),
        (
            "big.obj",
            b"v 0 0 1e39\n",
            "big.obj:1: `v` value `1e39` must lie within ±3.4028235e38 (single precision)",
        ),
        ("inf.obj", b"vn 0 0 inf\n", "inf.obj:1: `vn` value `inf` is not finite"),
        (
            "flat.obj",
            b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 4 4 1\n",
            "flat.obj: the OBJ file has nothing to render: all 2 of its triangles have zero area",
        ),
        (
            "tiny.obj",
            b"v 1e30 0 0 1e-20\n",
            "tiny.obj:1: `v` x, y and z divided by the weight w = 1e-20 are not all finite",
        ),
    ];
    for (name, bytes, words) in cases {
        fs::write(dir.path().join(name), bytes).unwrap();
        let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"{name}\"\n");
        let err = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap_err().to_string();
        assert!(err.contains(words), "{name}: {err}");
        assert!(
            err.contains(&format!(
                "(used at s.toml:{}:8)",
                line_of("[[objects]]\ntype = \"mesh\"\npath", "path")
            )),
            "{name}: {err}"
        );
    }
}

#[test]
fn valid_obj_forms_tobj_refuses_are_read() {
    // `vt u` (v is 0), colours on some vertices only (prism does not use
    // them), `mtllib` with no name (a warning).
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0\nvt 0.25\nvt 0.5 0.5\n\
               f 1/1 2/2 3/1\nf 2/2 4/1 3/1\n";
    fs::write(dir.path().join("c.obj"), obj).unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"c.obj\"\n");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
    assert_eq!(loaded.info.stored_triangles, 2);
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(
        loaded.warnings[0].contains("c.obj:1: `mtllib` without a file name; ignored"),
        "{:?}",
        loaded.warnings
    );
    let mesh = &loaded.scene.accel.meshes()[0];
    let uvs = mesh.uvs().unwrap();
    // Flipped to prism's v: `vt 0.25` is (0.25, 1).
    assert!(uvs.contains(&Vec2::new(0.25, 1.0)) && uvs.contains(&Vec2::new(0.5, 0.5)), "{uvs:?}");
}

/// A closed OBJ solid whose faces wind inward is turned outward, with a
/// warning: else glass made of it would be entered where it is left.
#[test]
fn a_solid_wound_inward_is_turned_outward() {
    let dir = tempfile::tempdir().unwrap();
    // One model (no `usemtl`, which would split it into open pieces).
    let cube: String = CUBE_OBJ
        .lines()
        .filter(|l| !l.starts_with("usemtl") && !l.starts_with("mtllib"))
        .map(|l| format!("{l}\n"))
        .collect();
    fs::write(dir.path().join("cube.obj"), &cube).unwrap();
    // The same cube with every face's corners in reverse order.
    let inward: String = cube
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(corners) => {
                format!("f {}\n", corners.split_whitespace().rev().collect::<Vec<_>>().join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect();
    assert_ne!(inward, cube);
    fs::write(dir.path().join("inward.obj"), &inward).unwrap();
    for (file, turned) in [("cube.obj", false), ("inward.obj", true)] {
        // The file twice, read with two normals modes: one warning.
        let text = format!(
            "{BASE}[[objects]]\ntype = \"mesh\"\npath = \"{file}\"\n[[objects]]\ntype = \"mesh\"\npath = \"{file}\"\nnormals = \"flat\"\n"
        );
        let loaded = parse_scene_str(&text, dir.path(), Path::new("s.toml")).unwrap();
        let warned: Vec<&String> =
            loaded.warnings.iter().filter(|w| w.contains("wound inside out")).collect();
        assert_eq!(warned.len(), usize::from(turned), "{file}: {:?}", loaded.warnings);
        if turned {
            assert!(
                warned[0].contains("inward.obj: model `cube` is a closed solid wound inside out (1 shell with face normals pointing into the solid); prism turns it the right way out"),
                "{warned:?}"
            );
        }
        let mesh = &loaded.scene.accel.meshes()[0];
        assert!(mesh.is_closed(), "{file}");
        // The 2-unit cube, its faces outward.
        assert!((mesh.signed_volume() - 8.0).abs() < 1e-6, "{file}: {}", mesh.signed_volume());
    }
}

#[test]
fn corrupt_textures_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("bad.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let extra =
        "[materials.m]\ntexture = { type = \"image\", path = \"bad.png\", mapping = \"spherical\" }\n";
    let text = format!("{BASE}{extra}");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(err.contains("bad.png") && err.contains("cannot use this texture"), "{err}");
    assert!(err.contains("cannot use this texture: the PNG data is corrupt or cut short ("), "{err}");
    assert!(err.contains(&format!("used at test.toml:{}:", line_of(extra, "bad.png"))), "{err}");
    // Named by an MTL file: which material, on which line of which file.
    fs::write(dir.path().join("t.mtl"), "newmtl shiny\nKd 1 1 1\nmap_Kd bad.png\n").unwrap();
    fs::write(dir.path().join("t.obj"), "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl shiny\nf 1 2 3\n")
        .unwrap();
    let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"t.obj\"\n");
    let err = parse_scene_str(&text, dir.path(), Path::new("test.toml")).unwrap_err().to_string();
    assert!(
        err.contains("the PNG data is corrupt")
            && err.contains("(the map_Kd of material `shiny` at ")
            && err.contains("t.mtl:3)"),
        "{err}"
    );
}

#[test]
fn image_textures_load_and_are_shared() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let extra = "[materials.a]\ntexture = { type = \"image\", path = \"tex.png\", mapping = \"spherical\", scale = [2, 1] }\n\
                 [materials.b]\ntexture = { type = \"image\", path = \"./tex.png\", wrap = \"repeat\", tint = [0.5, 0.5, 0.5] }\n";
    let loaded = parse_scene_str(&format!("{BASE}{extra}"), dir.path(), Path::new("t.toml")).unwrap();
    let (Texture::Image { image: a, mapping, scale, .. }, Texture::Image { image: b, .. }) =
        (&loaded.scene.materials[0].texture, &loaded.scene.materials[1].texture)
    else {
        panic!("image textures")
    };
    assert!(std::sync::Arc::ptr_eq(a, b));
    assert_eq!(*mapping, Mapping::Spherical);
    assert_eq!(scale.x, 2.0);
    assert_eq!(loaded.inputs.len(), 1);
}

#[test]
fn the_documented_example_and_every_shipped_scene_load() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let example = doc.split("## A complete example").nth(1).unwrap();
    let toml_block = example.split("```toml").nth(1).unwrap().split("```").next().unwrap();
    let loaded = parse_scene_str(toml_block, &root, Path::new("docs/scene-format.md")).unwrap();
    assert_eq!(loaded.info.objects, 3);
    let mut n = 0;
    for e in fs::read_dir(root.join("scenes")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let loaded = load_scene(&p).unwrap_or_else(|e| panic!("{e}"));
            assert!(loaded.warnings.is_empty(), "{}: {:?}", p.display(), loaded.warnings);
            n += 1;
        }
    }
    assert!(n >= 10, "{n} scenes");
}

#[test]
fn inputs_digest_follows_every_input_file_not_its_place() {
    let dir = tempfile::tempdir().unwrap();
    for d in ["a", "b"] {
        let sub = dir.path().join(d);
        fs::create_dir_all(&sub).unwrap();
        fs::write(sub.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let text = format!("{BASE}[[objects]]\ntype = \"mesh\"\npath = \"tri.obj\"\nmaterial = \"red\"\n");
        fs::write(sub.join("s.toml"), text).unwrap();
    }
    let digest =
        |d: &str| inputs_digest(&load_scene(&dir.path().join(d).join("s.toml")).unwrap().inputs).unwrap();
    let a = digest("a");
    assert_eq!(a.len(), 16);
    assert_eq!(a, digest("b"), "the same bytes in another directory");
    // One byte of the mesh (not the scene file) changes it.
    fs::write(dir.path().join("b/tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 2 0\nf 1 2 3\n").unwrap();
    assert_ne!(a, digest("b"));
    let e = inputs_digest(&[dir.path().join("missing.obj")]).unwrap_err().to_string();
    assert!(e.contains("missing.obj") && e.contains("no such file"), "{e}");
    // FNV-1a of nothing at all is its offset basis.
    assert_eq!(inputs_digest(&[]).unwrap(), "cbf29ce484222325");
}
