//! A small built-in scene (a chequered floor, a mirror sphere, two matte
//! spheres, one light, the report's linear fog), for the viewer's tests,
//! with no scene file.

use crate::{SceneSetup, ViewError};
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Instance, Plane, Shape, Sphere, Transform};
use prism_shade::{Camera, Fog, FogMode, Material, PointLight, RenderSettings, Scene, Texture};

/// The built-in scene at `width × height`, fog enabled, 4 samples per pixel.
///
/// # Errors
/// [`ViewError::Camera`] for an empty size.
pub fn demo_scene(width: u32, height: u32) -> Result<SceneSetup, ViewError> {
    let geometry =
        |e: prism_geometry::GeometryError| ViewError::Scene { path: "<demo>".into(), message: e.to_string() };
    let at = |s: Shape| Object::Shape(Instance::new(s, Transform::IDENTITY));
    let objects = vec![
        at(Shape::Plane(Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y).map_err(geometry)?)),
        at(Shape::Sphere(Sphere::new(Vec3::new(0.0, 0.5, -8.0), 1.5).map_err(geometry)?)),
        at(Shape::Sphere(Sphere::new(Vec3::new(-3.0, 0.0, -5.0), 1.0).map_err(geometry)?)),
        at(Shape::Sphere(Sphere::new(Vec3::new(3.5, 0.0, -14.0), 1.0).map_err(geometry)?)),
    ];
    let accel = Accel::build(Vec::new(), objects)
        .map_err(|e| ViewError::Scene { path: "<demo>".into(), message: e.to_string() })?;
    let floor = Material {
        texture: Texture::Checker {
            a: Vec3::splat(0.8),
            b: Vec3::new(0.1, 0.1, 0.4),
            size: 1.0,
            world: true,
        },
        ..Material::diffuse(Vec3::ONE)
    };
    let mirror = Material { reflectivity: 0.7, specular: 0.8, ..Material::diffuse(Vec3::new(0.1, 0.2, 0.8)) };
    let materials = vec![
        floor,
        mirror,
        Material { specular: 0.5, ..Material::diffuse(Vec3::new(0.9, 0.2, 0.1)) },
        Material::diffuse(Vec3::new(0.2, 0.8, 0.2)),
    ];
    let camera =
        Camera::new(Vec3::new(0.0, 1.5, 4.0), Vec3::new(0.0, 0.0, -8.0), Vec3::Y, 50.0, width, height)?;
    let scene = Scene {
        accel,
        object_materials: vec![0, 1, 2, 3],
        materials,
        lights: vec![
            PointLight { position: Vec3::new(8.0, 12.0, 4.0), color: Vec3::ONE, intensity: 1.0 }.into(),
        ],
        ambient: Vec3::splat(0.3),
        background: Vec3::new(0.05, 0.05, 0.1),
        environment: None,
        fog: Some(Fog { color: Vec3::ONE, mode: FogMode::Linear { start: 2.0, end: 40.0 } }),
    };
    Ok(SceneSetup {
        scene,
        settings: RenderSettings {
            camera,
            fog: true,
            spp: 4,
            max_depth: 5,
            min_contribution: 1e-3,
            threads: None,
            antialias: Default::default(),
        },
    })
}
