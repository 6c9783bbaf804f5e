//! The pure build: a scene from a TOML string and resources made in
//! memory (no file is touched), including errors with their line and
//! column.

use super::*;
use crate::build::build_scene;
use crate::check::Ctx;
use crate::error::Lines;
use crate::format::SceneFile;
use crate::obj::{NormalMode, ObjFile, ObjModel};
use crate::read::{Failure, Resources, TextureFile};
use prism_geometry::TriangleMesh;
use prism_geometry::glam::{Vec2, Vec3};
use prism_shade::{ImageTexture, Texture, Wrap};
use std::sync::Arc;

/// The base scene with a textured material, a mesh used twice and a sphere.
const EXTRA: &str = r#"
[materials.wood]
texture = { type = "image", path = "mem/wood.png" }

[[objects]]
type = "mesh"
path = "mem/tri.obj"

[[objects]]
type = "mesh"
path = "mem/tri.obj"
material = "wood"
transform = [{ translate = [2, 0, 0] }]

[[objects]]
type = "sphere"
radius = 0.5
material = "wood"
"#;

/// A one-triangle OBJ file, as the reader would give it.
fn triangle_obj(material_error: Option<&str>) -> Arc<ObjFile> {
    let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let mesh = TriangleMesh::new(positions, None, None, vec![[0, 1, 2]]).unwrap();
    Arc::new(ObjFile {
        path: PathBuf::from("/in-memory/tri.obj"),
        models: vec![ObjModel { mesh: Arc::new(mesh), material: None, degenerate: 0 }],
        materials: Vec::new(),
        material_error: material_error.map(str::to_owned),
        mtl_files: Vec::new(),
        warnings: Vec::new(),
        unknown_materials: Vec::new(),
        material_places: Vec::new(),
    })
}

fn wood() -> TextureFile {
    let texels = vec![Vec3::new(0.6, 0.4, 0.2); 4];
    let image = ImageTexture::from_linear(2, 2, texels, Wrap::Repeat).unwrap();
    TextureFile { path: PathBuf::from("/in-memory/wood.png"), image: Arc::new(image) }
}

fn resources() -> Resources {
    let mut res = Resources::default();
    res.insert_mesh("mem/tri.obj", NormalMode::Auto, Ok(triangle_obj(None)));
    res.insert_texture("mem/wood.png", Wrap::Repeat, Ok(wood()));
    res
}

fn scene() -> String {
    format!("{BASE}{EXTRA}")
}

fn build(text: &str, res: &Resources) -> Result<LoadedScene, SceneError> {
    let file_name = Path::new("mem.toml");
    let file = SceneFile::parse(text, file_name)?;
    build_scene(Ctx::new(file_name, &Lines::new(text)), &file, res, &LoadOptions::default())
}

/// `mem.toml:LINE:COLUMN` of the first `needle` in `text`.
fn place_of(text: &str, needle: &str) -> String {
    let (line, column) = line_col(text, text.find(needle).unwrap());
    format!("mem.toml:{line}:{column}")
}

