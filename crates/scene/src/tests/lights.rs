//! `[[lights]]` of every type, `[[cameras]]` with `--camera`, the lens and
//! projection keys, the environment background, and their refusals at the
//! place of the key.

use super::*;
use crate::format::SceneFile;
use crate::read::{Resources, TextureFile};
use prism_geometry::glam::Vec3;
use prism_shade::{AreaShape, Falloff, ImageTexture, LightKind, Projection, Wrap};
use std::sync::Arc;

const LIGHTS: &str = r#"
[[lights]]
type = "point"
position = [0, 5, 0]
falloff = "inverse_square"
intensity = 20

[[lights]]
type = "spot"
position = [0, 5, 0]
direction = [0, -2, 0]
inner_angle = 20
outer_angle = 30

[[lights]]
type = "directional"
direction = [1, -1, 0]
color = [1, 0.9, 0.8]

[[lights]]
type = "quad"
corner = [-1, 4, -1]
edge_u = [2, 0, 0]
edge_v = [0, 0, 2]
radiance = [2, 2, 2]
samples = 9
two_sided = true

[[lights]]
type = "disk"
center = [0, 4, 0]
normal = [0, -1, 0]
radius = 0.5
adaptive = false

[[lights]]
type = "sphere"
center = [3, 3, 0]
radius = 0.25
"#;

#[test]
fn every_light_type_parses() {
    let loaded = parse(&format!("{BASE}{LIGHTS}")).unwrap();
    let l = &loaded.scene.lights;
    assert_eq!(l.len(), 7, "the base scene's light and six more");
    assert_eq!(l[0].kind, LightKind::Point { position: Vec3::new(5.0, 8.0, 5.0), falloff: Falloff::None });
    assert_eq!(
        l[1].kind,
        LightKind::Point { position: Vec3::new(0.0, 5.0, 0.0), falloff: Falloff::InverseSquare }
    );
    assert_eq!(l[1].intensity, 20.0);
    let LightKind::Spot { direction, cos_inner, cos_outer, .. } = l[2].kind else { panic!("a spot") };
    assert_eq!(direction, Vec3::NEG_Y);
    assert!((cos_inner - 20f32.to_radians().cos()).abs() < 1e-6);
    assert!((cos_outer - 30f32.to_radians().cos()).abs() < 1e-6);
    let LightKind::Directional { direction } = l[3].kind else { panic!("directional") };
    assert!((direction - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-6);
    let LightKind::Area(q) = l[4].kind else { panic!("quad") };
    assert_eq!(q.samples, 9);
    assert!(q.two_sided && q.adaptive);
    assert_eq!(l[4].radiance(), Vec3::splat(2.0));
    assert!(matches!(q.shape, AreaShape::Quad { .. }));
    let LightKind::Area(d) = l[5].kind else { panic!("disk") };
    assert!(!d.adaptive && d.samples == 16, "the default sample count is 16");
    assert!(
        matches!(l[6].kind, LightKind::Area(a) if matches!(a.shape, AreaShape::Sphere { radius, .. } if radius == 0.25))
    );
    assert!(loaded.scene.validate().is_ok());
}

#[test]
fn bad_lights_are_refused_at_their_key() {
    refused(&[
        (
            "[[lights]]\ntype = \"quad\"\ncorner = [0, 1, 0]\nedge_u = [1, 0, 0]\nedge_v = [2, 0, 0]\n",
            "quad light has zero area",
            Some("edge_v"),
        ),
        (
            "[[lights]]\ntype = \"disk\"\nnormal = [0, 1, 0]\nradius = 0\n",
            "disk light radius",
            Some("radius = 0"),
        ),
        ("[[lights]]\ntype = \"sphere\"\nradius = -1\n", "sphere light radius", Some("radius = -1")),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ninner_angle = 30\nouter_angle = 20\n",
            "outer_angle (20) must not be smaller than inner_angle (30)",
            Some("outer_angle"),
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nouter_angle = 0\n",
            "spot light outer_angle 0 lights nothing",
            Some("outer_angle"),
        ),
        (
            "[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\n",
            "direction must not be zero",
            Some("direction = "),
        ),
        (
            "[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nposition = [1, 2, 3]\n",
            "`position` is not a key of a directional light",
            Some("position = [1"),
        ),
        ("[[lights]]\ntype = \"quad\"\ncorner = [0, 1, 0]\nedge_u = [1, 0, 0]\n", "needs `edge_v`", None),
        ("[[lights]]\ntype = \"sphere\"\nradius = 1\nsamples = 0\n", "light samples", Some("samples")),
        (
            "[[lights]]\ntype = \"sphere\"\nradius = 1\ntwo_sided = true\n",
            "`two_sided` is not a key",
            Some("two_sided"),
        ),
    ]);
}

