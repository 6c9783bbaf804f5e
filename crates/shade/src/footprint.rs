//! Texture footprints: how much surface one pixel sees at a hit, by ray
//! cones (Akenine-Möller et al., "Texture Level of Detail Strategies for
//! Real-Time Ray Tracing", *Ray Tracing Gems* ch. 20, and "Improved Shader
//! and Texture Level of Detail Using Ray Cones", JCGT 2021).
//!
//! Why cones rather than ray differentials: a cone is two numbers (width,
//! spread angle) carried down the recursion, and its change at a curved
//! mirror or lens is one curvature term, where differentials need the
//! normal's derivatives (dn/du, dn/dv), which no shape here provides. The
//! anisotropy that matters (a floor seen at a grazing angle) is kept: at a
//! hit the cone's circular cross-section is projected onto the surface as
//! an ellipse, whose two axes ([`Footprint::dp`]) are exactly what pbrt's
//! differentials give for a square pixel of a pinhole camera. A camera
//! cone spans one pixel whatever the samples per pixel, so that an image
//! converges, as samples grow, to the same limit at every sample count.

use crate::Scene;
use prism_bvh::{Object, SceneHit};
use prism_geometry::glam::{Vec2, Vec3};
use prism_geometry::{Intersect, Ray, Shape};

/// Smallest `|cos|` between a ray and a surface normal used to stretch a
/// footprint (a ray exactly along the surface would stretch it without end).
const MIN_COS: f32 = 1e-6;

/// A ray cone: the width of the beam at the ray's origin and its spread
/// angle (radians; negative when it converges).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RayCone {
    pub width: f32,
    pub spread: f32,
}

impl RayCone {
    /// The cone of a camera ray: zero width at the eye, `spread` per pixel.
    pub(crate) fn camera(spread: f32) -> Self {
        Self { width: 0.0, spread }
    }

    /// The width after `dist` along the ray.
    #[inline]
    pub(crate) fn width_at(self, dist: f32) -> f32 {
        (self.width + self.spread * dist).abs()
    }

    /// The cone of the mirror reflection at a surface of `curvature`
    /// (positive where convex toward the incoming ray), where this cone's
    /// width is `width`: a normal turning by `κ·w` over the footprint turns
    /// the reflected ray by twice that.
    #[inline]
    pub(crate) fn reflect(self, width: f32, curvature: f32) -> Self {
        Self { width, spread: self.spread + 2.0 * curvature * width }
    }

    /// The cone refracted with relative index `eta = n1 / n2`: angles scale
    /// by `eta` (small-angle Snell), and the surface's curvature bends the
    /// beam by `(1 − eta)·κ·w` (a thin-lens term; an approximation).
    #[inline]
    pub(crate) fn refract(self, width: f32, eta: f32, curvature: f32) -> Self {
        Self { width, spread: eta * self.spread + (1.0 - eta) * curvature * width }
    }
}

/// The surface a pixel sees around a hit: the two semi-axes of the
/// footprint ellipse, each spanning one pixel, in world space (`dp`) and,
/// where known, in the shape's own uv (`duv`). Zero axes mean a point:
/// textures are then point-sampled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// World-space footprint axes on the surface (each one pixel's extent).
    pub dp: [Vec3; 2],
    /// The same axes in the shape's uv (zero where unknown).
    pub duv: [Vec2; 2],
}

impl Footprint {
    /// A point: no filtering.
    pub const POINT: Self = Self { dp: [Vec3::ZERO; 2], duv: [Vec2::ZERO; 2] };

    /// The footprint of a beam of width `width` arriving along `dir` on a
    /// surface of unit normal `n`: one axis across the plane of incidence
    /// (length `width`), one along it (`width / |cos θ|`).
    #[must_use]
    pub fn on_surface(dir: Vec3, n: Vec3, width: f32) -> Self {
        if !(width > 0.0 && width.is_finite()) {
            return Self::POINT;
        }
        let d = dir.normalize_or_zero();
        let cos = d.dot(n).abs().max(MIN_COS);
        // `normalize_or(n.any_orthonormal_vector())`, with the fallback
        // (a division) computed only when it is taken.
        let v = d - n * d.dot(n);
        let rcp = v.length_recip();
        let along = if rcp.is_finite() && rcp > 0.0 { v * rcp } else { n.any_orthonormal_vector() };
        let across = n.cross(along);
        Self { dp: [across * width, along * (width / cos)], duv: [Vec2::ZERO; 2] }
    }
}

