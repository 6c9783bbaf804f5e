//! AOV passes against closed-form geometry, and their files.

mod common;
use common::*;
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{Cuboid, Plane, Shear, Sphere, Transform};
use prism_shade::{
    Aov, AovImages, AovParseError, Material, RenderHooks, RenderSettings, Texture, render_aovs,
};
use std::f32::consts::PI;

fn sphere(c: Vec3, r: f32) -> prism_geometry::Shape {
    Sphere::new(c, r).expect("valid sphere").into()
}

fn plane(p: Vec3, n: Vec3) -> prism_geometry::Shape {
    Plane::new(p, n).expect("valid plane").into()
}

const I: Transform = Transform::IDENTITY;

fn aovs(s: &Shot, spp: u32) -> AovImages {
    render_aovs(s, &s.settings(spp, 0), &Aov::ALL, RenderHooks::default()).0
}

fn get(a: &AovImages, aov: Aov, i: u32, j: u32) -> Vec3 {
    a.get(aov).and_then(|p| p.vec3(i, j)).expect("pass and pixel exist")
}

fn depth(a: &AovImages, i: u32, j: u32) -> f32 {
    get(a, Aov::Depth, i, j).x
}

fn id(a: &AovImages, i: u32, j: u32) -> f32 {
    get(a, Aov::ObjectId, i, j).x
}

/// The unit direction through image point `(x, y)` of a camera at the
/// origin looking down −Z with +Y up, written out independently of
/// `Camera::ray`.
fn pinhole_dir(x: f32, y: f32, w: u32, h: u32, vfov_deg: f32) -> Vec3 {
    let t = (vfov_deg.to_radians() * 0.5).tan();
    let sx = (2.0 * x / w as f32 - 1.0) * t * w as f32 / h as f32;
    let sy = (1.0 - 2.0 * y / h as f32) * t;
    Vec3::new(sx, sy, -1.0).normalize()
}

#[test]
fn names_parse_and_print() {
    for a in Aov::ALL {
        assert_eq!(a.name().parse::<Aov>(), Ok(a));
        assert_eq!(a.to_string(), a.name());
    }
    let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
    assert_eq!(names, ["depth", "normal", "geo_normal", "albedo", "object_id"]);
    assert_eq!(
        Aov::parse_list("depth, object_id,depth ,normal"),
        Ok(vec![Aov::Depth, Aov::ObjectId, Aov::Normal])
    );
    assert_eq!(Aov::parse_list("all"), Ok(Aov::ALL.to_vec()));
    assert_eq!(Aov::parse_list("albedo,all").map(|v| v[0]), Ok(Aov::Albedo));
    assert_eq!(Aov::parse_list("depth,Normal"), Err(AovParseError::Unknown { name: "Normal".into() }));
    assert_eq!(Aov::parse_list("depth,,normal"), Err(AovParseError::EmptyEntry));
    assert_eq!(Aov::parse_list(","), Err(AovParseError::EmptyEntry));
    assert_eq!(Aov::parse_list(" "), Err(AovParseError::EmptyList));
    // `none` alone is no pass (a flag that clears the scene's list).
    assert_eq!(Aov::parse_list(" none "), Ok(vec![]));
    assert_eq!(Aov::parse_list("depth,none"), Err(AovParseError::NoneWithOthers));
    // A file's names are exact, and say which one is wrong.
    assert_eq!(Aov::parse_names(["none"]), Ok(vec![]));
    assert_eq!(Aov::parse_names([]), Ok(vec![]));
    assert_eq!(
        Aov::parse_names(["depth", " normal"]),
        Err((1, AovParseError::Unknown { name: " normal".into() }))
    );
    assert_eq!(Aov::parse_names(["none", "depth"]), Err((0, AovParseError::NoneWithOthers)));
    let empty = AovParseError::EmptyEntry.to_string();
    assert!(!empty.contains("did you mean") && !empty.contains("``"), "{empty}");
    let msg = "zbuffer".parse::<Aov>().expect_err("unknown").to_string();
    assert!(msg.contains("zbuffer") && msg.contains("geo_normal"), "{msg}");
    assert_eq!(Aov::Depth.channels(), 1);
    assert_eq!(Aov::Albedo.channels(), 3);
}

