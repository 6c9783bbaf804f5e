//! Polygons cut into triangles: an OBJ face of four or more corners.
//!
//! A fan from the first corner, as most OBJ readers cut a polygon, is
//! wrong for a polygon that is not convex (the fan's triangles cover its
//! notches) and, for a polygon of many corners, gives thin slivers that
//! all meet at one point, which renders no better and makes a bounding
//! volume hierarchy slow to build and to walk. [`triangulate`] clips ears
//! instead.

use glam::{DVec2, DVec3, Vec3};

/// Cuts the polygon whose corners are `corners`, in order, into
/// `corners.len() - 2` triangles of indices into `corners`, each wound as
/// the polygon is.
///
/// The polygon is seen in the plane across its largest-area axis (its
/// Newell normal), and ears are clipped from that outline: a triangle of
/// three consecutive corners that turns the polygon's way and holds no
/// other corner. Corners are clipped every other one around the outline,
/// so the triangles of a convex polygon of many corners stay near each
/// other rather than fanning out from one corner. A convex quadrilateral
/// is cut along the diagonal from its first corner, as a fan would cut
/// it.
///
/// Where no ear is left (an outline that crosses itself, or corners all
/// in one line), the rest is cut as a fan, so that the number of
/// triangles is always `corners.len() - 2` (none for fewer than three
/// corners); triangles of zero area may result, as they would from the
/// input anyway.
#[must_use]
pub fn triangulate(corners: &[Vec3]) -> Vec<[u32; 3]> {
    let n = corners.len();
    if n < 3 {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(n - 2);
    if n == 3 {
        out.push([0, 1, 2]);
        return out;
    }
    let Some(flat) = outline(corners) else {
        fan(&(0..n).collect::<Vec<_>>(), &mut out);
        return out;
    };
    let mut ring = Ring::new(&flat);
    let mut cur = 1;
    // Corners tested since the last ear was clipped.
    let mut tested = 0;
    while ring.len > 3 {
        let (p, q) = (ring.prev[cur], ring.next[cur]);
        if ring.is_ear(p, cur, q) {
            out.push(index([p, cur, q]));
            ring.remove(cur);
            cur = ring.next[q];
            tested = 0;
        } else {
            cur = q;
            tested += 1;
            if tested > ring.len {
                break;
            }
        }
    }
    // Three corners left, or no ear among more: the rest as a fan from
    // its first corner in the file's order (a convex quadrilateral's
    // second triangle is then the fan's `0 2 3`).
    let first = ring.corners_from(cur).into_iter().min().unwrap_or(0);
    fan(&ring.corners_from(first), &mut out);
    out
}

/// Index triples as `u32`: a polygon of more than `u32::MAX` corners is
/// not an OBJ face anyone can load.
fn index([a, b, c]: [usize; 3]) -> [u32; 3] {
    let i = |x: usize| u32::try_from(x).unwrap_or(u32::MAX);
    [i(a), i(b), i(c)]
}

/// A fan of triangles from the first of `ring`'s corners.
fn fan(ring: &[usize], out: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = ring.split_first() {
        out.extend(rest.windows(2).map(|w| index([first, w[0], w[1]])));
    }
}

/// The corners in the plane across the polygon's Newell normal's largest
/// axis, turned so that the polygon runs counter-clockwise there; `None`
/// when that normal is zero or not finite (the corners in one line, or
/// not finite).
fn outline(corners: &[Vec3]) -> Option<Vec<DVec2>> {
    let c: Vec<DVec3> = corners.iter().map(|p| p.as_dvec3()).collect();
    let mut normal = DVec3::ZERO;
    for (i, a) in c.iter().enumerate() {
        let b = c[(i + 1) % c.len()];
        normal += DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    let size = normal.abs();
    if !(size.max_element() > 0.0 && size.is_finite()) {
        return None;
    }
    // Dropping axis `k` leaves the other two in right-handed order
    // (y, z), (z, x) or (x, y); a negative normal along `k` means the
    // polygon runs clockwise in that plane, so the two swap.
    let k = size.max_position();
    let (u, v) = ((k + 1) % 3, (k + 2) % 3);
    let (u, v) = if normal[k] < 0.0 { (v, u) } else { (u, v) };
    Some(c.iter().map(|p| DVec2::new(p[u], p[v])).collect())
}

/// Twice the signed area of the triangle `a b c`: positive where it turns
/// counter-clockwise.
fn turn(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// A polygon's outline as a ring of the corners not yet clipped.
struct Ring<'a> {
    at: &'a [DVec2],
    prev: Vec<usize>,
    next: Vec<usize>,
    /// Corners in the ring.
    len: usize,
    /// The corners that were reflex at the start, by place: the only
    /// corners that can lie inside an ear (clipping an ear can only make
    /// its neighbours convex, never reflex), so the only ones an ear test
    /// looks at, those near the ear.
    reflex: Grid,
    gone: Vec<bool>,
}

impl<'a> Ring<'a> {
    fn new(at: &'a [DVec2]) -> Self {
        let n = at.len();
        let prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
        let next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
        let reflex: Vec<usize> = (0..n).filter(|&i| turn(at[prev[i]], at[i], at[next[i]]) <= 0.0).collect();
        Self { at, prev, next, len: n, reflex: Grid::new(at, &reflex), gone: vec![false; n] }
    }

    /// Whether `p b q` (consecutive corners) turns the polygon's way and
    /// holds no other corner of the ring, on its edges included.
    fn is_ear(&self, p: usize, b: usize, q: usize) -> bool {
        let (a, m, c) = (self.at[p], self.at[b], self.at[q]);
        if turn(a, m, c) <= 0.0 {
            return false;
        }
        let inside = |r: usize| {
            let x = self.at[r];
            !self.gone[r]
                && r != p
                && r != b
                && r != q
                && x != a
                && x != m
                && x != c
                && turn(a, m, x) >= 0.0
                && turn(m, c, x) >= 0.0
                && turn(c, a, x) >= 0.0
                // Still reflex (else it cannot be inside without a reflex
                // corner inside too).
                && turn(self.at[self.prev[r]], x, self.at[self.next[r]]) <= 0.0
        };
        !self.reflex.near(a.min(m).min(c), a.max(m).max(c)).any(inside)
    }

    fn remove(&mut self, b: usize) {
        let (p, q) = (self.prev[b], self.next[b]);
        self.next[p] = q;
        self.prev[q] = p;
        self.gone[b] = true;
        self.len -= 1;
    }

    /// The ring's corners in order, from `start`.
    fn corners_from(&self, start: usize) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.len);
        let mut i = start;
        for _ in 0..self.len {
            out.push(i);
            i = self.next[i];
        }
        out
    }
}