const CAMERAS: &str = r#"
[[cameras]]
name = "top"
position = [0, 10, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
projection = "orthographic"

[[cameras]]
name = "close"
position = [0, 1, 3]
look_at = [0, 1, 0]
aperture = 0.1
focus_distance = 2.5
"#;

fn with_camera(text: &str, name: Option<&str>) -> Result<LoadedScene, SceneError> {
    let overrides = Overrides { camera: name.map(|n| CameraName::new(n).unwrap()), ..Overrides::default() };
    let opts = LoadOptions { overrides, ..LoadOptions::default() };
    parse_scene_str_with(text, Path::new("."), Path::new("test.toml"), &opts)
}

#[test]
fn named_cameras_are_chosen_with_the_flag() {
    let text = format!("{BASE}{CAMERAS}");
    // The default is the first: [camera].
    let cam = with_camera(&text, None).unwrap().settings.camera;
    assert_eq!(cam.position(), Vec3::new(0.0, 2.0, 10.0));
    assert_eq!(cam.projection(), Projection::Perspective);
    assert_eq!(cam.aperture(), 0.0);
    let top = with_camera(&text, Some("top")).unwrap().settings.camera;
    assert_eq!(top.position(), Vec3::new(0.0, 10.0, 0.0));
    assert_eq!(top.projection(), Projection::Orthographic);
    let close = with_camera(&text, Some("close")).unwrap().settings.camera;
    assert_eq!((close.aperture(), close.focus_distance()), (0.1, 2.5));
    let err = with_camera(&text, Some("side")).unwrap_err().to_string();
    assert!(err.contains("--camera") && err.contains("no camera named `side`"), "{err}");
    assert!(err.contains("top, close"), "lists the names: {err}");
    let err = with_camera(&text, Some("tpo")).unwrap_err().to_string();
    assert!(
        err.contains("no camera named `tpo`; did you mean `top`? (its cameras are: top, close)"),
        "{err}"
    );
    // Without [camera], the first of [[cameras]] is the default.
    let no_main = text.replace("[camera]\nposition = [0, 2, 10]\nlook_at = [0, 1, 0]\n", "");
    assert_eq!(with_camera(&no_main, None).unwrap().settings.camera.position(), Vec3::new(0.0, 10.0, 0.0));
}

#[test]
fn bad_cameras_are_refused_at_their_key() {
    refused(&[
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\naperture = -0.5\n",
            "camera aperture must be 0 or more",
            Some("aperture"),
        ),
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfocus_distance = 0\n",
            "camera focus_distance must be greater than 0",
            Some("focus_distance"),
        ),
        ("[[cameras]]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\n", "needs a `name`", Some("[[cameras]]")),
        (
            "[[cameras]]\nname = \"\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\n",
            "a camera name has 1 to 64 bytes, got 0",
            Some("name = \"\""),
        ),
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\n[[cameras]]\nname = \"a\"\nposition = [0, 0, 2]\nlook_at = [0, 0, 0]\n",
            "already a camera named `a`",
            None,
        ),
    ]);
    // Cameras that are not chosen are checked as `--camera` would find
    // them: a scene that loads has no camera that fails when chosen.
    refused(&[
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 1e39, 1]\nlook_at = [0, 0, 0]\n",
            "camera position",
            Some("1e39"),
        ),
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 1]\n",
            "look_at [0, 0, 1] must differ from the camera position [0, 0, 1]",
            Some("[[cameras]]"),
        ),
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nup = [0, 0, 0]\n",
            "camera up",
            Some("up = [0, 0, 0]"),
        ),
        (
            "[[cameras]]\nname = \"a\"\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 180\n",
            "camera fov",
            Some("fov = 180"),
        ),
    ]);
    // Chosen, the first camera's problem is found; a good one chosen, the
    // bad first camera is still refused.
    let bad_first = format!("{BASE}{CAMERAS}").replace("look_at = [0, 1, 0]", "look_at = [0, 2, 10]");
    for chosen in [None, Some("top")] {
        let err = with_camera(&bad_first, chosen).unwrap_err().to_string();
        assert!(err.contains("must differ from the camera position"), "{chosen:?}: {err}");
    }
    // The file's first camera is checked like the others.
    let text = BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\naperture = -1");
    assert!(parse(&text).unwrap_err().to_string().contains("aperture"));
}

