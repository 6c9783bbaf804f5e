//! Anti-aliasing end to end: footprint-filtered textures (the checker
//! floor to the horizon, image mip-maps on a sphere and a mesh), pixel
//! filters, adaptive supersampling, determinism across thread counts, and
//! the image-quality aim (few samples close to many) at a small size.

mod common;

use common::*;
use prism_bvh::{Accel, Object};
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{Plane, Sphere, Transform, TriangleMesh};
use prism_shade::{Antialias, Image, Mapping, PixelFilter, RenderHooks, RenderSettings, Scene, Texture};
use std::sync::Arc;

const A: Vec3 = Vec3::new(0.9, 0.9, 0.9);
const B: Vec3 = Vec3::new(0.1, 0.1, 0.1);

/// A flat-lit world checker floor (squares of 1) to the horizon, seen from
/// 1.5 above at a small angle, `w × h` pixels.
fn floor(w: u32, h: u32) -> Shot {
    let checker = Texture::Checker { a: A, b: B, size: 1.0, world: true };
    let plane = Plane::new(Vec3::ZERO, Vec3::Y).expect("valid").into();
    let cam = camera(Vec3::new(0.3, 1.5, 0.0), Vec3::new(0.3, 0.9, -10.0), Vec3::Y, 40.0, w, h);
    scene(vec![(plane, Transform::IDENTITY, flat_texture(checker))], vec![], cam)
}

fn settings(shot: &Shot, spp: u32, antialias: Antialias, threads: usize) -> RenderSettings {
    RenderSettings { antialias, threads: Some(threads), ..shot.settings(spp, 4) }
}

fn filtered() -> Antialias {
    Antialias::default()
}

fn point() -> Antialias {
    Antialias { point_textures: true, ..Antialias::default() }
}

fn render_with(shot: &Shot, s: &RenderSettings) -> Image {
    prism_shade::render(shot, s, RenderHooks::default()).0
}

/// RMSE over every channel of two images.
fn rmse(a: &Image, b: &Image) -> f32 {
    let sum: f32 = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x - *y).length_squared()).sum();
    (sum / (3 * a.pixels.len()) as f32).sqrt()
}

#[test]
fn far_floor_filters_to_the_mean_and_near_floor_matches_point_sampling() {
    let shot = floor(64, 48);
    let f = render_with(&shot, &settings(&shot, 1, filtered(), 1));
    let p = render_with(&shot, &settings(&shot, 1, point(), 1));
    let mean = (A + B) * 0.5;
    // Just below the horizon (row 18 of 48 looks ~120 units away), a pixel
    // spans several squares: the filtered floor is close to the mean, the
    // point-sampled one is one of the two colours.
    let horizon_row = (0..48).find(|&j| px(&f, 0, j) != Vec3::ZERO).expect("the floor is in view");
    let far = horizon_row + 1;
    for i in 0..64 {
        assert!((px(&f, i, far) - mean).abs().max_element() < 0.15, "far pixel {i}: {}", px(&f, i, far));
        let pt = px(&p, i, far);
        assert!(pt == A || pt == B, "point sample {pt}");
    }
    // The bottom row is ~2 units away: a pixel is a few hundredths of a
    // square, so wherever the point sample's neighbourhood is one colour,
    // filtering changes nothing.
    let mut same = 0;
    for i in 1..63 {
        let (l, c, r) = (px(&p, i - 1, 47), px(&p, i, 47), px(&p, i + 1, 47));
        if l == c && c == r {
            assert_eq!(px(&f, i, 47), c, "near pixel {i}");
            same += 1;
        }
    }
    assert!(same > 40, "{same}");
}

