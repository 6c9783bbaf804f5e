//! The watertight ray/triangle test of prism-geometry's `TriangleRay`
//! (Woop, Benthin and Wald, JCGT 2013), rearranged for a BVH's inner loop.
//!
//! The per-ray shear is stored as three row vectors, so the sheared vertex
//! `(a[kx] - sx·a[kz], a[ky] - sy·a[kz], sz·a[kz])` is three dot products
//! instead of dynamically indexed loads. The extra terms are products with
//! exact zeros, so every value (and so every edge-function sign, the
//! watertightness) is bit-for-bit the same as `TriangleRay`'s; the tests
//! compare both.

use prism_geometry::Ray;
use prism_geometry::glam::{Vec3, Vec3A};

#[derive(Clone, Copy, Debug)]
pub(crate) struct TriRay {
    origin: Vec3A,
    mx: Vec3A,
    my: Vec3A,
    mz: Vec3A,
    t_min: f32,
    pub t_max: f32,
}

impl TriRay {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = ray.dir[kz];
        let (sx, sy, sz) = (ray.dir[kx] / dz, ray.dir[ky] / dz, 1.0 / dz);
        let mut mx = Vec3::ZERO;
        let mut my = Vec3::ZERO;
        let mut mz = Vec3::ZERO;
        mx[kx] = 1.0;
        mx[kz] = -sx;
        my[ky] = 1.0;
        my[kz] = -sy;
        mz[kz] = sz;
        Self {
            origin: ray.origin.into(),
            mx: mx.into(),
            my: my.into(),
            mz: mz.into(),
            t_min: ray.t_min,
            t_max: ray.t_max,
        }
    }

    /// `(t, b1, b2)` if the ray meets the triangle within its interval.
    #[inline(always)]
    pub fn intersect(&self, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let a = Vec3A::from(v[0]) - self.origin;
        let b = Vec3A::from(v[1]) - self.origin;
        let c = Vec3A::from(v[2]) - self.origin;
        let (ax, ay) = (self.mx.dot(a), self.my.dot(a));
        let (bx, by) = (self.mx.dot(b), self.my.dot(b));
        let (cx, cy) = (self.mx.dot(c), self.my.dot(c));
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let t_scaled = u * self.mz.dot(a) + v * self.mz.dot(b) + w * self.mz.dot(c);
        let rcp = 1.0 / det;
        let t = t_scaled * rcp;
        if !(t >= self.t_min && t <= self.t_max) {
            return None;
        }
        Some((t, v * rcp, w * rcp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prism_geometry::TriangleRay;

    /// Bit-for-bit the same answers as prism-geometry's test.
    #[test]
    fn matches_triangle_ray_exactly() {
        let mut s = 0x1234_5678_u32;
        let mut f = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        let mut hits = 0;
        for k in 0..200_000 {
            let mut v = || Vec3::new(f(), f(), f());
            let tri = [v(), v(), v()];
            let o = v() * 3.0;
            let mut d = v();
            if k % 7 == 0 {
                d[k % 3] = 0.0;
            }
            if d == Vec3::ZERO {
                continue;
            }
            // Aim at a vertex or an edge midpoint now and then.
            if k % 11 == 0 {
                d = tri[k % 3] - o;
            } else if k % 13 == 0 {
                d = 0.5 * (tri[0] + tri[1]) - o;
            }
            let ray = Ray::with_interval(o, d, 0.0, 10.0);
            let want = TriangleRay::new(&ray).intersect(tri[0], tri[1], tri[2]);
            let got = TriRay::new(&ray).intersect(&tri);
            let bits =
                |x: Option<(f32, f32, f32)>| x.map(|(a, b, c)| (a.to_bits(), b.to_bits(), c.to_bits()));
            assert_eq!(bits(got), bits(want), "{ray:?} {tri:?}");
            hits += usize::from(want.is_some());
        }
        assert!(hits > 1000);
    }
}
