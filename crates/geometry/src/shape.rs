//! The intersection interface, the closed set of analytic shapes, and
//! instances placed by a transform.

use crate::shapes::{Cone, Cuboid, Cylinder, Disk, Plane, Sphere, Triangle};
use crate::{Aabb, Hit, Ray, Transform};

/// The two questions every shape answers.
pub trait Intersect {
    /// The nearest hit with `t` in `[ray.t_min, ray.t_max]`, if any.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;

    /// The `t` of [`Intersect::intersect`]'s hit, without building the
    /// hit record (no normal, point or uv): the cheap query for candidates
    /// that may lose to a nearer hit and for shadow tests. Every shape of
    /// this crate returns exactly `self.intersect(ray).map(|h| h.t)`, bit
    /// for bit, so the full hit of a winner at `t` is found again by
    /// `intersect` on the ray with `t_max = t`.
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.intersect(ray).map(|h| h.t)
    }

    /// `t` and `front_face` of [`Intersect::intersect`]'s hit, without the
    /// rest of the hit record (point, uv): what a shadow ray needs of an
    /// opaque occluder. Every shape of this crate returns exactly
    /// `self.intersect(ray).map(|h| (h.t, h.front_face))`, bit for bit.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        self.intersect(ray).map(|h| (h.t, h.front_face))
    }

    /// Bounds of the shape ([`Aabb::INFINITE`] for unbounded shapes).
    fn bounds(&self) -> Aabb;

    /// World bounds of the shape placed by `to_world`: by default those
    /// of [`Intersect::bounds`]'s box ([`Transform::aabb`]), which a
    /// rotation widens; spheres, disks, cylinders and cones give their
    /// exact ones (a rotated sphere's box stays its own size).
    fn bounds_in(&self, to_world: &Transform) -> Aabb {
        to_world.aabb(&self.bounds())
    }

    /// Whether anything is hit within the ray's interval.
    #[inline]
    fn occludes(&self, ray: &Ray) -> bool {
        self.intersect_t(ray).is_some()
    }
}

/// Any analytic shape, dispatched by `match` (no virtual calls).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// See [`Sphere`].
    Sphere(Sphere),
    /// See [`Plane`]; unbounded.
    Plane(Plane),
    /// See [`Cuboid`].
    Cuboid(Cuboid),
    /// See [`Cylinder`].
    Cylinder(Cylinder),
    /// See [`Cone`].
    Cone(Cone),
    /// See [`Disk`].
    Disk(Disk),
    /// See [`Triangle`].
    Triangle(Triangle),
}

impl Shape {
    /// Whether the shape has finite bounds (everything but planes).
    #[must_use]
    pub fn is_bounded(&self) -> bool {
        !matches!(self, Shape::Plane(_))
    }

    /// Whether the shape is a closed solid: its surface encloses a finite
    /// inside, so a ray leaving through it (a back-face hit) was inside.
    /// Spheres, boxes, capped cylinders and cones (with their base cap) are;
    /// planes, disks and single triangles are open surfaces. An affine
    /// [`Transform`] keeps the answer, so it holds for an [`Instance`] too.
    ///
    /// Triangle meshes are not [`Shape`]s and have no such answer: whether
    /// one is closed would have to be proven from its edges, so callers
    /// treat a mesh as open.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        match self {
            Shape::Sphere(_) | Shape::Cuboid(_) | Shape::Cylinder(_) | Shape::Cone(_) => true,
            Shape::Plane(_) | Shape::Disk(_) | Shape::Triangle(_) => false,
        }
    }

    /// A short lower-case name of the kind of shape.
    #[must_use]
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere(_) => "sphere",
            Shape::Plane(_) => "plane",
            Shape::Cuboid(_) => "cuboid",
            Shape::Cylinder(_) => "cylinder",
            Shape::Cone(_) => "cone",
            Shape::Disk(_) => "disk",
            Shape::Triangle(_) => "triangle",
        }
    }
}

