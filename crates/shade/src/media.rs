//! Nested dielectrics: the media a ray is inside.
//!
//! A medium is a closed solid whose material has `transmission > 0` (glass,
//! water): it has an inside, a refractive index and an absorption. A ray
//! carries the media it has entered and not left ([`Media`]), so that
//! refraction at a surface bends between the solid's index and the one
//! around it, and Beer–Lambert absorption applies to every segment inside a
//! solid, whatever the segment ends on.
//!
//! A solid inside another replaces it: where a ray is inside both, the
//! inner one's index and absorption hold (a clear air bubble in green glass
//! is clear, and bends light as air in glass does). Where solids overlap
//! rather than nest, the one entered last along the ray holds, and the
//! surface of an earlier one inside it does not bend the ray (a liquid
//! reaching into its glass wall). A shadow segment's crossings come
//! unordered from the acceleration structure: [`optical_depth`] sorts them
//! and applies the same rule.
//!
//! A camera ray starts in the media that hold its origin ([`CameraMedia`]):
//! a camera inside green glass sees what is in the glass green, and
//! refraction at the glass's inner surface bends into what is around it.
//! Which solids hold a point is found by a ray from it ([`media_at`]), once
//! per render for a pinhole's eye; for a thin lens or an orthographic view
//! only the media whose boxes meet the rectangle of the rays' origins are
//! tested, per ray, those of the origin's cell of a grid over it
//! ([`OriginGrid`]); a camera whose origins meet no medium's box costs
//! nothing per ray. An area light
//! seen from inside an absorbing medium is absorbed along the way as the
//! light it casts is.

use crate::{Projection, RenderSettings, Scene};
use prism_bvh::Object;
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Intersect, Ray};

/// The media a ray is inside, in the order it entered them (the innermost
/// last). Only the innermost [`Media::KEPT`] are kept.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Media {
    ids: [u32; Media::KEPT],
    len: usize,
    /// Bit `k` set: slot `k`'s medium holds the path's start (a camera
    /// inside glass), which entered it without crossing its surface
    /// ([`Media::at_start`]).
    at_start: u8,
}

impl Media {
    /// Media followed; more only in deep nesting, where entering another
    /// forgets the outermost.
    pub(crate) const KEPT: usize = 8;

    /// The innermost medium: the one the ray travels in.
    #[inline]
    pub(crate) fn innermost(&self) -> Option<u32> {
        self.len.checked_sub(1).and_then(|k| self.ids.get(k).copied())
    }

    /// The innermost medium other than `object`: the one around it, which a
    /// ray leaving `object` goes into and one entering it comes from.
    #[inline]
    pub(crate) fn around(&self, object: u32) -> Option<u32> {
        self.ids[..self.len].iter().rev().find(|&&i| i != object).copied()
    }

    /// Whether the ray is inside `object` (as far as it knows).
    #[inline]
    pub(crate) fn contains(&self, object: u32) -> bool {
        self.ids[..self.len].contains(&object)
    }

    /// Whether the ray is inside `object` without having crossed its
    /// surface: the path started in it ([`Media::at_start`]) and has not
    /// left it since.
    #[inline]
    pub(crate) fn started_in(&self, object: u32) -> bool {
        self.ids[..self.len].iter().rposition(|&i| i == object).is_some_and(|k| self.at_start >> k & 1 == 1)
    }

    /// These media, each marked as holding the path's start (entered
    /// without crossing a surface): a camera ray's starting media.
    #[inline]
    #[must_use]
    pub(crate) fn at_start(mut self) -> Self {
        self.at_start = ((1u32 << self.len) - 1) as u8;
        self
    }

    /// These media and then `object`, entered through its surface.
    #[inline]
    #[must_use]
    pub(crate) fn entered(mut self, object: u32) -> Self {
        if self.len == Self::KEPT {
            self.ids.copy_within(1.., 0);
            self.at_start >>= 1;
            self.len -= 1;
        }
        self.ids[self.len] = object;
        self.at_start &= !(1 << self.len);
        self.len += 1;
        self
    }

