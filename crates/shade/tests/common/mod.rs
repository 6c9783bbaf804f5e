//! Helpers to build small scenes directly in code.
#![allow(dead_code)]

use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Instance, Shape, Transform};
use prism_shade::{
    Camera, Fog, Image, Light, Material, PointLight, RenderHooks, RenderSettings, Scene, Texture,
};

/// A scene and the per-render choices the tests vary: the camera and
/// whether the fog is on (it derefs to the scene).
pub struct Shot {
    pub scene: Scene,
    pub camera: Camera,
    pub fog_on: bool,
}

impl std::ops::Deref for Shot {
    type Target = Scene;
    fn deref(&self) -> &Scene {
        &self.scene
    }
}

impl std::ops::DerefMut for Shot {
    fn deref_mut(&mut self) -> &mut Scene {
        &mut self.scene
    }
}

impl Shot {
    /// Settings for `spp` samples and recursion `max_depth`, one thread,
    /// no contribution cut-off, box filter, and textures point-sampled (the
    /// analytic tests compare pixels with texture lookups at a point; the
    /// footprint tests turn filtering back on).
    pub fn settings(&self, spp: u32, max_depth: u32) -> RenderSettings {
        RenderSettings {
            camera: self.camera,
            fog: self.fog_on,
            spp,
            max_depth,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: prism_shade::Antialias { point_textures: true, ..Default::default() },
        }
    }
}

/// A scene of `objects` (each with its own material), lit by `lights`,
/// seen by `camera`, fog (if any) on.
pub fn scene(objects: Vec<(Shape, Transform, Material)>, lights: Vec<PointLight>, camera: Camera) -> Shot {
    scene_lit(objects, lights.into_iter().map(Light::from).collect(), camera)
}

/// [`scene`] with lights of any kind.
pub fn scene_lit(objects: Vec<(Shape, Transform, Material)>, lights: Vec<Light>, camera: Camera) -> Shot {
    let mut objs = Vec::new();
    let mut materials = Vec::new();
    let mut object_materials = Vec::new();
    for (i, (shape, t, m)) in objects.into_iter().enumerate() {
        objs.push(Object::Shape(Instance::new(shape, t)));
        materials.push(m);
        object_materials.push(i as u32);
    }
    let scene = Scene {
        accel: Accel::build(Vec::new(), objs).expect("no meshes to miss"),
        object_materials,
        materials,
        lights,
        ambient: Vec3::ONE,
        background: Vec3::ZERO,
        environment: None,
        fog: None,
    };
    Shot { scene, camera, fog_on: true }
}

pub fn light(position: Vec3) -> PointLight {
    PointLight { position, color: Vec3::ONE, intensity: 1.0 }
}

/// A material that shows exactly its colour under ambient light 1.
pub fn flat(color: Vec3) -> Material {
    Material { ambient: 1.0, diffuse: 0.0, ..Material::diffuse(color) }
}

/// Only a texture, shown flat.
pub fn flat_texture(texture: Texture) -> Material {
    Material { texture, ..flat(Vec3::ONE) }
}

/// Clear glass.
pub fn glass(ior: f32) -> Material {
    Material {
        texture: Texture::Solid(Vec3::ONE),
        ambient: 0.0,
        diffuse: 0.0,
        specular: 0.0,
        transmission: 1.0,
        ior,
        ..Material::diffuse(Vec3::ONE)
    }
}

/// A 16×8 repeating texture whose texels all differ.
pub fn distinct_texture() -> std::sync::Arc<prism_shade::ImageTexture> {
    let (w, h) = (16u32, 8u32);
    let texels = (0..w * h)
        .map(|k| {
            Vec3::new((k % w) as f32 / w as f32, (k / w) as f32 / h as f32, ((k * 7) % 11) as f32 / 11.0)
        })
        .collect();
    let image =
        prism_shade::ImageTexture::from_linear(w, h, texels, prism_shade::Wrap::Repeat).expect("valid");
    std::sync::Arc::new(image)
}

pub fn camera(position: Vec3, look_at: Vec3, up: Vec3, vfov: f32, w: u32, h: u32) -> Camera {
    Camera::new(position, look_at, up, vfov, w, h).expect("valid camera")
}

pub fn render(shot: &Shot, spp: u32, max_depth: u32) -> Image {
    prism_shade::render(shot, &shot.settings(spp, max_depth), RenderHooks::default()).0
}

pub fn px(img: &Image, i: u32, j: u32) -> Vec3 {
    img.pixels[(j * img.width + i) as usize]
}

pub fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

#[track_caller]
pub fn assert_close(got: Vec3, want: Vec3, tol: f32) {
    assert!(close(got, want, tol), "got {got}, want {want} (tolerance {tol})");
}

/// Nearest `t` of the ray `o + t d` on the sphere `(c, r)`, if hit with
/// margin (not grazing).
pub fn sphere_t(o: Vec3, d: Vec3, c: Vec3, r: f32) -> Option<f32> {
    let f = o - c;
    let (a, b, cc) = (d.dot(d) as f64, f.dot(d) as f64, (f.dot(f) - r * r) as f64);
    let disc = b * b - a * cc;
    if disc < 1e-3 {
        return None;
    }
    Some(((-b - disc.sqrt()) / a) as f32)
}

pub fn fog(color: Vec3, mode: prism_shade::FogMode) -> Option<Fog> {
    Some(Fog { color, mode })
}
