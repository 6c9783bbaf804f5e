//! The Whitted integrator: local Phong shading with coloured shadows,
//! mirror reflection, unbent transparency, dielectric refraction, and fog
//! over every segment.
//!
//! A [`Tracer`] is made per row of the image; it holds no shared data and
//! counts the rays it traces, so that nothing is shared between threads
//! while a row is traced.

use crate::footprint::{Footprint, RayCone, curvature, uv_axes};
use crate::light::{Light, LightSample, Target, sample_seed};
use crate::media::{CameraMedia, Media, MediumCrossing, is_medium, optical_depth};
use crate::optics::{fresnel, reflect, refract};
use crate::{FogMode, Material, RenderSettings, Scene, Texture};
use prism_bvh::SceneHit;
use prism_geometry::glam::Vec3;
use prism_geometry::{Hit, Ray};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

/// Recursion never goes deeper than this, whatever the settings say (a
/// pair of perfect mirrors with no contribution cut-off would otherwise
/// exhaust the stack).
pub const MAX_DEPTH_LIMIT: u32 = 64;

/// How near its start (relative to the size of its origin's coordinates,
/// or the scene's offset scale near the origin) a ray inside a closed
/// solid may meet the solid's front face for that to count as the entry
/// met again ([`Tracer::trace_hit`]): a few thousand units in the last
/// place, well past a spawned ray's offset of 256.
const REENTRY: f32 = 4096.0 * f32::EPSILON;

/// No object: the "skip the exit of" argument of an ordinary ray.
const NO_OBJECT: u32 = u32::MAX;

/// The scene's first lights (of any kind) among which those of one sample
/// get their shadow rays from a packet of camera hits traced together
/// ([`Tracer::camera_shadows`]); the shadow rays toward the lights after
/// these go one by one.
pub(crate) const PRE_LIGHTS: usize = 8;

/// A camera hit's shadow toward one light, traced beforehand with the
/// shadow rays of the other hits of its packet ([`Tracer::camera_shadows`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) enum PreShadow {
    /// Not traced beforehand: the shading traces it.
    #[default]
    Unknown,
    /// The transmittance: 1 where nothing lies on the segment, 0 where
    /// something does and the scene has nothing see-through.
    Known(Vec3),
    /// Something lies on the segment of a scene with see-through
    /// materials: the shading walks its crossings for the transmittance.
    Occluded,
}

/// Per-row tracing state.
pub(crate) struct Tracer<'a> {
    scene: &'a Scene,
    max_depth: u32,
    min_contribution: f32,
    fog: Option<(FogMode, Vec3)>,
    /// The camera's view axis when fog is measured by eye-space depth.
    depth_axis: Option<Vec3>,
    /// The unit direction of the camera ray being traced.
    primary: Vec3,
    /// Whether any material lets light through (else shadows are yes/no).
    see_through: bool,
    /// Trace an area light's shadow rays from one point as a packet.
    pub(crate) packets: bool,
    /// The camera hit whose shadows `pre` holds (its point), while its
    /// camera ray is traced.
    pre_point: Option<Vec3>,
    /// Its shadow toward each of the first [`PRE_LIGHTS`] lights.
    pre: [PreShadow; PRE_LIGHTS],
    /// The media the camera rays start in.
    camera_media: &'a CameraMedia,
    /// The cone of every camera ray (one pixel wide): from a point at the
    /// eye for a perspective camera; a parallel beam one pixel wide at the
    /// look-at distance for an orthographic one.
    camera_cone: RayCone,
    /// The scene's offset scale for rays started off a surface
    /// ([`offset_scale`]).
    offset: f32,
    /// Rays traced so far (camera, secondary, shadow).
    pub rays: u64,
    /// Of `rays`, the shadow rays.
    pub shadow_rays: u64,
    /// Of `rays`, those traced in packets.
    pub packet_rays: u64,
    /// A see-through shadow ray's bookkeeping ([`Tracer::transmittance`]),
    /// kept between rays: emptied, not made again, for each.
    scratch: ShadowScratch,
    /// The render's cancel flag ([`Tracer::watching`]), and whether it was
    /// seen set: every ray traced after that returns black at once.
    cancel: Option<&'a AtomicBool>,
    stopped: bool,
    /// The ray count at which the flag is read next.
    next_check: u64,
    /// Rays on the stack that went on through a surface unshaded, at the
    /// same depth ([`Tracer::trace_hit`]); at most [`MAX_THROUGH`].
    through: u32,
}

/// The most unshaded continuations through surfaces one path may stack
/// up ([`Tracer::trace_hit`]'s re-entered front face and a see-through
/// solid's skipped exit), which do not count against `max_depth`. Where
/// the spawned ray's offset cannot carry it off the surface (a glass
/// sphere of radius 1e-20, a glass mesh of sliver triangles reaching
/// 1e4), each continuation met the same surface again, without end, until
/// the stack overflowed (an abort, found by a fuzz hunt). Past this many
/// the path counts as absorbed (black).
const MAX_THROUGH: u32 = 32;

/// A tracer with a cancel flag reads it once every this many rays
/// ([`Tracer::trace`]).
const CANCEL_RAYS: u64 = 4096;

