//! Renders a small scene with every shading feature and writes it as PNG.
//!
//! `cargo run --release -p prism-shade --example showcase -- OUT.png [WIDTH HEIGHT SPP THREADS]`

use prism_bvh::{Accel, Object};
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{Cone, Cuboid, Cylinder, Instance, Plane, Shape, Shear, Sphere, Transform};
use prism_shade::{
    Camera, Fog, FogMode, ImageTexture, Mapping, Material, PointLight, RenderHooks, RenderSettings, Scene,
    Texture, Wrap,
};
use std::sync::Arc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = args.first().cloned().unwrap_or_else(|| "showcase.png".into());
    let num = |i: usize, d: u32| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (w, h, spp, threads) = (num(1, 640), num(2, 360), num(3, 4), num(4, 0));

    // A banded "gas giant" made in code.
    let (tw, th) = (64u32, 32u32);
    let bands = (0..tw * th)
        .map(|k| {
            let y = (k / tw) as f32 / th as f32;
            let b = (y * 23.0).sin() * 0.5 + 0.5;
            Vec3::new(0.8, 0.55 + 0.2 * b, 0.3 + 0.3 * b)
        })
        .collect();
    let planet = Arc::new(ImageTexture::from_linear(tw, th, bands, Wrap::Repeat)?);

    let plain = |c: Vec3| Material { specular: 0.3, ..Material::diffuse(c) };
    let objects: Vec<(Shape, Transform, Material)> = vec![
        (
            Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y)?.into(),
            Transform::IDENTITY,
            Material {
                texture: Texture::Checker {
                    a: Vec3::splat(0.8),
                    b: Vec3::new(0.1, 0.1, 0.3),
                    size: 1.0,
                    world: true,
                },
                ..Material::diffuse(Vec3::ONE)
            },
        ),
        (
            Sphere::new(Vec3::new(-1.5, 1.0, -4.0), 2.0)?.into(),
            Transform::IDENTITY,
            Material {
                reflectivity: 0.7,
                specular: 0.8,
                shininess: 60.0,
                ..Material::diffuse(Vec3::new(0.1, 0.2, 0.8))
            },
        ),
        (
            Sphere::new(Vec3::new(1.2, -0.2, 0.5), 0.8)?.into(),
            Transform::IDENTITY,
            Material {
                texture: Texture::Solid(Vec3::ONE),
                ambient: 0.0,
                diffuse: 0.0,
                specular: 0.8,
                shininess: 200.0,
                transmission: 1.0,
                ior: 1.5,
                absorption: Vec3::new(0.2, 0.05, 0.4),
                ..Material::diffuse(Vec3::ONE)
            },
        ),
        (
            Sphere::new(Vec3::new(-1.3, -0.4, 1.2), 0.6)?.into(),
            Transform::IDENTITY,
            Material { transparency: 0.6, ..plain(Vec3::new(0.9, 0.3, 0.3)) },
        ),
        (
            Sphere::new(Vec3::ZERO, 0.8)?.into(),
            Transform::rotate_z(0.3).then(&Transform::translate(Vec3::new(3.3, 0.2, -1.5))?),
            Material {
                texture: Texture::Image {
                    image: planet,
                    mapping: Mapping::Spherical,
                    scale: Vec2::ONE,
                    offset: Vec2::ZERO,
                    tint: Vec3::ONE,
                },
                ..Material::diffuse(Vec3::ONE)
            },
        ),
        (
            Cuboid::new(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5))?.into(),
            Transform::rotate_y(45f32.to_radians()).then(&Transform::translate(Vec3::new(2.0, -1.0, -3.0))?),
            plain(Vec3::new(0.8, 0.5, 0.2)),
        ),
        (
            Cuboid::new(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5))?.into(),
            Transform::shear(Shear { xy: -0.4, ..Shear::NONE })?
                .then(&Transform::translate(Vec3::new(-3.6, -1.0, -1.0))?),
            plain(Vec3::new(0.2, 0.7, 0.2)),
        ),
        (
            Cone::new(Vec3::new(0.3, -1.0, -1.5), 0.6, 1.6)?.into(),
            Transform::IDENTITY,
            plain(Vec3::new(0.8, 0.8, 0.2)),
        ),
        (
            Cylinder::new(Vec3::new(2.4, -1.0, 1.2), 0.4, 1.0)?.into(),
            Transform::IDENTITY,
            plain(Vec3::new(0.5, 0.2, 0.7)),
        ),
    ];
    let mut objs = Vec::new();
    let mut materials = Vec::new();
    for (shape, t, m) in objects {
        objs.push(Object::Shape(Instance::new(shape, t)));
        materials.push(m);
    }
    let scene = Scene {
        accel: Accel::build(Vec::new(), objs)?,
        object_materials: (0..materials.len() as u32).collect(),
        materials,
        lights: vec![
            PointLight { position: Vec3::new(6.0, 10.0, 8.0), color: Vec3::ONE, intensity: 1.0 }.into(),
        ],
        ambient: Vec3::splat(0.25),
        background: Vec3::new(0.05, 0.05, 0.1),
        environment: None,
        fog: Some(Fog { color: Vec3::ONE, mode: FogMode::Linear { start: 6.0, end: 40.0 } }),
    };
    scene.validate()?;
    let settings = RenderSettings {
        camera: Camera::new(Vec3::new(0.0, 1.5, 8.0), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 45.0, w, h)?,
        fog: true,
        spp,
        max_depth: 8,
        min_contribution: 1e-3,
        threads: (threads > 0).then_some(threads as usize),
        antialias: Default::default(),
    };
    let (img, stats) = prism_shade::render(&scene, &settings, RenderHooks::default());
    prism_shade::write_image(
        std::path::Path::new(&out),
        &img,
        prism_shade::OutputFormat::from_path(std::path::Path::new(&out))?,
    )?;
    println!(
        "{out}: {w}×{h}, {spp} spp, {:.3} s, {} rays, {:.2} Mrays/s",
        stats.seconds,
        stats.rays,
        stats.rays as f64 / stats.seconds / 1e6
    );
    Ok(())
}
