//! The renderer as a whole: determinism, progressive passes, robustness,
//! ray counts.

mod common;
use common::*;
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{Cone, Cuboid, Cylinder, Plane, Shear, Sphere, Transform, Triangle};
use prism_shade::{
    FogMode, ImageTexture, Mapping, Material, PointLight, RenderHooks, RenderSettings, Texture, Wrap,
};
use std::sync::Arc;

const I: Transform = Transform::IDENTITY;

/// Every feature at once: the report's scene in miniature.
fn busy_scene(w: u32, h: u32) -> Shot {
    let planet = ImageTexture::from_linear(
        4,
        2,
        (0..8).map(|k| Vec3::new(k as f32 / 8.0, 0.5, 1.0 - k as f32 / 8.0)).collect(),
        Wrap::Repeat,
    )
    .expect("valid");
    let shear = Transform::shear(Shear { xy: 0.3, ..Shear::NONE }).expect("invertible");
    let rot = Transform::rotate_y(45f32.to_radians())
        .then(&Transform::translate(Vec3::new(2.0, 0.0, -2.0)).expect("ok"));
    let mut s = scene(
        vec![
            (
                Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y).expect("ok").into(),
                I,
                Material::diffuse(Vec3::ONE).with_texture(Texture::Checker {
                    a: Vec3::splat(0.9),
                    b: Vec3::new(0.1, 0.1, 0.4),
                    size: 1.0,
                    world: true,
                }),
            ),
            (
                Sphere::new(Vec3::new(-1.5, 0.5, -3.0), 1.5).expect("ok").into(),
                I,
                Material { reflectivity: 0.7, specular: 0.5, ..Material::diffuse(Vec3::new(0.1, 0.2, 0.8)) },
            ),
            (
                Sphere::new(Vec3::new(1.0, 0.0, 0.0), 0.8).expect("ok").into(),
                I,
                Material { absorption: Vec3::new(0.1, 0.0, 0.3), ..glass(1.5) },
            ),
            (
                Sphere::new(Vec3::new(-1.0, -0.3, 1.0), 0.6).expect("ok").into(),
                I,
                Material { transparency: 0.6, ..Material::diffuse(Vec3::new(0.9, 0.3, 0.3)) },
            ),
            (
                Sphere::new(Vec3::ZERO, 0.7).expect("ok").into(),
                Transform::translate(Vec3::new(3.0, 0.5, -1.0)).expect("ok"),
                Material::diffuse(Vec3::ONE).with_texture(Texture::Image {
                    image: Arc::new(planet),
                    mapping: Mapping::Spherical,
                    scale: Vec2::ONE,
                    offset: Vec2::ZERO,
                    tint: Vec3::ONE,
                }),
            ),
            (
                Cuboid::new(Vec3::new(-0.5, -1.0, -0.5), Vec3::new(0.5, 0.0, 0.5)).expect("ok").into(),
                rot,
                Material::diffuse(Vec3::new(0.8, 0.5, 0.2)),
            ),
            (
                Cuboid::new(Vec3::new(-3.5, -1.0, -0.5), Vec3::new(-2.5, 0.0, 0.5)).expect("ok").into(),
                shear,
                Material::diffuse(Vec3::new(0.2, 0.8, 0.2)),
            ),
            (
                Cone::new(Vec3::new(0.0, -1.0, -5.0), 0.8, 2.0).expect("ok").into(),
                I,
                Material::diffuse(Vec3::new(0.8, 0.8, 0.2)),
            ),
            (
                Cylinder::new(Vec3::new(2.5, -1.0, 2.0), 0.4, 1.0).expect("ok").into(),
                I,
                Material::diffuse(Vec3::new(0.5, 0.2, 0.7)),
            ),
        ],
        vec![
            light(Vec3::new(5.0, 8.0, 6.0)),
            PointLight {
                position: Vec3::new(-4.0, 3.0, 2.0),
                color: Vec3::new(0.3, 0.3, 0.5),
                intensity: 0.8,
            },
        ],
        camera(Vec3::new(0.0, 2.0, 8.0), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 50.0, w, h),
    );
    s.ambient = Vec3::splat(0.2);
    s.background = Vec3::new(0.3, 0.5, 0.8);
    s.fog = fog(Vec3::ONE, FogMode::Linear { start: 5.0, end: 30.0 });
    s
}