    /// These media without `object` (the last time it was entered), left
    /// through its surface. Leaving a medium the ray was not known to be
    /// in (one forgotten in deep nesting) changes nothing.
    #[inline]
    #[must_use]
    pub(crate) fn left(mut self, object: u32) -> Self {
        if let Some(k) = self.ids[..self.len].iter().rposition(|&i| i == object) {
            self.ids.copy_within(k + 1..self.len, k);
            let below = (1u16 << k) - 1;
            self.at_start =
                ((u16::from(self.at_start) & below) | (u16::from(self.at_start) >> 1 & !below)) as u8;
            self.len -= 1;
        }
        self
    }
}

impl PartialEq for Media {
    /// The same media in the same order (slots past `len` are stale),
    /// whether or not the path started in them.
    fn eq(&self, other: &Self) -> bool {
        self.ids[..self.len] == other.ids[..other.len]
    }
}

/// A segment's crossing of a medium's surface: its ray parameter, the
/// medium, and whether the segment enters it there (front face).
pub(crate) type MediumCrossing = (f32, u32, bool);

/// Whether `object` is a medium: a closed solid of a dielectric material
/// (`transmission > 0`), with an inside that has an index and absorption.
#[inline]
pub(crate) fn is_medium(scene: &Scene, object: u32) -> bool {
    scene.material_of(object).transmission > 0.0 && scene.is_closed(object)
}

/// The media a segment starts in, outermost first, given its crossings of
/// media's surfaces sorted by distance: those it leaves before it enters
/// them (the first left is the innermost; only the innermost
/// [`Media::KEPT`] are kept).
fn started_in(crossings: &[MediumCrossing]) -> Media {
    let mut entered = Media::default();
    let (mut started, mut n) = ([0u32; Media::KEPT], 0);
    for &(_, object, front) in crossings {
        if front {
            entered = entered.entered(object);
        } else if entered.contains(object) {
            entered = entered.left(object);
        } else if let Some(s) = started.get_mut(n) {
            *s = object;
            n += 1;
        }
    }
    started[..n].iter().rev().fold(Media::default(), |media, &object| media.entered(object))
}

/// The direction of the ray that finds which solids hold a point: along
/// no axis and no diagonal, so that from a point on a grid it runs through
/// no edge or corner of an axis-aligned box or a mesh. Only the order of
/// the crossings along it counts, so it need not be of unit length.
const INSIDE_TEST: Vec3 = Vec3::new(0.381_966, 0.618_034, 0.687_122);

/// The media that hold the point `p`, of the `candidates` (each an
/// object with how far along the test ray from `p` its box reaches),
/// outermost first ([`Media`]; the innermost [`Media::KEPT`] of them): a
/// solid whose nearest crossing along a ray from `p` is a back face (the
/// ray leaves it there) holds `p`, and of several the one left first is
/// the innermost. Each candidate is tested alone
/// ([`prism_bvh::Accel::first_crossing_of`]), so that the cost is that of
/// the candidates, not of every solid the test ray passes on the way.
/// Candidates that are not media are skipped. `exits` is scratch space.
pub(crate) fn media_at(
    scene: &Scene,
    p: Vec3,
    candidates: impl IntoIterator<Item = (u32, f32)>,
    exits: &mut Vec<MediumCrossing>,
) -> Media {
    exits.clear();
    for (object, reach) in candidates {
        if !is_medium(scene, object) {
            continue;
        }
        let test = Ray::with_interval(p, INSIDE_TEST, 0.0, reach);
        if let Some(c) = scene.accel.first_crossing_of(object, &test).filter(|c| !c.front_face) {
            exits.push((c.t, object, false));
        }
    }
    // The farthest exit (outermost) first, so that entering them in turn
    // keeps the innermost.
    exits.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    exits.iter().fold(Media::default(), |media, c| media.entered(c.1))
}

/// The media camera rays start in, found once per render: most cameras
/// are in none, and their rays start with no media at no cost per ray.
pub(crate) enum CameraMedia {
    /// Every camera ray starts in these: a pinhole's eye is in them, or no
    /// medium comes near any ray's origin.
    Fixed(Media),
    /// The origins vary (a thin lens, an orthographic view) and some
    /// media's world boxes (padded) meet the rectangle that holds them.
    PerRay {
        /// Those media's boxes, by object (`None` for every other object).
        boxes: Vec<Option<Aabb>>,
        /// The same media by where their boxes fall on the rectangle.
        grid: OriginGrid,
    },
}