#[test]
fn sphere_depth_at_the_centre_and_normals_on_the_silhouette() {
    let (r, d) = (1.5f32, 12.0f32);
    let (w, h, fov) = (401u32, 401u32, 16.0f32);
    let cam = camera(Vec3::new(0.0, 0.0, d), Vec3::ZERO, Vec3::Y, fov, w, h);
    let s = scene(vec![(sphere(Vec3::ZERO, r), I, flat(Vec3::ONE))], vec![], cam);
    let a = aovs(&s, 1);
    let centre = depth(&a, w / 2, h / 2);
    assert!(((centre - (d - r)) / (d - r)).abs() < 1e-4, "centre depth {centre}, want {}", d - r);

    // Pixel footprint at the sphere's distance, and the largest |n · v| a
    // pixel centre within √2 pixels of the silhouette can have:
    // n · v = √(1 − (b/r)²) ≤ √(2 (r − b) / r) for impact parameter b.
    let pixel = 2.0 * d * (fov.to_radians() * 0.5).tan() / h as f32;
    let tol = (2.0 * 2f32.sqrt() * pixel / r).sqrt() * 1.1;
    assert!(tol < 0.2, "the test needs small pixels, tolerance {tol}");
    let mut silhouette = 0;
    for j in 1..h - 1 {
        for i in 1..w - 1 {
            let here = depth(&a, i, j);
            let n = get(&a, Aov::Normal, i, j);
            let g = get(&a, Aov::GeoNormal, i, j);
            if !here.is_finite() {
                assert_eq!(here, f32::INFINITY);
                assert_eq!((n, g, id(&a, i, j)), (Vec3::ZERO, Vec3::ZERO, -1.0));
                continue;
            }
            // Everywhere: the normal is the analytic one at the hit point.
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let p = ray.origin + ray.dir * here;
            assert!((p.length() - r).abs() < 1e-4 * d, "hit point off the sphere at ({i}, {j})");
            assert_close(n, p / r, 1e-4);
            assert_eq!(n, g);
            let edge = [(1i32, 0i32), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|(di, dj)| !depth(&a, (i as i32 + di) as u32, (j as i32 + dj) as u32).is_finite());
            if edge {
                silhouette += 1;
                let view = ray.dir;
                assert!(n.dot(view).abs() <= tol, "({i}, {j}): n·v = {} > {tol}", n.dot(view));
                // Seen from outside, the normal faces the camera, never away.
                assert!(n.dot(view) <= 0.0);
            }
        }
    }
    assert!(silhouette > 100, "only {silhouette} silhouette pixels");
}

#[test]
fn plane_depth_is_analytic_at_every_pixel() {
    // A wall facing the camera at distance 7 and a floor 2 below the eye.
    let (w, h, fov) = (64u32, 48u32, 60.0f32);
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, fov, w, h);
    let wall = scene(vec![(plane(Vec3::new(0.0, 0.0, -7.0), Vec3::Z), I, flat(Vec3::ONE))], vec![], cam);
    let a = aovs(&wall, 1);
    for j in 0..h {
        for i in 0..w {
            let dir = pinhole_dir(i as f32 + 0.5, j as f32 + 0.5, w, h, fov);
            let want = 7.0 / -dir.z;
            let got = depth(&a, i, j);
            assert!(((got - want) / want).abs() < 2e-6, "({i}, {j}): {got} vs {want}");
            assert_eq!(get(&a, Aov::Normal, i, j), Vec3::Z);
            assert_eq!(id(&a, i, j), 0.0);
        }
    }
    let floor = scene(vec![(plane(Vec3::new(0.0, -2.0, 0.0), Vec3::Y), I, flat(Vec3::ONE))], vec![], cam);
    let a = aovs(&floor, 1);
    let mut hits = 0;
    for j in 0..h {
        for i in 0..w {
            let dir = pinhole_dir(i as f32 + 0.5, j as f32 + 0.5, w, h, fov);
            let got = depth(&a, i, j);
            if dir.y < 0.0 {
                let want = 2.0 / -dir.y;
                assert!(((got - want) / want).abs() < 2e-6, "({i}, {j}): {got} vs {want}");
                hits += 1;
            } else {
                assert_eq!(got, f32::INFINITY, "({i}, {j}) looks at the sky");
                assert_eq!(id(&a, i, j), -1.0);
            }
        }
    }
    assert_eq!(hits, w * h / 2);
}