/// The footprint cone of the camera's rays: one pixel wide (the image
/// plane's height at unit distance over the rows); none when textures are
/// point-sampled.
fn camera_cone(settings: &RenderSettings) -> RayCone {
    let cam = &settings.camera;
    if settings.antialias.point_textures {
        return RayCone::camera(0.0);
    }
    let (_, h) = cam.size();
    let spread = 2.0 * (cam.vfov_deg().to_radians() * 0.5).tan() / h.max(1) as f32;
    match cam.projection() {
        crate::Projection::Perspective => RayCone::camera(spread),
        // Parallel rays, each a pixel wide: the view spans the field of view at the look-at distance.
        crate::Projection::Orthographic => {
            RayCone { width: spread * (cam.look_at() - cam.position()).length(), spread: 0.0 }
        }
    }
}

/// Most shadow rays from one shading point traced as one packet (an area
/// light's samples go in groups of this many).
const SHADOW_PACKET: usize = 16;

/// The shadow ray from the surface point of `hit` toward `target`, in a
/// scene of offset scale `scale` ([`offset_scale`]).
#[inline]
fn shadow_ray(hit: &Hit, target: Target, scale: f32) -> Ray {
    match target {
        Target::Point(q) => Ray::spawn_to_scaled(hit.point, hit.geo_normal, q, scale),
        Target::Away(dir) => Ray::spawn_scaled(hit.point, hit.geo_normal, dir, scale),
    }
}

/// The scale of the offsets that start rays off a surface
/// (`prism_geometry::offset_scale`): from how far the scene's bounded
/// surfaces and its camera reach from the origin, so that a scene a
/// millionth of a unit across keeps its shadows and reflections.
fn offset_scale(scene: &Scene, settings: &RenderSettings) -> f32 {
    let b = scene.accel.bounds();
    let mut extent = settings.camera.position().abs().max_element();
    if b.min.is_finite() && b.max.is_finite() {
        extent = extent.max(b.min.abs().max_element()).max(b.max.abs().max_element());
    }
    prism_geometry::offset_scale(extent)
}

/// The one sample of light `index` (`light`, of one sample) at the point
/// `p` with shading normal `n` facing the viewer, if it lights the front:
/// the sample [`Tracer::local`] shades with and [`Tracer::camera_shadows`]
/// traces the shadow ray of.
#[inline]
fn one_sample(light: &Light, index: usize, p: Vec3, n: Vec3) -> Option<LightSample> {
    light.sample(p, 0, sample_seed(p, index, 1)).filter(|ls| n.dot(ls.dir) > 0.0)
}

/// The Lambert + Phong light of the light sample `ls` at a point with
/// shading normal `n` (facing the viewer, `n · ls.dir > 0`) seen from the
/// unit direction `v`, through the shadow transmittance `shadow`; `None`
/// where no light arrives (`shadow` black).
#[inline]
fn phong(mat: &Material, albedo: Vec3, n: Vec3, v: Vec3, ls: &LightSample, shadow: Vec3) -> Option<Vec3> {
    if !(shadow.max_element() > 0.0) {
        return None;
    }
    let n_dot_l = n.dot(ls.dir);
    let mut s = mat.diffuse * n_dot_l * albedo;
    if mat.specular > 0.0 {
        let r_dot_v = (2.0 * n_dot_l * n - ls.dir).dot(v);
        if r_dot_v > 0.0 {
            s += mat.specular * r_dot_v.powf(mat.shininess) * mat.specular_color;
        }
    }
    Some(shadow * ls.e * s)
}

/// Whether object `object` is a closed solid: [`Scene::is_closed`].
#[inline]
fn is_closed(scene: &Scene, object: u32) -> bool {
    scene.is_closed(object)
}

/// Beer–Lambert transmittance `exp(−absorption · seg)` of a stretch of
/// length `seg` inside `medium` (1 outside every medium).
#[inline]
fn absorbed(scene: &Scene, medium: Option<u32>, seg: f32) -> Vec3 {
    match medium.map(|m| scene.material_of(m).absorption) {
        Some(a) if a != Vec3::ZERO => (-a * seg).exp(),
        _ => Vec3::ONE,
    }
}

#[inline]
fn albedo(scene: &Scene, mat: &Material, h: &SceneHit) -> Vec3 {
    match &mat.texture {
        Texture::Solid(c) => *c,
        t => t.color_at(h.hit.point, h.hit.uv, &scene.texture_to_object(h.object, t)),
    }
}

impl<'a> Tracer<'a> {
    /// Whether the scene needs transmittance shadows (computed once per render).
    pub(crate) fn scene_is_see_through(scene: &Scene) -> bool {
        scene.materials.iter().any(Material::is_see_through)
    }

    /// A tracer of `scene` as `settings` render it, whose camera rays
    /// start in `camera_media` (found once per render).
    pub(crate) fn new(
        scene: &'a Scene,
        settings: &RenderSettings,
        see_through: bool,
        camera_media: &'a CameraMedia,
    ) -> Self {
        let min_contribution =
            if settings.min_contribution.is_finite() { settings.min_contribution.max(0.0) } else { 0.0 };
        Self {
            scene,
            max_depth: settings.max_depth.min(MAX_DEPTH_LIMIT),
            min_contribution,
            fog: scene.fog.filter(|_| settings.fog).map(|f| (f.mode, f.color)),
            depth_axis: scene.fog.filter(|f| settings.fog && f.by_depth()).map(|_| settings.camera.forward()),
            primary: Vec3::ZERO,
            see_through,
            packets: false,
            pre_point: None,
            pre: [PreShadow::Unknown; PRE_LIGHTS],
            camera_media,
            camera_cone: camera_cone(settings),
            offset: offset_scale(scene, settings),
            rays: 0,
            shadow_rays: 0,
            packet_rays: 0,
            scratch: ShadowScratch::default(),
            cancel: None,
            stopped: false,
            next_check: 0,
            through: 0,
        }
    }