impl CameraMedia {
    /// The media the camera rays of `settings` start in, in `scene`.
    pub(crate) fn new(scene: &Scene, settings: &RenderSettings) -> Self {
        let cam = &settings.camera;
        // Filtered samples reach up to the filter's radius past a pixel.
        let origins = cam.origin_rect(settings.antialias.filter.radius() + 1.0);
        let n = scene.accel.objects().len();
        let mut boxes: Vec<Option<Aabb>> = Vec::new();
        let mut near = Vec::new();
        for i in (0..n as u32).filter(|&i| is_medium(scene, i)) {
            let Some(b) = world_bounds(scene, i).map(padded) else { continue };
            if rect_meets_box(&origins, &b) {
                boxes.resize(n, None);
                boxes[i as usize] = Some(b);
                near.push((i, b));
            }
        }
        if near.is_empty() {
            return Self::Fixed(Media::default());
        }
        let per_ray = Self::PerRay { boxes, grid: OriginGrid::new(&origins, &near) };
        if cam.projection() == Projection::Perspective && cam.aperture() == 0.0 {
            return Self::Fixed(per_ray.at(scene, cam.position(), &mut Vec::new()));
        }
        per_ray
    }

    /// The media every camera ray starts in, where they all start in the
    /// same.
    #[inline]
    pub(crate) fn fixed(&self) -> Option<&Media> {
        match self {
            Self::Fixed(media) => Some(media),
            Self::PerRay { .. } => None,
        }
    }

    /// The media a camera ray from `origin` starts in; `scratch` is
    /// scratch space. Called per ray only for [`CameraMedia::PerRay`]
    /// (rare, hence cold: [`CameraMedia::fixed`] serves the rest): the
    /// boxes of the origin's grid cell are tested, and the solid of each
    /// box that holds the origin is tested alone ([`media_at`]).
    #[cold]
    pub(crate) fn at(&self, scene: &Scene, origin: Vec3, scratch: &mut Vec<MediumCrossing>) -> Media {
        match self {
            Self::Fixed(media) => *media,
            Self::PerRay { boxes, grid } => {
                // The media of the origin's cell whose boxes hold it, each
                // with where the test ray leaves its box.
                let test = Ray::new(origin, INSIDE_TEST);
                let holding = grid.cell(origin).iter().filter_map(|&o| {
                    let b = boxes.get(o as usize).copied().flatten().filter(|b| b.contains(origin, 0.0))?;
                    b.intersect_ray(&test).map(|(_, out)| (o, out))
                });
                media_at(scene, origin, holding, scratch).at_start()
            }
        }
    }
}

/// Media by where their boxes fall on the camera's origin rectangle: a
/// grid of cells over the rectangle's two sides, each listing the media
/// whose box, projected onto the rectangle, reaches the cell. An origin
/// is tested against its cell's boxes only, a handful however many media
/// the rectangle meets.
pub(crate) struct OriginGrid {
    centre: Vec3,
    /// The rectangle's sides, unit (zero where it has no extent), and
    /// their half-lengths.
    axes: [Vec3; 2],
    half: [f32; 2],
    /// Cells along each side.
    side: usize,
    /// Cell `k` lists `ids[starts[k]..starts[k + 1]]`.
    starts: Vec<u32>,
    ids: Vec<u32>,
}