/// The curvature of the surface at a hit, signed so that it is positive
/// where the surface bulges toward the ray (a sphere seen from outside):
/// `1 / r` on spheres, `1 / 2r` (the mean curvature) on cylinder and cone
/// sides, 0 on planes, boxes, disks, caps, triangles and meshes (mesh
/// facets are flat; smooth-shaded meshes are treated as flat too, an
/// underestimate). Under a non-uniform scale, `r` is scaled by the mean
/// scale.
pub(crate) fn curvature(scene: &Scene, h: &SceneHit) -> f32 {
    let Some(Object::Shape(inst)) = scene.accel.objects().get(h.object as usize) else {
        return 0.0;
    };
    if !matches!(inst.shape, Shape::Sphere(_) | Shape::Cylinder(_) | Shape::Cone(_)) {
        // Flat: 0, signed as below (-0 on a back face), without the transform's work.
        return if h.hit.front_face { 0.0 } else { -0.0 };
    }
    let m = inst.transform.matrix();
    let det = m.matrix3.determinant().abs();
    // cbrt(1) is 1 exactly: skip the libm call for unscaled objects.
    let scale = if det == 1.0 { 1.0 } else { det.cbrt() };
    // On a cap the normal is along the object's axis: flat.
    let side = |r: f32| {
        let axis = m.transform_vector3(Vec3::Y).normalize_or_zero();
        if axis.dot(h.hit.geo_normal).abs() > 0.999 { 0.0 } else { 0.5 / (r * scale) }
    };
    let k = match &inst.shape {
        Shape::Sphere(s) => 1.0 / (s.radius() * scale),
        Shape::Cylinder(c) => side(c.radius()),
        Shape::Cone(c) => side(c.radius()),
        _ => 0.0,
    };
    let k = if k.is_finite() { k } else { 0.0 };
    if h.hit.front_face { k } else { -k }
}

/// The footprint axes `dp` of a hit in the shape's own uv: for an analytic
/// shape by intersecting it alone with rays from `origin` through the
/// points `p ± dp[i]` (the smaller of the forward and backward difference,
/// so that a seam or an edge of the shape does not count), for a mesh from
/// its triangle's uvs (zero without uvs).
pub(crate) fn uv_axes(scene: &Scene, origin: Vec3, h: &SceneHit, dp: [Vec3; 2]) -> [Vec2; 2] {
    let hit = &h.hit;
    match scene.accel.objects().get(h.object as usize) {
        Some(Object::Shape(inst)) => dp.map(|e| {
            if e == Vec3::ZERO {
                return Vec2::ZERO;
            }
            let uv_at = |q: Vec3| inst.intersect(&Ray::new(origin, q - origin)).map(|x| x.uv);
            smaller(uv_at(hit.point + e).map(|uv| uv - hit.uv), uv_at(hit.point - e).map(|uv| hit.uv - uv))
        }),
        Some(Object::Mesh { mesh, transform }) => {
            let Some(mesh) = scene.accel.meshes().get(*mesh as usize) else { return [Vec2::ZERO; 2] };
            let (Some(uvs), Some(idx)) = (mesh.uvs(), mesh.indices().get(h.triangle as usize)) else {
                return [Vec2::ZERO; 2];
            };
            let p = mesh.triangle(h.triangle as usize).map(|p| transform.point(p));
            let uv = idx.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
            triangle_uv_axes(p, uv, dp)
        }
        None => [Vec2::ZERO; 2],
    }
}

/// The footprint axes `dp` (world space, in the plane of the triangle `p`)
/// in the uv that the triangle's corners carry (`uv`): each axis written
/// as `α·(p0 − p2) + β·(p1 − p2)` (least squares), then the same sum of
/// the uv differences. Lengths are measured in units of the triangle's
/// size: the Gram determinant is that size to the fourth, which left f32's
/// range for a mesh scaled by 1e10 (or 1e-12), and its texture filtering
/// went off.
fn triangle_uv_axes(p: [Vec3; 3], uv: [Vec2; 3], dp: [Vec3; 2]) -> [Vec2; 2] {
    let (a, b) = (p[0] - p[2], p[1] - p[2]);
    let k = a.abs().max_element().max(b.abs().max_element()).recip();
    if !(k.is_finite() && k > 0.0) {
        return [Vec2::ZERO; 2];
    }
    let (a, b) = (a * k, b * k);
    let (gaa, gab, gbb) = (a.dot(a), a.dot(b), b.dot(b));
    let det = gaa * gbb - gab * gab;
    if !(det.abs() > 0.0) {
        return [Vec2::ZERO; 2];
    }
    dp.map(|e| {
        let (ra, rb) = (a.dot(e * k), b.dot(e * k));
        let alpha = (gbb * ra - gab * rb) / det;
        let beta = (gaa * rb - gab * ra) / det;
        let d = alpha * (uv[0] - uv[2]) + beta * (uv[1] - uv[2]);
        if d.is_finite() { d } else { Vec2::ZERO }
    })
}