/// Corners bucketed in a square grid over their bounding box, about two
/// to a cell, so that an ear test visits the few near the ear: a polygon
/// of many corners in a line (a circle's, within rounding) has as many
/// reflex corners as convex ones.
struct Grid {
    min: DVec2,
    /// Cells per unit along each axis.
    scale: DVec2,
    side: usize,
    /// Cell `i`'s corners are `items[start[i]..start[i + 1]]`.
    start: Vec<usize>,
    items: Vec<usize>,
}

impl Grid {
    fn new(at: &[DVec2], corners: &[usize]) -> Self {
        let (mut min, mut max) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &i in corners {
            min = min.min(at[i]);
            max = max.max(at[i]);
        }
        // At most 2^20 cells; `as` saturates, and the square root of a
        // count is far below `usize::MAX`.
        let side = ((corners.len() as f64 / 2.0).sqrt().ceil() as usize).clamp(1, 1024);
        let size = max - min;
        let per = |s: f64| if s > 0.0 { side as f64 / s } else { 0.0 };
        let mut grid = Self {
            min,
            scale: DVec2::new(per(size.x), per(size.y)),
            side,
            start: vec![0; side * side + 1],
            items: vec![],
        };
        let cells: Vec<usize> = corners.iter().map(|&i| grid.cell(at[i])).collect();
        for &c in &cells {
            grid.start[c + 1] += 1;
        }
        for i in 1..grid.start.len() {
            grid.start[i] += grid.start[i - 1];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![0; corners.len()];
        for (&i, &c) in corners.iter().zip(&cells) {
            grid.items[fill[c]] = i;
            fill[c] += 1;
        }
        grid
    }

    /// Column and row of `p`, clamped to the grid.
    fn column_row(&self, p: DVec2) -> (usize, usize) {
        let last = (self.side - 1) as f64;
        // `as` maps NaN to 0 and saturates; the clamp keeps it in range.
        let f = ((p - self.min) * self.scale).clamp(DVec2::ZERO, DVec2::splat(last));
        (f.x as usize, f.y as usize)
    }

    fn cell(&self, p: DVec2) -> usize {
        let (x, y) = self.column_row(p);
        y * self.side + x
    }

    /// The corners in the cells that the box `lo..hi` meets.
    fn near(&self, lo: DVec2, hi: DVec2) -> impl Iterator<Item = usize> + '_ {
        let ((x0, y0), (x1, y1)) = (self.column_row(lo), self.column_row(hi));
        (y0..=y1).flat_map(move |y| {
            let row = y * self.side;
            self.items[self.start[row + x0]..self.start[row + x1 + 1]].iter().copied()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Twice the area of a triangle in 3D.
    fn area(c: &[Vec3], t: [u32; 3]) -> f64 {
        let [a, b, d] = t.map(|i| c[i as usize].as_dvec3());
        (b - a).cross(d - a).length()
    }

    /// The triangles' areas add up to the polygon's, every triangle turns
    /// the polygon's way, and there are `n - 2` of them.
    fn check_cover(c: &[Vec3], tris: &[[u32; 3]], normal: Vec3) {
        assert_eq!(tris.len(), c.len() - 2);
        let polygon = {
            let d: Vec<DVec3> = c.iter().map(|p| p.as_dvec3()).collect();
            let mut s = DVec3::ZERO;
            for i in 0..d.len() {
                s += d[i].cross(d[(i + 1) % d.len()]);
            }
            s.length()
        };
        let sum: f64 = tris.iter().map(|&t| area(c, t)).sum();
        assert!((sum - polygon).abs() <= 1e-6 * polygon.max(1.0), "area {sum} against {polygon}");
        for &t in tris {
            let [a, b, d] = t.map(|i| c[i as usize].as_dvec3());
            assert!((b - a).cross(d - a).dot(normal.as_dvec3()) > 0.0, "{t:?} is wound backwards");
        }
    }

    #[test]
    fn fewer_than_four_corners() {
        assert!(triangulate(&[]).is_empty());
        assert!(triangulate(&[Vec3::ZERO, Vec3::X]).is_empty());
        assert_eq!(triangulate(&[Vec3::ZERO, Vec3::X, Vec3::Y]), vec![[0, 1, 2]]);
    }

    #[test]
    fn a_convex_quad_is_cut_as_a_fan_cuts_it() {
        let q = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        assert_eq!(triangulate(&q), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn a_dart_is_cut_along_its_inside_diagonal() {
        // Corner 1 is reflex: the fan's diagonal 0-2 would lie outside.
        let q = [Vec3::ZERO, Vec3::new(1.0, 0.0, 0.3), Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 2.0)];
        let t = triangulate(&q);
        check_cover(&q, &t, Vec3::NEG_Y);
        assert!(t.iter().all(|t| t.contains(&1) && t.contains(&3)), "{t:?}");
    }

    #[test]
    fn a_u_shape_leaves_its_notch_open() {
        // The U of a floor seen from above (+Y), wound counter-clockwise
        // from above; no triangle may cover the notch's middle (1.5, 2).
        let xz = [(0., 0.), (0., 3.), (1., 3.), (1., 1.), (2., 1.), (2., 3.), (3., 3.), (3., 0.)];
        let c: Vec<Vec3> = xz.iter().map(|&(x, z)| Vec3::new(x, 0.0, z)).collect();
        let t = triangulate(&c);
        check_cover(&c, &t, Vec3::Y);
        let notch = DVec2::new(1.5, 2.0);
        for tri in &t {
            let [a, b, d] = tri.map(|i| DVec2::new(f64::from(c[i as usize].x), f64::from(c[i as usize].z)));
            let s = [turn(a, b, notch), turn(b, d, notch), turn(d, a, notch)];
            assert!(!(s.iter().all(|&x| x > 0.0) || s.iter().all(|&x| x < 0.0)), "{tri:?} covers the notch");
        }
    }

    #[test]
    fn a_many_cornered_disc_has_no_fan() {
        let n = 1000;
        let c: Vec<Vec3> = (0..n)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / n as f32;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let t = triangulate(&c);
        check_cover(&c, &t, Vec3::Z);
        // A fan puts every triangle at one corner; ear clipping every other
        // corner puts no corner in more than a few dozen (log2 n levels).
        let mut uses = vec![0; n];
        for tri in &t {
            for &i in tri {
                uses[i as usize] += 1;
            }
        }
        let most = uses.iter().copied().max().unwrap_or(0);
        assert!(most <= 2 * 10 + 2, "a corner is in {most} triangles");
    }

    #[test]
    fn corners_in_one_line_give_a_fan_of_flat_triangles() {
        let c = [Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)];
        assert_eq!(triangulate(&c), vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn a_square_with_a_hole_through_a_keyhole_cut() {
        // Exporters write a face with a hole as one outline that runs
        // in along a cut, around the hole the other way, and back out.
        let xy = [
            (0., 0.),
            (4., 0.),
            (4., 4.),
            (0., 4.),
            (0., 0.),
            (1., 1.),
            (1., 3.),
            (3., 3.),
            (3., 1.),
            (1., 1.),
        ];
        let c: Vec<Vec3> = xy.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
        let t = triangulate(&c);
        check_cover(&c, &t, Vec3::Z);
        let hole = DVec2::new(2.0, 2.0);
        for tri in &t {
            let [a, b, d] = tri.map(|i| c[i as usize].truncate().as_dvec2());
            assert!(!(turn(a, b, hole) > 0.0 && turn(b, d, hole) > 0.0 && turn(d, a, hole) > 0.0), "{tri:?}");
        }
    }

    #[test]
    fn a_bow_tie_still_gives_two_triangles() {
        let c = [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::X, Vec3::Y];
        let t = triangulate(&c);
        assert_eq!(t.len(), 2);
        for tri in t {
            assert!(tri.iter().all(|&i| i < 4));
        }
    }

    proptest! {
        /// Star-shaped polygons (one corner per angle, at random radii,
        /// tilted into a random plane) are cut into triangles that cover
        /// them exactly, all wound as the polygon.
        #[test]
        fn star_polygons_are_covered(
            radii in prop::collection::vec(0.2f32..2.0, 4..40),
            tilt in (-1.0f32..1.0, -1.0f32..1.0, 0.2f32..1.0),
        ) {
            let n = radii.len();
            let normal = Vec3::new(tilt.0, tilt.1, tilt.2).normalize();
            let u = normal.any_orthonormal_vector();
            let v = normal.cross(u);
            let c: Vec<Vec3> = radii
                .iter()
                .enumerate()
                .map(|(i, &r)| {
                    let a = std::f32::consts::TAU * i as f32 / n as f32;
                    r * (a.cos() * u + a.sin() * v)
                })
                .collect();
            let t = triangulate(&c);
            check_cover(&c, &t, normal);
            let mut seen = vec![false; n];
            for tri in &t {
                for &i in tri {
                    seen[i as usize] = true;
                }
            }
            prop_assert!(seen.iter().all(|&s| s));
        }
    }
}