impl OriginGrid {
    fn new(rect: &[Vec3; 3], near: &[(u32, Aabb)]) -> Self {
        let [centre, hu, hv] = *rect;
        let axes = [hu.normalize_or_zero(), hv.normalize_or_zero()];
        let half = [hu.length(), hv.length()];
        // About one box a cell, at most 256 × 256 cells; fewer where large
        // boxes would be listed in so many cells that the lists outgrow a
        // few entries a box.
        let mut side = ((near.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
        let (grid, spans) = loop {
            let grid = Self { centre, axes, half, side, starts: Vec::new(), ids: Vec::new() };
            // Each box's cells, from its corners' places on the rectangle.
            let spans: Vec<[std::ops::RangeInclusive<usize>; 2]> = near
                .iter()
                .map(|(_, b)| {
                    let corners = b.corners();
                    let span = |a: usize| {
                        let along = corners.iter().map(|&c| (c - centre).dot(grid.axes[a]));
                        let (lo, hi) =
                            along.fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), x| (l.min(x), h.max(x)));
                        grid.index(a, lo)..=grid.index(a, hi)
                    };
                    [span(0), span(1)]
                })
                .collect();
            let listed: usize = spans.iter().map(|[u, v]| u.clone().count() * v.clone().count()).sum();
            if side == 1 || listed <= 8 * near.len() + 4096 {
                break (grid, spans);
            }
            side /= 2;
        };
        let side = grid.side;
        let mut counts = vec![0u32; side * side + 1];
        for [su, sv] in &spans {
            for j in sv.clone() {
                for i in su.clone() {
                    counts[j * side + i + 1] += 1;
                }
            }
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let mut ids = vec![0u32; counts[side * side] as usize];
        let mut fill = counts.clone();
        for ((object, _), [su, sv]) in near.iter().zip(&spans) {
            for j in sv.clone() {
                for i in su.clone() {
                    let at = &mut fill[j * side + i];
                    ids[*at as usize] = *object;
                    *at += 1;
                }
            }
        }
        Self { starts: counts, ids, ..grid }
    }

    /// The cell index along side `a` of the point `x` along it from the
    /// centre (clamped to the grid).
    fn index(&self, a: usize, x: f32) -> usize {
        if self.half[a] <= 0.0 || x.is_nan() {
            return 0;
        }
        let f = (x / self.half[a] + 1.0) * 0.5 * self.side as f32;
        (f.max(0.0) as usize).min(self.side - 1)
    }

    /// The media listed in the cell of origin `p`.
    fn cell(&self, p: Vec3) -> &[u32] {
        let d = p - self.centre;
        let k = self.index(1, d.dot(self.axes[1])) * self.side + self.index(0, d.dot(self.axes[0]));
        let (from, to) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        self.ids.get(from..to).unwrap_or_default()
    }
}

/// Whether the rectangle `[centre, half_u, half_v]` (half-sides at right
/// angles, [`crate::Camera::origin_rect`]) may meet box `b`: no separating
/// axis among the world's three, the rectangle's normal and its sides
/// (the edge-by-edge axes are not tried, so a few rectangles near a
/// box's edge are taken to meet it: the caller then tests more, never
/// less).
fn rect_meets_box(rect: &[Vec3; 3], b: &Aabb) -> bool {
    let [centre, hu, hv] = *rect;
    let half = b.extent() * 0.5;
    let d = b.center() - centre;
    let apart =
        |axis: Vec3| d.dot(axis).abs() > half.dot(axis.abs()) + hu.dot(axis).abs() + hv.dot(axis).abs();
    ![
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        hu.cross(hv).normalize_or_zero(),
        hu.normalize_or_zero(),
        hv.normalize_or_zero(),
    ]
    .into_iter()
    .any(|axis| axis != Vec3::ZERO && apart(axis))
}

/// The world box of object `object`, if it has one.
fn world_bounds(scene: &Scene, object: u32) -> Option<Aabb> {
    Some(match scene.accel.objects().get(object as usize)? {
        Object::Shape(s) => s.bounds(),
        Object::Mesh { mesh, transform } => {
            transform.aabb(&scene.accel.meshes().get(*mesh as usize)?.bounds())
        }
    })
}

/// `b` grown on every side by a ten-thousandth of its largest coordinate,
/// past the rounding of its corners and of the camera's origins.
fn padded(b: Aabb) -> Aabb {
    let pad = Vec3::splat(1e-4 * b.min.abs().max(b.max.abs()).max_element());
    Aabb::new(b.min - pad, b.max + pad)
}

/// Optical depth `Σ absorption · length` of the segment `[0, end]` of a
/// unit-direction ray whose crossings of media's surfaces are `crossings`
/// (any order; sorted here), each medium's absorption given by
/// `absorption`. Each stretch is absorbed by the innermost medium there.
/// Media left before they are entered are those the segment starts in; the
/// first left is the innermost. A segment that ends inside an absorbing
/// medium with `end` infinite (a sun seen from inside glass) has an
/// infinite depth in its absorbing channels.
pub(crate) fn optical_depth(
    crossings: &mut [MediumCrossing],
    end: f32,
    absorption: impl Fn(u32) -> Vec3,
) -> Vec3 {
    crossings.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let mut media = started_in(crossings);
    let mut tau = Vec3::ZERO;
    let mut from = 0.0f32;
    let mut add = |media: &Media, to: f32| {
        if let Some(m) = media.innermost() {
            // `max(0)`: a crossing nearer than the ray's start (its offset)
            // adds nothing; per channel, so that a zero absorption over an
            // infinite stretch is 0, not NaN.
            let len = (to - from).max(0.0);
            tau += Vec3::from_array(absorption(m).to_array().map(|a| if a > 0.0 { a * len } else { 0.0 }));
        }
        from = from.max(to);
    };
    for &(t, object, front) in crossings.iter() {
        add(&media, t);
        media = if front { media.entered(object) } else { media.left(object) };
    }
    add(&media, end);
    tau
}

#[cfg(test)]
mod tests {
    use super::{CameraMedia, Media, media_at, optical_depth};
    use crate::{Camera, Material, Projection, RenderSettings, Scene};
    use prism_bvh::{Accel, Object};
    use prism_geometry::glam::Vec3;
    use prism_geometry::{Aabb, Cuboid, Instance, Shape, Sphere, Transform};