#[test]
fn background_images_are_built_with_their_rotation_and_refused_when_unreadable() {
    let text = BASE.replace("spp = 2", "spp = 2\nbackground = { image = \"mem/sky.exr\", rotation = 90 }");
    let file_name = Path::new("mem.toml");
    let file = SceneFile::parse(&text, file_name).unwrap();
    let mut res = Resources::default();
    let image = Arc::new(ImageTexture::from_linear(2, 1, vec![Vec3::X, Vec3::Y], Wrap::Repeat).unwrap());
    res.insert_texture(
        "mem/sky.exr",
        Wrap::Repeat,
        Ok(TextureFile { path: "/in-memory/sky.exr".into(), image }),
    );
    let loaded = crate::build::build_scene(
        crate::check::Ctx::new(file_name, &crate::error::Lines::new(&text)),
        &file,
        &res,
        &LoadOptions::default(),
    )
    .unwrap();
    let env = loaded.scene.environment.expect("an environment");
    assert_eq!(env.rotation_deg, 90.0);
    assert_eq!(loaded.scene.background, Vec3::ZERO);
    // A file that is not there: refused where the scene names it.
    let missing = BASE.replace("spp = 2", "spp = 2\nbackground = { image = \"no-such-sky.hdr\" }");
    let err = parse(&missing).unwrap_err().to_string();
    assert!(err.contains("background image") && err.contains("no-such-sky.hdr"), "{err}");
    let line = missing.lines().position(|l| l.contains("no-such-sky")).unwrap() + 1;
    assert!(err.starts_with(&format!("test.toml:{line}:")), "{err}");
    // Colours still work, and a bad key in the table is named.
    assert!(parse(&BASE.replace("spp = 2", "spp = 2\nbackground = \"#102030\"")).is_ok());
    let err = parse(&BASE.replace("spp = 2", "spp = 2\nbackground = { picture = \"a.png\" }"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("picture"), "{err}");
}

#[test]
fn float_texels_that_read_as_black_are_warned_about_where_the_image_is_named() {
    use prism_shade::{ExrChannel, ExrLayer, LayeredExr, PixelBounds, write_layered_exr};
    let dir = tempfile::tempdir().unwrap();
    // Columns 0.5, +inf, −2, −inf in R; G and B fine. (The writer
    // stores NaN as 0.)
    let r = [0.5, f32::INFINITY, -2.0, f32::NEG_INFINITY].repeat(2);
    let exr = LayeredExr {
        width: 4,
        height: 2,
        data_window: PixelBounds::new(0, 4, 0, 2).unwrap(),
        layers: vec![ExrLayer {
            name: String::new(),
            channels: vec![
                ExrChannel::f32("R", r),
                ExrChannel::f32("G", vec![0.25; 8]),
                ExrChannel::f32("B", vec![0.25; 8]),
            ],
        }],
        attributes: Default::default(),
    };
    write_layered_exr(&dir.path().join("sky.exr"), &exr).unwrap();
    let text = BASE.replace("spp = 2", "spp = 2\nbackground = { image = \"sky.exr\" }");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("t.toml")).unwrap();
    let line = text.lines().position(|l| l.contains("sky.exr")).unwrap() + 1;
    let want = "6 of the image's 8 texels have a negative, infinite or NaN channel, which reads as 0 (black)";
    assert!(
        loaded.warnings.iter().any(|w| w.starts_with(&format!("t.toml:{line}:")) && w.ends_with(want)),
        "{:?}",
        loaded.warnings
    );
    // Only the bad channel is 0: the texel keeps its G and B.
    let env = loaded.scene.environment.expect("an environment");
    assert_eq!(env.image.texel(1, 0), Vec3::new(0.0, 0.25, 0.25));
    assert_eq!(env.image.texel(0, 0), Vec3::new(0.5, 0.25, 0.25));
    // The same file as a texture.
    let text = BASE.replace(
        "[materials.red]",
        "[materials.sky]\ntexture = { type = \"image\", path = \"sky.exr\" }\n\n[materials.red]",
    );
    let loaded = parse_scene_str(&text, dir.path(), Path::new("t.toml")).unwrap();
    assert!(loaded.warnings.iter().any(|w| w.ends_with(want)), "{:?}", loaded.warnings);
}