trait WithTexture {
    fn with_texture(self, t: Texture) -> Self;
}

impl WithTexture for Material {
    fn with_texture(self, texture: Texture) -> Self {
        Material { texture, ..self }
    }
}

fn settings_t(s: &Shot, spp: u32, threads: usize) -> RenderSettings {
    RenderSettings { min_contribution: 1e-3, threads: Some(threads), ..s.settings(spp, 6) }
}

#[test]
fn busy_scene_validates() {
    busy_scene(4, 3).validate().expect("valid scene");
}

#[test]
fn one_and_two_threads_give_the_same_image_bit_for_bit() {
    let s = busy_scene(48, 32);
    let (a, sa) = prism_shade::render(&s, &settings_t(&s, 5, 1), RenderHooks::default());
    let (b, sb) = prism_shade::render(&s, &settings_t(&s, 5, 2), RenderHooks::default());
    let (c, _) = prism_shade::render(&s, &settings_t(&s, 5, 3), RenderHooks::default());
    assert!(
        a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits))
    );
    assert_eq!(a, c);
    assert_eq!(sa.rays, sb.rays);
    assert_eq!(sa.nonfinite_samples, 0);
    // The picture is not trivial: the scene's objects show.
    let distinct: std::collections::HashSet<[u32; 3]> =
        a.pixels.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    assert!(distinct.len() > 500);
}

#[test]
fn render_is_the_sum_of_sample_passes() {
    let s = busy_scene(24, 16);
    let set = settings_t(&s, 4, 2);
    let (full, full_stats) = prism_shade::render(&s, &set, RenderHooks::default());
    // One-sample passes, added in order to a zeroed buffer in f64 (as a
    // pixel's samples are summed): exact.
    let mut acc = vec![prism_geometry::glam::DVec3::ZERO; full.pixels.len()];
    let mut rays = 0;
    for k in 0..4 {
        let (pass, st) = prism_shade::render_samples(&s, &set, k..k + 1, RenderHooks::default());
        rays += st.rays;
        for (a, p) in acc.iter_mut().zip(&pass.pixels) {
            *a += p.as_dvec3();
        }
    }
    assert_eq!(rays, full_stats.rays);
    let inv = 1.0 / 4.0f32;
    for (a, f) in acc.iter().zip(&full.pixels) {
        assert_eq!(a.as_vec3() * inv, *f);
    }
    // Two two-sample passes: the same up to float rounding of the sums.
    let (p1, _) = prism_shade::render_samples(&s, &set, 0..2, RenderHooks::default());
    let (p2, _) = prism_shade::render_samples(&s, &set, 2..4, RenderHooks::default());
    for ((a, b), f) in p1.pixels.iter().zip(&p2.pixels).zip(&full.pixels) {
        assert_close((*a + *b) * inv, *f, 1e-6 * (1.0 + f.max_element()));
    }
}