    #[test]
    fn media_nest_and_unnest() {
        let m = Media::default().entered(3).entered(5);
        assert_eq!(m.innermost(), Some(5));
        assert_eq!(m.around(5), Some(3));
        assert_eq!(m.around(3), Some(5));
        assert_eq!(m.around(7), Some(5));
        assert!(m.contains(3) && m.contains(5) && !m.contains(7));
        assert_eq!(m.left(5).innermost(), Some(3));
        assert_eq!(m.left(5).left(3), Media::default());
        // Overlapping solids: leaving the outer one keeps the inner.
        assert_eq!(m.left(3).innermost(), Some(5));
        assert_eq!(m.left(3).around(5), None);
        // A medium not entered (one forgotten): nothing to leave.
        assert_eq!(m.left(9), m);
        assert_eq!(Media::default().innermost(), None);
        assert_eq!(Media::default().around(1), None);
    }

    #[test]
    fn media_the_path_started_in_stay_marked_until_left() {
        let m = Media::default().entered(0).entered(1).entered(2).at_start().entered(3);
        assert!(m.started_in(0) && m.started_in(1) && m.started_in(2) && !m.started_in(3));
        // Leaving the middle one keeps the others' marks in their slots.
        let m = m.left(1);
        assert!(m.started_in(0) && !m.started_in(1) && m.started_in(2) && !m.started_in(3));
        // Entered again through its surface: no longer started in.
        let m = m.entered(1).entered(4);
        assert!(!m.started_in(1) && m.started_in(2));
        // Deep nesting forgets the outermost, and the marks move with the rest.
        let mut deep = (0..Media::KEPT as u32).fold(Media::default(), Media::entered).at_start();
        deep = deep.entered(99);
        assert!(
            !deep.started_in(0)
                && (1..Media::KEPT as u32).all(|k| deep.started_in(k))
                && !deep.started_in(99)
        );
        assert_eq!(deep, (1..Media::KEPT as u32).chain([99]).fold(Media::default(), Media::entered));
    }

    #[test]
    fn deep_nesting_forgets_the_outermost() {
        let mut m = Media::default();
        for k in 0..Media::KEPT as u32 + 2 {
            m = m.entered(k);
        }
        assert_eq!(m.innermost(), Some(Media::KEPT as u32 + 1));
        let mut depth = 0;
        while let Some(k) = m.innermost() {
            m = m.left(k);
            depth += 1;
        }
        assert_eq!(depth, Media::KEPT);
    }

    fn absorption(object: u32) -> Vec3 {
        match object {
            0 => Vec3::new(1.0, 0.0, 2.0),
            1 => Vec3::splat(0.5),
            _ => Vec3::ZERO,
        }
    }

