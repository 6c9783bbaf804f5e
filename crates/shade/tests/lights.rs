//! Light kinds against closed-form answers: inverse-square fall-off, a
//! spot's cone edge, a sun's shadow direction, the irradiance under disk,
//! sphere and quad area lights; area lights seen by camera and mirror
//! rays; determinism across threads; adaptive sampling; the environment
//! image; emission.

mod common;
use common::*;
use prism_geometry::glam::Vec3;
use prism_geometry::{Plane, Sphere, Transform};
use prism_shade::{
    AreaLight, AreaShape, Environment, Falloff, ImageTexture, Light, LightKind, Material, RenderHooks, Wrap,
    spot_weight,
};
use std::f32::consts::PI;
use std::sync::Arc;

const I: Transform = Transform::IDENTITY;

/// Pure Lambert, albedo 1, no ambient: the radiance is the irradiance E.
fn lambert() -> Material {
    Material { ambient: 0.0, diffuse: 1.0, specular: 0.0, ..Material::diffuse(Vec3::ONE) }
}

fn floor() -> (prism_geometry::Shape, Transform, Material) {
    (Plane::new(Vec3::ZERO, Vec3::Y).expect("ok").into(), I, lambert())
}

/// The radiance seen at the floor point `p` (camera straight above it, one
/// pixel, its centre ray hits `p`).
fn seen_at(objects: Vec<(prism_geometry::Shape, Transform, Material)>, lights: Vec<Light>, p: Vec3) -> Vec3 {
    let cam = camera(p + Vec3::new(0.0, 0.5, 0.0), p, Vec3::Z, 1.0, 1, 1);
    let s = scene_lit(objects, lights, cam);
    px(&render(&s, 1, 0), 0, 0)
}

fn point(position: Vec3, falloff: Falloff, intensity: f32) -> Light {
    Light { kind: LightKind::Point { position, falloff }, color: Vec3::ONE, intensity }
}

fn area(shape: AreaShape, samples: u32, radiance: f32) -> Light {
    Light {
        kind: LightKind::Area(AreaLight { shape, samples, two_sided: false, adaptive: false }),
        color: Vec3::ONE,
        intensity: radiance,
    }
}

fn rel(got: f32, want: f32) -> f32 {
    (got - want).abs() / want.abs()
}

#[test]
fn inverse_square_point_light() {
    let l = Vec3::new(0.0, 3.0, 0.0);
    for x in [0.0f32, 1.0, 2.5, 4.0] {
        let p = Vec3::new(x, 0.0, 0.0);
        let r2 = (l - p).length_squared();
        let cos = 3.0 / r2.sqrt();
        let got = seen_at(vec![floor()], vec![point(l, Falloff::InverseSquare, 10.0)], p).x;
        assert!(rel(got, 10.0 * cos / r2) < 1e-5, "x {x}: {got} vs {}", 10.0 * cos / r2);
        // Without fall-off: the report's light, intensity · cos θ.
        let none = seen_at(vec![floor()], vec![point(l, Falloff::None, 10.0)], p).x;
        assert!(rel(none, 10.0 * cos) < 1e-5);
    }
}

#[test]
fn spot_light_cone_edge() {
    // A spot 4 above the floor pointing down, inner 20°, outer 30°.
    let (inner, outer) = (20f32.to_radians(), 30f32.to_radians());
    let spot = Light {
        kind: LightKind::Spot {
            position: Vec3::new(0.0, 4.0, 0.0),
            direction: Vec3::NEG_Y,
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
            falloff: Falloff::None,
        },
        color: Vec3::ONE,
        intensity: 1.0,
    };
    for deg in [0.0f32, 10.0, 19.9, 20.1, 25.0, 29.9, 30.1, 40.0] {
        let a = deg.to_radians();
        let p = Vec3::new(4.0 * a.tan(), 0.0, 0.0);
        let got = seen_at(vec![floor()], vec![spot], p).x;
        let w = if deg < 20.0 {
            1.0
        } else if deg > 30.0 {
            0.0
        } else {
            let x = (a.cos() - outer.cos()) / (inner.cos() - outer.cos());
            x * x * (3.0 - 2.0 * x)
        };
        let want = w * a.cos();
        assert!((got - want).abs() < 1e-4, "{deg}°: {got} vs {want}");
        if deg > 30.0 {
            assert_eq!(got, 0.0, "outside the outer cone");
        }
    }
    assert_eq!(spot_weight(0.5, 0.9, 0.9), 0.0);
    assert_eq!(spot_weight(0.95, 0.9, 0.9), 1.0);
}