impl Intersect for Shape {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray),
            Shape::Plane(s) => s.intersect(ray),
            Shape::Cuboid(s) => s.intersect(ray),
            Shape::Cylinder(s) => s.intersect(ray),
            Shape::Cone(s) => s.intersect(ray),
            Shape::Disk(s) => s.intersect(ray),
            Shape::Triangle(s) => s.intersect(ray),
        }
    }

    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        match self {
            Shape::Sphere(s) => s.intersect_t(ray),
            Shape::Plane(s) => s.intersect_t(ray),
            Shape::Cuboid(s) => s.intersect_t(ray),
            Shape::Cylinder(s) => s.intersect_t(ray),
            Shape::Cone(s) => s.intersect_t(ray),
            Shape::Disk(s) => s.intersect_t(ray),
            Shape::Triangle(s) => s.intersect_t(ray),
        }
    }

    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        match self {
            Shape::Sphere(s) => s.intersect_side(ray),
            Shape::Plane(s) => s.intersect_side(ray),
            Shape::Cuboid(s) => s.intersect_side(ray),
            Shape::Cylinder(s) => s.intersect_side(ray),
            Shape::Cone(s) => s.intersect_side(ray),
            Shape::Disk(s) => s.intersect_side(ray),
            Shape::Triangle(s) => s.intersect_side(ray),
        }
    }

    fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Plane(s) => s.bounds(),
            Shape::Cuboid(s) => s.bounds(),
            Shape::Cylinder(s) => s.bounds(),
            Shape::Cone(s) => s.bounds(),
            Shape::Disk(s) => s.bounds(),
            Shape::Triangle(s) => s.bounds(),
        }
    }

    fn bounds_in(&self, to_world: &Transform) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds_in(to_world),
            Shape::Plane(s) => s.bounds_in(to_world),
            Shape::Cuboid(s) => s.bounds_in(to_world),
            Shape::Cylinder(s) => s.bounds_in(to_world),
            Shape::Cone(s) => s.bounds_in(to_world),
            Shape::Disk(s) => s.bounds_in(to_world),
            Shape::Triangle(s) => s.bounds_in(to_world),
        }
    }
}

macro_rules! impl_from_shape {
    ($($t:ident),*) => {$(
        impl From<$t> for Shape {
            fn from(s: $t) -> Self {
                Shape::$t(s)
            }
        }
    )*};
}
impl_from_shape!(Sphere, Plane, Cuboid, Cylinder, Cone, Disk, Triangle);

/// A shape placed in the world by a [`Transform`]: rays are mapped into the
/// shape's object space, hits mapped back (normals by the inverse
/// transpose). `t` is the same in both spaces.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance<S> {
    /// The shape in its object space.
    pub shape: S,
    /// Object to world.
    pub transform: Transform,
}

impl<S> Instance<S> {
    /// `shape` placed by `transform`.
    pub fn new(shape: S, transform: Transform) -> Self {
        Self { shape, transform }
    }
}