    /// This tracer, stopping when `cancel` is set: a path that one sample
    /// spends long in (thousands of rays under a deep `max_depth` between
    /// parallel glass panes, 2^40 of them at depth 40) gives up within
    /// [`CANCEL_RAYS`] rays of a Ctrl-C, returning black for every ray
    /// after. The render drops the row (see [`crate::render()`]).
    pub(crate) fn watching(mut self, cancel: Option<&'a AtomicBool>) -> Self {
        self.cancel = cancel;
        self
    }

    /// `go` (a ray traced on through a surface at the same depth), unless
    /// [`MAX_THROUGH`] such rays are already on the stack: then black.
    fn through(&mut self, go: impl FnOnce(&mut Self) -> Vec3) -> Vec3 {
        if self.through >= MAX_THROUGH {
            return Vec3::ZERO;
        }
        self.through += 1;
        let l = go(self);
        self.through -= 1;
        l
    }

    /// Whether a ray of this tracer gave up because the render was
    /// cancelled: what it traced since is not the picture.
    pub(crate) fn gave_up(&self) -> bool {
        self.stopped
    }

    /// Whether the render was cancelled (read every [`CANCEL_RAYS`] rays).
    #[inline]
    fn stopping(&mut self) -> bool {
        // Read once the count has passed the mark, not when it is a
        // multiple: between two calls it grows by a hit's shadow rays too,
        // and a path whose steps add an even number from an odd count
        // would never land on one.
        if !self.stopped
            && self.rays >= self.next_check
            && let Some(c) = self.cancel
        {
            self.next_check = self.rays + CANCEL_RAYS;
            self.stopped = c.load(Ordering::Relaxed);
        }
        self.stopped
    }

    /// Radiance arriving at the origin of the camera ray `ray` (unit
    /// direction).
    #[inline]
    pub(crate) fn trace_camera(&mut self, ray: &Ray) -> Vec3 {
        self.primary = ray.dir;
        self.in_camera_media(ray.origin, |t, media| {
            t.trace(ray, 0, Vec3::ONE, 0.0, NO_OBJECT, t.camera_cone, media)
        })
    }

    /// `f` of this tracer and the media a camera ray from `origin` starts
    /// in: those of every camera ray, found once, where they all start in
    /// the same (no work per ray).
    #[inline]
    fn in_camera_media<R>(&mut self, origin: Vec3, f: impl FnOnce(&mut Self, &Media) -> R) -> R {
        let camera_media = self.camera_media;
        match camera_media.fixed() {
            Some(media) => f(self, media),
            None => {
                let media = camera_media.at(self.scene, origin, &mut self.scratch.media);
                f(self, &media)
            }
        }
    }

    /// [`Tracer::trace_camera`] with the ray's closest hit already found
    /// (by a packet of camera rays), and the hit's shadows toward the first
    /// [`PRE_LIGHTS`] lights that were traced beforehand (`pre`, from
    /// [`Tracer::camera_shadows`]; all [`PreShadow::Unknown`] if none): the
    /// same radiance.
    pub(crate) fn trace_camera_hit(
        &mut self,
        ray: &Ray,
        hit: Option<SceneHit>,
        pre: [PreShadow; PRE_LIGHTS],
    ) -> Vec3 {
        self.primary = ray.dir;
        self.pre_point = hit.map(|h| h.hit.point);
        self.pre = pre;
        let l = self.in_camera_media(ray.origin, |t, media| {
            t.trace_hit(ray, hit, 0, Vec3::ONE, 0.0, NO_OBJECT, t.camera_cone, media)
        });
        self.pre_point = None;
        l
    }

    /// For camera hits traced together (`hits`), the shadow of each toward
    /// each light of one sample (point, spot and directional lights, and
    /// an area light of one sample) among the scene's first [`PRE_LIGHTS`]
    /// lights that its shading will ask for, into
    /// `out[k]` for `hits[k]`: per light, the shadow rays of the hits go as
    /// one packet of occlusion rays. They are the rays [`Tracer::local`]
    /// would trace (same point, same target), so the shading takes their
    /// answers and the image is the same bit for bit. Hits whose material
    /// has no local term, and lights behind a hit, get
    /// [`PreShadow::Unknown`], as does a light that fewer than four hits
    /// ask about (too few to pay for a packet).
    pub(crate) fn camera_shadows(&mut self, hits: &[Option<SceneHit>], out: &mut [[PreShadow; PRE_LIGHTS]]) {
        const N: usize = prism_bvh::PACKET_SIZE;
        out.fill([PreShadow::Unknown; PRE_LIGHTS]);
        let scene = self.scene;
        for (index, light) in scene.lights.iter().enumerate().take(PRE_LIGHTS) {
            if light.sample_count() != 1 || !(light.radiance().max_element() > 0.0) {
                continue;
            }
            let mut rays = [Ray { dir: Vec3::ZERO, ..Ray::new(Vec3::ZERO, Vec3::X) }; N];
            let mut from = [0usize; N];
            let mut n = 0;
            for (k, h) in hits.iter().enumerate() {
                let Some(h) = h else { continue };
                if n >= N || !(scene.material_of(h.object).local_weight() > 0.0) {
                    continue;
                }
                let Some(ls) = one_sample(light, index, h.hit.point, h.hit.facing_normal()) else {
                    continue;
                };
                rays[n] = shadow_ray(&h.hit, ls.target, self.offset);
                from[n] = k;
                n += 1;
            }
            if n < 4 {
                continue;
            }
            let mut occluded = [false; N];
            scene.accel.occluded_packet(&rays[..n], &mut occluded[..n]);
            for (&k, &occ) in from[..n].iter().zip(&occluded) {
                if let Some(o) = out.get_mut(k) {
                    o[index] = match (occ, self.see_through) {
                        (false, _) => PreShadow::Known(Vec3::ONE),
                        (true, false) => PreShadow::Known(Vec3::ZERO),
                        (true, true) => PreShadow::Occluded,
                    };
                }
            }
        }
    }

