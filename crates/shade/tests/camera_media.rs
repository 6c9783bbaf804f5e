//! Camera rays start in the dielectric solids that hold their origins: a
//! camera inside absorbing glass sees through it, whatever the projection.

mod common;
use common::*;
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Cuboid, Shape, Sphere, Transform, TriangleMesh};
use prism_shade::{Camera, Image, Material, Projection, RenderHooks, RenderSettings, RenderStats, Scene};
use std::sync::Arc;

const I: Transform = Transform::IDENTITY;
const ABSORPTION: Vec3 = Vec3::new(0.1, 0.3, 0.0);

fn sphere(c: Vec3, r: f32) -> Shape {
    Sphere::new(c, r).expect("valid sphere").into()
}

fn cuboid(min: Vec3, max: Vec3) -> Shape {
    Cuboid::new(min, max).expect("valid cuboid").into()
}

/// Absorbing glass of index `ior`.
fn green_glass(ior: f32) -> Material {
    Material { absorption: ABSORPTION, ..glass(ior) }
}

/// Beer–Lambert through `length` of [`green_glass`].
fn through(length: f32) -> Vec3 {
    (-ABSORPTION * length).exp()
}

/// A 1×1 view from `eye` to `at` of a white ball of radius 0.5 at `at`
/// inside a ball of absorbing glass (index 1.5, radius 10, centred at the
/// origin), with `more` objects too, traced to depth `depth`: the pixel
/// and the distance from the eye to the white ball.
fn white_ball_in_glass(
    eye: Vec3,
    at: Vec3,
    more: Vec<(Shape, Transform, Material)>,
    depth: u32,
) -> (Vec3, f32) {
    let mut objects =
        vec![(sphere(Vec3::ZERO, 10.0), I, green_glass(1.5)), (sphere(at, 0.5), I, flat(Vec3::ONE))];
    objects.extend(more);
    let s = scene(objects, vec![], camera(eye, at, Vec3::Y, 1.0, 1, 1));
    (px(&render(&s, 1, depth), 0, 0), (at - eye).length() - 0.5)
}

const EYE: Vec3 = Vec3::new(1.0, 0.5, 2.0);
const BALL: Vec3 = Vec3::new(-3.0, 1.0, -4.0);

#[test]
fn a_camera_inside_absorbing_glass_sees_an_object_in_it_through_the_glass() {
    let (got, d) = white_ball_in_glass(EYE, BALL, vec![], 4);
    assert!(d > 6.5);
    assert_close(got, through(d), 1e-5);
}

#[test]
fn a_camera_in_a_clear_bubble_in_the_glass_is_absorbed_only_past_the_bubble() {
    // An air bubble of radius 1 about the eye: the view ray leaves it at
    // normal incidence (no bending; Fresnel from air into glass, 1 → 1.5),
    // then crosses d − 1 of glass. At depth 1 the reflected part ends on
    // the bubble's far side, black.
    let bubble = (sphere(EYE, 1.0), I, glass(1.0));
    let (got, d) = white_ball_in_glass(EYE, BALL, vec![bubble], 1);
    let f = prism_shade::optics::fresnel(1.0, 1.0, 1.5);
    assert!(f > 0.03);
    assert_close(got, (1.0 - f) * through(d - 1.0), 1e-5);
}

#[test]
fn a_camera_outside_the_glass_but_in_its_box_sees_no_absorption() {
    // The eye at (8, 8, 0) is in the glass ball's bounding box but 11.3
    // from its centre; the view along +Z stays outside the ball.
    let (got, _) = white_ball_in_glass(Vec3::new(8.0, 8.0, 0.0), Vec3::new(8.0, 8.0, 5.0), vec![], 4);
    assert_eq!(got, Vec3::ONE);
    // And far from it.
    let (got, _) = white_ball_in_glass(Vec3::new(30.0, 0.0, 0.0), Vec3::new(30.0, 0.0, 6.0), vec![], 4);
    assert_eq!(got, Vec3::ONE);
}

/// Absorbing glass of index 1 (no bending, no reflection) filling x < 0
/// (`[-10, 0] × [-10, 10]²`), and a white wall at z = −3 across both
/// halves, seen by `cam`.
fn half_space_of_glass(cam: Camera) -> Image {
    let s = scene(
        vec![
            (cuboid(Vec3::splat(-10.0), Vec3::new(0.0, 10.0, 10.0)), I, green_glass(1.0)),
            (cuboid(Vec3::new(-20.0, -20.0, -4.0), Vec3::new(20.0, 20.0, -3.0)), I, flat(Vec3::ONE)),
        ],
        vec![],
        cam,
    );
    render(&s, 1, 4)
}

#[test]
fn an_orthographic_view_straddling_the_glass_absorbs_the_rays_that_start_in_it() {
    // Parallel rays along −Z from the plane z = 5: those from x < 0 cross
    // 8 of glass to the wall, those from x > 0 none (they run beside its
    // face x = 0).
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 4)
        .with_projection(Projection::Orthographic);
    let img = half_space_of_glass(cam);
    for j in 0..4 {
        for i in 0..8 {
            let o = cam.ray(i as f32 + 0.5, j as f32 + 0.5).origin;
            let want = if o.x < 0.0 { through(8.0) } else { Vec3::ONE };
            assert_close(px(&img, i, j), want, 1e-5);
        }
    }
}

