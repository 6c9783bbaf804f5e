mod common;
use common::*;
use prism_geometry::glam::Vec3;
use prism_geometry::{Plane, Sphere, Transform};

#[test]
fn a_lit_sphere_renders_finite_and_nonblack() {
    let s = scene(
        vec![
            (
                Sphere::new(Vec3::ZERO, 1.0).unwrap().into(),
                Transform::IDENTITY,
                prism_shade::Material::diffuse(Vec3::new(0.8, 0.2, 0.2)),
            ),
            (
                Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y).unwrap().into(),
                Transform::IDENTITY,
                prism_shade::Material::diffuse(Vec3::splat(0.5)),
            ),
        ],
        vec![light(Vec3::new(3.0, 5.0, 5.0))],
        camera(Vec3::new(0.0, 0.5, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 32, 24),
    );
    let img = render(&s, 4, 5);
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    assert!(px(&img, 16, 12).x > 0.3);
}