/// The shorter of two differences (either may be missing); zero if both are.
pub(crate) fn smaller(a: Option<Vec2>, b: Option<Vec2>) -> Vec2 {
    let a = a.filter(|v| v.is_finite());
    let b = b.filter(|v| v.is_finite());
    match (a, b) {
        (Some(a), Some(b)) => {
            if a.length_squared() <= b.length_squared() {
                a
            } else {
                b
            }
        }
        (Some(v), None) | (None, Some(v)) => v,
        (None, None) => Vec2::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprint_stretches_along_the_plane_of_incidence() {
        // Looking down −Z at 60° from the normal of the floor (+Y).
        let dir = Vec3::new(0.0, -0.5, -(0.75f32).sqrt());
        let f = Footprint::on_surface(dir, Vec3::Y, 0.1);
        // One axis across (along x), one along −z, stretched by 1 / cos 60° = 2.
        assert!((f.dp[0].abs() - Vec3::new(0.1, 0.0, 0.0)).length() < 1e-6, "{:?}", f.dp);
        assert!((f.dp[1] - Vec3::new(0.0, 0.0, -0.2)).length() < 1e-6, "{:?}", f.dp);
        // Head-on: a circle of the beam's width.
        let f = Footprint::on_surface(Vec3::NEG_Y, Vec3::Y, 0.1);
        assert!((f.dp[0].length() - 0.1).abs() < 1e-6 && (f.dp[1].length() - 0.1).abs() < 1e-6);
        assert!(f.dp[0].dot(f.dp[1]).abs() < 1e-9 && f.dp[0].y == 0.0 && f.dp[1].y == 0.0);
        // Grazing: long but finite; no width: a point.
        let f = Footprint::on_surface(Vec3::NEG_Z, Vec3::Y, 0.1);
        assert!(f.dp[1].is_finite() && f.dp[1].length() > 1e3);
        assert_eq!(Footprint::on_surface(dir, Vec3::Y, 0.0), Footprint::POINT);
    }

    #[test]
    fn cones_widen_and_bend_at_curved_mirrors() {
        let c = RayCone::camera(0.01);
        assert_eq!(c.width_at(0.0), 0.0);
        assert!((c.width_at(10.0) - 0.1).abs() < 1e-7);
        // A flat mirror keeps the spread: the image of the floor in it is
        // as far as the path is long.
        let r = c.reflect(0.1, 0.0);
        assert_eq!(r.spread, 0.01);
        assert!((r.width_at(10.0) - 0.2).abs() < 1e-6);
        // A convex mirror spreads it by twice the normal's turn over the footprint.
        let r = c.reflect(0.1, 1.0);
        assert!((r.spread - 0.21).abs() < 1e-6);
        // Flat glass: angles scale by n1/n2.
        let t = c.refract(0.1, 1.0 / 1.5, 0.0);
        assert!((t.spread - 0.01 / 1.5).abs() < 1e-7);
    }

    #[test]
    fn a_triangles_uv_axes_do_not_depend_on_its_scale() {
        // A right triangle whose uv is its position over 4, so that an
        // axis `e` in its plane maps to `e / 4` in uv, scaled as a whole.
        let uv = [Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0), Vec2::ZERO];
        for exp in -14..=14 {
            let s = 10f32.powi(exp);
            let p = [Vec3::new(4.0, 0.0, 0.0) * s, Vec3::new(0.0, 4.0, 0.0) * s, Vec3::ZERO];
            let dp = [Vec3::new(0.02, 0.0, 0.0) * s, Vec3::new(0.01, 0.03, 0.0) * s];
            let got = triangle_uv_axes(p, uv, dp);
            for (g, want) in got.iter().zip([Vec2::new(0.005, 0.0), Vec2::new(0.0025, 0.0075)]) {
                assert!((*g - want).length() < 1e-6, "scale {s}: {g} for {want}");
            }
        }
        // A triangle of no area has no uv axes.
        let line = [Vec3::ZERO, Vec3::X, 2.0 * Vec3::X];
        assert_eq!(triangle_uv_axes(line, uv, [Vec3::X; 2]), [Vec2::ZERO; 2]);
    }

    #[test]
    fn smaller_difference_wins() {
        let a = Some(Vec2::new(0.5, 0.0));
        let b = Some(Vec2::new(0.0, 0.1));
        assert_eq!(smaller(a, b), Vec2::new(0.0, 0.1));
        assert_eq!(smaller(a, None), Vec2::new(0.5, 0.0));
        assert_eq!(smaller(None, Some(Vec2::NAN)), Vec2::ZERO);
    }
}
