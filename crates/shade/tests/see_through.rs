//! The see-through filter where its colour varies: a textured sheet tints
//! the view by the texel it is seen through, and a smooth-shaded glass
//! mesh tints every path through it once, whichever way its shading
//! normal sends the path in.

mod common;
use common::*;
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Instance, Plane, Transform, TriangleMesh};
use prism_shade::{Material, Scene, Texture};
use std::sync::Arc;

const I: Transform = Transform::IDENTITY;

fn wall_plane() -> prism_geometry::Shape {
    Plane::new(Vec3::new(0.0, 0.0, -3.0), Vec3::Z).expect("valid plane").into()
}

/// A sheet with a world checker, 60 % see-through, in front of a flat
/// wall: each square's colour tints what is seen through it, as it tints
/// the sheet's shadow.
#[test]
fn a_textured_sheet_tints_the_view_by_the_texel_seen_through() {
    let (a, b) = (Vec3::new(0.2, 0.9, 0.5), Vec3::new(0.8, 0.1, 0.3));
    let sheet =
        Material { transparency: 0.6, ..flat_texture(Texture::Checker { a, b, size: 1.0, world: true }) };
    let wall = Vec3::new(0.9, 0.8, 0.7);
    let sheet_plane = Plane::new(Vec3::new(0.0, 0.0, 0.5), Vec3::Z).expect("valid plane").into();
    let at = |x: f32| camera(Vec3::new(x, 0.25, 5.0), Vec3::new(x, 0.25, 0.0), Vec3::Y, 0.5, 1, 1);
    let mut s = scene(vec![(sheet_plane, I, sheet), (wall_plane(), I, flat(wall))], vec![], at(0.25));
    // (0.25, 0.25, 0.5) lies in an even square (colour a), (1.25, 0.25,
    // 0.5) in an odd one (b): 0.4 · colour + 0.6 · colour · wall.
    for (x, c) in [(0.25, a), (1.25, b)] {
        s.camera = at(x);
        assert_close(px(&render(&s, 1, 1), 0, 0), 0.4 * c + 0.6 * c * wall, 1e-6);
    }
}

/// The slab `[-10, 10]² × [-0.5, 0.5]` as a closed mesh, each face with
/// its own four corners; the front face's (+Z) shading normals are all
/// `front`, the others the faces' own.
fn slab(front: Vec3) -> TriangleMesh {
    let (x, y, z) = (Vec3::X * 10.0, Vec3::Y * 10.0, Vec3::Z * 0.5);
    // (centre, u, v) with u × v the outward normal.
    let faces = [(z, x, y), (-z, y, x), (x, y, z), (-x, z, y), (y, z, x), (-y, x, z)];
    let (mut p, mut n, mut tris) = (Vec::new(), Vec::new(), Vec::new());
    for (k, &(c, u, v)) in faces.iter().enumerate() {
        let normal = if k == 0 { front } else { u.cross(v).normalize() };
        let first = p.len() as u32;
        p.extend([c - u - v, c + u - v, c + u + v, c - u + v]);
        n.extend([normal; 4]);
        tris.extend([[first, first + 1, first + 2], [first, first + 2, first + 3]]);
    }
    TriangleMesh::new(p, Some(n), None, tris).expect("valid mesh")
}

/// The slab of glass of colour `color` (index 1.5) with its front normals
/// tilted `tilt_deg` about Y, seen along −Z through one pixel to depth 2
/// (in, out, and the wall): a wall red where x < 0 and green where x ≥ 0
/// (a world checker of squares 100 wide), so that a path's channel says
/// which way it left the glass.
fn through_slab(tilt_deg: f32, color: Vec3) -> Vec3 {
    let t = tilt_deg.to_radians();
    let mesh = slab(Vec3::new(t.sin(), 0.0, t.cos()));
    assert!(mesh.is_closed());
    let halves = Texture::Checker { a: Vec3::X, b: Vec3::Y, size: 100.0, world: true };
    let scene = Scene {
        accel: Accel::build(
            vec![Arc::new(mesh)],
            vec![Object::Mesh { mesh: 0, transform: I }, Object::Shape(Instance::new(wall_plane(), I))],
        )
        .expect("builds"),
        object_materials: vec![0, 1],
        materials: vec![Material { texture: Texture::Solid(color), ..glass(1.5) }, flat_texture(halves)],
        lights: vec![],
        ambient: Vec3::ONE,
        background: Vec3::ZERO,
        environment: None,
        fog: None,
    };
    let eye = Vec3::new(0.3, 0.2, 5.0);
    let cam = camera(eye, eye - Vec3::Z, Vec3::Y, 0.5, 1, 1);
    px(&render(&Shot { scene, camera: cam, fog_on: false }, 1, 2), 0, 0)
}

/// Every path from the eye to the wall enters the glass once, so coloured
/// glass shows exactly its colour times what clear glass shows. The
/// refracted ray bends toward −X (red); at a 75° tilt the shading normal
/// also sends the reflected ray in through the front face, toward +X
/// (green), and that path must be tinted too.
#[test]
fn a_smooth_glass_mesh_tints_every_path_through_it_once() {
    let c = Vec3::new(0.2, 0.6, 1.0);
    let clear: Vec<Vec3> = [0.0, 30.0, 75.0].map(|tilt| through_slab(tilt, Vec3::ONE)).into();
    // Head-on: straight through to x = 0.3 (green). At 30°: the refracted
    // ray alone, bent to x < 0 (red). At 75°: both.
    assert!(clear[0].x == 0.0 && clear[0].y > 0.8, "0°: {}", clear[0]);
    assert!(clear[1].x > 0.8 && clear[1].y == 0.0, "30°: {}", clear[1]);
    assert!(clear[2].x > 0.4 && clear[2].y > 0.1, "75°: {}", clear[2]);
    for (tilt, clear) in [0.0, 30.0, 75.0].into_iter().zip(clear) {
        assert_close(through_slab(tilt, c), c * clear, 1e-5);
    }
}
