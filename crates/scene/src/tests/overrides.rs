//! Command-line overrides of the camera, and an OBJ file as a scene.

use super::*;
use prism_geometry::glam::Vec3;

// ----- camera overrides ------------------------------------------------

fn with_overrides(overrides: Overrides) -> Result<LoadedScene, SceneError> {
    let opts = LoadOptions { overrides, ..LoadOptions::default() };
    parse_scene_str_with(BASE, Path::new("."), Path::new("test.toml"), &opts)
}

#[test]
fn camera_overrides_replace_the_file() {
    let loaded = with_overrides(Overrides {
        camera_pos: Some(Vec3::new(1.0, 2.0, 3.0)),
        fov: Some(30.0),
        ..Overrides::default()
    })
    .unwrap();
    let c = &loaded.settings.camera;
    assert_eq!(c.position(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(c.look_at(), Vec3::new(0.0, 1.0, 0.0), "look_at stays the file's");
    assert!((c.vfov_deg() - 30.0).abs() < 1e-5);
    let loaded = with_overrides(Overrides {
        look_at: Some(Vec3::new(0.0, 2.0, 0.0)),
        up: Some(Vec3::X),
        ..Overrides::default()
    })
    .unwrap();
    assert_eq!(loaded.info.camera.look_at(), Vec3::new(0.0, 2.0, 0.0));
    assert_eq!(loaded.info.camera.position(), Vec3::new(0.0, 2.0, 10.0));
}

#[test]
fn bad_camera_overrides_name_the_flag() {
    let cases: [(Overrides, &str, &str); 7] = [
        // The file's camera looks along (0, -1, -10).
        (Overrides { up: Some(Vec3::new(0.0, 1.0, 10.0)), ..Overrides::default() }, "--up: ", "parallel"),
        (Overrides { up: Some(Vec3::ZERO), ..Overrides::default() }, "--up: ", "zero"),
        (
            Overrides { camera_pos: Some(Vec3::new(f32::INFINITY, 0.0, 0.0)), ..Overrides::default() },
            "--camera-pos: ",
            "finite",
        ),
        (Overrides { look_at: Some(Vec3::splat(f32::NAN)), ..Overrides::default() }, "--look-at: ", "finite"),
        (Overrides { fov: Some(180.0), ..Overrides::default() }, "--fov: ", "between 0 and 180"),
        (Overrides { fov: Some(f32::NAN), ..Overrides::default() }, "--fov: ", "between 0 and 180"),
        (
            Overrides { camera_pos: Some(Vec3::new(0.0, 1.0, 0.0)), ..Overrides::default() },
            "--camera-pos: ",
            "must differ",
        ),
    ];
    for (ov, start, words) in cases {
        let err = with_overrides(ov).unwrap_err().to_string();
        assert!(err.starts_with(start) && err.contains(words), "{ov:?}: {err}");
    }
    // Looking straight down along the file's up: the moved end is named.
    let err =
        with_overrides(Overrides { camera_pos: Some(Vec3::new(0.0, 9.0, 0.0)), ..Overrides::default() })
            .unwrap_err()
            .to_string();
    assert!(err.starts_with("--camera-pos: ") && err.contains("--up"), "{err}");
}

// ----- an OBJ file as a scene ------------------------------------------

#[test]
fn an_obj_file_is_a_framed_scene() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let obj = dir.path().join("cube.obj");
    let loaded = load_path(&obj, &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let info = &loaded.info;
    assert_eq!((info.width, info.height), (640, 480));
    assert_eq!(info.objects, 3);
    assert_eq!(info.materials, ["cube.obj/glass", "cube.obj/mirror", "cube.obj/painted"]);
    assert_eq!(info.lights.len(), 1);
    // Bounds [-1, 1]³: centre 0, r = √3; eye at r / sin 20° on +Z.
    let r = 3f32.sqrt();
    let c = &info.camera;
    assert_eq!(c.look_at(), Vec3::ZERO);
    assert!((c.position() - Vec3::new(0.0, 0.0, r / 20f32.to_radians().sin())).length() < 1e-4);
    assert!((c.vfov_deg() - 40.0).abs() < 1e-5);
    let prism_shade::LightKind::Point { position, .. } = info.lights[0].kind else { panic!("a point light") };
    assert!((position - r * Vec3::new(1.0, 2.0, 1.5)).length() < 1e-4);
    // The mesh is in frame: the centre ray hits it, the corners miss.
    let cam = &loaded.settings.camera;
    assert!(loaded.scene.accel.closest_hit(&cam.ray(320.0, 240.0)).is_some());
    assert!(loaded.scene.accel.closest_hit(&cam.ray(0.5, 0.5)).is_none());
    // Inputs: the OBJ, its MTL, the texture.
    assert_eq!(loaded.inputs.len(), 3, "{:?}", loaded.inputs);
    // The extension is matched in any case; load_scene_with would read TOML.
    let upper = dir.path().join("CUBE.OBJ");
    fs::copy(&obj, &upper).unwrap();
    assert!(load_path(&upper, &LoadOptions::default()).is_ok());
    assert!(load_scene_with(&upper, &LoadOptions::default()).is_err());
}

#[test]
fn an_obj_scene_takes_overrides_and_frames_for_them() {
    let dir = tempfile::tempdir().unwrap();
    write_cube(dir.path());
    let obj = dir.path().join("cube.obj");
    let opts = |overrides| LoadOptions { overrides, ..LoadOptions::default() };
    // A portrait image: the horizontal field of view is the narrower one.
    let loaded =
        load_path(&obj, &opts(Overrides { width: Some(100), height: Some(400), ..Overrides::default() }))
            .unwrap();
    let half_h = (20f32.to_radians().tan() * 0.25).atan();
    let z = loaded.info.camera.position().z;
    assert!((z - 3f32.sqrt() / half_h.sin()).abs() < 1e-3, "{z}");
    // --width alone keeps 4:3; --fov reframes; --camera-pos keeps the look-at.
    let loaded = load_path(
        &obj,
        &opts(Overrides {
            width: Some(64),
            fov: Some(60.0),
            camera_pos: Some(Vec3::new(5.0, 5.0, 5.0)),
            ..Overrides::default()
        }),
    )
    .unwrap();
    assert_eq!((loaded.info.width, loaded.info.height), (64, 48));
    assert_eq!(loaded.info.camera.position(), Vec3::splat(5.0));
    assert_eq!(loaded.info.camera.look_at(), Vec3::ZERO);
    assert!((loaded.info.camera.vfov_deg() - 60.0).abs() < 1e-5);
    let err = load_path(&obj, &opts(Overrides { up: Some(Vec3::Z), ..Overrides::default() }))
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("--up: "), "{err}");
}

#[test]
fn an_obj_without_materials_is_grey_and_errors_point_into_it() {
    let dir = tempfile::tempdir().unwrap();
    let tri = dir.path().join("tri.obj");
    fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let loaded = load_obj_scene(&tri, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.info.materials, ["(default)"]);
    // A material library that is missing: grey, with a warning.
    write_cube(dir.path());
    fs::remove_file(dir.path().join("cube.mtl")).unwrap();
    let loaded = load_path(&dir.path().join("cube.obj"), &LoadOptions::default()).unwrap();
    assert_eq!(loaded.info.materials, ["(default)"]);
    assert!(
        loaded.warnings.iter().any(|w| w.contains("cube.mtl: no such file") && w.contains("grey")),
        "{:?}",
        loaded.warnings
    );
    assert!(!loaded.warnings.iter().any(|w| w.contains("open file failed")), "{:?}", loaded.warnings);
    // A malformed OBJ: its own line, not "used at" itself.
    let bad = dir.path().join("bad.obj");
    fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    let err = load_path(&bad, &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.starts_with(&format!("{}:4: face corner `9`", bad.display())), "{err}");
    assert!(!err.contains("used at"), "{err}");
    let err = load_path(&dir.path().join("none.obj"), &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.contains("none.obj") && err.contains("no such file"), "{err}");
    let err = load_path(dir.path(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(err.contains("directory"), "{err}");
    // Size limits apply to the default 640×480 too.
    let opts =
        LoadOptions { limits: Limits { max_side: 100, ..Limits::default() }, ..LoadOptions::default() };
    let err = load_path(&tri, &opts).unwrap_err().to_string();
    assert!(err.starts_with(&format!("{}: image width 640", tri.display())), "{err}");
    // So does the samples limit to the default 4 spp, for an OBJ file and
    // a scene that sets no `spp`; a flag or a value in range loads.
    let opts = LoadOptions { limits: Limits { max_spp: 2, ..Limits::default() }, ..LoadOptions::default() };
    let err = load_path(&tri, &opts).unwrap_err().to_string();
    assert_eq!(
        err,
        format!(
            "{}: spp 4 is over the limit of 2 samples per pixel (raise it with --max-spp); it is the default, as the scene sets none",
            tri.display()
        )
    );
    let no_spp = BASE.replace("spp = 2\n", "");
    assert_ne!(no_spp, BASE);
    let err = parse_scene_str_with(&no_spp, Path::new("."), Path::new("test.toml"), &opts).unwrap_err();
    assert!(err.to_string().starts_with("test.toml: spp 4 is over the limit of 2"), "{err}");
    let flag = LoadOptions { overrides: Overrides { spp: Some(2), ..Overrides::default() }, ..opts.clone() };
    assert_eq!(load_path(&tri, &flag).unwrap().settings.spp, 2);
    assert_eq!(
        parse_scene_str_with(BASE, Path::new("."), Path::new("test.toml"), &opts).unwrap().settings.spp,
        2
    );
}

#[test]
fn a_side_over_the_limit_names_where_it_came_from() {
    // BASE is 320×180. A side a flag derives names that flag, not the file.
    let limited = |overrides: Overrides, sets: &[&str]| {
        let opts = LoadOptions {
            overrides,
            limits: Limits { max_side: 1000, ..Limits::default() },
            sets: sets.iter().map(|s| (*s).to_owned()).collect(),
            ..LoadOptions::default()
        };
        parse_scene_str_with(BASE, Path::new("."), Path::new("test.toml"), &opts).unwrap_err().to_string()
    };
    let e = limited(Overrides { height: Some(1000), ..Overrides::default() }, &[]);
    assert!(
        e.starts_with("--height: image width 1778 (from --height 1000, keeping the scene's aspect) is over"),
        "{e}"
    );
    let e = limited(
        Overrides { width: Some(100), ..Overrides::default() },
        &["render.height=1800", "render.width=10"],
    );
    assert!(
        e.starts_with("--width: image height 18000 (from --width 100, keeping the scene's aspect) is over"),
        "{e}"
    );
    let e = limited(Overrides { width: Some(2000), ..Overrides::default() }, &[]);
    assert!(e.starts_with("--width: image width 2000 is over"), "{e}");
    // From the file (or a set): its place.
    let e = limited(Overrides::default(), &["render.width=2000"]);
    assert!(e.starts_with("--set: render.width=2000: image width 2000 is over"), "{e}");
}

#[test]
fn fit_size_keeps_the_aspect_rounds_halves_up_and_stays_in_range() {
    assert_eq!(fit_size(1280, 720, Some(160), None), (160, 90));
    assert_eq!(fit_size(1280, 720, None, Some(90)), (160, 90));
    // 3 × 3 / 2 = 4.5 → 5; 1 × 3 / 4 = 0.75 → 1; 1 × 1 / 4 = 0.25 → at least 1.
    assert_eq!(fit_size(2, 3, Some(3), None), (3, 5));
    assert_eq!(fit_size(4, 3, Some(1), None), (1, 1));
    assert_eq!(fit_size(4, 1, Some(1), None), (1, 1));
    // Exact in integers where floating point would not be.
    assert_eq!(fit_size(3, u32::MAX - 1, Some(3), None), (3, u32::MAX - 1));
    // Over u32::MAX saturates; a zero side to scale from keeps the other side.
    assert_eq!(fit_size(1, 2, Some(u32::MAX), None), (u32::MAX, u32::MAX));
    assert_eq!(fit_size(0, 7, Some(5), None), (5, 7));
    assert_eq!(fit_size(7, 0, None, Some(5)), (7, 5));
}

// ----- pixel filter and adaptive sampling ---------------------------------

#[test]
fn filter_and_adaptive_come_from_the_file_or_the_flags() {
    use prism_shade::PixelFilter;
    let aa = |text: &str, overrides: Overrides| {
        let opts = LoadOptions { overrides, ..LoadOptions::default() };
        parse_scene_str_with(text, Path::new("."), Path::new("test.toml"), &opts)
            .map(|l| l.settings.antialias)
    };
    let plain = aa(BASE, Overrides::default()).unwrap();
    assert_eq!((plain.filter, plain.adaptive, plain.point_textures), (PixelFilter::Box, None, false));
    let file = BASE.replace("spp = 2", "spp = 2\nfilter = \"blackman-harris\"\nadaptive = 0.25");
    let got = aa(&file, Overrides::default()).unwrap();
    assert_eq!((got.filter, got.adaptive), (PixelFilter::BlackmanHarris, Some(0.25)));
    let ov = Overrides { filter: Some(PixelFilter::Gaussian), adaptive: Some(0.0), ..Overrides::default() };
    let got = aa(&file, ov).unwrap();
    assert_eq!((got.filter, got.adaptive), (PixelFilter::Gaussian, Some(0.0)));
    // Errors: at the value in the file, or naming the flag.
    let bad = BASE.replace("spp = 2", "spp = 2\nfilter = \"mitchell\"");
    let err = aa(&bad, Overrides::default()).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:6:10:") && err.contains("blackman-harris"), "{err}");
    let bad = BASE.replace("spp = 2", "spp = 2\nadaptive = -1");
    let err = aa(&bad, Overrides::default()).unwrap_err().to_string();
    assert!(err.starts_with("test.toml:6:12:") && err.contains(">= 0"), "{err}");
    for v in [-0.5, f32::NAN, f32::INFINITY] {
        let err = aa(BASE, Overrides { adaptive: Some(v), ..Overrides::default() }).unwrap_err().to_string();
        assert!(err.starts_with("--adaptive: "), "{err}");
    }
}