#[test]
fn directional_shadow_falls_along_the_light() {
    // Sun travelling down and toward +X at 45°; a ball of radius 0.5 at
    // height 2 over the origin casts its shadow centre at x = +2.
    let dir = Vec3::new(1.0, -1.0, 0.0).normalize();
    let sun = Light { kind: LightKind::Directional { direction: dir }, color: Vec3::ONE, intensity: 1.0 };
    let ball = (Sphere::new(Vec3::new(0.0, 2.0, 0.0), 0.5).expect("ok").into(), I, lambert());
    let lit = (45f32).to_radians().cos();
    let at = |x: f32| seen_at(vec![floor(), ball.clone()], vec![sun], Vec3::new(x, 0.0, 0.0)).x;
    assert_eq!(at(2.0), 0.0, "shadow centre");
    assert_eq!(at(2.5), 0.0, "inside the shadow ellipse (half-width 0.5·√2)");
    assert!(rel(at(0.0), lit) < 1e-5, "under the ball, but the light comes slanting");
    assert!(rel(at(-2.0), lit) < 1e-5);
    assert!(rel(at(3.5), lit) < 1e-5, "past the shadow");
}

#[test]
fn disk_sphere_and_quad_lights_give_the_closed_form_irradiance() {
    let p = Vec3::ZERO;
    let h = 2.0f32;
    // Disk of radius R at height h facing down: E = π L R² / (h² + R²).
    let disk =
        area(AreaShape::Disk { center: Vec3::new(0.0, h, 0.0), normal: Vec3::NEG_Y, radius: 1.5 }, 256, 1.0);
    let got = seen_at(vec![floor()], vec![disk], p).x;
    let want = PI * 1.5 * 1.5 / (h * h + 1.5 * 1.5);
    assert!(rel(got, want) < 0.01, "disk {got} vs {want}");
    // Sphere of radius R at distance d straight up: E = π L (R / d)².
    let sphere = area(AreaShape::Sphere { center: Vec3::new(0.0, 3.0, 0.0), radius: 1.0 }, 256, 1.0);
    let got = seen_at(vec![floor()], vec![sphere], p).x;
    let want = PI / 9.0;
    assert!(rel(got, want) < 0.01, "sphere {got} vs {want}");
    // A 2a × 2b rectangle centred over p at height h, facing down: four
    // corner rectangles, E_corner = L/2 · [a/√(a²+h²) atan(b/√(a²+h²)) + b/√(b²+h²) atan(a/√(b²+h²))].
    let (a, b) = (1.0f32, 1.5f32);
    let quad = area(
        AreaShape::Quad {
            corner: Vec3::new(-a, h, -b),
            edge_u: Vec3::new(2.0 * a, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0 * b),
        },
        256,
        1.0,
    );
    let (sa, sb) = ((a * a + h * h).sqrt(), (b * b + h * h).sqrt());
    let want = 4.0 * 0.5 * (a / sa * (b / sa).atan() + b / sb * (a / sb).atan());
    let got = seen_at(vec![floor()], vec![quad], p).x;
    assert!(rel(got, want) < 0.01, "quad {got} vs {want}");
    // Edges the other way round: it emits upward, the floor gets nothing.
    let LightKind::Area(mut back) = quad.kind else { unreachable!() };
    back.shape = AreaShape::Quad {
        corner: Vec3::new(-a, h, -b),
        edge_u: Vec3::new(0.0, 0.0, 2.0 * b),
        edge_v: Vec3::new(2.0 * a, 0.0, 0.0),
    };
    let one_sided = Light { kind: LightKind::Area(back), ..quad };
    assert_eq!(seen_at(vec![floor()], vec![one_sided], p).x, 0.0);
    back.two_sided = true;
    let got = seen_at(vec![floor()], vec![Light { kind: LightKind::Area(back), ..quad }], p).x;
    assert!(rel(got, want) < 0.01, "two-sided {got} vs {want}");
}