#[test]
fn degenerate_inputs_never_make_nan() {
    let mut s = busy_scene(24, 16);
    // A light exactly on a surface, a light inside a sphere, a dark light,
    // shininess 0, ior 1 and huge, enormous absorption, zero fog density.
    s.lights.push(light(Vec3::new(0.0, -1.0, 0.0)).into());
    s.lights.push(light(Vec3::new(1.0, 0.0, 0.0)).into());
    s.lights
        .push(PointLight { position: Vec3::new(0.0, 5.0, 0.0), color: Vec3::ZERO, intensity: 0.0 }.into());
    s.materials[1].shininess = 0.0;
    s.materials[1].specular = 1.0;
    s.materials[2].ior = 1.0;
    s.materials[2].absorption = Vec3::splat(1e30);
    s.materials[3] = Material { transmission: 0.5, transparency: 0.5, ior: 1e6, ..s.materials[3].clone() };
    s.materials[4] = s.materials[4].clone().with_texture(Texture::Image {
        image: Arc::new(ImageTexture::from_linear(1, 1, vec![Vec3::ONE], Wrap::Clamp).expect("valid")),
        mapping: Mapping::Cylindrical,
        scale: Vec2::ZERO,
        offset: Vec2::ZERO,
        tint: Vec3::ONE,
    });
    for mode in [
        FogMode::Exponential { density: 0.0 },
        FogMode::ExponentialSquared { density: 0.0 },
        FogMode::Linear { start: 3.0, end: 3.0 },
        FogMode::Linear { start: -5.0, end: 1.0 },
        FogMode::Exponential { density: 1e30 },
    ] {
        s.fog = fog(Vec3::splat(0.5), mode);
        for (max_depth, min_contribution) in [(u32::MAX, 0.0), (3, f32::NAN), (2, f32::INFINITY), (1, -1.0)] {
            let set = RenderSettings { min_contribution, threads: Some(2), ..s.settings(2, max_depth) };
            let (img, stats) = prism_shade::render(&s, &set, RenderHooks::default());
            assert!(img.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0), "{mode:?}");
            assert_eq!(stats.nonfinite_samples, 0);
        }
    }
    // A camera inside a glass sphere, and an object naming no material.
    s.camera = camera(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, -1.0), Vec3::Y, 90.0, 8, 8);
    s.object_materials[5] = 99;
    assert!(s.validate().is_err());
    let (img, _) = prism_shade::render(&s, &settings_t(&s, 3, 1), RenderHooks::default());
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    // spp 0 acts as 1.
    let (img, _) = prism_shade::render(&s, &settings_t(&s, 0, 1), RenderHooks::default());
    assert!(img.pixels.iter().all(|p| p.is_finite()));
}

fn wall_scene(material: Material, lights: Vec<PointLight>, w: u32, h: u32) -> Shot {
    scene(
        vec![(Plane::new(Vec3::ZERO, Vec3::Z).expect("ok").into(), I, material)],
        lights,
        camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 20.0, w, h),
    )
}

fn rays(s: &Shot, spp: u32, max_depth: u32) -> u64 {
    prism_shade::render(s, &s.settings(spp, max_depth), RenderHooks::default()).1.rays
}

#[test]
fn every_ray_is_counted() {
    let front = light(Vec3::new(0.0, 1.0, 4.0));
    let behind = light(Vec3::new(0.0, 0.0, -4.0));
    // A lit wall: a camera ray and a shadow ray per sample.
    assert_eq!(rays(&wall_scene(Material::diffuse(Vec3::ONE), vec![front], 2, 2), 3, 5), 4 * 3 * 2);
    // Two lights, one behind the wall (no shadow ray for it).
    assert_eq!(
        rays(&wall_scene(Material::diffuse(Vec3::ONE), vec![front, behind, front], 2, 1), 1, 5),
        2 * 3
    );
    // A perfect mirror: no local shading, one reflection ray (a miss).
    let mirror = Material { reflectivity: 1.0, ..Material::diffuse(Vec3::ONE) };
    assert_eq!(rays(&wall_scene(mirror.clone(), vec![front], 1, 1), 1, 5), 2);
    assert_eq!(rays(&wall_scene(mirror, vec![front], 1, 1), 1, 0), 1);
    // A half mirror: camera, shadow, reflection.
    let half = Material { reflectivity: 0.5, ..Material::diffuse(Vec3::ONE) };
    assert_eq!(rays(&wall_scene(half, vec![front], 1, 1), 1, 5), 3);
    // A transparent sphere in front of nothing: camera, the straight ray to
    // the exit, the ray from the far side.
    let glassy = Material { transparency: 1.0, ..Material::diffuse(Vec3::ONE) };
    let s = scene(
        vec![(Sphere::new(Vec3::ZERO, 1.0).expect("ok").into(), I, glassy)],
        vec![],
        camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 10.0, 1, 1),
    );
    assert_eq!(rays(&s, 1, 5), 3);
    // Nothing at all: one ray per sample.
    let empty = scene(vec![], vec![front], camera(Vec3::Z, Vec3::ZERO, Vec3::Y, 10.0, 3, 2));
    assert_eq!(rays(&empty, 2, 5), 12);
}