impl<S: Intersect> Intersect for Instance<S> {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let local = self.transform.ray_to_object(ray);
        let hit = self.shape.intersect(&local)?;
        Some(self.transform.hit_to_world(&hit))
    }

    /// The ray is mapped into object space; no hit is mapped back.
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        self.shape.intersect_t(&self.transform.ray_to_object(ray))
    }

    /// The ray is mapped into object space; the side is the object-space
    /// hit's, which [`Transform::hit_to_world`] keeps.
    #[inline]
    fn intersect_side(&self, ray: &Ray) -> Option<(f32, bool)> {
        self.shape.intersect_side(&self.transform.ray_to_object(ray))
    }

    fn bounds(&self) -> Aabb {
        self.shape.bounds_in(&self.transform)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Every kind of shape, once.
    fn one_of_each() -> [Shape; 7] {
        [
            Sphere::new(Vec3::ZERO, 1.0).unwrap().into(),
            Plane::new(Vec3::ZERO, Vec3::Y).unwrap().into(),
            Cuboid::new(Vec3::ZERO, Vec3::ONE).unwrap().into(),
            Cylinder::new(Vec3::ZERO, 1.0, 2.0).unwrap().into(),
            Cone::new(Vec3::ZERO, 1.0, 2.0).unwrap().into(),
            Disk::new(Vec3::ZERO, Vec3::Y, 1.0).unwrap().into(),
            Triangle::new([Vec3::ZERO, Vec3::X, Vec3::Y]).unwrap().into(),
        ]
    }

    /// Points on the surfaces that reach farthest (a sphere's, the
    /// rims of caps and a cone's apex), in object space.
    fn extreme_points(s: &Shape) -> Vec<Vec3> {
        let ring = |c: Vec3, u: Vec3, v: Vec3, r: f32| {
            (0..720).map(move |k| {
                let a = k as f32 * std::f32::consts::TAU / 720.0;
                c + r * (a.cos() * u + a.sin() * v)
            })
        };
        match s {
            Shape::Sphere(b) => (0..180)
                .flat_map(|i| {
                    let lat = (i as f32 + 0.5) / 180.0 * std::f32::consts::PI - std::f32::consts::FRAC_PI_2;
                    ring(
                        b.center() + b.radius() * lat.sin() * Vec3::Y,
                        Vec3::X,
                        Vec3::Z,
                        b.radius() * lat.cos(),
                    )
                })
                .collect(),
            Shape::Cylinder(c) => ring(c.base(), Vec3::X, Vec3::Z, c.radius())
                .chain(ring(c.base() + c.height() * Vec3::Y, Vec3::X, Vec3::Z, c.radius()))
                .collect(),
            Shape::Cone(c) => ring(c.base(), Vec3::X, Vec3::Z, c.radius())
                .chain(std::iter::once(c.base() + c.height() * Vec3::Y))
                .collect(),
            Shape::Disk(d) => {
                let u = d.normal().any_orthonormal_vector();
                ring(d.center(), u, d.normal().cross(u), d.radius()).collect()
            }
            _ => Vec::new(),
        }
    }

    #[test]
    fn round_shapes_placed_by_any_transform_have_their_exact_bounds() {
        // A rotated sphere's bounds were those of its rotated box, up to
        // √3 wider (the default fog's end and `prism info` read them).
        let shapes: [Shape; 5] = [
            Sphere::new(Vec3::new(1.0, -2.0, 0.5), 1.5).unwrap().into(),
            Cylinder::new(Vec3::new(0.5, 1.0, -1.0), 0.7, 2.5).unwrap().into(),
            Cone::new(Vec3::new(-1.0, 0.0, 2.0), 1.2, 3.0).unwrap().into(),
            Disk::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 2.0) / 3.0, 2.0).unwrap().into(),
            // Tilted a thousandth of a degree: its thin extent along Y is
            // about 3.5e-5, which `√(1 − n_y²)` rounded to 0.
            Disk::new(Vec3::ZERO, Vec3::new(1.75e-5, 1.0, 0.0), 2.0).unwrap().into(),
        ];
        let shear = crate::transform::Shear { xy: 0.4, zx: -0.3, ..Default::default() };
        let transforms = [
            Transform::IDENTITY,
            Transform::rotate_y(45f32.to_radians()),
            // A cap's thin extent along an axis it is nearly across.
            Transform::rotate_x(1e-5),
            Transform::rotate_axis(Vec3::new(1.0, 2.0, 3.0), 1.0)
                .unwrap()
                .then(&Transform::scale(Vec3::new(2.0, 0.5, 1.0)).unwrap())
                .then(&Transform::shear(shear).unwrap())
                .then(&Transform::translate(Vec3::new(10.0, -3.0, 4.0)).unwrap()),
        ];
        for s in shapes {
            for t in &transforms {
                let b = Instance::new(s, *t).bounds();
                let corners = t.aabb(&s.bounds());
                let pts: Vec<Vec3> = extreme_points(&s).into_iter().map(|p| t.point(p)).collect();
                let reach = Aabb::from_points(&pts);
                let size = reach.extent().max_element();
                // Every point inside; the bounds no wider than the points'
                // reach (sampled every half degree) by more than 1e-4 of
                // the size; never wider than the box's bounds.
                for p in &pts {
                    assert!(b.contains(*p, 1e-6 * size), "{} {t:?}: {p} outside {b:?}", s.kind());
                }
                let slack = (reach.min - b.min).max(b.max - reach.max).max_element();
                assert!(slack <= 1e-4 * size, "{} {t:?}: {b:?} against {reach:?}", s.kind());
                assert!(
                    b.min.cmpge(corners.min).all() && b.max.cmple(corners.max).all(),
                    "{} {t:?}: {b:?} wider than {corners:?}",
                    s.kind()
                );
            }
        }
        // Rotated a quarter of a turn about Y, a unit sphere's box is its own.
        let b = Instance::new(Shape::from(Sphere::new(Vec3::ZERO, 1.0).unwrap()), Transform::rotate_y(0.7))
            .bounds();
        assert!(
            (b.max - Vec3::ONE).abs().max_element() < 1e-6 && (b.min + Vec3::ONE).abs().max_element() < 1e-6,
            "{b:?}"
        );
    }

    #[test]
    fn closed_solids_are_the_sphere_box_cylinder_and_cone() {
        for s in one_of_each() {
            let want = matches!(s.kind(), "sphere" | "cuboid" | "cylinder" | "cone");
            assert_eq!(s.is_closed(), want, "{}", s.kind());
        }
    }

    /// What "closed" promises: a ray from inside a closed shape leaves
    /// through a back face, and one from far outside aimed at its middle
    /// enters through a front face and then leaves through a back face.
    #[test]
    fn closed_shapes_are_entered_and_left() {
        for s in one_of_each().into_iter().filter(Shape::is_closed) {
            let c = s.bounds().center();
            for d in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(1.0, -0.3, 0.2)] {
                let out = s.intersect(&Ray::new(c, d)).unwrap_or_else(|| panic!("{} from inside", s.kind()));
                assert!(!out.front_face, "{} from inside along {d}", s.kind());
                let from = c - 10.0 * d;
                let enter = s.intersect(&Ray::new(from, d)).unwrap_or_else(|| panic!("{}", s.kind()));
                assert!(enter.front_face, "{} from outside along {d}", s.kind());
                let past = Ray::with_interval(from, d, enter.t.next_up(), f32::INFINITY);
                let leave = s.intersect(&past).unwrap_or_else(|| panic!("{} exit along {d}", s.kind()));
                assert!(!leave.front_face, "{} exit along {d}", s.kind());
            }
        }
    }
}
