//! OBJ mode's `--view`, `--light` and `--floor` (`LoadOptions::obj`),
//! through `load_path`.

use super::*;
use prism_geometry::Ray;
use prism_geometry::glam::Vec3;
use prism_shade::LightKind;

/// The position of the scene's one light, a point light in OBJ mode.
fn point_light(l: &LoadedScene) -> Vec3 {
    match l.info.lights.as_slice() {
        [light] => match light.kind {
            LightKind::Point { position, .. } => position,
            other => panic!("OBJ mode's light is a point light, got {other:?}"),
        },
        other => panic!("OBJ mode has one light, got {}", other.len()),
    }
}

/// A box 2 wide (X), 1 high, 6 deep (Z), bottom at y = 0.
fn deep_box(dir: &Path) -> PathBuf {
    let path = dir.join("deep.obj");
    let mut s = String::new();
    for z in [-3.0, 3.0] {
        for y in [0.0, 1.0] {
            for x in [-1.0, 1.0] {
                s.push_str(&format!("v {x} {y} {z}\n"));
            }
        }
    }
    // Faces of the box (1-based; index = 1 + x + 2y + 4z).
    s.push_str("f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n");
    fs::write(&path, s).unwrap();
    path
}

fn load(path: &Path, obj: ObjOptions) -> LoadedScene {
    load_path(path, &LoadOptions { obj, ..LoadOptions::default() }).unwrap()
}

#[test]
fn views_put_the_eye_on_their_side_and_auto_faces_the_larger_side() {
    let dir = tempfile::tempdir().unwrap();
    let path = deep_box(dir.path());
    let c = Vec3::new(0.0, 0.5, 0.0);
    for (view, side) in [
        (None, Vec3::X),
        (Some(ObjView::Auto), Vec3::X),
        (Some(ObjView::Front), Vec3::Z),
        (Some(ObjView::Back), Vec3::NEG_Z),
        (Some(ObjView::Left), Vec3::NEG_X),
        (Some(ObjView::Right), Vec3::X),
        (Some(ObjView::Top), Vec3::Y),
        (Some(ObjView::Iso), Vec3::ONE.normalize()),
    ] {
        let l = load(&path, ObjOptions { view, ..ObjOptions::default() });
        let cam = &l.settings.camera;
        assert!((cam.look_at() - c).length() < 1e-5, "{view:?}");
        let toward = (cam.position() - c).normalize();
        assert!((toward - side).length() < 1e-5, "{view:?}: eye toward {toward}");
        // The mesh is in the middle of the image; the light is on the eye's side.
        assert!(l.scene.accel.closest_hit(&cam.ray(320.0, 240.0)).is_some(), "{view:?}");
        assert!((point_light(&l) - c).dot(side) > 0.0, "{view:?}");
    }
}