    #[test]
    fn the_innermost_medium_absorbs_each_stretch() {
        // Outer 0 over [1, 9], inner clear 2 over [3, 5], inner 1 over [6, 8]:
        // 0 absorbs 1..3, 5..6 and 8..9 (length 4), 1 absorbs 6..8 (2).
        let mut c = [
            (9.0, 0, false),
            (3.0, 2, true),
            (6.0, 1, true),
            (1.0, 0, true),
            (8.0, 1, false),
            (5.0, 2, false),
        ];
        let tau = optical_depth(&mut c, 20.0, absorption);
        assert_eq!(tau, 4.0 * absorption(0) + 2.0 * absorption(1));
        // The order the crossings come in does not matter.
        c.reverse();
        assert_eq!(optical_depth(&mut c, 20.0, absorption), tau);
    }

    #[test]
    fn a_segment_starting_inside_nested_media() {
        // Starts inside 1 inside 0: leaves 1 at 2, then 0 at 5.
        let mut c = [(5.0, 0, false), (2.0, 1, false)];
        assert_eq!(optical_depth(&mut c, 10.0, absorption), 2.0 * absorption(1) + 3.0 * absorption(0));
        // Ends inside 0 (the light is in the glass): up to the end.
        let mut c = [(4.0, 0, true)];
        assert_eq!(optical_depth(&mut c, 10.0, absorption), 6.0 * absorption(0));
        // Toward a sun: absorbing channels infinite, the clear one 0.
        let tau = optical_depth(&mut c, f32::INFINITY, absorption);
        assert_eq!((tau.x, tau.y, tau.z), (f32::INFINITY, 0.0, f32::INFINITY));
        assert_eq!(optical_depth(&mut [], 10.0, absorption), Vec3::ZERO);
    }

    /// Glass balls 0 (radius 4) and 1 (radius 2) about the origin, 2
    /// (radius 1) at x = 6; an opaque box 3 about the origin; an opaque
    /// ball 4 at x = −6.
    fn nested() -> Scene {
        let glass = Material { transmission: 1.0, ior: 1.5, ..Material::diffuse(Vec3::ONE) };
        let ball = |c: Vec3, r: f32| Shape::from(Sphere::new(c, r).expect("valid sphere"));
        let shapes = [
            ball(Vec3::ZERO, 4.0),
            ball(Vec3::ZERO, 2.0),
            ball(Vec3::new(6.0, 0.0, 0.0), 1.0),
            Cuboid::new(Vec3::splat(-3.0), Vec3::splat(3.0)).expect("valid cuboid").into(),
            ball(Vec3::new(-6.0, 0.0, 0.0), 1.0),
        ];
        let objects =
            shapes.into_iter().map(|s| Object::Shape(Instance::new(s, Transform::IDENTITY))).collect();
        Scene {
            object_materials: vec![0, 0, 0, 1, 1],
            materials: vec![glass, Material::diffuse(Vec3::ONE)],
            ..scene_of(objects)
        }
    }

    /// A scene of `objects`, all of material 0 (white, diffuse), no lights.
    fn scene_of(objects: Vec<Object>) -> Scene {
        let n = objects.len();
        Scene {
            accel: Accel::build(Vec::new(), objects).expect("no meshes"),
            object_materials: vec![0; n],
            materials: vec![Material::diffuse(Vec3::ONE)],
            lights: Vec::new(),
            ambient: Vec3::ZERO,
            background: Vec3::ZERO,
            environment: None,
            fog: None,
        }
    }

    /// Every object of `scene` as a candidate of [`media_at`], its test
    /// ray reaching as far as `reach`.
    fn all(scene: &Scene, reach: f32) -> impl Iterator<Item = (u32, f32)> {
        (0..scene.accel.objects().len() as u32).map(move |o| (o, reach))
    }

    fn media(ids: &[u32]) -> Media {
        ids.iter().fold(Media::default(), |m, &i| m.entered(i))
    }