    /// The shadow toward light `index` of the camera hit at `p` traced
    /// beforehand, if it was (counted as one shadow ray in a packet, as
    /// [`Tracer::shadows`] counts its rays); each is taken once.
    #[inline]
    fn pre_shadow(&mut self, index: usize, p: Vec3) -> Option<Vec3> {
        if self.pre_point != Some(p) {
            return None;
        }
        let pre = std::mem::take(self.pre.get_mut(index)?);
        if pre != PreShadow::Unknown {
            self.packet_rays += 1;
        }
        // An occluded ray of a see-through scene is traced again, and
        // counted, by [`Tracer::shadow`]: one shadow ray, not two.
        if let PreShadow::Known(_) = pre {
            self.rays += 1;
            self.shadow_rays += 1;
        }
        match pre {
            PreShadow::Known(s) => Some(s),
            PreShadow::Unknown | PreShadow::Occluded => None,
        }
    }

    /// Should a ray of path weight `w` be traced?
    #[inline]
    fn worth(&self, w: Vec3) -> bool {
        let m = w.max_element();
        m > 0.0 && m >= self.min_contribution
    }

    /// The fog distance of a segment of length `seg` along `ray`: its
    /// eye-space depth when fog is measured by depth and the ray runs along
    /// the camera ray's line, else its length (see [`FogMode`]).
    #[inline]
    fn fog_length(&self, ray: &Ray, seg: f32) -> f32 {
        match self.depth_axis {
            Some(axis) => {
                let d = ray.dir.normalize_or_zero();
                if d.dot(self.primary) >= 1.0 - 1e-6 { seg * d.dot(axis).max(0.0) } else { seg }
            }
            None => seg,
        }
    }

    /// Fog transmittance of the path segment `[a, b]`.
    #[inline]
    fn fog_t(&self, a: f32, b: f32) -> f32 {
        match &self.fog {
            Some((mode, _)) => mode.transmittance(a, b),
            None => 1.0,
        }
    }

    #[inline]
    fn fog_blend(&self, radiance: Vec3, t: f32) -> Vec3 {
        match &self.fog {
            Some((_, color)) if t < 1.0 => t * radiance + (1.0 - t) * *color,
            _ => radiance,
        }
    }