#[test]
fn a_radiance_hdr_background_is_read_linear() {
    let dir = tempfile::tempdir().unwrap();
    // A 4 × 2 Radiance HDR sky, every texel (2, 0.5, 0.25): brighter than 1, linear.
    let texels = vec![image::Rgb([2.0f32, 0.5, 0.25]); 8];
    let file = std::fs::File::create(dir.path().join("sky.hdr")).unwrap();
    image::codecs::hdr::HdrEncoder::new(file).encode(&texels, 4, 2).unwrap();
    let text = BASE.replace("spp = 2", "spp = 2\nbackground = { image = \"sky.hdr\", rotation = -45 }");
    let loaded = parse_scene_str(&text, dir.path(), Path::new("t.toml")).unwrap();
    let env = loaded.scene.environment.expect("an environment image");
    assert_eq!((env.image.width(), env.image.height(), env.rotation_deg), (4, 2, -45.0));
    let c = env.radiance(Vec3::new(0.3, 0.2, -1.0));
    assert!((c - Vec3::new(2.0, 0.5, 0.25)).abs().max_element() < 0.02, "{c}");
    assert!(loaded.inputs.iter().any(|p| p.ends_with("sky.hdr")), "the image is an input");
}

#[test]
fn a_light_whose_colour_times_intensity_overflows_is_refused_at_its_intensity() {
    let too_bright = "(color × intensity overflows: beyond 3.4e38, the largest finite value)";
    refused(&[
        (
            "[[lights]]\nposition = [0, 5, 0]\nintensity = 3e38\ncolor = [10, 10, 10]\n",
            &format!(":13: point light is too bright {too_bright}"),
            Some("3e38"),
        ),
        (
            "[[lights]]\ntype = \"spot\"\nposition = [0, 5, 0]\ndirection = [0, -1, 0]\nouter_angle = 30\n\
             color = [0, 2, 0]\nintensity = 3e38\n",
            "spot light is too bright",
            Some("3e38"),
        ),
        (
            "[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nintensity = 2e38\nradiance = [1, 2, 1]\n",
            "directional light is too bright",
            Some("2e38"),
        ),
        (
            "[[lights]]\ntype = \"quad\"\ncorner = [-1, 4, -1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, 2]\n\
             radiance = [1e20, 1, 1]\nintensity = 1e19\n",
            "quad light is too bright",
            Some("1e19"),
        ),
        (
            "[[lights]]\ntype = \"disk\"\ncenter = [0, 4, 0]\nnormal = [0, -1, 0]\nradius = 1\nintensity = 1e38\ncolor = [4, 1, 1]\n",
            "disk light is too bright",
            Some("1e38"),
        ),
        (
            "[[lights]]\ntype = \"sphere\"\ncenter = [0, 4, 0]\nradius = 1\nintensity = 1e38\ncolor = [1, 1, 5]\n",
            "sphere light is too bright",
            Some("1e38"),
        ),
    ]);
    // At the edge: large, but finite, is accepted.
    parse(&format!("{BASE}[[lights]]\nposition = [0, 5, 0]\nintensity = 3e38\ncolor = [1, 1, 1]\n")).unwrap();
}

#[test]
fn quad_lights_of_any_representable_area_are_accepted() {
    // Edges of 1e10 (area 1e20) and 1e-12 (area 1e-24): the cross
    // product's squared length is out of f32's range, its length is not
    // (they were refused as overflowing and as having zero area).
    for (edge, area) in [(1e10f32, 1e20f32), (1e-12, 1e-24), (1.0, 1.0)] {
        let quad = format!(
            "[[lights]]\ntype = \"quad\"\ncorner = [0, 1, 0]\nedge_u = [{edge:e}, 0, 0]\nedge_v = [0, 0, {edge:e}]\n"
        );
        let loaded = parse(&format!("{BASE}{quad}")).unwrap_or_else(|e| panic!("edge {edge}: {e}"));
        let Some(LightKind::Area(q)) = loaded.scene.lights.last().map(|l| l.kind) else { panic!("a quad") };
        assert!((q.shape.area() - area).abs() <= 1e-6 * area, "edge {edge}: area {}", q.shape.area());
        assert!(loaded.scene.validate().is_ok());
    }
    // An area past f32::MAX is still refused, saying so.
    refused(&[(
        "[[lights]]\ntype = \"quad\"\ncorner = [0, 1, 0]\nedge_u = [1e20, 0, 0]\nedge_v = [0, 0, 1e20]\n",
        "area overflows 32-bit floats",
        Some("edge_v"),
    )]);
}