    #[test]
    fn a_point_is_in_the_media_that_hold_it_outermost_first() {
        let scene = nested();
        let at = |p: Vec3| media_at(&scene, p, all(&scene, f32::INFINITY), &mut Vec::new());
        assert_eq!(at(Vec3::new(0.5, -0.3, 0.2)), media(&[0, 1]));
        assert_eq!(at(Vec3::new(0.0, 3.0, 0.0)), media(&[0]));
        assert_eq!(at(Vec3::new(6.2, 0.1, 0.0)), media(&[2]));
        // Opaque solids are no media; outside every solid, none.
        assert_eq!(at(Vec3::new(-6.0, 0.0, 0.0)), Media::default());
        assert_eq!(at(Vec3::new(0.0, 0.0, 9.0)), Media::default());
        // Only the candidates count.
        assert_eq!(
            media_at(&scene, Vec3::ZERO, all(&scene, f32::INFINITY).filter(|c| c.0 != 0), &mut Vec::new()),
            media(&[1])
        );
        // Not as far as the big ball's far side: only the small one is left.
        assert_eq!(media_at(&scene, Vec3::ZERO, all(&scene, 3.0), &mut Vec::new()), media(&[1]));
    }

    /// Ten glass balls about the origin, radii 1 to 10 (object k has
    /// radius 10 − k).
    fn onion() -> Scene {
        let glass = Material { transmission: 1.0, ior: 1.5, ..Material::diffuse(Vec3::ONE) };
        let objects = (0..10)
            .map(|k| {
                let ball = Sphere::new(Vec3::ZERO, 10.0 - k as f32).expect("valid sphere");
                Object::Shape(Instance::new(Shape::from(ball), Transform::IDENTITY))
            })
            .collect();
        Scene { object_materials: vec![0; 10], materials: vec![glass], ..scene_of(objects) }
    }

    #[test]
    fn a_point_beside_many_nested_solids_is_in_none_and_one_inside_them_in_the_innermost() {
        let scene = onion();
        let at = |p: Vec3| media_at(&scene, p, all(&scene, f32::INFINITY), &mut Vec::new());
        // Outside all ten; the test ray enters all ten before it leaves any.
        let outside = Vec3::new(-12.0, -12.0, -12.0) * super::INSIDE_TEST.normalize();
        assert_eq!(at(outside), Media::default());
        // Inside all ten: the innermost eight, outermost first.
        assert_eq!(at(Vec3::splat(0.1)), media(&[2, 3, 4, 5, 6, 7, 8, 9]));
        // Between the radii 5 and 6: the five outer balls.
        assert_eq!(at(Vec3::new(5.5, 0.0, 0.0)), media(&[0, 1, 2, 3, 4]));
    }

    fn settings(camera: Camera) -> RenderSettings {
        RenderSettings {
            camera,
            fog: false,
            spp: 1,
            max_depth: 1,
            min_contribution: 0.0,
            threads: Some(1),
            antialias: crate::Antialias::default(),
        }
    }