#[test]
fn few_samples_come_close_to_many_with_filtered_textures() {
    // The measure at a small size: 4 spp against 256 spp of the
    // same settings. Point-sampled, the far floor is noise; filtered, the
    // error falls by more than half and below an absolute bound.
    let shot = floor(64, 36);
    let err = |aa: Antialias| {
        let few = render_with(&shot, &settings(&shot, 4, aa, 2));
        let many = render_with(&shot, &settings(&shot, 256, aa, 2));
        rmse(&few, &many)
    };
    let (e_point, e_filtered) = (err(point()), err(filtered()));
    assert!(e_filtered < 0.5 * e_point, "filtered {e_filtered} vs point {e_point}");
    assert!(e_filtered < 0.03, "filtered {e_filtered}");
}

#[test]
fn renders_are_identical_on_any_number_of_threads_with_every_filter_and_adaptive() {
    let shot = floor(37, 23);
    for filter in PixelFilter::ALL {
        for adaptive in [None, Some(0.05)] {
            let aa = Antialias { filter, adaptive, point_textures: false };
            let one = render_with(&shot, &settings(&shot, 9, aa, 1));
            let three = render_with(&shot, &settings(&shot, 9, aa, 3));
            assert_eq!(one, three, "{filter} adaptive {adaptive:?}");
        }
    }
}

#[test]
fn adaptive_regions_are_bit_identical_to_the_full_render() {
    // A region's edge pixels compare with neighbours outside it (a farm
    // tile's), as they do in the full image.
    use prism_shade::{PixelBounds, render_region};
    let (w, h) = (37, 23);
    let shot = floor(w, h);
    let aa = Antialias { adaptive: Some(0.05), ..Antialias::default() };
    let full = render_with(&shot, &settings(&shot, 9, aa, 2));
    let mut rng = prism_testkit::rng::Rng::new(7);
    let mut regions: Vec<_> = (0..16)
        .map(|_| {
            let (xa, xb) = (rng.below(w as usize) as u32, rng.below(w as usize) as u32);
            let (ya, yb) = (rng.below(h as usize) as u32, rng.below(h as usize) as u32);
            PixelBounds::new(xa.min(xb), xa.max(xb) + 1, ya.min(yb), ya.max(yb) + 1).unwrap()
        })
        .collect();
    // Rows of tiles as a farm splits them, and the image's own corners.
    regions.extend((0..4).map(|k| PixelBounds::new(0, w, k * h / 4, (k + 1) * h / 4).unwrap()));
    regions.push(PixelBounds::new(0, 1, 0, 1).unwrap());
    regions.push(PixelBounds::new(w - 1, w, h - 1, h).unwrap());
    for (k, b) in regions.into_iter().enumerate() {
        let set = settings(&shot, 9, aa, 1 + k % 3);
        let (img, _, _) = render_region(&shot, &set, b, &[], RenderHooks::default()).unwrap();
        for y in 0..b.height() {
            for x in 0..b.width() {
                let (i, j) = (b.x0() + x, b.y0() + y);
                let mean = img.pixels[(y * b.width() + x) as usize];
                let want = full.pixels[(j * w + i) as usize];
                assert_eq!(
                    mean.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{b} at ({i}, {j})"
                );
            }
        }
    }
}

/// Looking down at a checker floor of squares of 4 from above: every
/// pixel sees the floor, and pixels on square edges see two colours.
fn floor_from_above(w: u32, h: u32) -> Shot {
    let checker = Texture::Checker { a: A, b: B, size: 4.0, world: true };
    let plane = Plane::new(Vec3::ZERO, Vec3::Y).expect("valid").into();
    let cam = camera(Vec3::new(0.37, 5.0, 0.21), Vec3::new(0.37, 0.0, 0.2), Vec3::Y, 60.0, w, h);
    scene(vec![(plane, Transform::IDENTITY, flat_texture(checker))], vec![], cam)
}

