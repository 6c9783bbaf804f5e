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
//! only the media whose boxes reach the rays' origins are tested, per ray,
//! and a camera far from every medium costs nothing per ray. An area light
//! seen from inside an absorbing medium is absorbed along the way as the
//! light it casts is.

use crate::{Projection, RenderSettings, Scene};
use prism_bvh::Object;
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Intersect, Ray};
use std::ops::ControlFlow;

/// The media a ray is inside, in the order it entered them (the innermost
/// last). Only the innermost [`Media::KEPT`] are kept.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Media {
    ids: [u32; Media::KEPT],
    len: usize,
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

    /// These media and then `object`, entered through its surface.
    #[inline]
    #[must_use]
    pub(crate) fn entered(mut self, object: u32) -> Self {
        if self.len == Self::KEPT {
            self.ids.copy_within(1.., 0);
            self.len -= 1;
        }
        self.ids[self.len] = object;
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
            self.len -= 1;
        }
        self
    }
}

impl PartialEq for Media {
    /// The same media in the same order (slots past `len` are stale).
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

/// The media that hold the point `p`, of those `candidate` accepts,
/// outermost first ([`Media`]): along a ray from `p`, a solid whose
/// nearest crossing is a back face (the ray leaves it there) holds `p`,
/// and of several the one left first is the innermost. `crossings` is
/// scratch space.
pub(crate) fn media_at(
    scene: &Scene,
    p: Vec3,
    candidate: impl Fn(u32) -> bool,
    crossings: &mut Vec<MediumCrossing>,
) -> Media {
    crossings.clear();
    scene.accel.for_each_crossing(&Ray::new(p, INSIDE_TEST), |c| {
        if candidate(c.object) && is_medium(scene, c.object) {
            crossings.push((c.t, c.object, c.front_face));
        }
        ControlFlow::Continue(())
    });
    crossings.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    started_in(crossings)
}

/// The media camera rays start in, found once per render: most cameras
/// are in none, and their rays start with no media at no cost per ray.
pub(crate) enum CameraMedia {
    /// Every camera ray starts in these: a pinhole's eye is in them, or no
    /// medium comes near any ray's origin.
    Fixed(Media),
    /// The origins vary (a thin lens, an orthographic view) and these
    /// media's world boxes (padded) reach some of them: a ray's origin is
    /// tested against those whose box holds it.
    PerRay(Vec<(u32, Aabb)>),
}

impl CameraMedia {
    /// The media the camera rays of `settings` start in, in `scene`.
    pub(crate) fn new(scene: &Scene, settings: &RenderSettings) -> Self {
        let cam = &settings.camera;
        // Filtered samples reach up to the filter's radius past a pixel.
        let origins = cam.origin_bounds(settings.antialias.filter.radius() + 1.0);
        let near: Vec<(u32, Aabb)> = (0..scene.accel.objects().len() as u32)
            .filter(|&i| is_medium(scene, i))
            .filter_map(|i| Some((i, padded(world_bounds(scene, i)?))))
            .filter(|(_, b)| b.min.cmple(origins.max).all() && b.max.cmpge(origins.min).all())
            .collect();
        if near.is_empty() {
            return Self::Fixed(Media::default());
        }
        if cam.projection() == Projection::Perspective && cam.aperture() == 0.0 {
            let eye = cam.position();
            return Self::Fixed(Self::PerRay(near).at(scene, eye, &mut Vec::new()));
        }
        Self::PerRay(near)
    }

    /// The media every camera ray starts in, where they all start in the
    /// same.
    #[inline]
    pub(crate) fn fixed(&self) -> Option<&Media> {
        match self {
            Self::Fixed(media) => Some(media),
            Self::PerRay(_) => None,
        }
    }

    /// The media a camera ray from `origin` starts in; `scratch` is
    /// scratch space. Called per ray only for [`CameraMedia::PerRay`]
    /// (rare, hence cold: [`CameraMedia::fixed`] serves the rest).
    #[cold]
    pub(crate) fn at(&self, scene: &Scene, origin: Vec3, scratch: &mut Vec<MediumCrossing>) -> Media {
        match self {
            Self::Fixed(media) => *media,
            Self::PerRay(near) => {
                let holds = |b: &Aabb| b.contains(origin, 0.0);
                if !near.iter().any(|(_, b)| holds(b)) {
                    return Media::default();
                }
                media_at(scene, origin, |o| near.iter().any(|(i, b)| *i == o && holds(b)), scratch)
            }
        }
    }
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
    use prism_geometry::{Cuboid, Instance, Shape, Sphere, Transform};

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
            accel: Accel::build(Vec::new(), objects).expect("no meshes"),
            object_materials: vec![0, 0, 0, 1, 1],
            materials: vec![glass, Material::diffuse(Vec3::ONE)],
            lights: Vec::new(),
            ambient: Vec3::ZERO,
            background: Vec3::ZERO,
            environment: None,
            fog: None,
        }
    }

    fn media(ids: &[u32]) -> Media {
        ids.iter().fold(Media::default(), |m, &i| m.entered(i))
    }

    #[test]
    fn a_point_is_in_the_media_that_hold_it_outermost_first() {
        let scene = nested();
        let at = |p: Vec3| media_at(&scene, p, |_| true, &mut Vec::new());
        assert_eq!(at(Vec3::new(0.5, -0.3, 0.2)), media(&[0, 1]));
        assert_eq!(at(Vec3::new(0.0, 3.0, 0.0)), media(&[0]));
        assert_eq!(at(Vec3::new(6.2, 0.1, 0.0)), media(&[2]));
        // Opaque solids are no media; outside every solid, none.
        assert_eq!(at(Vec3::new(-6.0, 0.0, 0.0)), Media::default());
        assert_eq!(at(Vec3::new(0.0, 0.0, 9.0)), Media::default());
        // Only the candidates count.
        assert_eq!(media_at(&scene, Vec3::ZERO, |o| o != 0, &mut Vec::new()), media(&[1]));
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
            CameraMedia::PerRay(_) => panic!("a pinhole's media are found once"),
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
        let CameraMedia::PerRay(near) = &per_ray else { panic!("a lens's media are found per ray") };
        assert_eq!(near.iter().map(|n| n.0).collect::<Vec<_>>(), [2]);
        let mut scratch = Vec::new();
        assert_eq!(per_ray.at(&scene, Vec3::new(6.3, 0.2, 0.0), &mut scratch), media(&[2]));
        assert_eq!(per_ray.at(&scene, Vec3::new(6.0, 0.0, 3.0), &mut scratch), Media::default());
        // An orthographic view whose rectangle (8.7 wide) reaches the nested balls from beside them.
        let ortho = Camera::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0, 0.0, 9.0), Vec3::Y, 40.0, 8, 6)
            .expect("valid camera")
            .with_projection(Projection::Orthographic);
        let per_ray = CameraMedia::new(&scene, &settings(ortho));
        let CameraMedia::PerRay(near) = &per_ray else {
            panic!("an orthographic view's media are found per ray")
        };
        assert_eq!(near.iter().map(|n| n.0).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(per_ray.at(&scene, Vec3::new(1.0, 0.5, 0.0), &mut scratch), media(&[0, 1]));
    }
}