    #[test]
    fn camera_rays_start_in_the_media_found_once_where_they_can() {
        let scene = nested();
        let cam = |eye: Vec3| Camera::new(eye, eye + Vec3::Z, Vec3::Y, 40.0, 8, 6).expect("valid camera");
        let fixed = |eye: Vec3| match CameraMedia::new(&scene, &settings(cam(eye))) {
            CameraMedia::Fixed(m) => m,
            CameraMedia::PerRay { .. } => panic!("a pinhole's media are found once"),
        };
        // A pinhole: once, whether in media or not.
        assert_eq!(fixed(Vec3::new(0.5, 0.0, 0.0)), media(&[0, 1]));
        assert_eq!(fixed(Vec3::new(20.0, 0.0, 0.0)), Media::default());
        // Origins that vary, no medium's box near them: none, once.
        let far = cam(Vec3::new(20.0, 0.0, 0.0)).with_lens(0.5, 3.0).expect("valid lens");
        assert!(
            matches!(CameraMedia::new(&scene, &settings(far)), CameraMedia::Fixed(m) if m == Media::default())
        );
        // A lens by the small ball: only it is tested, per ray.
        let lens = cam(Vec3::new(6.0, 0.0, 0.0)).with_lens(0.5, 3.0).expect("valid lens");
        let per_ray = CameraMedia::new(&scene, &settings(lens));
        assert_eq!(tested(&per_ray), [2], "a lens's media are found per ray");
        let mut scratch = Vec::new();
        assert_eq!(per_ray.at(&scene, Vec3::new(6.3, 0.2, 0.0), &mut scratch), media(&[2]));
        assert_eq!(per_ray.at(&scene, Vec3::new(6.0, 0.0, 3.0), &mut scratch), Media::default());
        // An orthographic view whose rectangle (8.7 wide) reaches the nested balls from beside them.
        let ortho = Camera::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0, 0.0, 9.0), Vec3::Y, 40.0, 8, 6)
            .expect("valid camera")
            .with_projection(Projection::Orthographic);
        let per_ray = CameraMedia::new(&scene, &settings(ortho));
        assert_eq!(tested(&per_ray), [0, 1, 2], "an orthographic view's media are found per ray");
        assert_eq!(per_ray.at(&scene, Vec3::new(1.0, 0.5, 0.0), &mut scratch), media(&[0, 1]));
        // A tilted orthographic view whose rectangle's box takes in the
        // balls' boxes, but whose plane passes 14 units from them: none.
        let tilted = Camera::new(Vec3::new(0.0, 10.0, 10.0), Vec3::ZERO, Vec3::Y, 90.0, 8, 6)
            .expect("valid camera")
            .with_projection(Projection::Orthographic);
        assert!(
            matches!(CameraMedia::new(&scene, &settings(tilted)), CameraMedia::Fixed(m) if m == Media::default())
        );
    }

    #[test]
    fn an_origins_grid_cell_lists_every_box_that_holds_it() {
        // Boxes of many sizes over a tilted rectangle; points on it.
        let mut seed = 7u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32
        };
        let rect = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 0.0, 4.0), Vec3::new(-2.0, 3.0, 2.0)];
        let on = |a: f32, b: f32| rect[0] + rect[1] * (2.0 * a - 1.0) + rect[2] * (2.0 * b - 1.0);
        for count in [1usize, 40, 3000] {
            let near: Vec<(u32, Aabb)> = (0..count as u32)
                .map(|i| {
                    let c = on(next(), next()) + Vec3::splat(next() - 0.5);
                    let r = Vec3::new(next(), next(), next()) * if i % 50 == 0 { 8.0 } else { 0.4 };
                    (i, Aabb::new(c - r, c + r))
                })
                .collect();
            let grid = super::OriginGrid::new(&rect, &near);
            for _ in 0..2000 {
                let p = on(next(), next());
                let listed = grid.cell(p);
                for (i, b) in &near {
                    if b.contains(p, 0.0) {
                        assert!(listed.contains(i), "{count} boxes: box {i} holds {p} but is not listed");
                    }
                }
            }
        }
    }

    /// The objects a [`CameraMedia::PerRay`] tests (none for a fixed one).
    fn tested(m: &CameraMedia) -> Vec<usize> {
        match m {
            CameraMedia::PerRay { boxes, .. } => (0..boxes.len()).filter(|&i| boxes[i].is_some()).collect(),
            CameraMedia::Fixed(_) => Vec::new(),
        }
    }

    #[test]
    fn a_rectangle_meets_a_box_unless_an_axis_parts_them() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let rect = |c: Vec3, hu: Vec3, hv: Vec3| super::rect_meets_box(&[c, hu, hv], &b);
        // A point, in and out.
        assert!(rect(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
        assert!(!rect(Vec3::splat(1.5), Vec3::ZERO, Vec3::ZERO));
        // A square in z = 1.5 (above), and one in z = 0.5 far to the side, and reaching in.
        assert!(!rect(Vec3::new(0.0, 0.0, 1.5), Vec3::X * 5.0, Vec3::Y * 5.0));
        assert!(!rect(Vec3::new(7.0, 0.0, 0.5), Vec3::X * 5.0, Vec3::Y * 5.0));
        assert!(rect(Vec3::new(5.5, 0.0, 0.5), Vec3::X * 5.0, Vec3::Y * 5.0));
        // Tilted 45° about X, its plane through (0, 3, 3): its box takes in
        // the cube's, its plane passes 3.54 from the centre (the cube
        // reaches 1.41 along that normal).
        let (u, v) = (Vec3::X * 10.0, Vec3::new(0.0, 1.0, -1.0).normalize() * 10.0);
        assert!(!rect(Vec3::new(0.0, 3.0, 3.0), u, v));
        assert!(rect(Vec3::new(0.0, 0.9, 0.9), u, v));
    }
}