#[test]
fn sheared_box_faces_report_inverse_transpose_normals() {
    let unit = Cuboid::new(Vec3::splat(-1.0), Vec3::splat(1.0)).expect("valid box").into();
    let placed = Transform::shear(Shear { xy: 0.6, zx: -0.3, ..Shear::NONE })
        .expect("invertible")
        .then(&Transform::rotate_y(0.4))
        .then(&Transform::translate(Vec3::new(0.5, 0.0, -1.0)).expect("finite"));
    let (w, h) = (96u32, 96u32);
    let cam = camera(Vec3::new(4.0, 3.5, 6.0), Vec3::new(0.5, 0.0, -1.0), Vec3::Y, 40.0, w, h);
    let s = scene(vec![(unit, placed, flat(Vec3::ONE))], vec![], cam);
    let a = aovs(&s, 1);
    let m = placed.matrix();
    let inv = placed.inverse_matrix();
    let normal_matrix = prism_geometry::glam::Mat3::from(m.matrix3).inverse().transpose();
    let mut faces_seen = std::collections::BTreeSet::new();
    for j in 0..h {
        for i in 0..w {
            let d = depth(&a, i, j);
            if !d.is_finite() {
                continue;
            }
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let local = inv.transform_point3(ray.origin + ray.dir * d);
            // The face hit: the coordinate at ±1 (skip pixels near edges).
            let abs = local.abs();
            let axis = if abs.x >= abs.y && abs.x >= abs.z {
                0
            } else if abs.y >= abs.z {
                1
            } else {
                2
            };
            let mut others = abs.to_array();
            assert!((others[axis] - 1.0).abs() < 1e-4, "({i}, {j}): hit point {local} is not on the box");
            others[axis] = 0.0;
            if others.iter().any(|&c| c > 0.98) {
                continue;
            }
            let mut n_local = Vec3::ZERO;
            n_local[axis] = local[axis].signum();
            let want = (normal_matrix * n_local).normalize();
            assert_close(get(&a, Aov::Normal, i, j), want, 2e-6);
            assert_close(get(&a, Aov::GeoNormal, i, j), want, 2e-6);
            faces_seen.insert((axis, local[axis] > 0.0));
        }
    }
    assert_eq!(faces_seen.len(), 3, "the camera sees three faces: {faces_seen:?}");
}

#[test]
fn textured_sphere_albedo_is_the_texture_lookup() {
    let image = distinct_texture();
    let tint = Vec3::new(1.0, 0.5, 0.25);
    let tex = Texture::Image {
        image: image.clone(),
        mapping: prism_shade::Mapping::Uv,
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        tint,
    };
    let (w, h) = (41u32, 41u32);
    let cam = camera(Vec3::new(1.0, 2.0, 5.0), Vec3::ZERO, Vec3::Y, 30.0, w, h);
    // Lit from nowhere and dark: albedo is the texture, not the radiance.
    let dark = Material { ambient: 0.0, diffuse: 0.3, texture: tex, ..Material::diffuse(Vec3::ONE) };
    let s = scene(vec![(sphere(Vec3::ZERO, 1.0), I, dark)], vec![], cam);
    let a = aovs(&s, 1);
    let mut checked = 0;
    for j in 0..h {
        for i in 0..w {
            let got = get(&a, Aov::Albedo, i, j);
            let d = depth(&a, i, j);
            if !d.is_finite() {
                assert_eq!(got, Vec3::ZERO);
                continue;
            }
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let n = (ray.origin + ray.dir * d).normalize();
            // Azimuth from +Z growing toward +X (docs/scene-format.md), and
            // the report's equation 8.
            let u = 0.5 + n.x.atan2(n.z) / (2.0 * PI);
            let v = 0.5 - n.y.asin() / PI;
            let want = image.sample(Vec2::new(u, v)) * tint;
            assert_close(got, want, 2e-3);
            checked += 1;
        }
    }
    assert!(checked > 300, "{checked}");
}