    /// Radiance arriving at `ray.origin` along `ray`, `depth` bounces from
    /// the camera, with path weight `weight` and fog distance `path` so far
    /// (path length, or depth: [`FogMode`]).
    /// When the ray leaves object `skip_exit` through its back face (the
    /// unbent continuation through a transparent solid), it goes on from
    /// the far side without shading the exit. `cone` is the ray's footprint
    /// cone (for texture filtering), `media` the dielectrics it is inside
    /// ([`Media`]).
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &mut self,
        ray: &Ray,
        depth: u32,
        weight: Vec3,
        path: f32,
        skip_exit: u32,
        cone: RayCone,
        media: &Media,
    ) -> Vec3 {
        if self.stopping() {
            return Vec3::ZERO;
        }
        let hit = self.scene.accel.closest_hit(ray);
        self.trace_hit(ray, hit, depth, weight, path, skip_exit, cone, media)
    }

    /// [`Tracer::trace`] past the closest-hit query: `hit` is the ray's.
    #[allow(clippy::too_many_arguments)]
    fn trace_hit(
        &mut self,
        ray: &Ray,
        hit: Option<SceneHit>,
        depth: u32,
        weight: Vec3,
        path: f32,
        skip_exit: u32,
        cone: RayCone,
        media: &Media,
    ) -> Vec3 {
        self.rays += 1;
        let scene = self.scene;
        // An area light nearer than the surface (or than nothing) is seen,
        // through the medium the ray is in as the light it casts is.
        if let Some((t, l)) = self.light_hit(ray, hit.as_ref().map_or(ray.t_max, |h| h.hit.t)) {
            let seg = t * ray.dir.length();
            let end = path + self.fog_length(ray, seg);
            return self.fog_blend(l * absorbed(scene, media.innermost(), seg), self.fog_t(path, end));
        }
        let Some(h) = hit else {
            // The environment over the ray's cone (its width adds nothing
            // at infinity).
            let sky = scene
                .environment
                .as_ref()
                .map_or(scene.background, |e| e.radiance_over(ray.dir, cone.spread.abs()));
            return self.fog_blend(sky, self.fog_t(path, f32::INFINITY));
        };
        let seg = h.hit.t * ray.dir.length();
        let end = path + self.fog_length(ray, seg);
        let fog_t = self.fog_t(path, end);
        let weight = weight * fog_t;
        let cone = RayCone { width: cone.width_at(seg), spread: cone.spread };
        let mat = scene.material_of(h.object);
        // Beer–Lambert over a segment travelled inside an absorbing
        // dielectric: the innermost medium the ray is in or, where it is
        // not known to be in one (one forgotten in deep nesting), the solid
        // whose inner surface the segment ends on.
        let medium = media
            .innermost()
            .or_else(|| (!h.hit.front_face && is_medium(scene, h.object)).then_some(h.object));
        let absorb = absorbed(scene, medium, seg);
        if h.hit.front_face
            && (h.object == skip_exit || media.contains(h.object))
            && seg <= REENTRY * ray.origin.abs().max_element().max(self.offset)
            && is_closed(scene, h.object)
        {
            // Inside a closed solid its surface is met from behind: its
            // front face right at the ray's start is the entry met again,
            // where the ray went in through a mesh's edge or corner and the
            // next triangle's plane lies beyond the ray's offset. Go on
            // through it, unshaded.
            let next = Ray::spawn_scaled(h.hit.point, h.hit.geo_normal, ray.dir, self.offset);
            let l = self.through(|t| t.trace(&next, depth, weight * absorb, end, skip_exit, cone, media))
                * absorb;
            return self.fog_blend(l, fog_t);
        }
        if h.object == skip_exit && !h.hit.front_face && is_closed(scene, h.object) {
            // The unbent ray through a see-through solid crossed its inside
            // too, and is absorbed as the refracted one is.
            let next = Ray::spawn_scaled(h.hit.point, h.hit.geo_normal, ray.dir, self.offset);
            let media = media.left(h.object);
            let l = self.through(|t| t.trace(&next, depth, weight * absorb, end, NO_OBJECT, cone, &media))
                * absorb;
            return self.fog_blend(l, fog_t);
        }
        let l = self.shade(ray, &h, mat, depth, weight * absorb, end, cone, media) * absorb;
        self.fog_blend(l, fog_t)
    }

    /// Radiance leaving the hit `h` toward the origin of `ray`, by the
    /// material formula (see [`Material`]); `cone` is the ray's cone, its
    /// width the one at the hit, and `media` the dielectrics the ray is in.
    #[allow(clippy::too_many_arguments)]
    fn shade(
        &mut self,
        ray: &Ray,
        h: &SceneHit,
        mat: &Material,
        depth: u32,
        weight: Vec3,
        path: f32,
        cone: RayCone,
        media: &Media,
    ) -> Vec3 {
        let hit = &h.hit;
        let d = ray.dir.normalize_or(Vec3::NEG_Z);
        let n = hit.facing_normal();
        let mut out = mat.emission;
        let w_local = mat.local_weight();
        // Whether what passes through the surface here is multiplied by its
        // filter (`filter_color`, else its colour), as the light of a shadow
        // ray through it is ([`Tracer::transmittance`]): at every crossing
        // of an open surface, and once per closed solid, where the ray
        // enters it (an unbent ray skips its exit), or where it leaves one
        // its path started in (a camera inside glass).
        let tints = mat.is_see_through()
            && depth < self.max_depth
            && (hit.front_face || !is_closed(self.scene, h.object) || media.started_in(h.object));
        let albedo = if w_local > 0.0 || (tints && mat.filter_color.is_none()) {
            self.albedo_over(ray, h, mat, cone.width)
        } else {
            Vec3::ZERO
        };
        if w_local > 0.0 {
            out += w_local * self.local(mat, albedo, hit, n, -d);
        }
        if depth >= self.max_depth {
            return out;
        }
        let filter =
            if tints { mat.filter_color.unwrap_or(albedo).clamp(Vec3::ZERO, Vec3::ONE) } else { Vec3::ONE };
        // Dielectric split: Fresnel reflectance F and the refracted direction,
        // between the material's index and that of the medium around it.
        let (fresnel, refracted, eta) = if mat.transmission > 0.0 {
            let ior = |m: u32| self.scene.material_of(m).ior;
            let (n1, n2) = match media.innermost() {
                // Leaving a solid that one entered after it overlaps: the
                // ray stays in that one, and this surface does not bend it.
                Some(m) if !hit.front_face && m != h.object && media.contains(h.object) => (ior(m), ior(m)),
                _ => {
                    let outside = media.around(h.object).map_or(1.0, ior);
                    if hit.front_face { (outside, mat.ior) } else { (mat.ior, outside) }
                }
            };
            match refract(d, n, n1 / n2) {
                Some(t) => (fresnel(-d.dot(n), n1, n2), Some(t), n1 / n2),
                None => (1.0, None, n1 / n2),
            }
        } else {
            (0.0, None, 1.0)
        };
        // The media beyond the surface: a ray through a dielectric solid's
        // surface enters or leaves it. Whether a new ray goes through is
        // which side of the geometric surface it leaves on (a shading
        // normal can send a reflected ray through, or a refracted one back).
        let beyond = if (mat.transmission > 0.0 || mat.transparency > 0.0) && is_medium(self.scene, h.object)
        {
            if hit.front_face { media.entered(h.object) } else { media.left(h.object) }
        } else {
            *media
        };
        let side = d.dot(hit.geo_normal);
        let crosses = |dir: Vec3| dir.dot(hit.geo_normal) * side > 0.0;
        let media_along = |dir: Vec3| if crosses(dir) { &beyond } else { media };
        // A new ray that goes through the surface carries its filter; one
        // that stays on this side does not (a shading normal can send a
        // refracted ray back, or a reflected one through).
        let tint = |dir: Vec3| if tints && crosses(dir) { filter } else { Vec3::ONE };
        // At grazing incidence a shading normal (interpolated on a mesh)
        // can send the reflected ray through the geometric surface. Into a
        // surface that lets light through, it goes on (tinted, in the
        // media beyond, as a refracted ray would); into an opaque mirror it
        // would be lost (black specks on the outline of a smooth mirror
        // mesh), so there it is mirrored back across the surface's plane,
        // the direction on this side nearest the intended one.
        let opaque = mat.transmission == 0.0 && mat.transparency == 0.0;
        let onto_this_side = |dir: Vec3| {
            if opaque && crosses(dir) { dir - 2.0 * dir.dot(hit.geo_normal) * hit.geo_normal } else { dir }
        };
        // Mirror reflection and the dielectric's reflected part share one ray.
        let k_mirror = mat.reflectivity + mat.transmission * fresnel;
        if k_mirror > 0.0 {
            let dir = onto_this_side(reflect(d, n));
            let k = k_mirror * tint(dir);
            if self.worth(weight * k) {
                let r = Ray::spawn_scaled(hit.point, hit.geo_normal, dir, self.offset);
                let c = cone.reflect(cone.width, curvature(self.scene, h));
                out += k * self.trace(&r, depth + 1, weight * k, path, NO_OBJECT, c, media_along(dir));
            }
        }
        let k_through = mat.transparency * tint(d);
        if mat.transparency > 0.0 && self.worth(weight * k_through) {
            let r = Ray::spawn_scaled(hit.point, hit.geo_normal, d, self.offset);
            let skip = if hit.front_face { h.object } else { NO_OBJECT };
            let w = weight * k_through;
            out += k_through * self.trace(&r, depth + 1, w, path, skip, cone, media_along(d));
        }
        if let Some(t) = refracted {
            let k = mat.transmission * (1.0 - fresnel) * tint(t);
            if self.worth(weight * k) {
                let r = Ray::spawn_scaled(hit.point, hit.geo_normal, t, self.offset);
                let c = cone.refract(cone.width, eta, curvature(self.scene, h));
                out += k * self.trace(&r, depth + 1, weight * k, path, NO_OBJECT, c, media_along(t));
            }
        }
        out
    }

    /// The material's colour at `h` averaged over the footprint of a beam
    /// of width `width` arriving along `ray` ([`Texture::color_over`]).
    fn albedo_over(&self, ray: &Ray, h: &SceneHit, mat: &Material, width: f32) -> Vec3 {
        if let Texture::Solid(c) = &mat.texture {
            return *c;
        }
        let mut fp = Footprint::on_surface(ray.dir, h.hit.geo_normal, width);
        if mat.texture.needs_uv_footprint() && fp != Footprint::POINT {
            fp.duv = uv_axes(self.scene, ray.origin, h, fp.dp);
        }
        mat.texture.color_over(
            h.hit.point,
            h.hit.uv,
            &self.scene.texture_to_object(h.object, &mat.texture),
            &fp,
        )
    }

    /// The nearest area light `ray` meets before `t_max`: its distance
    /// (in the ray's parameter) and the radiance seen there.
    fn light_hit(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let mut best: Option<(f32, Vec3)> = None;
        for light in &self.scene.lights {
            if let Some((t, l)) = light.intersect(ray, best.map_or(t_max, |b| b.0)) {
                best = Some((t, l));
            }
        }
        best
    }

    /// Ambient + Lambert + Phong over every light sample, each through its
    /// shadow transmittance. `n` is the shading normal facing the viewer,
    /// `v` the unit direction toward the viewer. An adaptive area light is
    /// probed at four rim points first; when all four see the same
    /// transmittance (fully lit or fully hidden) its samples take that
    /// instead of tracing their own shadow rays.
    fn local(&mut self, mat: &Material, albedo: Vec3, hit: &Hit, n: Vec3, v: Vec3) -> Vec3 {
        let scene = self.scene;
        let mut c = mat.ambient * albedo * scene.ambient;
        for (index, light) in scene.lights.iter().enumerate() {
            if !(light.radiance().max_element() > 0.0) {
                continue;
            }
            let p = hit.point;
            let shared = light.probes(p).and_then(|probes| {
                if self.packets {
                    let mut seen = [Vec3::ZERO; 4];
                    self.shadows(hit, &probes.map(|q| Some(Target::Point(q))), &mut seen);
                    return seen[1..].iter().all(|s| *s == seen[0]).then_some(seen[0]);
                }
                // One by one, stopping at the first probe that differs.
                let first = self.shadow(hit, Target::Point(probes[0]));
                probes[1..].iter().all(|q| self.shadow(hit, Target::Point(*q)) == first).then_some(first)
            });
            if shared == Some(Vec3::ZERO) {
                continue;
            }
            let seed = sample_seed(p, index, light.sample_count());
            let count = light.sample_count();
            if count == 1 {
                // One sample (a point, spot or directional light): no batch
                // to gather, one shadow ray, the same sum.
                if let Some(ls) = one_sample(light, index, p, n) {
                    let shadow = match shared.or_else(|| self.pre_shadow(index, p)) {
                        Some(s) => s,
                        None => self.shadow(hit, ls.target),
                    };
                    if let Some(term) = phong(mat, albedo, n, v, &ls, shadow) {
                        c += term;
                    }
                }
                continue;
            }
            let mut k = 0;
            while k < count {
                // Up to a packet's worth of samples; their shadow rays are
                // traced together.
                let end = count.min(k + SHADOW_PACKET as u32);
                let mut batch = [None; SHADOW_PACKET];
                let mut targets = [None; SHADOW_PACKET];
                for (slot, j) in (k..end).enumerate().take(SHADOW_PACKET) {
                    batch[slot] = light.sample(p, j, seed).filter(|ls| n.dot(ls.dir) > 0.0);
                    targets[slot] = batch[slot].filter(|_| shared.is_none()).map(|ls| ls.target);
                }
                let len = (end - k) as usize;
                let mut seen = [Vec3::ZERO; SHADOW_PACKET];
                self.shadows(hit, &targets[..len], &mut seen[..len]);
                for (slot, ls) in batch[..len].iter().enumerate() {
                    let Some(ls) = ls else { continue };
                    if let Some(term) = phong(mat, albedo, n, v, ls, shared.unwrap_or(seen[slot])) {
                        c += term;
                    }
                }
                k = end;
            }
        }
        c
    }

    /// [`Tracer::shadow`] toward each target (`None`: left as it is in
    /// `out`). Four or more are traced together as one packet of
    /// occlusion rays: an unoccluded ray's transmittance is exactly 1, and
    /// only an occluded one in a see-through scene is traced again for its
    /// crossings. The values are `shadow`'s either way.
    fn shadows(&mut self, hit: &Hit, targets: &[Option<Target>], out: &mut [Vec3]) {
        let n = targets.len().min(out.len());
        if !self.packets || !(4..=SHADOW_PACKET).contains(&n) {
            for (t, o) in targets.iter().zip(out.iter_mut()) {
                if let Some(t) = t {
                    *o = self.shadow(hit, *t);
                }
            }
            return;
        }
        let mut rays = [Ray { dir: Vec3::ZERO, ..Ray::new(hit.point, Vec3::X) }; SHADOW_PACKET];
        for (r, t) in rays.iter_mut().zip(targets) {
            if let Some(t) = t {
                *r = shadow_ray(hit, *t, self.offset);
                self.rays += 1;
                self.shadow_rays += 1;
                self.packet_rays += 1;
            }
        }
        let mut occluded = [false; SHADOW_PACKET];
        self.scene.accel.occluded_packet(&rays[..n], &mut occluded[..n]);
        for ((t, o), &occ) in targets.iter().zip(out.iter_mut()).zip(&occluded) {
            if let Some(t) = t {
                *o = match (occ, self.see_through) {
                    (false, _) => Vec3::ONE,
                    (true, false) => Vec3::ZERO,
                    // Counted above, with the packet.
                    (true, true) => self.transmittance(hit, *t),
                };
            }
        }
    }

    /// The fraction of a light at `target` that reaches the surface point
    /// of `hit`: the product over the occluders on the segment of each
    /// one's see-through fraction (`transparency + transmission`) times its
    /// colour at the crossing, clamped to `[0, 1]` per channel. A closed
    /// solid (sphere, cuboid, cylinder, cone, closed mesh) counts once, at the crossing
    /// where the segment enters it (or, for a point inside it, where the
    /// segment leaves it); open surfaces (planes, disks,
    /// triangles, open meshes) count at every crossing. Opaque occluders give 0,
    /// from either side: a segment that leaves a closed opaque solid is blocked.
    /// A mesh crossed exactly at an edge or a corner, which each triangle
    /// there reports, is crossed once.
    ///
    /// Light crossing an absorbing dielectric (a closed solid with
    /// `transmission > 0` and non-zero `absorption`) is also attenuated by
    /// Beer–Lambert, `exp(−absorption · L)` over the length `L` of the
    /// segment inside it, as the view through it is: green glass casts a
    /// green shadow. Where solids nest, the innermost absorbs
    /// ([`crate::media`]); a segment that starts inside a solid counts from
    /// its start, one that ends inside (a light in the glass) up to its end.
    fn shadow(&mut self, hit: &Hit, target: Target) -> Vec3 {
        self.rays += 1;
        self.shadow_rays += 1;
        self.transmittance(hit, target)
    }

    /// [`Tracer::shadow`]'s value, the ray not counted (a packet counted it).
    fn transmittance(&mut self, hit: &Hit, target: Target) -> Vec3 {
        let ray = shadow_ray(hit, target, self.offset);
        let scene = self.scene;
        if !self.see_through {
            return if scene.accel.occluded(&ray) { Vec3::ZERO } else { Vec3::ONE };
        }
        let mut t = Vec3::ONE;
        // Mesh crossings counted so far: where the ray runs exactly
        // through an edge or a corner, every triangle there reports the
        // same crossing of the surface, which must count once. The solids
        // entered and left, and the media's crossings (and whether any
        // medium there absorbs).
        let ShadowScratch { counted, inside, media } = &mut self.scratch;
        (counted.len, inside.len) = (0, 0);
        media.clear();
        let mut absorbed = false;
        // Crossings without their hit records: only a textured see-through
        // occluder's colour needs the point and uv.
        scene.accel.for_each_crossing(&ray, |c| {
            if c.triangle != SceneHit::NO_TRIANGLE && counted.again(c.object, c.t, c.front_face) {
                return ControlFlow::Continue(());
            }
            let closed = is_closed(scene, c.object);
            let m = scene.material_of(c.object);
            if closed && m.transmission > 0.0 {
                absorbed |= m.absorption != Vec3::ZERO;
                media.push((c.t, c.object, c.front_face));
            }
            let through = m.transparency + m.transmission;
            // An opaque surface blocks from either side: a segment that
            // leaves a closed opaque solid (a point inside a room, a light
            // outside) is as blocked as `occluded` finds it.
            if !(through > 0.0) {
                t = Vec3::ZERO;
                return ControlFlow::Break(());
            }
            let tint = || match (m.filter_color, &m.texture) {
                (Some(filter), _) => Some(through * filter.clamp(Vec3::ZERO, Vec3::ONE)),
                (None, Texture::Solid(solid)) => Some(through * solid.clamp(Vec3::ZERO, Vec3::ONE)),
                // `None` is not reached: the crossing is this structure's own.
                (None, _) => scene
                    .accel
                    .crossing_hit(&ray, c)
                    .map(|sh| through * albedo(scene, m, &sh).clamp(Vec3::ZERO, Vec3::ONE)),
            };
            // A see-through closed solid counts once, where the segment
            // enters it; its exits are counted below, for a segment that
            // starts inside it.
            if closed {
                inside.cross(c.object, c.front_face, tint);
                if !c.front_face {
                    return ControlFlow::Continue(());
                }
            }
            let Some(tint) = tint() else { return ControlFlow::Continue(()) };
            t *= tint;
            if t.max_element() > 0.0 { ControlFlow::Continue(()) } else { ControlFlow::Break(()) }
        });
        // A segment that starts inside a see-through solid (a point in a
        // glass case, the light outside) leaves it once more than it
        // enters: the surface dims it there, once.
        t *= inside.started_inside();
        // The shadow ray's direction is unit: `t` is distance. A ray toward
        // a directional light (t_max infinite) that starts inside glass
        // crosses an unbounded length of it in each absorbing channel. An
        // opaque occluder ended the walk early with `t` zero.
        if absorbed && t.max_element() > 0.0 {
            t *= (-optical_depth(media, ray.t_max, |m| scene.material_of(m).absorption)).exp();
        }
        t
    }
}