#[test]
fn a_scene_builds_from_a_string_and_in_memory_resources() {
    let res = resources();
    let loaded = build(&scene(), &res).unwrap();
    let info = &loaded.info;
    // The mesh is stored once and instanced twice; the sphere is a shape.
    assert_eq!(info.objects, 3);
    assert_eq!(info.objects_by_kind.get("mesh"), Some(&2));
    assert_eq!(info.stored_triangles, 1);
    assert_eq!(info.instanced_triangles, 2);
    assert_eq!(info.meshes.len(), 1);
    assert_eq!(info.meshes[0].instances, 2);
    assert_eq!(info.meshes[0].path, Path::new("/in-memory/tri.obj"));
    // The first mesh object names no material: the default.
    assert_eq!(info.materials, ["red", "wood", "(default)"]);
    assert_eq!(loaded.scene.object_materials[..2], [2, 1]);
    // The texture is the image given, shared, not a copy.
    let Texture::Image { image, .. } = &loaded.scene.materials[1].texture else { panic!("an image texture") };
    let Some(Ok(t)) = res.texture("mem/wood.png", Wrap::Repeat) else { panic!("in the resources") };
    assert!(Arc::ptr_eq(image, &t.image));
    // Inputs in order of use: the texture (materials come first), the mesh.
    assert_eq!(loaded.inputs, [PathBuf::from("/in-memory/wood.png"), PathBuf::from("/in-memory/tri.obj")]);
    // The translated instance is where the transform puts it.
    let hit = loaded
        .scene
        .accel
        .closest_hit(&prism_geometry::Ray::new(Vec3::new(2.2, 0.2, 5.0), Vec3::new(0.0, 0.0, -1.0)));
    assert!(hit.is_some_and(|h| h.object == 1 && (h.hit.t - 5.0).abs() < 1e-4), "{hit:?}");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn errors_point_at_the_value_in_the_string() {
    let res = resources();
    // A value the build refuses.
    let text = scene().replace("radius = 0.5", "radius = -0.5");
    let err = build(&text, &res).unwrap_err().to_string();
    assert_eq!(err, format!("{}: sphere radius must be greater than 0, got -0.5", place_of(&text, "-0.5")));
    // Greater than 0 as written, but 0 in the single precision prism
    // computes in: said so, not "got 1e-50" beside "greater than 0".
    let text = scene().replace("radius = 0.5", "radius = 1e-50");
    let err = build(&text, &res).unwrap_err().to_string();
    assert_eq!(
        err,
        format!(
            "{}: sphere radius must be greater than 0, got 1e-50, which is 0 in single precision (the smallest is 1e-45)",
            place_of(&text, "1e-50")
        )
    );

    // A file the reader could not read: reported where the scene names it.
    let mut res = resources();
    let failure = Failure::Read {
        what: "texture",
        path: PathBuf::from("/in-memory/wood.png"),
        reason: "no such file".into(),
    };
    res.insert_texture("mem/wood.png", Wrap::Repeat, Err(failure));
    let err = build(&scene(), &res).unwrap_err().to_string();
    let at = place_of(&scene(), "\"mem/wood.png\"");
    assert_eq!(err, format!("{at}: cannot read texture /in-memory/wood.png: no such file"));

    // An OBJ whose material library cannot be used, for the object without
    // a `material`: at the object's path; with a `material` it is fine.
    let mut res = resources();
    res.insert_mesh(
        "mem/tri.obj",
        NormalMode::Auto,
        Ok(triangle_obj(Some("cannot use material library x.mtl"))),
    );
    let err = build(&scene(), &res).unwrap_err().to_string();
    let at = place_of(&scene(), "\"mem/tri.obj\"");
    assert!(err.starts_with("/in-memory/tri.obj: cannot use material library x.mtl"), "{err}");
    assert!(err.ends_with(&format!("(used at {at})")), "{err}");
    let with_material =
        scene().replacen("path = \"mem/tri.obj\"\n", "path = \"mem/tri.obj\"\nmaterial = \"wood\"\n", 1);
    assert!(build(&with_material, &res).is_ok());

    // Resources that lack a file the scene names.
    let text = scene().replace("mem/wood.png", "mem/other.png");
    let err = build(&text, &resources()).unwrap_err().to_string();
    assert_eq!(
        err,
        format!("{}: internal error: `mem/other.png` was not read", place_of(&text, "\"mem/other.png\""))
    );
}

#[test]
fn an_image_texture_offset_is_read_and_a_non_finite_offset_or_scale_refused_at_its_place() {
    let res = resources();
    let text = format!(
        "{BASE}[materials.wood]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", offset = [0.5, -0.25] }}\n"
    );
    let loaded = build(&text, &res).unwrap();
    let image = loaded.scene.materials.iter().find_map(|m| match &m.texture {
        Texture::Image { offset, scale, .. } => Some((*offset, *scale)),
        _ => None,
    });
    assert_eq!(image, Some((Vec2::new(0.5, -0.25), Vec2::ONE)));
    for key in ["offset", "scale"] {
        for value in ["inf", "[0, nan]"] {
            let text = format!(
                "{BASE}[materials.wood]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", {key} = {value} }}\n"
            );
            let at = format!("{key} = {value}");
            let (line, column) = line_col(&text, text.find(&at).unwrap() + key.len() + 3);
            let err = build(&text, &res).err().map(|e| e.to_string()).unwrap_or_default();
            assert_eq!(err, format!("mem.toml:{line}:{column}: texture {key} must be finite"));
        }
    }
}