fn quad_over_floor(samples: u32, adaptive: bool) -> Light {
    Light {
        kind: LightKind::Area(AreaLight {
            shape: AreaShape::Quad {
                corner: Vec3::new(-1.0, 4.0, -1.0),
                edge_u: Vec3::new(2.0, 0.0, 0.0),
                edge_v: Vec3::new(0.0, 0.0, 2.0),
            },
            samples,
            two_sided: false,
            adaptive,
        }),
        color: Vec3::new(1.0, 0.9, 0.8),
        intensity: 3.0,
    }
}

/// A floor and a ball under a quad light, seen from the side and above.
fn soft_shadow_scene(light: Light, w: u32, h: u32) -> Shot {
    let ball = (Sphere::new(Vec3::new(0.3, 1.0, 0.0), 0.7).expect("ok").into(), I, lambert());
    let cam = camera(Vec3::new(0.0, 6.0, 7.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 60.0, w, h);
    scene_lit(vec![floor(), ball], vec![light], cam)
}

#[test]
fn area_lights_are_the_same_on_any_number_of_threads() {
    let s = soft_shadow_scene(quad_over_floor(16, true), 40, 30);
    let mut settings = s.settings(2, 2);
    let one = prism_shade::render(&s, &settings, RenderHooks::default()).0;
    settings.threads = Some(3);
    let three = prism_shade::render(&s, &settings, RenderHooks::default()).0;
    assert_eq!(one.pixels, three.pixels);
    // A penumbra: some pixels strictly between lit and dark.
    let max = one.pixels.iter().map(|p| p.x).fold(0.0, f32::max);
    assert!(one.pixels.iter().any(|p| p.x > 0.05 * max && p.x < 0.6 * max));
}

#[test]
fn adaptive_sampling_skips_shadow_rays_where_the_probes_agree() {
    let full = soft_shadow_scene(quad_over_floor(16, false), 40, 30);
    let adaptive = soft_shadow_scene(quad_over_floor(16, true), 40, 30);
    let (a, a_stats) = prism_shade::render(&full, &full.settings(1, 0), RenderHooks::default());
    let (b, b_stats) = prism_shade::render(&adaptive, &adaptive.settings(1, 0), RenderHooks::default());
    assert!(b_stats.rays < a_stats.rays / 2, "{} vs {}", b_stats.rays, a_stats.rays);
    // Fully lit and fully hidden points are exact; the penumbra is sampled
    // by every ray, the same ones: every pixel agrees.
    let diff = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x - *y).abs().max_element()).fold(0.0, f32::max);
    assert!(diff < 1e-5, "{diff}");
}

#[test]
fn camera_and_mirror_rays_see_area_lights() {
    let light = quad_over_floor(4, false);
    // Looking straight up at the light's emitting side.
    let cam = camera(Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::Z, 5.0, 1, 1);
    let s = scene_lit(vec![], vec![light], cam);
    assert_close(px(&render(&s, 1, 0), 0, 0), light.radiance(), 1e-6);
    // From above it shows its back: black, and hides what is behind it.
    let cam = camera(Vec3::new(0.0, 8.0, 0.0), Vec3::ZERO, Vec3::Z, 5.0, 1, 1);
    let s = scene_lit(vec![floor()], vec![light], cam);
    assert_eq!(px(&render(&s, 1, 0), 0, 0), Vec3::ZERO);
    // A mirror floor shows it to a camera looking down at the mirror.
    let mirror = Material { reflectivity: 1.0, ..lambert() };
    let mfloor = (Plane::new(Vec3::ZERO, Vec3::Y).expect("ok").into(), I, mirror);
    let cam = camera(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::Z, 5.0, 1, 1);
    let s = scene_lit(vec![mfloor], vec![light], cam);
    assert_close(px(&render(&s, 1, 1), 0, 0), light.radiance(), 1e-6);
}