#[test]
fn an_orthographic_view_starting_in_coloured_glass_sees_out_tinted_once() {
    // Glass of colour c and index 1 filling x < 0, z > 0 (the camera's
    // plane z = 5 is in it for x < 0), and a white wall at z = −3 outside
    // it: rays from x < 0 leave the glass at z = 0, tinted there once
    // (index 1: no Fresnel loss); those from x > 0 never meet it.
    let c = Vec3::new(0.2, 0.6, 1.0);
    let tinted = Material { texture: prism_shade::Texture::Solid(c), ..glass(1.0) };
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 4)
        .with_projection(Projection::Orthographic);
    let s = scene(
        vec![
            (cuboid(Vec3::new(-10.0, -10.0, 0.0), Vec3::new(0.0, 10.0, 10.0)), I, tinted),
            (cuboid(Vec3::new(-20.0, -20.0, -4.0), Vec3::new(20.0, 20.0, -3.0)), I, flat(Vec3::ONE)),
        ],
        vec![],
        cam,
    );
    let img = render(&s, 1, 4);
    for j in 0..4 {
        for i in 0..8 {
            let o = cam.ray(i as f32 + 0.5, j as f32 + 0.5).origin;
            let want = if o.x < 0.0 { c } else { Vec3::ONE };
            assert_close(px(&img, i, j), want, 1e-5);
        }
    }
}

#[test]
fn a_thin_lens_straddling_the_glass_absorbs_each_ray_over_its_stretch_inside() {
    // The lens (radius 1) centred on the glass's face x = 0, focused on
    // the wall: a ray is absorbed over the part of its way to the wall
    // that lies at x < 0, from its start for one that starts in the glass.
    let (w, h) = (12u32, 8u32);
    let cam = camera(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 30.0, w, h)
        .with_lens(1.0, 8.0)
        .expect("valid lens");
    let img = half_space_of_glass(cam);
    let (mut inside, mut outside) = (0, 0);
    for j in 0..h {
        for i in 0..w {
            let r = cam.ray(i as f32 + 0.5, j as f32 + 0.5);
            let (o, d) = (r.origin, r.dir);
            let wall = (o.z + 3.0) / -d.z;
            // The stretch of [0, wall] with o.x + t·d.x < 0.
            let cross = if d.x != 0.0 { (-o.x / d.x).clamp(0.0, wall) } else { wall };
            let in_glass = match (o.x < 0.0, d.x > 0.0) {
                (true, true) => cross,
                (true, false) => wall,
                (false, false) => wall - cross,
                (false, true) => 0.0,
            };
            if o.x < 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
            assert_close(px(&img, i, j), through(in_glass), 1e-4);
        }
    }
    assert!(inside > 10 && outside > 10, "{inside} rays start in the glass, {outside} outside");
}

/// A closed octahedron `|x| + |y| + |z| ≤ 1` (outward faces).
fn octahedron() -> TriangleMesh {
    let corners = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z];
    let faces = vec![[0, 1, 2], [1, 3, 2], [3, 4, 2], [4, 0, 2], [1, 0, 5], [3, 1, 5], [4, 3, 5], [0, 4, 5]];
    TriangleMesh::new(corners, None, None, faces).expect("valid mesh")
}

/// The quad `[-3, 3]² × {z}` facing +Z.
fn quad(z: f32) -> TriangleMesh {
    let p = vec![
        Vec3::new(-3.0, -3.0, z),
        Vec3::new(3.0, -3.0, z),
        Vec3::new(3.0, 3.0, z),
        Vec3::new(-3.0, 3.0, z),
    ];
    TriangleMesh::new(p, None, None, vec![[0, 1, 2], [0, 2, 3]]).expect("valid mesh")
}

#[test]
fn camera_packets_inside_a_glass_mesh_are_absorbed_as_single_rays_are() {
    // An absorbing octahedron of glass 10 across holds the eye and a flat
    // white quad at z = −2: meshes, so camera rays go in packets.
    let gem = octahedron();
    assert!(gem.is_closed());
    let scale = Transform::scale(Vec3::splat(10.0)).expect("valid scale");
    let scene = Scene {
        accel: Accel::build(
            vec![Arc::new(gem), Arc::new(quad(-2.0))],
            vec![Object::Mesh { mesh: 0, transform: scale }, Object::Mesh { mesh: 1, transform: I }],
        )
        .expect("builds"),
        object_materials: vec![0, 1],
        materials: vec![green_glass(1.0), flat(Vec3::ONE)],
        lights: vec![],
        ambient: Vec3::ONE,
        background: Vec3::ZERO,
        environment: None,
        fog: None,
    };
    let eye = Vec3::new(0.1, 0.2, 3.0);
    let cam = camera(eye, Vec3::new(0.1, 0.2, -2.0), Vec3::Y, 30.0, 8, 8);
    let settings = RenderSettings {
        camera: cam,
        fog: false,
        spp: 1,
        max_depth: 4,
        min_contribution: 0.0,
        threads: Some(1),
        antialias: prism_shade::Antialias::default(),
    };
    let (img, stats): (Image, RenderStats) = prism_shade::render(&scene, &settings, RenderHooks::default());
    assert!(stats.packet_rays >= 64, "{} rays in packets", stats.packet_rays);
    for j in 0..8 {
        for i in 0..8 {
            let d = cam.ray(i as f32 + 0.5, j as f32 + 0.5).dir;
            assert_close(px(&img, i, j), through(5.0 / -d.z), 1e-5);
        }
    }
}
