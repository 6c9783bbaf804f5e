//! The report's two boxes: one rotated 45° about Y, one sheared along X
//! (x' = x + y·tan φ), against hand-computed hits.

use prism_geometry::glam::Vec3;
use prism_geometry::{Cuboid, Instance, Intersect, Ray, Shear, Transform};

fn close3(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} != {b}");
}

fn unit_box() -> Cuboid {
    Cuboid::new(Vec3::splat(-1.0), Vec3::ONE).unwrap()
}

fn at(z: f32) -> Transform {
    Transform::translate(Vec3::new(0.0, 0.0, z)).unwrap()
}

#[test]
fn box_rotated_45_degrees_about_y() {
    let b = Instance::new(unit_box(), Transform::rotate_y(45f32.to_radians()).then(&at(-10.0)));
    let s = 0.5f32.sqrt();
    // Head-on: the vertical edge nearest the camera, √2 from the centre.
    let h = b.intersect(&Ray::new(Vec3::ZERO, Vec3::NEG_Z)).unwrap();
    assert!((h.t - (10.0 - 2f32.sqrt())).abs() < 1e-4);
    // Right of the edge: the +Z face, turned to (√½, 0, √½); the plane
    // n·(p − c) = 1 gives z + 10 = √2 − x.
    let h = b.intersect(&Ray::new(Vec3::new(0.5, 0.3, 0.0), Vec3::NEG_Z)).unwrap();
    assert!((h.t - (10.0 - 2f32.sqrt() + 0.5)).abs() < 1e-4, "{h:?}");
    close3(h.point, Vec3::new(0.5, 0.3, -10.0 + 2f32.sqrt() - 0.5), 1e-4);
    close3(h.geo_normal, Vec3::new(s, 0.0, s), 1e-6);
    assert!(h.front_face);
    // Left of the edge: the −X face, turned to (−√½, 0, √½).
    let h = b.intersect(&Ray::new(Vec3::new(-0.5, -0.3, 0.0), Vec3::NEG_Z)).unwrap();
    close3(h.geo_normal, Vec3::new(-s, 0.0, s), 1e-6);
    // The silhouette is |x| ≤ √2: just outside misses, just inside hits.
    assert!(b.intersect(&Ray::new(Vec3::new(1.4143, 0.0, 0.0), Vec3::NEG_Z)).is_none());
    assert!(b.intersect(&Ray::new(Vec3::new(1.4141, 0.0, 0.0), Vec3::NEG_Z)).is_some());
    // From above: the top face, normal +Y, anywhere inside the diamond.
    let h = b.intersect(&Ray::new(Vec3::new(0.0, 5.0, -10.0 + 1.4), Vec3::NEG_Y)).unwrap();
    assert!((h.t - 4.0).abs() < 1e-5);
    close3(h.geo_normal, Vec3::Y, 1e-6);
    // Bounds of the rotated box.
    let bb = b.bounds();
    close3(bb.max, Vec3::new(2f32.sqrt(), 1.0, -10.0 + 2f32.sqrt()), 1e-5);
}

#[test]
fn box_sheared_along_x() {
    let phi = 30f32.to_radians();
    let tan = phi.tan();
    let b = Instance::new(
        unit_box(),
        Transform::shear(Shear { xy: tan, ..Shear::NONE }).unwrap().then(&at(-10.0)),
    );
    // From +X at height y: the sheared face x' = 1 + y·tan φ, normal (cos φ, −sin φ, 0).
    for y in [-0.75f32, 0.0, 0.5] {
        let h = b.intersect(&Ray::new(Vec3::new(10.0, y, -10.0), Vec3::NEG_X)).unwrap();
        assert!((h.t - (9.0 - y * tan)).abs() < 1e-5, "{h:?}");
        close3(h.point, Vec3::new(1.0 + y * tan, y, -10.0), 1e-5);
        close3(h.geo_normal, Vec3::new(phi.cos(), -phi.sin(), 0.0), 1e-6);
    }
    // From above: the top face, unchanged normal.
    let h = b.intersect(&Ray::new(Vec3::new(0.3, 10.0, -10.0), Vec3::NEG_Y)).unwrap();
    assert!((h.t - 9.0).abs() < 1e-5);
    close3(h.geo_normal, Vec3::Y, 1e-6);
    // Head-on at (x, y) = (−1.2, −0.8): inside the sheared front face
    // (x ∈ [−1 − 0.8 tan φ, 1 − 0.8 tan φ]) though outside the unsheared one.
    let h = b.intersect(&Ray::new(Vec3::new(-1.2, -0.8, 0.0), Vec3::NEG_Z)).unwrap();
    assert!((h.t - 9.0).abs() < 1e-5);
    close3(h.geo_normal, Vec3::Z, 1e-6);
    // And (1.2, −0.8) is outside it.
    assert!(b.intersect(&Ray::new(Vec3::new(1.2, -0.8, 0.0), Vec3::NEG_Z)).is_none());
    // Bottom-left corner of the parallelogram silhouette: (−1 − tan φ, −1).
    let x0 = -1.0 - tan;
    assert!(b.intersect(&Ray::new(Vec3::new(x0 + 1e-3, -0.999, 0.0), Vec3::NEG_Z)).is_some());
    assert!(b.intersect(&Ray::new(Vec3::new(x0 - 1e-3, -0.999, 0.0), Vec3::NEG_Z)).is_none());
}