#[test]
fn an_area_light_inside_absorbing_glass_is_seen_through_the_glass() {
    // The quad light (y = 4) inside a ball of absorbing glass of index 1
    // (radius 10): seen from the centre through 4 of glass, from below
    // (y = −20) through 14, as the light it casts is absorbed.
    let light = quad_over_floor(4, false);
    let absorption = Vec3::new(0.05, 0.1, 0.0);
    let ball = Sphere::new(Vec3::ZERO, 10.0).expect("ok").into();
    let green = Material { absorption, ..glass(1.0) };
    for (eye, inside) in [(Vec3::ZERO, 4.0), (Vec3::new(0.0, -20.0, 0.0), 14.0)] {
        let cam = camera(eye, eye + Vec3::Y, Vec3::Z, 5.0, 1, 1);
        let s = scene_lit(vec![(ball, I, green.clone())], vec![light], cam);
        // To 1e-4: the ray into the glass starts its offset (~2e-4) past
        // the surface.
        let want = light.radiance() * (-absorption * inside).exp();
        assert_close(px(&render(&s, 1, 2), 0, 0) / want, Vec3::ONE, 1e-4);
    }
}

#[test]
fn environment_is_seen_by_missing_camera_and_mirror_rays_but_lights_nothing() {
    let texels = vec![Vec3::new(0.2, 0.4, 0.8); 8];
    let image = Arc::new(ImageTexture::from_linear(4, 2, texels, Wrap::Repeat).expect("ok"));
    let env = Environment { image, rotation_deg: 30.0 };
    let cam = camera(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, -1.0), Vec3::Y, 5.0, 1, 1);
    let mut s = scene_lit(vec![floor()], vec![], cam);
    s.scene.environment = Some(env.clone());
    assert_close(px(&render(&s, 1, 0), 0, 0), Vec3::new(0.2, 0.4, 0.8), 1e-6);
    // A Lambert floor under the sky alone stays black.
    let cam = camera(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::Z, 5.0, 1, 1);
    let mut s = scene_lit(vec![floor()], vec![], cam);
    s.scene.environment = Some(env.clone());
    assert_eq!(px(&render(&s, 1, 2), 0, 0), Vec3::ZERO);
    // A mirror floor shows it.
    let mfloor =
        (Plane::new(Vec3::ZERO, Vec3::Y).expect("ok").into(), I, Material { reflectivity: 1.0, ..lambert() });
    let mut s = scene_lit(vec![mfloor], vec![], cam);
    s.scene.environment = Some(env);
    assert_close(px(&render(&s, 1, 1), 0, 0), Vec3::new(0.2, 0.4, 0.8), 1e-6);
}

#[test]
fn emission_is_seen_and_reflected_but_lights_nothing() {
    let glow = Material { emission: Vec3::new(0.5, 0.25, 0.0), ..lambert() };
    let ball = (Sphere::new(Vec3::new(0.0, 3.0, 0.0), 1.0).expect("ok").into(), I, glow);
    // Looking at the ball: its emission (no lights, no ambient).
    let cam = camera(Vec3::new(0.0, 3.0, 5.0), Vec3::new(0.0, 3.0, 0.0), Vec3::Y, 5.0, 1, 1);
    let s = scene_lit(vec![floor(), ball.clone()], vec![], cam);
    assert_close(px(&render(&s, 1, 0), 0, 0), Vec3::new(0.5, 0.25, 0.0), 1e-6);
    // The floor under it stays black.
    assert_eq!(seen_at(vec![floor(), ball], vec![], Vec3::new(2.0, 0.0, 0.0)), Vec3::ZERO);
}