#[test]
fn cancel_and_progress() {
    let s = busy_scene(16, 8);
    let seen = std::sync::atomic::AtomicU32::new(0);
    let progress = |done: u32, all: u32| {
        assert!(done <= all && all == 8);
        seen.fetch_max(done, std::sync::atomic::Ordering::Relaxed);
    };
    let (_, stats) = prism_shade::render(
        &s,
        &settings_t(&s, 1, 2),
        RenderHooks { progress: Some(&progress), cancel: None },
    );
    assert_eq!(seen.into_inner(), 8);
    assert!(!stats.cancelled);
    let cancel = std::sync::atomic::AtomicBool::new(true);
    let (img, stats) =
        prism_shade::render(&s, &settings_t(&s, 1, 2), RenderHooks { progress: None, cancel: Some(&cancel) });
    assert!(stats.cancelled);
    assert_eq!(stats.rays, 0);
    assert!(img.pixels.iter().all(|p| *p == Vec3::ZERO));
}

#[test]
fn any_region_on_any_thread_count_is_bit_identical_to_the_full_render() {
    use prism_shade::{Aov, PixelBounds, render_region, render_with_aovs};
    let s = busy_scene(37, 23);
    let aovs = [Aov::Depth, Aov::Normal, Aov::ObjectId];
    let (full, full_aovs, _) = render_with_aovs(&s, &settings_t(&s, 3, 1), &aovs, RenderHooks::default());
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut rng = prism_testkit::rng::Rng::new(13);
    for round in 0..24 {
        let (xa, xb) = (rng.below(37) as u32, rng.below(37) as u32);
        let (ya, yb) = (rng.below(23) as u32, rng.below(23) as u32);
        let b = PixelBounds::new(xa.min(xb), xa.max(xb) + 1, ya.min(yb), ya.max(yb) + 1).unwrap();
        let threads = 1 + round % 4;
        let with = if round % 2 == 0 { &aovs[..] } else { &[] };
        let (img, passes, stats) =
            render_region(&s, &settings_t(&s, 3, threads), b, with, RenderHooks::default()).unwrap();
        assert_eq!((img.width, img.height), (b.width(), b.height()));
        assert_eq!(stats.camera_rays, u64::from(b.width() * b.height()) * 3, "camera rays of {b}");
        for y in 0..b.height() {
            for x in 0..b.width() {
                let (i, j) = (b.x0() + x, b.y0() + y);
                let want = full.pixels[(j * 37 + i) as usize];
                assert_eq!(bits(img.pixels[(y * b.width() + x) as usize]), bits(want), "{b} at ({i}, {j})");
                for p in &passes.passes {
                    let whole = full_aovs.get(p.aov).unwrap().pixel(i, j).unwrap();
                    let part = p.pixel(x, y).unwrap();
                    assert_eq!(
                        part.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        whole.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        "{} {b}",
                        p.aov
                    );
                }
            }
        }
        assert_eq!(passes.passes.len(), with.len());
    }
    // A region past the image is refused.
    let past = PixelBounds::new(30, 38, 0, 1).unwrap();
    assert!(render_region(&s, &settings_t(&s, 1, 1), past, &[], RenderHooks::default()).is_err());
}