#[test]
fn object_ids_and_misses() {
    // Object 0 in front of object 1 (overlapping on screen), object 2 alone.
    let cam = camera(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 40.0, 81, 61);
    let s = scene(
        vec![
            (sphere(Vec3::new(-1.0, 0.0, 2.0), 1.0), I, flat(Vec3::X)),
            (sphere(Vec3::new(-2.0, 0.0, -2.0), 2.0), I, flat(Vec3::Y)),
            (sphere(Vec3::new(3.0, 0.0, 0.0), 1.0), I, flat(Vec3::Z)),
        ],
        vec![],
        cam,
    );
    let a = aovs(&s, 1);
    let mut counts = [0u32; 4];
    for j in 0..61 {
        for i in 0..81 {
            let ray = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let nearest = [(-1.0f32, 0.0f32, 2.0f32, 1.0f32), (-2.0, 0.0, -2.0, 2.0), (3.0, 0.0, 0.0, 1.0)]
                .iter()
                .enumerate()
                .filter_map(|(k, &(x, y, z, r))| {
                    let oc = ray.origin - Vec3::new(x, y, z);
                    let b = oc.dot(ray.dir);
                    let disc = b * b - (oc.length_squared() - r * r);
                    (disc > 1e-3).then(|| (-b - disc.sqrt(), k))
                })
                .min_by(|x, y| x.0.total_cmp(&y.0));
            let got = id(&a, i, j);
            match nearest {
                Some((_, k)) => {
                    assert_eq!(got, k as f32, "({i}, {j})");
                    assert_eq!(get(&a, Aov::Albedo, i, j), [Vec3::X, Vec3::Y, Vec3::Z][k]);
                    counts[k] += 1;
                }
                None if got == -1.0 => counts[3] += 1,
                // Grazing rays (disc within the tolerance) may go either way.
                None => {}
            }
        }
    }
    assert!(counts.iter().all(|&c| c > 20), "{counts:?}");
}