#[test]
fn invalid_lights_are_refused() {
    let zero_quad =
        area(AreaShape::Quad { corner: Vec3::ZERO, edge_u: Vec3::X, edge_v: Vec3::X * 2.0 }, 4, 1.0);
    assert!(zero_quad.validate().is_err());
    assert!(
        area(AreaShape::Disk { center: Vec3::ZERO, normal: Vec3::Y, radius: 0.0 }, 4, 1.0)
            .validate()
            .is_err()
    );
    let spot = Light {
        kind: LightKind::Spot {
            position: Vec3::ZERO,
            direction: Vec3::Y,
            cos_inner: 0.5,
            cos_outer: 0.9,
            falloff: Falloff::None,
        },
        color: Vec3::ONE,
        intensity: 1.0,
    };
    assert!(spot.validate().is_err(), "outer narrower than inner");
    assert!(point(Vec3::ZERO, Falloff::None, 1.0).validate().is_ok());
}

#[test]
fn an_area_light_seen_against_the_background_covers_its_pixels() {
    // A disk light facing the camera, nothing else: under --alpha its
    // pixels are covered (alpha 1, its radiance), the rest transparent.
    let disk = area(AreaShape::Disk { center: Vec3::ZERO, normal: Vec3::Z, radius: 1.0 }, 4, 2.0);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 9, 9);
    let s = scene_lit(vec![], vec![disk], cam);
    let (rgba, _, _) = prism_shade::render_with_alpha(&s, &s.settings(1, 0), &[], RenderHooks::default());
    let centre = 4 * 9 + 4;
    assert_eq!(rgba.alpha[centre], 1.0);
    assert_eq!(rgba.color.pixels[centre], Vec3::splat(2.0));
    assert_eq!((rgba.alpha[0], rgba.color.pixels[0]), (0.0, Vec3::ZERO), "a corner sees only background");
}

/// A light set flush into a ceiling (a Cornell box's lamp): the ceiling,
/// which holds every sample point, blocks none of its light, and the
/// camera sees the lamp, not the ceiling, where they meet; the same for a
/// point light on a surface.
#[test]
fn a_light_flush_with_a_surface_is_not_blocked_by_it() {
    let h = 3.0f32;
    let quad = area(
        AreaShape::Quad {
            corner: Vec3::new(-1.0, h, -1.0),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0),
        },
        64,
        1.0,
    );
    let ceiling = || (Plane::new(Vec3::new(0.0, h, 0.0), Vec3::NEG_Y).expect("ok").into(), I, lambert());
    let slab = || {
        let b = prism_geometry::Cuboid::new(Vec3::new(-10.0, h, -10.0), Vec3::new(10.0, h + 1.0, 10.0));
        (b.expect("ok").into(), I, lambert())
    };
    for p in [Vec3::ZERO, Vec3::new(0.7, 0.0, -0.4), Vec3::new(2.5, 0.0, 1.0)] {
        let open = seen_at(vec![floor()], vec![quad], p).x;
        assert!(open > 0.01, "{open}");
        for (name, roof) in [("plane", ceiling()), ("cuboid", slab())] {
            let got = seen_at(vec![floor(), roof], vec![quad], p).x;
            assert!(rel(got, open) < 1e-4, "{name} at {p}: {got} vs {open} without it");
        }
        let lamp = point(Vec3::new(0.2, h, 0.1), Falloff::InverseSquare, 5.0);
        let open = seen_at(vec![floor()], vec![lamp], p).x;
        let got = seen_at(vec![floor(), ceiling()], vec![lamp], p).x;
        assert!(rel(got, open) < 1e-5, "point light at {p}: {got} vs {open}");
    }
    // Looking up at the lamp through the room: the lamp, not the ceiling.
    let cam = camera(Vec3::new(0.3, 1.0, 0.2), Vec3::new(0.3, h, 0.2), Vec3::Z, 5.0, 1, 1);
    let s = scene_lit(vec![floor(), ceiling()], vec![quad], cam);
    assert_close(px(&render(&s, 1, 0), 0, 0), quad.radiance(), 1e-6);
}