/// What [`Tracer::transmittance`] notes along one shadow ray.
#[derive(Default)]
struct ShadowScratch {
    /// The mesh crossings counted.
    counted: Counted,
    /// The closed see-through solids entered and left.
    inside: Inside,
    /// The crossings of media's surfaces, for the optical depth once the
    /// walk is done (they come unordered).
    media: Vec<MediumCrossing>,
}

/// The closed see-through solids a shadow ray crosses
/// ([`Tracer::transmittance`]): per solid (the first [`Inside::KEPT`]),
/// entries minus exits and the tint of its first exit, once one is seen.
#[derive(Default)]
struct Inside {
    solids: [(u32, i32, Option<Vec3>); Inside::KEPT],
    len: usize,
}

impl Inside {
    /// Solids followed; a ray starts inside more only in deep nesting.
    const KEPT: usize = 8;

    /// Notes a crossing of `object`, entering where `front`; `tint` gives
    /// its tint at the crossing (asked for only at a solid's first exit).
    fn cross(&mut self, object: u32, front: bool, tint: impl FnOnce() -> Option<Vec3>) {
        let kept = self.len.min(Self::KEPT);
        let solid = match self.solids[..kept].iter().position(|s| s.0 == object) {
            Some(k) => &mut self.solids[k],
            None if kept < Self::KEPT => {
                self.len += 1;
                self.solids[kept] = (object, 0, None);
                &mut self.solids[kept]
            }
            None => return,
        };
        if front {
            solid.1 += 1;
        } else {
            solid.1 -= 1;
            if solid.2.is_none() {
                solid.2 = Some(tint().unwrap_or(Vec3::ONE));
            }
        }
    }