#[test]
fn a_scene_scaled_up_or_down_renders_the_same_picture() {
    // A mirror ball, a glass ball and a tilted triangle on a floor under a
    // point light, every length times `s`: the same picture (ray offsets
    // scale with the scene; a fixed one put a small scene's reflected and
    // shadow rays past the surfaces they should meet). Also scaled up, and
    // by 2⁻⁴⁶ and 2⁴³, where the triangle test's `f32` products under- and
    // overflow (the triangle was unlit, or missed).
    let shot = |s: f32| {
        let mirror = Material { reflectivity: 1.0, ..Material::diffuse(Vec3::ONE) };
        let corners = [Vec3::new(-0.4, 0.0, 1.6), Vec3::new(0.4, 0.0, 1.2), Vec3::new(0.0, 0.9, 1.0)];
        let mut sh = scene(
            vec![
                (Plane::new(Vec3::ZERO, Vec3::Y).expect("ok").into(), I, Material::diffuse(Vec3::splat(0.7))),
                (Sphere::new(Vec3::new(-0.8, 1.0, 0.0) * s, s).expect("ok").into(), I, mirror),
                (Sphere::new(Vec3::new(1.2, 0.6, 0.5) * s, 0.6 * s).expect("ok").into(), I, glass(1.5)),
                (
                    Triangle::new(corners.map(|c| c * s)).expect("ok").into(),
                    I,
                    Material::diffuse(Vec3::new(0.9, 0.3, 0.2)),
                ),
            ],
            vec![light(Vec3::new(1.0, 6.0, 3.0) * s)],
            camera(Vec3::new(0.0, 2.0, 6.0) * s, Vec3::new(0.0, 0.6, 0.0) * s, Vec3::Y, 45.0, 48, 36),
        );
        sh.scene.background = Vec3::new(0.2, 0.4, 0.8);
        sh
    };
    let one = render(&shot(1.0), 1, 6);
    for s in [1e-2, 1e-4, 1e-6, 2f32.powi(-46), 1e4, 1e8, 2f32.powi(43)] {
        let small = render(&shot(s), 1, 6);
        let off = one
            .pixels
            .iter()
            .zip(&small.pixels)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 0.05)
            .count();
        assert!(off <= 2, "scale {s}: {off} of {} pixels differ", one.pixels.len());
    }
}

/// A Ctrl-C is seen inside one sample's path, not only between samples:
/// between six parallel glass panes at depth 40 with no contribution
/// cut-off, one camera ray splits into up to 2^40 rays (hours). A cancel
/// set while that sample is traced stops it within a few thousand rays;
/// the unfinished row is dropped (black), the render reports the cancel.
#[test]
fn a_cancel_stops_a_sample_whose_path_never_ends() {
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let panes: Vec<_> = (0..6)
        .map(|k| {
            let x = k as f32 - 2.5;
            (Plane::new(Vec3::new(x, 0.0, 0.0), Vec3::X).expect("ok").into(), I, glass(1.5))
        })
        .collect();
    let cam = camera(Vec3::new(0.1, 0.0, 0.0), Vec3::new(1.1, 0.0, 0.3), Vec3::Y, 45.0, 1, 1);
    let shot = scene(panes, vec![light(Vec3::new(0.0, 5.0, 0.0))], cam);
    let set = shot.settings(1, 40);
    let cancel = AtomicBool::new(false);
    let (img, stats) = std::thread::scope(|s| {
        let render = s.spawn(|| {
            prism_shade::render(
                &shot.scene,
                &set,
                RenderHooks { cancel: Some(&cancel), ..RenderHooks::default() },
            )
        });
        std::thread::sleep(std::time::Duration::from_millis(200));
        assert!(!render.is_finished(), "the sample's path should take hours");
        cancel.store(true, Relaxed);
        // Without the check inside the path this join would wait for hours.
        render.join().expect("no panic")
    });
    assert!(stats.cancelled);
    assert_eq!(img.pixels, vec![Vec3::ZERO], "the unfinished pixel is dropped");
}

/// A see-through solid too small for a spawned ray's offset to leave its
/// surface: each unshaded continuation through it (a re-entered front
/// face) met the same surface again at the same depth, until the stack
/// overflowed and the process aborted, even at depth 1. Now such a path
/// counts as absorbed after a few dozen, and the render finishes with
/// finite pixels.
#[test]
fn a_glass_sphere_too_small_for_the_ray_offset_renders() {
    for see_through in [
        Material { transmission: 1.0, ior: 1.5, ..Material::diffuse(Vec3::splat(0.8)) },
        Material { transparency: 1.0, ..Material::diffuse(Vec3::splat(0.8)) },
    ] {
        let radius = 1e-20;
        let ball = (Sphere::new(Vec3::ZERO, radius).expect("ok").into(), I, see_through);
        let cam = camera(Vec3::new(0.0, 0.0, 5.0 * radius), Vec3::ZERO, Vec3::Y, 45.0, 32, 24);
        let shot = scene(vec![ball], vec![], cam);
        for depth in [1, 8] {
            let img = render(&shot, 1, depth);
            assert!(img.pixels.iter().all(|p| p.is_finite()), "depth {depth}");
        }
    }
}