#[test]
fn an_adaptive_render_cancelled_keeps_finished_rows_and_blacks_the_rest() {
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let (w, h) = (24, 24);
    let shot = floor_from_above(w, h);
    let set = settings(&shot, 9, Antialias { adaptive: Some(0.1), ..Antialias::default() }, 1);
    let full = render_with(&shot, &set);
    let rows = |img: &Image| img.pixels.chunks(w as usize).map(<[Vec3]>::to_vec).collect::<Vec<_>>();
    assert!(rows(&full).iter().all(|r| r.iter().all(|p| p.min_element() > 0.0)));
    // Progress counts the base pass's rows, then the refine pass's; one
    // thread renders them in turn, so a cancel at `done` stops the rest.
    for refined in [0, 5, h - 1] {
        let cancel = AtomicBool::new(false);
        let progress = |done: u32, all: u32| {
            assert_eq!(all, 2 * h);
            if done == h + refined {
                cancel.store(true, Relaxed);
            }
        };
        let hooks = RenderHooks { progress: Some(&progress), cancel: Some(&cancel) };
        let (img, stats) = prism_shade::render(&shot, &set, hooks);
        assert!(stats.cancelled);
        let mut kept = 0;
        for (j, (row, whole)) in rows(&img).iter().zip(rows(&full)).enumerate() {
            if *row == whole {
                kept += 1;
            } else {
                // Not the base pass's dim sums: a row not refined is black.
                assert!(row.iter().all(|p| *p == Vec3::ZERO), "{refined} refined, row {j}: {row:?}");
            }
        }
        assert_eq!(kept, refined, "rows finished before the cancel");
    }
}

#[test]
fn adaptive_sampling_refines_only_where_samples_disagree() {
    // Looking down at the floor from above: squares of 4 under a camera
    // that sees ~6 units across 24 pixels; only pixels on square edges
    // see two colours (and they and their neighbours are refined).
    let shot = floor_from_above(24, 24);
    let spp = 16;
    let aa = Antialias { adaptive: Some(0.1), point_textures: true, ..Antialias::default() };
    let (adaptive, stats) = prism_shade::render(&shot, &settings(&shot, spp, aa, 2), RenderHooks::default());
    let full_set = settings(&shot, spp, Antialias { adaptive: None, ..aa }, 2);
    let (full, full_stats) = prism_shade::render(&shot, &full_set, RenderHooks::default());
    // No lights: one ray per sample.
    assert_eq!(full_stats.rays, 24 * 24 * u64::from(spp));
    assert!(stats.rays < full_stats.rays / 2, "{} of {}", stats.rays, full_stats.rays);
    let mut refined = 0;
    for (k, (a, f)) in adaptive.pixels.iter().zip(&full.pixels).enumerate() {
        let uniform = *f == A || *f == B;
        if uniform {
            // Every sample agreed: the base samples' mean is the colour.
            assert!((*a - *f).abs().max_element() < 1e-6, "pixel {k}: {a} vs {f}");
        } else if (*a - *f).abs().max_element() < 1e-6 {
            // A refined pixel took every sample: the same sum.
            refined += 1;
        }
    }
    assert!(refined > 0);
    // Threshold 0 refines every pixel that is not exactly flat (its own
    // samples or a neighbour's mean differ), so every mixed pixel takes all
    // its samples and equals the full render; flat ones keep their base.
    let zero = Antialias { adaptive: Some(0.0), ..aa };
    let (exact, exact_stats) =
        prism_shade::render(&shot, &settings(&shot, spp, zero, 2), RenderHooks::default());
    let mut mixed = 0;
    for (k, (a, f)) in exact.pixels.iter().zip(&full.pixels).enumerate() {
        mixed += usize::from(*f != A && *f != B);
        assert!((*a - *f).abs().max_element() < 1e-6, "threshold 0, pixel {k}: {a} vs {f}");
    }
    assert!(mixed > 10 && refined <= mixed, "{mixed} mixed pixels, {refined} refined at 0.1");
    assert!(
        exact_stats.rays >= stats.rays && exact_stats.rays < full_stats.rays,
        "{} {}",
        exact_stats.rays,
        stats.rays
    );
    // A huge threshold refines none.
    let none = Antialias { adaptive: Some(10.0), ..aa };
    let (_, few) = prism_shade::render(&shot, &settings(&shot, spp, none, 2), RenderHooks::default());
    assert_eq!(few.rays, 24 * 24 * u64::from(prism_shade::ADAPTIVE_BASE_SAMPLES));
}