    /// The product of the first-exit tints of the solids left more often
    /// than entered: those the segment started in.
    fn started_inside(&self) -> Vec3 {
        let kept = self.len.min(Self::KEPT);
        self.solids[..kept].iter().filter(|s| s.1 < 0).filter_map(|s| s.2).product()
    }
}

/// The mesh crossings a shadow ray has counted ([`Tracer::transmittance`]):
/// object, distance and side of the last [`Counted::KEPT`].
#[derive(Default)]
struct Counted {
    seen: [(u32, f32, bool); Counted::KEPT],
    len: usize,
}

impl Counted {
    /// Crossings remembered; a ray meets more only through many layers.
    const KEPT: usize = 16;

    /// Whether a crossing of `object` at `t` on side `front` was counted
    /// already: the same object, the same side and the same distance to a
    /// few units in the last place (two triangles' tests of one edge point
    /// round differently). Remembers it otherwise.
    fn again(&mut self, object: u32, t: f32, front: bool) -> bool {
        let near = |u: f32| (u - t).abs() <= 8.0 * f32::EPSILON * t.abs().max(u.abs());
        if self.seen[..self.len.min(Self::KEPT)].iter().any(|&(o, u, f)| o == object && f == front && near(u))
        {
            return true;
        }
        self.seen[self.len % Self::KEPT] = (object, t, front);
        self.len += 1;
        false
    }
}
