//! The benchmark's fixed scenes and ray sets (issue 7), shared by
//! `prism-bench` and prism-bvh's measuring examples so that every number in
//! docs/benchmarks.md comes from the same rays.
//!
//! * primary: the bbox-framing camera, one ray per pixel centre;
//! * incoherent: 8 hemisphere rays from each primary hit point;
//! * shadow: one segment from each primary hit point to a light.
//!
//! Hit points come from the caller's closest-hit query (this crate knows no
//! acceleration structure) and are offset along the normal turned toward
//! the primary ray, by `2e-4` of the scene's bounding radius.

use crate::Rng;
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Ray};

/// Vertical field of view of the framing camera.
const VFOV_DEGREES: f32 = 40.0;

/// Seed state of the incoherent rays' generator.
const INCOHERENT_STATE: u64 = 0x5eed_0007;

/// Half the diagonal of `b`: the radius of the sphere the camera frames.
#[must_use]
pub fn bounding_radius(b: Aabb) -> f32 {
    (b.max - b.min).length() / 2.0
}

/// The bbox-framing camera: from the centre of `b`, back along +Z until
/// the bounding sphere fits the 40° vertical field, looking along −Z with
/// +Y up; one unit ray per pixel centre of a `w`×`h` image, row by row from
/// the top.
#[must_use]
pub fn primary_rays(b: Aabb, w: u32, h: u32) -> Vec<Ray> {
    let c = b.center();
    let r = bounding_radius(b);
    let vfov = VFOV_DEGREES.to_radians();
    let eye = c + Vec3::new(0.0, 0.0, r / (vfov / 2.0).sin());
    let forward = (c - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (vfov / 2.0).tan();
    let aspect = w as f32 / h as f32;
    let mut rays = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let sx = (2.0 * (i as f32 + 0.5) / w as f32 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (j as f32 + 0.5) / h as f32) * tan;
            rays.push(Ray::new(eye, (forward + sx * right + sy * up).normalize()));
        }
    }
    rays
}

/// `rays` (one per pixel of a `w`×`h` image, row by row) reordered into
/// `tile`×`tile` pixel blocks, blocks row by row and pixels row by row in
/// each: consecutive rays then belong to neighbouring pixels, as a
/// renderer's packets do.
#[must_use]
pub fn tile_order(rays: &[Ray], w: u32, h: u32, tile: u32) -> Vec<Ray> {
    let tile = tile.max(1);
    let mut out = Vec::with_capacity(rays.len());
    for ty in (0..h).step_by(tile as usize) {
        for tx in (0..w).step_by(tile as usize) {
            for j in ty..(ty + tile).min(h) {
                for i in tx..(tx + tile).min(w) {
                    if let Some(r) = rays.get((j * w + i) as usize) {
                        out.push(*r);
                    }
                }
            }
        }
    }
    out
}

/// For each of `primary` that `closest` hits (it returns the hit point and
/// geometric normal), the point offset off the surface toward the ray's
/// side, and that side's normal: the origins of the secondary sets.
pub fn offset_hit_points(
    primary: &[Ray],
    b: Aabb,
    mut closest: impl FnMut(&Ray) -> Option<(Vec3, Vec3)>,
) -> Vec<(Vec3, Vec3)> {
    let r = bounding_radius(b);
    primary
        .iter()
        .filter_map(|ray| {
            let (p, n) = closest(ray)?;
            let n = if n.dot(ray.dir) > 0.0 { -n } else { n };
            Some((p + n * (2e-4 * r), n))
        })
        .collect()
}

/// `per_point` rays from each point, uniform on the hemisphere of its
/// normal, from a fixed generator state.
#[must_use]
pub fn incoherent_rays(points: &[(Vec3, Vec3)], per_point: usize) -> Vec<Ray> {
    let mut rng = Rng::from_state(INCOHERENT_STATE);
    let mut rays = Vec::with_capacity(points.len() * per_point);
    for &(p, n) in points {
        for _ in 0..per_point {
            rays.push(Ray::new(p, rng.hemisphere(n)));
        }
    }
    rays
}

/// A segment from each point to the light at `centre(b) + r·(1, 2, 1.5)`
/// (unit direction, `t_max` = the distance).
#[must_use]
pub fn shadow_rays(points: &[(Vec3, Vec3)], b: Aabb) -> Vec<Ray> {
    let light = b.center() + bounding_radius(b) * Vec3::new(1.0, 2.0, 1.5);
    points
        .iter()
        .map(|&(p, _)| {
            let to = light - p;
            let dist = to.length();
            Ray::with_interval(p, to / dist, 0.0, dist)
        })
        .collect()
}

/// Offsets of an `n`×`n`×`n` grid of copies of a model of size `extent`,
/// spaced 1.25 of its size apart (the benchmark's `bunny-grid6` for `n = 6`).
#[must_use]
pub fn grid_offsets(extent: Vec3, n: u32) -> Vec<Vec3> {
    let n = n.max(1);
    let mut v = Vec::with_capacity((n * n * n) as usize);
    for ix in 0..n {
        for iy in 0..n {
            for iz in 0..n {
                v.push(1.25 * Vec3::new(ix as f32, iy as f32, iz as f32) * extent);
            }
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::{Intersect, Sphere};

    #[test]
    fn tile_order_is_a_permutation_into_blocks() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let rays = primary_rays(b, 20, 11);
        let tiled = tile_order(&rays, 20, 11, 8);
        assert_eq!(tiled.len(), rays.len());
        // The first block's second row starts with pixel (0, 1).
        assert_eq!(tiled[8].dir, rays[20].dir);
        // Every ray appears once.
        let mut a: Vec<_> = rays.iter().map(|r| r.dir.to_array().map(f32::to_bits)).collect();
        let mut t: Vec<_> = tiled.iter().map(|r| r.dir.to_array().map(f32::to_bits)).collect();
        a.sort_unstable();
        t.sort_unstable();
        assert_eq!(a, t);
    }

    #[test]
    fn the_camera_frames_the_box_and_secondary_rays_leave_the_surface() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let primary = primary_rays(b, 64, 36);
        assert_eq!(primary.len(), 64 * 36);
        // Every corner of the box projects inside the image: the middle rays
        // point at the centre, and all start at one eye on +Z.
        let eye = primary[0].origin;
        assert!(eye.z > 1.0 && eye.x == 0.0 && eye.y == 0.0);
        let mid = primary[18 * 64 + 32].dir;
        assert!(mid.dot(Vec3::NEG_Z) > 0.99, "{mid}");
        let sphere = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let points = offset_hit_points(&primary, b, |r| sphere.intersect(r).map(|h| (h.point, h.geo_normal)));
        assert!(points.len() > primary.len() / 10, "{}", points.len());
        for &(p, n) in &points {
            assert!(p.length() > 1.0 && n.dot(p) > 0.0, "offset outward: {p} {n}");
        }
        let inc = incoherent_rays(&points, 8);
        assert_eq!(inc.len(), points.len() * 8);
        assert!(inc.iter().zip(points.iter().flat_map(|p| [p; 8])).all(|(r, &(_, n))| r.dir.dot(n) >= 0.0));
        for r in shadow_rays(&points, b) {
            assert!(r.t_max.is_finite() && (r.dir.length() - 1.0).abs() < 1e-5);
        }
        assert_eq!(grid_offsets(Vec3::ONE, 2).len(), 8);
        assert_eq!(grid_offsets(Vec3::ONE, 2)[7], Vec3::splat(1.25));
    }
}