#[test]
fn gaussian_filter_blurs_an_edge_over_more_pixels_than_the_box() {
    // A vertical edge between two half-planes at a pixel boundary: the box
    // keeps it within one pixel on each side, the Gaussian spreads it.
    let checker = Texture::Checker { a: A, b: B, size: 100.0, world: true };
    let plane = Plane::new(Vec3::ZERO, Vec3::Y).expect("valid").into();
    // Looking straight down at x = 0 (a checker edge), 16 px across 2 units.
    let cam = camera(Vec3::new(0.0, 1.0, -50.0), Vec3::new(0.0, 0.0, -50.0), Vec3::Z, 90.0, 16, 4);
    let shot = scene(vec![(plane, Transform::IDENTITY, flat_texture(checker))], vec![], cam);
    let row = |filter| {
        let aa = Antialias { filter, adaptive: None, point_textures: true };
        let img = render_with(&shot, &settings(&shot, 64, aa, 1));
        (0..16).map(|i| px(&img, i, 2).x).collect::<Vec<_>>()
    };
    let mixed = |r: &[f32]| r.iter().filter(|v| (**v - A.x).abs() > 1e-3 && (**v - B.x).abs() > 1e-3).count();
    let (b, g) = (row(PixelFilter::Box), row(PixelFilter::Gaussian));
    assert_eq!(mixed(&b), 0, "{b:?}");
    assert!(mixed(&g) >= 2, "{g:?}");
    // Symmetric about the edge: the mean stays the mean of the colours.
    assert!(((g[7] + g[8]) * 0.5 - (A.x + B.x) * 0.5).abs() < 0.02, "{g:?}");
}

#[test]
fn image_textures_use_coarser_mip_levels_far_away() {
    // A 2-texel-period stripe texture on a plane (planar mapping, 8 repeats
    // per unit): far away, the filtered colour is the stripe mean.
    let texels = (0..64 * 64).map(|k| if (k % 64) % 2 == 0 { Vec3::ONE } else { Vec3::ZERO }).collect();
    let image =
        prism_shade::ImageTexture::from_linear(64, 64, texels, prism_shade::Wrap::Repeat).expect("ok");
    assert_eq!(image.levels(), 7);
    let tex = |point_textures: bool| {
        let t = Texture::Image {
            image: Arc::new(image.clone()),
            mapping: Mapping::Planar,
            scale: Vec2::splat(0.125),
            offset: Vec2::ZERO,
            tint: Vec3::ONE,
        };
        let plane = Plane::new(Vec3::ZERO, Vec3::Y).expect("valid").into();
        let cam = camera(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, -20.0), Vec3::Y, 30.0, 32, 32);
        let shot = scene(vec![(plane, Transform::IDENTITY, flat_texture(t))], vec![], cam);
        let aa = Antialias { point_textures, ..Antialias::default() };
        render_with(&shot, &settings(&shot, 1, aa, 1))
    };
    let (f, p) = (tex(false), tex(true));
    let far = (0..32).find(|&j| px(&f, 16, j) != Vec3::ZERO).expect("floor in view") + 1;
    let spread = |img: &Image| {
        let v: Vec<f32> = (0..32).map(|i| px(img, i, far).x).collect();
        v.iter().copied().fold(f32::MIN, f32::max) - v.iter().copied().fold(f32::MAX, f32::min)
    };
    assert!(spread(&p) > 0.5, "point-sampled far row should alias");
    assert!(spread(&f) < 0.05, "filtered far row {}", spread(&f));
    assert!((px(&f, 16, far).x - 0.5).abs() < 0.05);
}