#[test]
fn light_and_floor_are_placed_as_asked() {
    let dir = tempfile::tempdir().unwrap();
    let path = deep_box(dir.path());
    let l = load(&path, ObjOptions { light: Some(Vec3::new(0.0, 9.0, 0.0)), ..ObjOptions::default() });
    assert_eq!(point_light(&l), Vec3::new(0.0, 9.0, 0.0));
    assert!(!l.info.objects_by_kind.contains_key("plane"));
    let down = Ray::new(Vec3::new(5.0, 3.0, 0.0), Vec3::NEG_Y);
    assert!(l.scene.accel.closest_hit(&down).is_none());
    let l = load(&path, ObjOptions { floor: true, ..ObjOptions::default() });
    assert_eq!(l.info.objects_by_kind.get("plane"), Some(&1));
    // The floor is at the bottom of the mesh, beside it and under it.
    let hit = l.scene.accel.closest_hit(&down).expect("the floor");
    assert!((hit.hit.point.y - 0.0).abs() < 1e-5, "{:?}", hit.hit.point);
    // A non-finite light names its flag.
    let err = load_path(
        &path,
        &LoadOptions {
            obj: ObjOptions { light: Some(Vec3::new(f32::INFINITY, 0.0, 0.0)), ..ObjOptions::default() },
            ..LoadOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(err.starts_with("--light: X,Y,Z must be finite"), "{err}");
}

#[test]
fn a_toml_scene_refuses_obj_options_naming_the_flag() {
    for (obj, flag) in [
        (ObjOptions { view: Some(ObjView::Top), ..ObjOptions::default() }, "--view"),
        (ObjOptions { light: Some(Vec3::ONE), ..ObjOptions::default() }, "--light"),
        (ObjOptions { floor: true, ..ObjOptions::default() }, "--floor"),
    ] {
        let err = parse_scene_str_with(
            BASE,
            Path::new("."),
            Path::new("t.toml"),
            &LoadOptions { obj, ..LoadOptions::default() },
        )
        .unwrap_err()
        .to_string();
        assert!(err.starts_with(&format!("{flag}: applies to an OBJ file")), "{err}");
    }
}

#[test]
fn an_obj_file_refuses_named_cameras_and_sets_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let path = deep_box(dir.path());
    let camera = crate::CameraName::new("top").ok();
    let opts =
        LoadOptions { overrides: Overrides { camera, ..Overrides::default() }, ..LoadOptions::default() };
    let e = load_obj_scene(&path, &opts).unwrap_err().to_string();
    assert!(
        e.starts_with("--camera: `top`: an OBJ file as a scene has one framed camera")
            && e.contains("--view"),
        "{e}"
    );
    let opts = LoadOptions { sets: vec!["render.spp=2".into()], ..LoadOptions::default() };
    let e = load_obj_scene(&path, &opts).unwrap_err().to_string();
    assert!(e.starts_with("--set: render.spp=2"), "{e}");
}

#[test]
fn a_field_of_view_too_narrow_to_frame_the_mesh_names_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let path = deep_box(dir.path());
    let with_fov = |fov: f32| {
        let opts = LoadOptions {
            overrides: Overrides { fov: Some(fov), ..Overrides::default() },
            ..LoadOptions::default()
        };
        load_obj_scene(&path, &opts)
    };
    for fov in [1e-45, 1e-30, 1e-3] {
        let e = with_fov(fov).unwrap_err().to_string();
        assert!(e.starts_with(&format!("--fov: {fov}° is too narrow to frame the mesh")), "{e}");
    }
    // Narrow but usable: the eye within 10⁴ radii, the view on the mesh.
    let cam = with_fov(0.02).unwrap().settings.camera;
    let centre = Vec3::new(0.0, 0.5, 0.0);
    let radius = Vec3::new(2.0, 1.0, 6.0).length() / 2.0;
    let away = (cam.position() - centre).length() / radius;
    assert!(away > 5000.0 && away <= 1e4, "{away}");
}

#[test]
fn a_mesh_too_large_to_frame_renders_from_a_given_camera_and_light() {
    // Corners near f32::MAX: no framed eye or default light is finite.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("far.obj");
    fs::write(&path, "v 3e38 0 0\nv 0 3e38 0\nv 0 0 3e38\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 4 5 6\n")
        .unwrap();
    let with = |camera: bool, light: bool| {
        let overrides = Overrides {
            camera_pos: camera.then_some(Vec3::new(0.3, 0.3, 5.0)),
            look_at: camera.then_some(Vec3::new(0.3, 0.3, 0.0)),
            ..Overrides::default()
        };
        let obj = ObjOptions { light: light.then_some(Vec3::new(0.0, 5.0, 5.0)), ..ObjOptions::default() };
        load_obj_scene(&path, &LoadOptions { overrides, obj, ..LoadOptions::default() })
    };
    let e = with(false, true).unwrap_err().to_string();
    assert!(e.contains("cannot frame the mesh, its bounds [0, 0, 0] to [3e38, 3e38, 3e38]"), "{e}");
    assert!(e.ends_with("give --camera-pos and --look-at"), "{e}");
    let e = with(true, false).unwrap_err().to_string();
    assert!(e.contains("cannot place the default light") && e.ends_with("give --light X,Y,Z"), "{e}");
    let loaded = with(true, true).unwrap();
    assert_eq!(loaded.settings.camera.position(), Vec3::new(0.3, 0.3, 5.0));
}