#[test]
fn an_image_texture_scale_of_zero_is_refused_at_its_place() {
    let res = resources();
    for scale in ["0", "[0, 2]", "[2, 0]", "-0.0"] {
        let text = format!(
            "{BASE}[materials.wood]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", scale = {scale} }}\n"
        );
        let (line, column) =
            line_col(&text, text.find(&format!("scale = {scale}")).unwrap() + "scale = ".len());
        let err = build(&text, &res).err().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(
            err,
            format!(
                "mem.toml:{line}:{column}: texture scale must not be 0 on either axis (it would stretch one texel \
                 over the whole surface; a negative scale mirrors), got {scale}"
            ),
        );
    }
    // Negative: a mirror image, accepted.
    let text = format!(
        "{BASE}[materials.wood]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", scale = [-1, 2] }}\n"
    );
    build(&text, &res).unwrap();
}

/// A texture's `tint` above 1 warns as a surface colour above 1 does (the
/// brighter texels reflect more light than reaches them); 0–1 does not.
#[test]
fn an_image_texture_tint_above_1_warns() {
    let res = resources();
    let with = |tint: &str| {
        let text = format!(
            "{BASE}[materials.wood]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", tint = {tint} }}\n"
        );
        let notes = std::cell::RefCell::new(Vec::new());
        let file_name = Path::new("mem.toml");
        let file = SceneFile::parse(&text, file_name).unwrap();
        let lines = Lines::new(&text);
        let ctx = Ctx::new(file_name, &lines).noting(&notes);
        build_scene(ctx, &file, &res, &LoadOptions::default()).unwrap();
        let warnings = notes.into_inner();
        (text, warnings)
    };
    let (text, w) = with("[2, 2, 1]");
    let (line, column) = line_col(&text, text.find("[2, 2, 1]").unwrap());
    assert_eq!(
        w,
        [format!(
            "mem.toml:{line}:{column}: texture tint [2, 2, 1] is above 1: texels brighter than 0.5 reflect more light than reaches them (components are 0–1)"
        )]
    );
    for tint in ["[1, 1, 1]", "[0.5, 0.2, 1]"] {
        assert_eq!(with(tint).1, Vec::<String>::new(), "{tint}");
    }
}

/// Every file a scene names (a mesh's `path`, an image texture's) is
/// given a place, for a message should it fail, and every warning is;
/// finding each by counting the text's lines from its start made loading
/// quadratic in their number (20 000 meshes: 18 s, 40 000 textures: 36 s).
/// The lines are counted once, however many places there are.
#[test]
fn the_scene_text_is_scanned_for_lines_once_however_many_files_and_warnings_it_has() {
    let res = resources();
    for n in [1, 10, 200] {
        let mut text = BASE.to_owned();
        for i in 0..n {
            // Each material names the texture and warns (a tint above 1);
            // each object names the mesh.
            text += &format!(
                "[materials.m{i}]\ntexture = {{ type = \"image\", path = \"mem/wood.png\", tint = [2, 2, 1] }}\n\
                 [[objects]]\ntype = \"mesh\"\npath = \"mem/tri.obj\"\nmaterial = \"m{i}\"\n"
            );
        }
        let notes = std::cell::RefCell::new(Vec::new());
        let file_name = Path::new("mem.toml");
        let file = SceneFile::parse(&text, file_name).unwrap();
        let lines = Lines::new(&text);
        let before = crate::error::scans();
        let loaded =
            build_scene(Ctx::new(file_name, &lines).noting(&notes), &file, &res, &LoadOptions::default())
                .unwrap();
        let scans = crate::error::scans() - before;
        assert_eq!(loaded.info.objects, n);
        // The places are still the text's own (materials come in order of name).
        let mut places: Vec<String> =
            notes.into_inner().iter().filter_map(|w| Some(w.split_once(": ")?.0.to_owned())).collect();
        places.sort();
        let mut written: Vec<String> = text
            .match_indices("[2, 2, 1]")
            .map(|(o, _)| {
                let (line, column) = line_col(&text, o);
                format!("mem.toml:{line}:{column}")
            })
            .collect();
        written.sort();
        assert_eq!(places, written);
        assert_eq!(scans, 1, "{n} meshes and textures named, {n} warnings: the text scanned {scans} times");
    }
}