#[test]
fn samples_are_averaged_except_the_object_id() {
    let spp = 4;
    let (w, h, fov) = (24u32, 16u32, 50.0f32);
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, fov, w, h);
    // A tilted floor (depth varies inside each pixel) and a sphere whose
    // edge crosses pixels.
    let s = scene(
        vec![
            (plane(Vec3::new(0.0, -2.0, 0.0), Vec3::new(0.0, 1.0, 0.2)), I, flat(Vec3::ONE)),
            (sphere(Vec3::new(1.0, 0.5, -6.0), 1.3), I, flat(Vec3::X)),
        ],
        vec![],
        cam,
    );
    let avg = aovs(&s, spp);
    let one = aovs(&s, 1);
    let mut edge_pixels = 0;
    for j in 0..h {
        for i in 0..w {
            // Recompute every sample from its published position.
            let mut sum_d = 0.0f32;
            let mut sum_n = Vec3::ZERO;
            let mut ids = Vec::new();
            for k in 0..spp {
                let (x, y) = prism_shade::sample_position(spp, w, i, j, k);
                assert!(x >= i as f32 && x < i as f32 + 1.0 && y >= j as f32 && y < j as f32 + 1.0);
                let hit = s.accel.closest_hit(&cam.ray(x, y));
                sum_d += hit.map_or(f32::INFINITY, |h| h.hit.t);
                sum_n += hit.map_or(Vec3::ZERO, |h| h.hit.normal);
                ids.push(hit.map_or(-1.0, |h| h.object as f32));
            }
            let got_d = depth(&avg, i, j);
            let want_d = sum_d / spp as f32;
            if want_d.is_finite() {
                assert!((got_d - want_d).abs() <= 1e-5 * want_d, "({i}, {j}): {got_d} vs {want_d}");
            } else {
                assert_eq!(got_d, f32::INFINITY);
            }
            assert_close(get(&avg, Aov::Normal, i, j), sum_n / spp as f32, 1e-6);
            // The id is the centre ray's, exactly the 1-spp pass.
            let centre = s.accel.closest_hit(&cam.ray(i as f32 + 0.5, j as f32 + 0.5));
            assert_eq!(id(&avg, i, j), centre.map_or(-1.0, |h| h.object as f32), "({i}, {j})");
            assert_eq!(id(&avg, i, j), id(&one, i, j));
            if ids.iter().any(|&x| x != ids[0]) {
                edge_pixels += 1;
                assert!(get(&avg, Aov::Normal, i, j).length() < 0.999 || ids.contains(&-1.0));
            }
        }
    }
    assert!(edge_pixels > 5, "{edge_pixels}");
    // No NaN anywhere; +∞ only in depth.
    for p in &avg.passes {
        assert!(p.data.iter().all(|v| !v.is_nan()));
        if p.aov != Aov::Depth {
            assert!(p.data.iter().all(|v| v.is_finite()), "{}", p.aov);
        }
    }
}

