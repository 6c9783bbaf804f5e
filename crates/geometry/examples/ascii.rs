//! The report's scene in ASCII, using prism-geometry alone (and glam through
//! its re-export): a sphere, a box rotated 45° about Y, a box sheared along
//! X, a cylinder, a cone and a floor plane, shaded with a Lambert term.
//!
//! Run with `cargo run -p prism-geometry --example ascii`.

use prism_geometry::glam::Vec3;
use prism_geometry::{
    Cone, Cuboid, Cylinder, GeometryError, Instance, Intersect, Plane, Ray, Shape, Shear, Sphere, Transform,
};

fn main() -> Result<(), GeometryError> {
    let unit_box = Cuboid::new(Vec3::splat(-0.5), Vec3::splat(0.5))?;
    let place = |t: Transform, at: Vec3| -> Result<Transform, GeometryError> {
        Ok(t.then(&Transform::translate(at)?))
    };
    let scene: Vec<Instance<Shape>> = vec![
        Instance::new(Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y)?.into(), Transform::IDENTITY),
        Instance::new(Sphere::new(Vec3::new(0.0, 0.2, -7.0), 1.2)?.into(), Transform::IDENTITY),
        Instance::new(
            unit_box.into(),
            place(Transform::rotate_y(45f32.to_radians()), Vec3::new(-2.6, -0.5, -6.0))?,
        ),
        Instance::new(
            unit_box.into(),
            place(
                Transform::shear(Shear { xy: 30f32.to_radians().tan(), ..Shear::NONE })?,
                Vec3::new(2.6, -0.5, -6.0),
            )?,
        ),
        Instance::new(Cylinder::new(Vec3::new(-1.5, -1.0, -9.5), 0.5, 1.5)?.into(), Transform::IDENTITY),
        Instance::new(Cone::new(Vec3::new(1.6, -1.0, -9.5), 0.6, 1.8)?.into(), Transform::IDENTITY),
    ];
    let light = Vec3::new(-4.0, 6.0, 2.0);
    let ramp = b" .:-=+*#%@";
    let (w, h) = (78, 30);
    let mut out = String::new();
    for j in 0..h {
        for i in 0..w {
            // A pinhole camera at the origin looking down −Z; characters are
            // about twice as tall as wide.
            let x = (i as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let y = 1.0 - (j as f32 + 0.5) / h as f32 * 2.0;
            let ray = Ray::new(Vec3::new(0.0, 0.6, 0.0), Vec3::new(x * 0.75, y * 0.38 - 0.12, -1.0));
            let nearest = scene.iter().filter_map(|s| s.intersect(&ray)).min_by(|a, b| a.t.total_cmp(&b.t));
            let c = match nearest {
                None => b' ',
                Some(hit) => {
                    let n = hit.facing_normal();
                    // A shadow ray leaves from the surface with Ray::spawn_to.
                    let shadow = Ray::spawn_to(hit.point, hit.geo_normal, light);
                    let lit = !scene.iter().any(|s| s.occludes(&shadow));
                    let lambert = if lit { n.dot((light - hit.point).normalize()).max(0.0) } else { 0.0 };
                    let level = 0.1 + 0.9 * lambert;
                    ramp[((level * (ramp.len() - 1) as f32).round() as usize).min(ramp.len() - 1)]
                }
            };
            out.push(c as char);
        }
        out.push('\n');
    }
    print!("{out}");
    Ok(())
}