/// The uv footprint of a mesh comes from its triangle's uvs: a textured
/// quad far away reads as its texture's mean, near as its texels.
#[test]
fn mesh_uv_footprint_selects_the_mip_level() {
    let texels = (0..32 * 32)
        .map(|k| if ((k % 32) / 2 + (k / 32) / 2) % 2 == 0 { Vec3::ONE } else { Vec3::ZERO })
        .collect();
    let image = Arc::new(
        prism_shade::ImageTexture::from_linear(32, 32, texels, prism_shade::Wrap::Repeat).expect("ok"),
    );
    let quad = TriangleMesh::new(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        None,
        Some(vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)]),
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .expect("valid mesh");
    let render_at = |z: f32, point_textures: bool| {
        let t = Texture::Image {
            image: image.clone(),
            mapping: Mapping::Uv,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
            tint: Vec3::ONE,
        };
        let scene = Scene {
            accel: Accel::build(
                vec![Arc::new(quad.clone())],
                vec![Object::Mesh {
                    mesh: 0,
                    transform: Transform::translate(Vec3::new(0.0, 0.0, z)).expect("ok"),
                }],
            )
            .expect("builds"),
            object_materials: vec![0],
            materials: vec![flat_texture(t)],
            lights: vec![],
            ambient: Vec3::ONE,
            background: Vec3::ZERO,
            environment: None,
            fog: None,
        };
        let cam = camera(Vec3::new(0.13, 0.07, 5.0), Vec3::new(0.13, 0.07, 0.0), Vec3::Y, 20.0, 16, 16);
        let s = RenderSettings {
            camera: cam,
            fog: false,
            spp: 1,
            max_depth: 0,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: Antialias { point_textures, ..Antialias::default() },
        };
        prism_shade::render(&scene, &s, RenderHooks::default()).0
    };
    // At z = −40 a pixel spans about half the quad (16 texels): the mean.
    let (far, pt) = (render_at(-40.0, false), render_at(-40.0, true));
    let on_quad: Vec<(u32, u32)> = (6..10)
        .flat_map(|j| (6..10).map(move |i| (i, j)))
        .filter(|&(i, j)| px(&far, i, j) != Vec3::ZERO)
        .collect();
    assert!(on_quad.len() >= 4, "{on_quad:?}");
    for &(i, j) in &on_quad {
        assert!((px(&far, i, j).x - 0.5).abs() < 0.05, "({i}, {j}): {}", px(&far, i, j));
    }
    // Near (z = 3.5, a pixel about a third of a texel), the footprint is
    // under a texel: level 0, the same as point sampling.
    assert_eq!(render_at(3.5, false), render_at(3.5, true));
    assert_ne!(far, pt);
}

#[test]
fn sphere_uv_footprint_comes_from_the_shape() {
    // A sphere far away with a fine uv checker: filtered it is the mean colour.
    let checker = Texture::Checker { a: Vec3::ONE, b: Vec3::ZERO, size: 1.0 / 64.0, world: false };
    let shape = Sphere::new(Vec3::ZERO, 1.0).expect("valid").into();
    let render_it = |point_textures: bool| {
        let cam = camera(Vec3::new(0.0, 0.0, 40.0), Vec3::ZERO, Vec3::Y, 3.0, 9, 9);
        let shot = scene(vec![(shape, Transform::IDENTITY, flat_texture(checker.clone()))], vec![], cam);
        let aa = Antialias { point_textures, ..Antialias::default() };
        render_with(&shot, &settings(&shot, 1, aa, 1))
    };
    let f = render_it(false);
    let c = px(&f, 4, 4);
    assert!((c.x - 0.5).abs() < 0.1, "{c}");
    let p = px(&render_it(true), 4, 4);
    assert!(p == Vec3::ONE || p == Vec3::ZERO);
}