#[test]
fn beauty_is_unchanged_and_threads_do_not_matter() {
    let cam = camera(Vec3::new(0.0, 1.0, 6.0), Vec3::ZERO, Vec3::Y, 45.0, 40, 30);
    let mut s = scene(
        vec![
            (plane(Vec3::new(0.0, -1.0, 0.0), Vec3::Y), I, Material::diffuse(Vec3::splat(0.8))),
            (sphere(Vec3::ZERO, 1.0), I, Material { reflectivity: 0.5, ..Material::diffuse(Vec3::X) }),
            (sphere(Vec3::new(1.5, 0.0, 1.0), 0.6), I, glass(1.5)),
        ],
        vec![light(Vec3::new(3.0, 5.0, 4.0))],
        cam,
    );
    s.background = Vec3::new(0.1, 0.2, 0.3);
    for spp in [1, 5] {
        let set = RenderSettings { threads: Some(1), ..s.settings(spp, 4) };
        let (beauty, _) = prism_shade::render(&s, &set, RenderHooks::default());
        let (b2, passes, stats) = prism_shade::render_with_aovs(&s, &set, &Aov::ALL, RenderHooks::default());
        assert_eq!(beauty, b2, "spp {spp}");
        assert!(stats.rays > 0 && !stats.cancelled);
        let (alone, _) = render_aovs(&s, &set, &Aov::ALL, RenderHooks::default());
        assert_eq!(passes, alone);
        let three = RenderSettings { threads: Some(3), ..set.clone() };
        let (b3, passes3, _) = prism_shade::render_with_aovs(&s, &three, &Aov::ALL, RenderHooks::default());
        assert_eq!(
            b3.pixels.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
            b2.pixels.iter().map(|p| p.to_array()).collect::<Vec<_>>()
        );
        assert_eq!(passes3, passes);
    }
    // Only what was asked, in that order, repeats dropped.
    let (p, _) = render_aovs(
        &s,
        &s.settings(1, 0),
        &[Aov::ObjectId, Aov::Depth, Aov::ObjectId],
        RenderHooks::default(),
    );
    assert_eq!(p.passes.iter().map(|p| p.aov).collect::<Vec<_>>(), [Aov::ObjectId, Aov::Depth]);
    assert_eq!(p.passes[0].data.len(), 40 * 30);
    // Cancelled before the start: every pixel holds the miss values.
    let stop = std::sync::atomic::AtomicBool::new(true);
    let hooks = RenderHooks { cancel: Some(&stop), ..RenderHooks::default() };
    let (p, stats) = render_aovs(&s, &s.settings(1, 0), &[Aov::Depth, Aov::Normal], hooks);
    assert!(stats.cancelled);
    assert!(p.passes[0].data.iter().all(|&d| d == f32::INFINITY));
    assert!(p.passes[1].data.iter().all(|&d| d == 0.0));
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("prism-aov-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn dir_names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("readable")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn exr_round_trip_keeps_every_value() {
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 23, 17);
    let s = scene(
        vec![
            (sphere(Vec3::ZERO, 1.0), I, flat(Vec3::new(0.25, 0.5, 0.75))),
            (sphere(Vec3::new(1.5, 0.5, -1.0), 0.7), I, flat(Vec3::new(0.9, 0.1, 0.3))),
        ],
        vec![light(Vec3::new(0.0, 3.0, 5.0))],
        cam,
    );
    let set = s.settings(2, 2);
    let (beauty, passes, _) = prism_shade::render_with_aovs(&s, &set, &Aov::ALL, RenderHooks::default());
    let dir = temp_dir("roundtrip");
    let base = dir.join("out.exr");
    prism_shade::write_image_exr(&base, &beauty).expect("beauty written");
    let written = prism_shade::write_aov_files(&base, &passes, true).expect("passes written");
    let names: Vec<String> =
        written.iter().map(|p| p.file_name().expect("name").to_string_lossy().into_owned()).collect();
    assert_eq!(
        names,
        [
            "out.depth.exr",
            "out.depth.png",
            "out.normal.exr",
            "out.normal.png",
            "out.geo_normal.exr",
            "out.geo_normal.png",
            "out.albedo.exr",
            "out.albedo.png",
            "out.object_id.exr",
            "out.object_id.png"
        ]
    );
    let mut all = names.clone();
    all.push("out.exr".into());
    all.sort();
    assert_eq!(dir_names(&dir), all, "no temporary files left");

    let (w, h, rgb) = prism_shade::read_exr_rgb(&base).expect("beauty reads back");
    assert_eq!((w, h), (23, 17));
    let want: Vec<f32> = beauty.pixels.iter().flat_map(|p| p.to_array()).collect();
    assert_eq!(
        rgb.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        want.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );

    let mut saw_inf = false;
    for pass in &passes.passes {
        let path = prism_shade::aov_path(&base, pass.aov, "exr").expect("path");
        // Read with the image crate directly, as a user would.
        let img = image::open(&path).expect("decodes").into_rgb32f();
        assert_eq!(img.dimensions(), (23, 17));
        let back = img.into_raw();
        assert_eq!(back.len(), 23 * 17 * 3);
        let want = pass.to_rgb();
        for (k, (a, b)) in back.iter().zip(&want).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "{} value {k}: {a} vs {b}", pass.aov);
        }
        saw_inf |= back.contains(&f32::INFINITY);
        let png =
            image::open(prism_shade::aov_path(&base, pass.aov, "png").expect("path")).expect("png decodes");
        assert_eq!((png.width(), png.height()), (23, 17));
    }
    assert!(saw_inf, "the depth pass keeps +inf for misses");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn failed_writes_are_typed_and_leave_nothing_behind() {
    let dir = temp_dir("errors");
    let pass = prism_shade::AovImage { aov: Aov::Depth, width: 2, height: 1, data: vec![1.0, f32::INFINITY] };
    // A missing directory.
    let err = prism_shade::write_aov_exr(&dir.join("missing/out.exr"), &pass).expect_err("no directory");
    assert!(matches!(err, prism_shade::OutputError::Io { .. }), "{err}");
    // Wrong buffer lengths and empty images.
    let bad = prism_shade::AovImage { data: vec![1.0], ..pass.clone() };
    assert!(matches!(
        prism_shade::write_aov_exr(&dir.join("a.exr"), &bad),
        Err(prism_shade::OutputError::Invalid { .. })
    ));
    assert!(matches!(
        prism_shade::write_exr_rgb(&dir.join("b.exr"), 0, 0, &[]),
        Err(prism_shade::OutputError::Invalid { .. })
    ));
    assert!(matches!(
        prism_shade::write_png_rgb8(&dir.join("c.png"), 2, 2, &[0; 11]),
        Err(prism_shade::OutputError::Invalid { .. })
    ));
    // The target is a directory: the rename fails, the temp file goes.
    std::fs::create_dir(dir.join("taken.exr")).expect("dir");
    let err =
        prism_shade::write_aov_exr(&dir.join("taken.exr"), &pass).expect_err("a directory is in the way");
    assert!(matches!(err, prism_shade::OutputError::Io { .. }), "{err}");
    assert_eq!(dir_names(&dir), ["taken.exr"]);
    // An existing file is replaced whole.
    let target = dir.join("depth.exr");
    std::fs::write(&target, b"old").expect("write");
    prism_shade::write_aov_exr(&target, &pass).expect("replaced");
    let (w, h, rgb) = prism_shade::read_exr_rgb(&target).expect("reads");
    assert_eq!((w, h, rgb), (2, 1, vec![1.0, 1.0, 1.0, f32::INFINITY, f32::INFINITY, f32::INFINITY]));
    let err = prism_shade::read_exr_rgb(&dir.join("nope.exr")).expect_err("missing");
    assert!(matches!(err, prism_shade::OutputError::Read { .. }), "{err}");
    assert!(err.to_string().starts_with("cannot read "), "{err}");
    assert!(prism_shade::aov_path(std::path::Path::new(".."), Aov::Depth, "exr").is_err());
    assert_eq!(
        prism_shade::aov_path(std::path::Path::new("renders/out.png"), Aov::GeoNormal, "exr").expect("path"),
        std::path::Path::new("renders/out.geo_normal.exr")
    );
    assert_eq!(
        prism_shade::aov_path(std::path::Path::new("out"), Aov::ObjectId, "png").expect("path"),
        std::path::Path::new("out.object_id.png")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn previews_map_values_to_colours() {
    let normal = prism_shade::AovImage {
        aov: Aov::Normal,
        width: 3,
        height: 1,
        data: vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
    };
    assert_eq!(prism_shade::aov_preview_rgb8(&normal), [255, 128, 128, 0, 0, 0, 128, 0, 128]);
    let depth =
        prism_shade::AovImage { aov: Aov::Depth, width: 3, height: 1, data: vec![2.0, 4.0, f32::INFINITY] };
    let d = prism_shade::aov_preview_rgb8(&depth);
    assert_eq!(d[0..3], [255; 3]);
    assert!((25..=26).contains(&d[3]) && d[3] == d[4] && d[4] == d[5], "{d:?}");
    assert_eq!(d[6..9], [0; 3]);
    let albedo =
        prism_shade::AovImage { aov: Aov::Albedo, width: 1, height: 1, data: vec![1.0, 0.0, 0.214_041_14] };
    let a = prism_shade::aov_preview_rgb8(&albedo);
    assert_eq!(a[0..2], [255, 0]);
    assert!((127..=128).contains(&a[2]), "{a:?}");
    let ids =
        prism_shade::AovImage { aov: Aov::ObjectId, width: 4, height: 1, data: vec![-1.0, 0.0, 1.0, 0.0] };
    let c = prism_shade::aov_preview_rgb8(&ids);
    assert_eq!(&c[0..3], [0, 0, 0]);
    assert_ne!(&c[3..6], &c[6..9]);
    assert_eq!(&c[3..6], &c[9..12]);
    assert!(c[3..9].iter().all(|&b| b >= 64));
}