/// Objects a thousand times their size or more from the origin are warned
/// about: 32-bit floats there cannot hold their detail (a scene moved
/// 10⁵ away lost every shadow, silently).
#[test]
fn objects_far_from_the_origin_for_their_size_are_warned_about() {
    let offset =
        |loaded: &LoadedScene| loaded.warnings.iter().find(|w| w.contains("the objects lie")).cloned();
    assert_eq!(offset(&parse(BASE).unwrap()), None);
    let scene = |x: &str| {
        format!(
            "[camera]\nposition = [{x}, 0, 10]\nlook_at = [{x}, 0, 0]\n[[lights]]\nposition = [{x}, 5, 5]\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [{x}, 0, 0]\nradius = 1\n\
             [[objects]]\ntype = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\n"
        )
    };
    // 1e5 from the origin, 2 across (the infinite plane does not count).
    let w = offset(&parse(&scene("1e5")).unwrap()).expect("a warning");
    assert!(
        w.starts_with("test.toml: the objects lie up to 1.0e5 from the origin but span only 2.0e0: 32-bit floats there are about 1e-2 apart"),
        "{w}"
    );
    assert!(w.ends_with("(its centre is at (1.000e5, 0.000e0, 0.000e0))"), "{w}");
    // 1000 sizes away is quiet, and so is a large scene far out.
    assert_eq!(offset(&parse(&scene("1999")).unwrap()), None);
    assert_eq!(offset(&parse(&scene("1e5").replace("radius = 1", "radius = 1000")).unwrap()), None);
}

/// A light, the camera or its focus point more than 1e18 from the origin is
/// warned about, naming each: past about 1.8e19 from what they light or
/// see, squared distances overflow and the picture comes out black (the
/// fuzzing found each rendering black without a word). 1e18 itself is
/// quiet, as is the base scene.
#[test]
fn lights_and_cameras_too_far_away_are_warned_about() {
    let far =
        |loaded: &LoadedScene| loaded.warnings.iter().find(|w| w.contains("from the origin (up to")).cloned();
    assert_eq!(far(&parse(BASE).unwrap()), None);
    let at = |text: &str| far(&parse(text).unwrap());
    let light =
        "[[lights]]\ntype = \"spot\"\nposition = [0, 2e19, 0]\ndirection = [0, -1, 0]\nouter_angle = 30\n";
    let w = at(&format!("{BASE}{light}")).expect("a warning");
    assert!(w.starts_with("test.toml: light 2 lies more than 1e18 from the origin (up to 2.0e19)"), "{w}");
    assert!(w.contains("square distances past about 1.8e19 to infinity"), "{w}");
    let quad = "[[lights]]\ntype = \"quad\"\ncorner = [0, 5, 0]\nedge_u = [3e18, 0, 0]\nedge_v = [0, 0, 1]\n";
    assert!(
        at(&format!("{BASE}{quad}"))
            .expect("a warning")
            .contains("light 2 lies more than 1e18 from the origin (up to 3.0e18)")
    );
    let camera = BASE.replace("position = [0, 2, 10]", "position = [0, 2, -5e19]");
    assert!(
        at(&camera)
            .expect("a warning")
            .starts_with("test.toml: the camera lies more than 1e18 from the origin (up to 5.0e19)")
    );
    let focus =
        BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\naperture = 0.1\nfocus_distance = 2e19");
    assert!(at(&focus).expect("a warning").contains("the camera's focus point lies more than 1e18"));
    // A lens wider than that (its points are the rays' origins).
    let lens = BASE.replace("look_at = [0, 1, 0]", "look_at = [0, 1, 0]\naperture = 1e20");
    assert!(at(&lens).expect("a warning").contains("the camera's lens lies more than 1e18"));
    let both =
        BASE.replace("position = [5, 8, 5]", "position = [5, 1e19, 5]").replace("[0, 2, 10]", "[0, 2, 3e19]");
    assert!(
        at(&both)
            .expect("a warning")
            .contains("the camera, light 1 lie more than 1e18 from the origin (up to 3.0e19)")
    );
    assert_eq!(at(&BASE.replace("position = [5, 8, 5]", "position = [5, 1e18, 5]")), None);
}