/// The cancel is read once the ray count passes a mark, not when it is a
/// multiple of one: here every pane hit adds one shadow ray per light
/// (two), the count stays odd after pixel 0 (an opaque face that sees
/// neither light), and a check on multiples never came (a review found
/// the render still running 20 s after the cancel).
#[test]
fn a_cancel_is_seen_whatever_the_ray_count_steps_by() {
    use prism_geometry::Cuboid;
    use prism_shade::{Light, LightKind};
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let half = Material { diffuse: 0.5, transmission: 0.5, ..glass(1.5) };
    let wall = Material { diffuse: 0.5, transmission: 0.0, reflectivity: 0.5, ..glass(1.5) };
    let mut objects: Vec<_> = (0..6)
        .map(|k| {
            let m = if k == 0 || k == 5 { wall.clone() } else { half.clone() };
            (Plane::new(Vec3::new(k as f32 - 2.5, 0.0, 0.0), Vec3::X).expect("ok").into(), I, m)
        })
        .collect();
    let block = Cuboid::new(Vec3::new(0.001, -3.0, 0.3), Vec3::new(0.49, 3.0, 0.4)).expect("ok");
    objects.push((block.into(), I, Material::diffuse(Vec3::ONE)));
    let sun = |x: f32| Light {
        kind: LightKind::Directional { direction: Vec3::new(x, -1.0, 0.0).normalize() },
        color: Vec3::ONE,
        intensity: 1.0,
    };
    let cam = camera(Vec3::ZERO, Vec3::Z, Vec3::Y, 45.0, 2, 1);
    let shot = scene_lit(objects, vec![sun(1.0), sun(-1.0)], cam);
    let set = shot.settings(1, 40);
    let cancel = AtomicBool::new(false);
    let stats = std::thread::scope(|s| {
        let render = s.spawn(|| {
            let hooks = RenderHooks { cancel: Some(&cancel), ..RenderHooks::default() };
            prism_shade::render(&shot.scene, &set, hooks).1
        });
        std::thread::sleep(std::time::Duration::from_millis(300));
        assert!(!render.is_finished(), "the path should take hours");
        cancel.store(true, Relaxed);
        render.join().expect("no panic")
    });
    assert!(stats.cancelled);
}

#[test]
fn the_mean_of_many_equal_samples_is_that_sample() {
    // 2¹⁸ samples of one colour per pixel. Summed in f32 they drifted:
    // 0.7 averaged 0.69955 over 65 536 samples and 0.72 over 3 M.
    use prism_bvh::{Accel, Object};
    use prism_geometry::TriangleMesh;
    let colour = Vec3::new(0.3, 0.7, 0.013);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0, 2, 1);
    // Nothing to hit (single rays), and a mesh behind the eye (a scene of
    // meshes traces its camera rays in packets, another sum).
    for mesh in [false, true] {
        let mut shot = scene(vec![], vec![], cam);
        if mesh {
            let p = vec![Vec3::new(0.0, 0.0, 9.0), Vec3::new(1.0, 0.0, 9.0), Vec3::new(0.0, 1.0, 9.0)];
            let tri = TriangleMesh::new(p, None, None, vec![[0, 1, 2]]).expect("valid mesh");
            shot.scene.accel =
                Accel::build(vec![Arc::new(tri)], vec![Object::Mesh { mesh: 0, transform: I }])
                    .expect("builds");
            assert!(shot.scene.accel.packets_pay());
            shot.scene.object_materials = vec![0];
            shot.scene.materials = vec![flat(Vec3::ONE)];
        }
        shot.scene.background = colour;
        let img = render(&shot, 1 << 18, 0);
        for i in 0..2 {
            let got = px(&img, i, 0);
            assert!(((got - colour) / colour).abs().max_element() < 1e-6, "mesh {mesh}: {got}");
        }
    }
}
