//! Shapes with their implicit functions, shared by the integration tests.
#![allow(dead_code)]

use prism_geometry::glam::Vec3;
use prism_geometry::{Cone, Cuboid, Cylinder, Disk, Intersect, Shape, Sphere, Transform, Triangle};

/// A test shape: the shape, whether it is a closed convex solid, and a
/// function `f` that is zero on its surface (negative inside for solids;
/// for flat shapes, the distance to the surface).
pub struct Case {
    pub name: &'static str,
    pub shape: Shape,
    pub solid: bool,
    pub f: fn(Vec3) -> f32,
}

fn max3(a: f32, b: f32, c: f32) -> f32 {
    a.max(b).max(c)
}

pub const SPHERE_C: Vec3 = Vec3::new(0.2, -0.1, 0.3);
pub const BOX_MIN: Vec3 = Vec3::new(-1.0, -0.5, -0.8);
pub const BOX_MAX: Vec3 = Vec3::new(0.9, 1.2, 0.7);
pub const DISK_N: Vec3 = Vec3::new(0.3, 1.0, 0.2);
pub const TRI: [Vec3; 3] = [Vec3::new(-1.0, -0.7, 0.2), Vec3::new(1.1, -0.3, -0.4), Vec3::new(0.1, 1.2, 0.5)];

pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "sphere",
            shape: Sphere::new(SPHERE_C, 1.1).unwrap().into(),
            solid: true,
            f: |p| (p - SPHERE_C).length() - 1.1,
        },
        Case {
            name: "cuboid",
            shape: Cuboid::new(BOX_MIN, BOX_MAX).unwrap().into(),
            solid: true,
            f: |p| {
                let c = 0.5 * (BOX_MIN + BOX_MAX);
                let half = 0.5 * (BOX_MAX - BOX_MIN);
                ((p - c).abs() - half).max_element()
            },
        },
        Case {
            name: "cylinder",
            shape: Cylinder::new(Vec3::new(0.0, -1.0, 0.0), 0.8, 2.0).unwrap().into(),
            solid: true,
            f: |p| max3(Vec3::new(p.x, 0.0, p.z).length() - 0.8, -1.0 - p.y, p.y - 1.0),
        },
        Case {
            name: "cone",
            shape: Cone::new(Vec3::new(0.0, -1.0, 0.0), 1.0, 2.0).unwrap().into(),
            solid: true,
            f: |p| {
                // k = 1/2; the side's distance is (ρ − k(1 − y))·cos α.
                let side = (Vec3::new(p.x, 0.0, p.z).length() - 0.5 * (1.0 - p.y)) / 1.25f32.sqrt();
                max3(side, -1.0 - p.y, p.y - 1.0)
            },
        },
        Case {
            name: "disk",
            shape: Disk::new(Vec3::ZERO, DISK_N, 1.0).unwrap().into(),
            solid: false,
            f: |p| {
                let n = DISK_N.normalize();
                let off = p.dot(n);
                let rim = ((p - off * n).length() - 1.0).max(0.0);
                off.abs().max(rim)
            },
        },
        Case {
            name: "triangle",
            shape: Triangle::new(TRI).unwrap().into(),
            solid: false,
            f: |p| {
                let [a, b, c] = TRI;
                let n = (b - a).cross(c - a).normalize();
                let off = (p - a).dot(n);
                let q = p - off * n;
                // Outside distance to the edges (0 when inside).
                let mut out = 0.0f32;
                for (u, v) in [(a, b), (b, c), (c, a)] {
                    let e = (v - u).cross(n).normalize();
                    out = out.max((q - u).dot(e));
                }
                off.abs().max(out)
            },
        },
    ]
}

/// `f` of a case evaluated at a world point through the instance transform.
pub fn f_world(case: &Case, xf: &Transform, p: Vec3) -> f32 {
    (case.f)(xf.inverse().point(p))
}

/// Bounds check helper: `shape.bounds()` grown by `eps` contains `p`.
pub fn in_bounds<S: Intersect>(s: &S, p: Vec3, eps: f32) -> bool {
    s.bounds().contains(p, eps)
}
