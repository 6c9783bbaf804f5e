//! From the parsed file to a renderable scene: validation with spans,
//! path resolution, mesh and texture caches.

use crate::error::{Location, SceneError};
use crate::format::{
    CameraDef, Color, FogModeDef, LightDef, MappingDef, MaterialDef, NormalsDef, Num, ObjectDef, ObjectKind,
    RenderDef, SceneFile, SpaceDef, Step, TextureDef, TextureKind, V3, WrapDef,
};
use crate::obj::{self, NormalMode};
use crate::{LoadOptions, LoadedScene, MeshInfo, SceneInfo};
use prism_bvh::{Accel, Object};
use prism_geometry::glam::{Mat4, Vec2, Vec3};
use prism_geometry::{
    Aabb, Cone, Cuboid, Cylinder, Disk, GeometryError, Instance, Plane, Shape, Shear, Sphere, Transform,
    Triangle, TriangleMesh,
};
use prism_shade::{
    Aov, Camera, Fog, FogMode, ImageTexture, Mapping, Material, PointLight, RenderSettings, Scene, Texture,
    Wrap,
};
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

type Result<T> = std::result::Result<T, SceneError>;

/// Render defaults (also in docs/scene-format.md).
pub(crate) const DEFAULT_WIDTH: u64 = 1280;
pub(crate) const DEFAULT_HEIGHT: u64 = 720;
pub(crate) const DEFAULT_SPP: u64 = 4;
pub(crate) const DEFAULT_MAX_DEPTH: u64 = 8;
pub(crate) const DEFAULT_MIN_CONTRIBUTION: f64 = 0.001;

/// An OBJ file as a scene ([`crate::load_obj_scene`]): image size,
/// vertical field of view (degrees) and background.
const OBJ_WIDTH: u64 = 640;
const OBJ_HEIGHT: u64 = 480;
const OBJ_FOV: f32 = 40.0;
const OBJ_BACKGROUND: [f64; 3] = [0.05, 0.05, 0.07];

/// A mesh file loaded once and shared by every object that names it.
struct CachedMesh {
    /// `(mesh index, MTL material index or None, model name)` per model.
    models: Vec<(u32, Option<usize>)>,
    /// MTL materials converted to prism's, added lazily: index into
    /// `Builder::materials` per MTL material.
    mtl_materials: Vec<Option<u32>>,
    raw_materials: Vec<tobj::Material>,
    material_error: Option<String>,
    mtl_dir: PathBuf,
    obj_path: PathBuf,
    info: usize,
}

pub(crate) struct Builder<'a> {
    file: &'a Path,
    text: &'a str,
    base: &'a Path,
    opts: &'a LoadOptions,
    inputs: Vec<PathBuf>,
    warnings: Vec<String>,
    textures: HashMap<(PathBuf, bool), Arc<ImageTexture>>,
    meshes: Vec<Arc<TriangleMesh>>,
    mesh_cache: HashMap<PathBuf, CachedMesh>,
    mesh_info: Vec<MeshInfo>,
    materials: Vec<Material>,
    material_names: Vec<String>,
    by_name: HashMap<String, u32>,
    default_material: Option<u32>,
    objects: Vec<Object>,
    object_materials: Vec<u32>,
    kinds: BTreeMap<String, usize>,
    /// Building a scene of one OBJ file ([`Builder::build_obj_scene`]): a
    /// material library that cannot be used gives grey, with a warning.
    obj_scene: bool,
}

impl<'a> Builder<'a> {
    pub(crate) fn new(file: &'a Path, text: &'a str, base: &'a Path, opts: &'a LoadOptions) -> Self {
        Self {
            file,
            text,
            base,
            opts,
            inputs: Vec::new(),
            warnings: Vec::new(),
            textures: HashMap::new(),
            meshes: Vec::new(),
            mesh_cache: HashMap::new(),
            mesh_info: Vec::new(),
            materials: Vec::new(),
            material_names: Vec::new(),
            by_name: HashMap::new(),
            default_material: None,
            objects: Vec::new(),
            object_materials: Vec::new(),
            kinds: BTreeMap::new(),
            obj_scene: false,
        }
    }

    // ----- locations and checked numbers -------------------------------

    fn loc(&self, span: &Range<usize>) -> Location {
        Location::at_span(self.file, self.text, span)
    }

    fn invalid(&self, span: &Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid { location: self.loc(span), message: message.into() }
    }

    fn finite(&self, n: &Num, what: &str) -> Result<f32> {
        let v = *n.get_ref();
        let f = v as f32;
        if f.is_finite() {
            Ok(f)
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be a finite number, got {v}")))
        }
    }

    fn positive(&self, n: &Num, what: &str) -> Result<f32> {
        let f = self.finite(n, what)?;
        if f > 0.0 {
            Ok(f)
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be greater than 0, got {}", n.get_ref())))
        }
    }

    fn non_negative(&self, n: &Num, what: &str) -> Result<f32> {
        let f = self.finite(n, what)?;
        if f >= 0.0 {
            Ok(f)
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be 0 or more, got {}", n.get_ref())))
        }
    }

    fn unit(&self, n: &Num, what: &str) -> Result<f32> {
        let f = self.finite(n, what)?;
        if (0.0..=1.0).contains(&f) {
            Ok(f)
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be between 0 and 1, got {}", n.get_ref())))
        }
    }

    fn vec3(&self, v: &V3, what: &str) -> Result<Vec3> {
        vec3_of(v.get_ref()).ok_or_else(|| {
            self.invalid(&v.span(), format!("{what} must be three finite numbers, got {:?}", v.get_ref()))
        })
    }

    fn color(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        match vec3_of(&c.get_ref().0) {
            Some(v) if v.min_element() >= 0.0 => Ok(v),
            _ => Err(self.invalid(
                &c.span(),
                format!("{what} must be three finite numbers >= 0, got {:?}", c.get_ref().0),
            )),
        }
    }

    fn geometry(&self, span: &Range<usize>, e: GeometryError) -> SceneError {
        self.invalid(span, e.to_string())
    }

    /// `p` resolved against the scene's directory and checked to be a file.
    fn resolve(&mut self, p: &Spanned<String>, what: &'static str) -> Result<PathBuf> {
        let raw = p.get_ref();
        if raw.trim().is_empty() {
            return Err(self.invalid(&p.span(), format!("{what} path is empty")));
        }
        let path = self.base.join(raw);
        let read_err = |reason: String| SceneError::Read {
            location: self.loc(&p.span()),
            what,
            path: path.clone(),
            reason,
        };
        let meta = std::fs::metadata(&path).map_err(|e| read_err(io_reason(&e)))?;
        if !meta.is_file() {
            return Err(read_err(not_a_file_reason(&meta)));
        }
        std::fs::canonicalize(&path).map_err(|e| read_err(io_reason(&e)))
    }

    fn note_input(&mut self, p: &Path) {
        if !self.inputs.iter().any(|q| q == p) {
            self.inputs.push(p.to_path_buf());
        }
    }

    // ----- the whole scene ---------------------------------------------

    pub(crate) fn build(mut self, file: SceneFile) -> Result<LoadedScene> {
        let limits = self.opts.limits;
        let ov = self.opts.overrides;
        let render = file.render.as_ref().map(Spanned::get_ref);
        let field_u64 = |f: Option<&Spanned<u64>>| f.map(|s| (*s.get_ref(), s.span()));

        // Resolution: overrides first (named by flag), else the file.
        let width_f = render.and_then(|r| field_u64(r.width.as_ref()));
        let height_f = render.and_then(|r| field_u64(r.height.as_ref()));
        let (fw, fh) = (
            width_f.as_ref().map_or(DEFAULT_WIDTH, |w| w.0),
            height_f.as_ref().map_or(DEFAULT_HEIGHT, |h| h.0),
        );
        let (width, height) = match (ov.width, ov.height) {
            (Some(w), Some(h)) => (u64::from(w), u64::from(h)),
            (Some(w), None) => (u64::from(w), scaled(fh, fw, u64::from(w))),
            (None, Some(h)) => (scaled(fw, fh, u64::from(h)), u64::from(h)),
            (None, None) => (fw, fh),
        };
        for (value, flag, spanned, name) in [
            (width, "--width", if ov.width.is_none() { width_f.as_ref() } else { None }, "width"),
            (height, "--height", if ov.height.is_none() { height_f.as_ref() } else { None }, "height"),
        ] {
            let problem = if value == 0 {
                Some(format!("image {name} must be at least 1 pixel"))
            } else if value > u64::from(limits.max_side) {
                Some(format!(
                    "image {name} {value} is over the limit of {} pixels per side (raise it with --max-side)",
                    limits.max_side
                ))
            } else {
                None
            };
            if let Some(message) = problem {
                return Err(match spanned {
                    Some((_, span)) => self.invalid(span, message),
                    None if ov.width.is_some() || ov.height.is_some() => SceneError::Option { flag, message },
                    None => SceneError::Invalid { location: Location::file(self.file), message },
                });
            }
        }
        if width * height > limits.max_pixels {
            let message = format!(
                "image of {width}×{height} = {} pixels is over the limit of {} pixels (raise it with --max-pixels)",
                width * height,
                limits.max_pixels
            );
            return Err(match (ov.width.or(ov.height), width_f.as_ref().or(height_f.as_ref())) {
                (Some(_), _) => SceneError::Option { flag: "--width/--height", message },
                (None, Some((_, span))) => self.invalid(span, message),
                (None, None) => SceneError::Invalid { location: Location::file(self.file), message },
            });
        }
        let (width, height) = (width as u32, height as u32);

        let spp_f = render.and_then(|r| field_u64(r.spp.as_ref()));
        let spp = match ov.spp {
            Some(s) => check_spp(u64::from(s), limits.max_spp)
                .map_err(|message| SceneError::Option { flag: "--spp", message })?,
            None => match &spp_f {
                Some((s, span)) => check_spp(*s, limits.max_spp).map_err(|m| self.invalid(span, m))?,
                None => DEFAULT_SPP as u32,
            },
        };
        let depth_f = render.and_then(|r| field_u64(r.max_depth.as_ref()));
        let max_depth = match ov.max_depth {
            Some(d) => check_depth(u64::from(d), limits.max_depth)
                .map_err(|message| SceneError::Option { flag: "--max-depth", message })?,
            None => match &depth_f {
                Some((d, span)) => check_depth(*d, limits.max_depth).map_err(|m| self.invalid(span, m))?,
                None => DEFAULT_MAX_DEPTH as u32,
            },
        };
        let min_contribution = match render.and_then(|r| r.min_contribution.as_ref()) {
            Some(n) => {
                let v = self.finite(n, "min_contribution")?;
                if !(0.0..1.0).contains(&v) {
                    return Err(
                        self.invalid(&n.span(), format!("min_contribution must be in [0, 1), got {v}"))
                    );
                }
                v
            }
            None => DEFAULT_MIN_CONTRIBUTION as f32,
        };
        let background = match render.and_then(|r| r.background.as_ref()) {
            Some(c) => self.color(c, "background")?,
            None => Vec3::ZERO,
        };
        let ambient = match render.and_then(|r| r.ambient.as_ref()) {
            Some(c) => self.color(c, "ambient")?,
            None => Vec3::ONE,
        };

        let mut aovs = Vec::new();
        if let Some(list) = render.and_then(|r| r.aov.as_ref()) {
            for name in list.get_ref() {
                let found = if name.get_ref() == "all" {
                    Aov::ALL.to_vec()
                } else {
                    vec![
                        name.get_ref()
                            .parse::<Aov>()
                            .map_err(|e| self.invalid(&name.span(), e.to_string()))?,
                    ]
                };
                for a in found {
                    if !aovs.contains(&a) {
                        aovs.push(a);
                    }
                }
            }
        }
        let aov_preview = render.and_then(|r| r.aov_preview).unwrap_or(false);

        let camera = self.camera(&file.camera, width, height)?;

        let mut lights = Vec::with_capacity(file.lights.len());
        for l in &file.lights {
            let d = l.get_ref();
            lights.push(PointLight {
                position: self.vec3(&d.position, "light position")?,
                color: match &d.color {
                    Some(c) => self.color(c, "light color")?,
                    None => Vec3::ONE,
                },
                intensity: match &d.intensity {
                    Some(n) => self.non_negative(n, "light intensity")?,
                    None => 1.0,
                },
            });
        }
        if lights.is_empty() {
            self.warnings.push(format!(
                "{}: the scene has no lights; only ambient light will show",
                self.file.display()
            ));
        }

        let (mut fog, file_fog_on) = match &file.fog {
            Some(f) => {
                let (fog, on) = self.fog(f)?;
                (Some(fog), on)
            }
            None => (None, false),
        };

        for (name, def) in &file.materials {
            self.material(name, def)?;
        }
        for o in &file.objects {
            self.object(o)?;
        }
        if self.objects.is_empty() {
            self.warnings.push(format!("{}: the scene has no objects", self.file.display()));
        }

        let objects_len = self.objects.len();
        let accel = Accel::build(std::mem::take(&mut self.meshes), std::mem::take(&mut self.objects))
            .map_err(|e| SceneError::Invalid {
                location: Location::file(self.file),
                message: format!("internal error: {e}"),
            })?;
        let bounds = accel.bounds();

        if ov.fog == Some(true) && fog.is_none() {
            let end = default_fog_end(camera.position(), bounds);
            self.warnings.push(format!(
                "{}: the scene has no [fog]; --fog uses linear white fog from 0 to {end:.1}",
                self.file.display()
            ));
            fog = Some(Fog { color: Vec3::ONE, mode: FogMode::Linear { start: 0.0, end } });
        }

        let stats = accel.stats();
        let info = SceneInfo {
            file: self.file.to_path_buf(),
            width,
            height,
            spp,
            max_depth,
            min_contribution,
            objects: objects_len,
            objects_by_kind: std::mem::take(&mut self.kinds),
            meshes: std::mem::take(&mut self.mesh_info),
            stored_triangles: stats.stored_triangles,
            instanced_triangles: stats.instanced_triangles,
            materials: std::mem::take(&mut self.material_names),
            lights: lights.clone(),
            bounds,
            fog,
            camera,
        };
        let scene = Scene {
            accel,
            object_materials: std::mem::take(&mut self.object_materials),
            materials: std::mem::take(&mut self.materials),
            lights,
            ambient,
            background,
            fog,
        };
        let settings = RenderSettings {
            camera,
            fog: ov.fog.unwrap_or(file_fog_on),
            spp,
            max_depth,
            min_contribution,
            threads: ov.threads,
        };
        Ok(LoadedScene {
            scene,
            settings,
            info,
            inputs: self.inputs,
            warnings: self.warnings,
            aovs,
            aov_preview,
        })
    }

    /// A scene of the OBJ file `name` (in the base directory) alone: the
    /// mesh, a camera framing its bounds, one light; see
    /// [`crate::load_obj_scene`] for the exact placement.
    pub(crate) fn build_obj_scene(mut self, name: &str) -> Result<LoadedScene> {
        fn at<T>(value: T) -> Spanned<T> {
            Spanned::new(0..0, value)
        }
        let v3 = |v: Vec3| at([f64::from(v.x), f64::from(v.y), f64::from(v.z)]);
        self.obj_scene = true;
        let mesh = ObjectDef {
            kind: at(ObjectKind::Mesh),
            material: None,
            transform: None,
            name: None,
            center: None,
            radius: None,
            point: None,
            normal: None,
            min: None,
            max: None,
            size: None,
            base: None,
            height: None,
            vertices: None,
            path: Some(at(name.to_owned())),
            normals: None,
        };
        self.object(&at(mesh))?;

        let bounds = self.meshes.iter().fold(Aabb::EMPTY, |b, m| b.union(Aabb::from_points(m.positions())));
        let (c, r) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.extent().length() / 2.0)
        };
        let r = if r > 0.0 { r } else { 1.0 };
        let ov = self.opts.overrides;
        let (w, h) = match (ov.width, ov.height) {
            (Some(w), Some(h)) => (u64::from(w), u64::from(h)),
            (Some(w), None) => (u64::from(w), scaled(OBJ_HEIGHT, OBJ_WIDTH, u64::from(w))),
            (None, Some(h)) => (scaled(OBJ_WIDTH, OBJ_HEIGHT, u64::from(h)), u64::from(h)),
            (None, None) => (OBJ_WIDTH, OBJ_HEIGHT),
        };
        let vfov = ov.fov.filter(|f| f.is_finite() && *f > 0.0 && *f < 180.0).unwrap_or(OBJ_FOV);
        let half_v = (vfov / 2.0).to_radians();
        let half_h = (half_v.tan() * w.max(1) as f32 / h.max(1) as f32).atan();
        let eye = c + Vec3::new(0.0, 0.0, r / half_v.min(half_h).sin());
        let light = c + r * Vec3::new(1.0, 2.0, 1.5);
        if !(c.is_finite() && r.is_finite() && eye.is_finite() && light.is_finite() && eye != c) {
            return Err(SceneError::Invalid {
                location: Location::file(self.file),
                message: format!(
                    "cannot frame the mesh, its bounds {} to {} are too large (or too small for their distance from the origin)",
                    bounds.min, bounds.max
                ),
            });
        }
        let file = SceneFile {
            render: Some(at(RenderDef {
                width: Some(at(OBJ_WIDTH)),
                height: Some(at(OBJ_HEIGHT)),
                background: Some(at(Color(OBJ_BACKGROUND))),
                ..RenderDef::default()
            })),
            camera: at(CameraDef {
                position: v3(eye),
                look_at: v3(c),
                up: None,
                fov: Some(at(f64::from(OBJ_FOV))),
            }),
            lights: vec![at(LightDef { position: v3(light), color: None, intensity: None })],
            fog: None,
            materials: BTreeMap::new(),
            objects: Vec::new(),
        };
        self.build(file)
    }

    fn camera(&self, c: &Spanned<crate::format::CameraDef>, width: u32, height: u32) -> Result<Camera> {
        let d = c.get_ref();
        let ov = self.opts.overrides;
        let flag_vec3 = |v: Vec3, flag: &'static str| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(SceneError::Option { flag, message: format!("X,Y,Z must be finite numbers, got {v}") })
            }
        };
        let position = match ov.camera_pos {
            Some(p) => flag_vec3(p, "--camera-pos")?,
            None => self.vec3(&d.position, "camera position")?,
        };
        let look_at = match ov.look_at {
            Some(p) => flag_vec3(p, "--look-at")?,
            None => self.vec3(&d.look_at, "camera look_at")?,
        };
        let up = match (ov.up, &d.up) {
            (Some(u), _) => flag_vec3(u, "--up")?,
            (None, Some(u)) => self.vec3(u, "camera up")?,
            (None, None) => Vec3::Y,
        };
        let fov = match (ov.fov, &d.fov) {
            (Some(f), _) => {
                if !(f.is_finite() && f > 0.0 && f < 180.0) {
                    return Err(SceneError::Option {
                        flag: "--fov",
                        message: format!(
                            "the vertical field of view in degrees must be between 0 and 180 (exclusive), got {f}"
                        ),
                    });
                }
                f
            }
            (None, Some(n)) => {
                let f = self.finite(n, "camera fov")?;
                if !(f > 0.0 && f < 180.0) {
                    return Err(self.invalid(
                        &n.span(),
                        format!("camera fov is the vertical field of view in degrees and must be between 0 and 180 (exclusive), got {f}"),
                    ));
                }
                f
            }
            (None, None) => 45.0,
        };
        // The flag to blame when the direction or up is unusable: the one
        // given, if any.
        let moved = if ov.camera_pos.is_some() {
            Some("--camera-pos")
        } else if ov.look_at.is_some() {
            Some("--look-at")
        } else {
            None
        };
        let forward = look_at - position;
        if forward.length_squared() == 0.0 || !forward.is_finite() {
            return Err(match moved {
                Some(flag) => SceneError::Option {
                    flag,
                    message: format!(
                        "the camera position {position} and the look-at point {look_at} must differ (and be less than 1e38 apart)"
                    ),
                },
                None => {
                    self.invalid(&d.look_at.span(), "camera look_at must differ from the camera position")
                }
            });
        }
        let f = forward.normalize();
        if up.length_squared() == 0.0 || f.cross(up.normalize()).length() < 1e-6 {
            let message = format!(
                "camera up {up} is zero or parallel to the view direction {f}; choose an up vector across it"
            );
            return Err(match (ov.up.map(|_| "--up").or(moved), &d.up) {
                (Some(flag), _) => SceneError::Option {
                    flag,
                    message: if flag == "--up" { message } else { format!("{message} (with --up)") },
                },
                (None, Some(u)) => self.invalid(&u.span(), message),
                (None, None) => self.invalid(&c.span(), message),
            });
        }
        Camera::new(position, look_at, up, fov, width, height).map_err(|e| {
            if ov.camera_pos.is_some() || ov.look_at.is_some() || ov.up.is_some() || ov.fov.is_some() {
                SceneError::Option { flag: "--camera-pos/--look-at/--up/--fov", message: e.to_string() }
            } else {
                self.invalid(&c.span(), e.to_string())
            }
        })
    }

    /// The fog's medium and whether the file turns it on (`enabled`).
    fn fog(&self, f: &Spanned<crate::format::FogDef>) -> Result<(Fog, bool)> {
        let d = f.get_ref();
        let mode = d.mode.as_ref().map_or(FogModeDef::Linear, |m| *m.get_ref());
        let color = match &d.color {
            Some(c) => self.color(c, "fog color")?,
            None => Vec3::ONE,
        };
        let mode = match mode {
            FogModeDef::Linear => {
                if let Some(n) = &d.density {
                    return Err(self.invalid(
                        &n.span(),
                        "`density` belongs to exponential fog; linear fog takes `start` and `end`",
                    ));
                }
                let start = match &d.start {
                    Some(n) => self.non_negative(n, "fog start")?,
                    None => 0.0,
                };
                let Some(end_n) = &d.end else {
                    return Err(self
                        .invalid(&f.span(), "linear fog needs `end`, the distance where the fog is total"));
                };
                let end = self.finite(end_n, "fog end")?;
                if !(end > start) {
                    return Err(self.invalid(
                        &end_n.span(),
                        format!("fog end ({end}) must be greater than fog start ({start})"),
                    ));
                }
                FogMode::Linear { start, end }
            }
            FogModeDef::Exponential | FogModeDef::ExponentialSquared => {
                if let Some(n) = d.start.as_ref().or(d.end.as_ref()) {
                    return Err(self.invalid(
                        &n.span(),
                        "`start` and `end` belong to linear fog; exponential fog takes `density`",
                    ));
                }
                let Some(n) = &d.density else {
                    return Err(self.invalid(&f.span(), "exponential fog needs `density` (per scene unit)"));
                };
                let density = self.positive(n, "fog density")?;
                if mode == FogModeDef::Exponential {
                    FogMode::Exponential { density }
                } else {
                    FogMode::ExponentialSquared { density }
                }
            }
        };
        Ok((Fog { color, mode }, d.enabled.unwrap_or(true)))
    }

    // ----- materials ---------------------------------------------------

    fn add_material(&mut self, name: String, m: Material) -> u32 {
        let i = self.materials.len() as u32;
        self.materials.push(m);
        self.material_names.push(name);
        i
    }

    fn material(&mut self, name: &Spanned<String>, def: &Spanned<MaterialDef>) -> Result<()> {
        let d = def.get_ref();
        let mut m = Material::diffuse(Vec3::splat(0.8));
        m.ambient = 0.1;
        m.diffuse = 0.9;
        m.specular = 0.3;
        m.shininess = 32.0;
        if let (Some(_), Some(t)) = (&d.color, &d.texture) {
            return Err(self.invalid(
                &t.span(),
                "a material takes `color` or `texture`, not both (an image texture has `tint`)",
            ));
        }
        if let Some(c) = &d.color {
            m.texture = Texture::Solid(self.color(c, "color")?);
        }
        if let Some(t) = &d.texture {
            m.texture = self.texture(t)?;
        }

        if let Some(n) = d.ambient.as_ref() {
            m.ambient = self.non_negative(n, "ambient")?;
        }
        if let Some(n) = d.diffuse.as_ref() {
            m.diffuse = self.non_negative(n, "diffuse")?;
        }
        if let Some(n) = d.specular.as_ref() {
            m.specular = self.non_negative(n, "specular")?;
        }
        if let Some(n) = d.shininess.as_ref() {
            m.shininess = self.non_negative(n, "shininess")?;
        }
        if let Some(c) = &d.specular_color {
            m.specular_color = self.color(c, "specular_color")?;
        }
        if let Some(n) = d.reflectivity.as_ref() {
            m.reflectivity = self.unit(n, "reflectivity")?;
        }
        if let Some(n) = d.transparency.as_ref() {
            m.transparency = self.unit(n, "transparency")?;
        }
        if let Some(n) = d.transmission.as_ref() {
            m.transmission = self.unit(n, "transmission")?;
        }
        if let Some(n) = d.ior.as_ref() {
            m.ior = self.positive(n, "ior")?;
        }
        if let Some(c) = &d.absorption {
            m.absorption = self.color(c, "absorption")?;
        }
        let sum = m.reflectivity + m.transparency + m.transmission;
        if sum > 1.0 + 1e-6 {
            return Err(self.invalid(
                &def.span(),
                format!("reflectivity + transparency + transmission must not exceed 1, got {sum}"),
            ));
        }
        m.validate().map_err(|e| self.invalid(&def.span(), e.to_string()))?;
        let key = name.get_ref().clone();
        if key.trim().is_empty() {
            return Err(self.invalid(&name.span(), "material names must not be empty"));
        }
        let i = self.add_material(key.clone(), m);
        self.by_name.insert(key, i);
        Ok(())
    }

    fn texture(&mut self, t: &Spanned<TextureDef>) -> Result<Texture> {
        let d = t.get_ref();
        let kind = *d.kind.get_ref();
        let foreign: Vec<(&str, Range<usize>)> = match kind {
            TextureKind::Checker => [
                ("path", d.path.as_ref().map(Spanned::span)),
                ("mapping", d.mapping.as_ref().map(Spanned::span)),
                ("wrap", d.wrap.as_ref().map(Spanned::span)),
                ("scale", d.scale.as_ref().map(Spanned::span)),
                ("tint", d.tint.as_ref().map(Spanned::span)),
            ]
            .into_iter()
            .filter_map(|(k, s)| s.map(|s| (k, s)))
            .collect(),
            TextureKind::Image => [
                ("a", d.a.as_ref().map(Spanned::span)),
                ("b", d.b.as_ref().map(Spanned::span)),
                ("size", d.size.as_ref().map(Spanned::span)),
                ("space", d.space.as_ref().map(Spanned::span)),
            ]
            .into_iter()
            .filter_map(|(k, s)| s.map(|s| (k, s)))
            .collect(),
        };
        if let Some((key, span)) = foreign.first() {
            let allowed = match kind {
                TextureKind::Checker => "a, b, size, space",
                TextureKind::Image => "path, mapping, wrap, scale, tint",
            };
            let kname = if kind == TextureKind::Checker { "checker" } else { "image" };
            return Err(self.invalid(
                span,
                format!("`{key}` is not a key of a {kname} texture (it takes: type, {allowed})"),
            ));
        }
        match kind {
            TextureKind::Checker => {
                let a = match &d.a {
                    Some(c) => self.color(c, "checker colour a")?,
                    None => Vec3::splat(0.9),
                };
                let b = match &d.b {
                    Some(c) => self.color(c, "checker colour b")?,
                    None => Vec3::splat(0.1),
                };
                let size = match &d.size {
                    Some(n) => self.positive(n, "checker size")?,
                    None => 1.0,
                };
                let world = d.space.as_ref().is_none_or(|s| *s.get_ref() == SpaceDef::World);
                Ok(Texture::Checker { a, b, size, world })
            }
            TextureKind::Image => {
                let Some(p) = &d.path else {
                    return Err(self.invalid(
                        &t.span(),
                        "an image texture needs `path`, the image file (PNG, JPEG or BMP)",
                    ));
                };
                let wrap = match d.wrap.as_ref().map(|w| *w.get_ref()) {
                    Some(WrapDef::Clamp) => Wrap::Clamp,
                    _ => Wrap::Repeat,
                };
                let image = self.load_texture(p, wrap, None)?;
                let mapping = match d.mapping.as_ref().map_or(MappingDef::Uv, |m| *m.get_ref()) {
                    MappingDef::Uv => Mapping::Uv,
                    MappingDef::Spherical => Mapping::Spherical,
                    MappingDef::Cylindrical => Mapping::Cylindrical,
                    MappingDef::Planar => Mapping::Planar,
                };
                let scale = match &d.scale {
                    Some(s) => {
                        let [u, v] = s.get_ref().0;
                        let sc = Vec2::new(u as f32, v as f32);
                        if !sc.is_finite() {
                            return Err(self.invalid(&s.span(), "texture scale must be finite"));
                        }
                        sc
                    }
                    None => Vec2::ONE,
                };
                let tint = match &d.tint {
                    Some(c) => self.color(c, "texture tint")?,
                    None => Vec3::ONE,
                };
                Ok(Texture::Image { image, mapping, scale, tint })
            }
        }
    }

    /// Loads (once) the texture named by `p` (relative to the scene, or to
    /// `mtl_dir` for textures named in an MTL file).
    fn load_texture(
        &mut self,
        p: &Spanned<String>,
        wrap: Wrap,
        mtl: Option<(&Path, &str)>,
    ) -> Result<Arc<ImageTexture>> {
        let path = match mtl {
            None => self.resolve(p, "texture")?,
            Some((dir, name)) => {
                let path = dir.join(name);
                let read_err = |reason: String| SceneError::Read {
                    location: self.loc(&p.span()),
                    what: "texture named in a material library",
                    path: path.clone(),
                    reason,
                };
                let meta = std::fs::metadata(&path).map_err(|e| read_err(io_reason(&e)))?;
                if !meta.is_file() {
                    return Err(read_err(not_a_file_reason(&meta)));
                }
                std::fs::canonicalize(&path).map_err(|e| read_err(io_reason(&e)))?
            }
        };
        let key = (path.clone(), wrap == Wrap::Repeat);
        if let Some(t) = self.textures.get(&key) {
            return Ok(Arc::clone(t));
        }
        let tex = ImageTexture::load(&path, wrap).map_err(|e| SceneError::Asset {
            location: Location::file(&path),
            message: match e {
                prism_shade::ShadeError::Texture { reason, .. } => {
                    format!("cannot use this texture: {reason}")
                }
                other => other.to_string(),
            },
            referenced_at: Box::new(self.loc(&p.span())),
        })?;
        self.note_input(&path);
        let tex = Arc::new(tex);
        self.textures.insert(key, Arc::clone(&tex));
        Ok(tex)
    }

    fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        let mut m = Material::diffuse(Vec3::splat(0.8));
        m.specular = 0.3;
        let i = self.add_material("(default)".into(), m);
        self.default_material = Some(i);
        i
    }

    fn named_material(&self, name: &Spanned<String>) -> Result<u32> {
        self.by_name.get(name.get_ref()).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
            known.sort_unstable();
            let list = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            self.invalid(
                &name.span(),
                format!("unknown material `{}`; the scene defines: {list}", name.get_ref()),
            )
        })
    }

    // ----- objects -----------------------------------------------------

    fn object(&mut self, o: &Spanned<ObjectDef>) -> Result<()> {
        let d = o.get_ref();
        let kind = *d.kind.get_ref();
        self.check_keys(d, kind)?;
        let transform = self.transform(d)?;
        let material = match &d.material {
            Some(name) => Some(self.named_material(name)?),
            None => None,
        };
        let ospan = o.span();
        let shape: Shape = match kind {
            ObjectKind::Sphere => {
                let center = self.opt_vec3(&d.center, "sphere center", Vec3::ZERO)?;
                let r = self.required_num(&d.radius, &ospan, "sphere", "radius")?;
                let radius = self.positive(r, "sphere radius")?;
                Sphere::new(center, radius).map_err(|e| self.geometry(&ospan, e))?.into()
            }
            ObjectKind::Plane => {
                let point = self.opt_vec3(&d.point, "plane point", Vec3::ZERO)?;
                let normal = self.opt_vec3(&d.normal, "plane normal", Vec3::Y)?;
                let span = d.normal.as_ref().map_or_else(|| ospan.clone(), Spanned::span);
                Plane::new(point, normal).map_err(|e| self.geometry(&span, e))?.into()
            }
            ObjectKind::Cuboid => self.cuboid(d, &ospan)?,
            ObjectKind::Cylinder | ObjectKind::Cone => {
                let name = kind.name();
                let base = self.opt_vec3(&d.base, &format!("{name} base"), Vec3::ZERO)?;
                let r = self.required_num(&d.radius, &ospan, name, "radius")?;
                let radius = self.positive(r, &format!("{name} radius"))?;
                let h = self.required_num(&d.height, &ospan, name, "height")?;
                let height = self.positive(h, &format!("{name} height"))?;
                if kind == ObjectKind::Cone {
                    Cone::new(base, radius, height).map_err(|e| self.geometry(&ospan, e))?.into()
                } else {
                    Cylinder::new(base, radius, height).map_err(|e| self.geometry(&ospan, e))?.into()
                }
            }
            ObjectKind::Disk => {
                let center = self.opt_vec3(&d.center, "disk center", Vec3::ZERO)?;
                let normal = self.opt_vec3(&d.normal, "disk normal", Vec3::Y)?;
                let r = self.required_num(&d.radius, &ospan, "disk", "radius")?;
                let radius = self.positive(r, "disk radius")?;
                let span = d.normal.as_ref().map_or_else(|| ospan.clone(), Spanned::span);
                Disk::new(center, normal, radius).map_err(|e| self.geometry(&span, e))?.into()
            }
            ObjectKind::Triangle => {
                let Some(v) = &d.vertices else {
                    return Err(self
                        .invalid(&ospan, "a triangle needs `vertices = [[x, y, z], [x, y, z], [x, y, z]]`"));
                };
                let mut pts = [Vec3::ZERO; 3];
                for (p, raw) in pts.iter_mut().zip(v.get_ref()) {
                    *p = vec3_of(raw)
                        .ok_or_else(|| self.invalid(&v.span(), "triangle vertices must be finite numbers"))?;
                }
                Triangle::new(pts).map_err(|e| self.geometry(&v.span(), e))?.into()
            }
            ObjectKind::Mesh => return self.mesh(d, &ospan, transform, material),
        };
        let material = match material {
            Some(m) => m,
            None => self.default_material(),
        };
        *self.kinds.entry(shape.kind().to_string()).or_default() += 1;
        self.objects.push(Object::Shape(Instance::new(shape, transform)));
        self.object_materials.push(material);
        Ok(())
    }

    fn required_num<'n>(
        &self,
        n: &'n Option<Num>,
        span: &Range<usize>,
        kind: &str,
        key: &str,
    ) -> Result<&'n Num> {
        n.as_ref().ok_or_else(|| self.invalid(span, format!("a {kind} needs `{key}`")))
    }

    fn opt_vec3(&self, v: &Option<V3>, what: &str, default: Vec3) -> Result<Vec3> {
        match v {
            Some(v) => self.vec3(v, what),
            None => Ok(default),
        }
    }

    fn check_keys(&self, d: &ObjectDef, kind: ObjectKind) -> Result<()> {
        let present: [(&str, Option<Range<usize>>); 12] = [
            ("center", d.center.as_ref().map(Spanned::span)),
            ("radius", d.radius.as_ref().map(Spanned::span)),
            ("point", d.point.as_ref().map(Spanned::span)),
            ("normal", d.normal.as_ref().map(Spanned::span)),
            ("min", d.min.as_ref().map(Spanned::span)),
            ("max", d.max.as_ref().map(Spanned::span)),
            ("size", d.size.as_ref().map(Spanned::span)),
            ("base", d.base.as_ref().map(Spanned::span)),
            ("height", d.height.as_ref().map(Spanned::span)),
            ("vertices", d.vertices.as_ref().map(Spanned::span)),
            ("path", d.path.as_ref().map(Spanned::span)),
            ("normals", d.normals.as_ref().map(Spanned::span)),
        ];
        let allowed: &[&str] = match kind {
            ObjectKind::Sphere => &["center", "radius"],
            ObjectKind::Plane => &["point", "normal"],
            ObjectKind::Cuboid => &["center", "size", "min", "max"],
            ObjectKind::Cylinder | ObjectKind::Cone => &["base", "radius", "height"],
            ObjectKind::Disk => &["center", "normal", "radius"],
            ObjectKind::Triangle => &["vertices"],
            ObjectKind::Mesh => &["path", "normals"],
        };
        for (key, span) in present {
            if let Some(span) = span
                && !allowed.contains(&key)
            {
                return Err(self.invalid(
                    &span,
                    format!(
                        "`{key}` is not a key of a {} (it takes: {}, plus material, transform, name)",
                        kind.name(),
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    fn cuboid(&self, d: &ObjectDef, ospan: &Range<usize>) -> Result<Shape> {
        let cuboid = match (&d.min, &d.max, &d.size) {
            (Some(min), Some(max), None) => {
                if let Some(c) = &d.center {
                    return Err(self.invalid(
                        &c.span(),
                        "a cuboid takes `min` and `max`, or `size` (and `center`), not both",
                    ));
                }
                let (lo, hi) = (self.vec3(min, "cuboid min")?, self.vec3(max, "cuboid max")?);
                if !(hi - lo).cmpgt(Vec3::ZERO).all() {
                    return Err(self.invalid(
                        &max.span(),
                        format!("cuboid max {hi} must be greater than min {lo} on every axis"),
                    ));
                }
                Cuboid::new(lo, hi).map_err(|e| self.geometry(&max.span(), e))?
            }
            (None, None, Some(size)) => {
                let center = self.opt_vec3(&d.center, "cuboid center", Vec3::ZERO)?;
                let s = vec3_of(&size.get_ref().0)
                    .ok_or_else(|| self.invalid(&size.span(), "cuboid size must be finite"))?;
                if !(s.min_element() > 0.0) {
                    return Err(self.invalid(
                        &size.span(),
                        format!("cuboid size must be greater than 0 on every axis, got {s}"),
                    ));
                }
                Cuboid::from_center_size(center, s).map_err(|e| self.geometry(&size.span(), e))?
            }
            _ => {
                return Err(self.invalid(
                    ospan,
                    "a cuboid needs `size` (a number or [x, y, z], with an optional `center`), or both `min` and `max`",
                ));
            }
        };
        Ok(cuboid.into())
    }

    fn transform(&self, d: &ObjectDef) -> Result<Transform> {
        let Some(steps) = &d.transform else { return Ok(Transform::IDENTITY) };
        let mut acc = Transform::IDENTITY;
        for step in steps.get_ref() {
            let span = step.span();
            let bad =
                |what: &str| self.invalid(&span, format!("transform step: {what} must be finite numbers"));
            let f = |v: f64| v as f32;
            let t = match step.get_ref() {
                Step::Translate(v) => Transform::translate(vec3_of(v).ok_or_else(|| bad("translate"))?)
                    .map_err(|e| self.geometry(&span, e))?,
                Step::RotateX(a) | Step::RotateY(a) | Step::RotateZ(a) => {
                    let a = f(*a);
                    if !a.is_finite() {
                        return Err(bad("a rotation angle"));
                    }
                    match step.get_ref() {
                        Step::RotateX(_) => Transform::rotate_x(a.to_radians()),
                        Step::RotateY(_) => Transform::rotate_y(a.to_radians()),
                        _ => Transform::rotate_z(a.to_radians()),
                    }
                }
                Step::Rotate(r) => {
                    let axis = vec3_of(&r.axis).ok_or_else(|| bad("a rotation axis"))?;
                    let deg = f(r.degrees);
                    if !deg.is_finite() {
                        return Err(bad("a rotation angle"));
                    }
                    Transform::rotate_axis(axis, deg.to_radians()).map_err(|e| self.geometry(&span, e))?
                }
                Step::Scale(s) => {
                    let s = vec3_of(&s.0).ok_or_else(|| bad("scale"))?;
                    if s.cmpeq(Vec3::ZERO).any() {
                        return Err(self.invalid(&span, format!("scale {s} has a zero factor; it would flatten the object (singular transform)")));
                    }
                    Transform::scale(s).map_err(|e| self.geometry(&span, e))?
                }
                Step::Shear(s) | Step::ShearAngle(s) => {
                    let angle = matches!(step.get_ref(), Step::ShearAngle(_));
                    let raw = [s.xy, s.xz, s.yx, s.yz, s.zx, s.zy];
                    let mut k = [0f32; 6];
                    for (o, v) in k.iter_mut().zip(raw) {
                        let v = f(v);
                        if !v.is_finite() {
                            return Err(bad("shear factors"));
                        }
                        if angle && !(v.abs() < 90.0) {
                            return Err(self.invalid(
                                &span,
                                format!("shear angles must be between -90 and 90 degrees, got {v}"),
                            ));
                        }
                        *o = if angle { v.to_radians().tan() } else { v };
                    }
                    let [xy, xz, yx, yz, zx, zy] = k;
                    Transform::shear(Shear { xy, xz, yx, yz, zx, zy }).map_err(|e| self.geometry(&span, e))?
                }
                Step::Matrix(rows) => {
                    let mut cols = [[0f32; 4]; 4];
                    for (r, row) in rows.iter().enumerate() {
                        for (c, v) in row.iter().enumerate() {
                            let v = f(*v);
                            if !v.is_finite() {
                                return Err(bad("matrix entries"));
                            }
                            cols[c][r] = v;
                        }
                    }
                    Transform::try_from_mat4(Mat4::from_cols_array_2d(&cols))
                        .map_err(|e| self.geometry(&span, e))?
                }
            };
            acc = acc.then(&t);
        }
        // The product of invertible steps can still be numerically singular.
        Transform::try_from_affine(acc.matrix()).map_err(|e| self.geometry(&steps.span(), e))
    }

    // ----- meshes ------------------------------------------------------

    fn mesh(
        &mut self,
        d: &ObjectDef,
        ospan: &Range<usize>,
        transform: Transform,
        mut material: Option<u32>,
    ) -> Result<()> {
        let Some(p) = &d.path else {
            return Err(self.invalid(ospan, "a mesh needs `path`, an OBJ file (relative to the scene file)"));
        };
        let path = self.resolve(p, "mesh")?;
        let mode = match d.normals.as_ref().map(|n| *n.get_ref()) {
            None | Some(NormalsDef::Auto) => NormalMode::Auto,
            Some(NormalsDef::Smooth) => NormalMode::Smooth,
            Some(NormalsDef::Flat) => NormalMode::Flat,
        };
        let key = {
            let mut k = path.clone().into_os_string();
            k.push(match mode {
                NormalMode::Auto => "#auto",
                NormalMode::Smooth => "#smooth",
                NormalMode::Flat => "#flat",
            });
            PathBuf::from(k)
        };
        let referenced_at = self.loc(&p.span());
        if !self.mesh_cache.contains_key(&key) {
            let bytes = std::fs::read(&path).map_err(|e| SceneError::Read {
                location: referenced_at.clone(),
                what: "mesh",
                path: path.clone(),
                reason: io_reason(&e),
            })?;
            let file = obj::load_obj(&path, &bytes, mode, &referenced_at)?;
            self.note_input(&path);
            for m in &file.mtl_files {
                if let Ok(c) = std::fs::canonicalize(m) {
                    self.note_input(&c);
                }
            }
            let mut models = Vec::with_capacity(file.models.len());
            let mut triangles = 0;
            let mut degenerate = 0;
            for model in file.models {
                triangles += model.mesh.len();
                degenerate += model.degenerate;
                let i = self.meshes.len() as u32;
                self.meshes.push(Arc::new(model.mesh));
                models.push((i, model.material));
            }
            if degenerate > 0 {
                self.warnings.push(format!(
                    "{}: {degenerate} of {triangles} triangles have zero area and will not be rendered",
                    path.display()
                ));
            }
            let info = self.mesh_info.len();
            self.mesh_info.push(MeshInfo {
                path: path.clone(),
                models: models.len(),
                triangles,
                instances: 0,
            });
            let n_mat = file.materials.len();
            self.mesh_cache.insert(
                key.clone(),
                CachedMesh {
                    models,
                    mtl_materials: vec![None; n_mat],
                    raw_materials: file.materials,
                    material_error: file.material_error,
                    mtl_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                    obj_path: path.clone(),
                    info,
                },
            );
        }
        if self.obj_scene
            && material.is_none()
            && let Some(e) = self.mesh_cache.get(&key).and_then(|c| c.material_error.clone())
        {
            self.warnings.push(format!("{}: {e}; rendering the mesh in neutral grey", path.display()));
            material = Some(self.default_material());
        }
        let Some(cached) = self.mesh_cache.get(&key) else {
            return Err(self.invalid(ospan, "internal error: mesh cache"));
        };
        if let (None, Some(e)) = (material, &cached.material_error) {
            return Err(SceneError::Asset {
                location: Location::file(&cached.obj_path),
                message: format!("{e}; give the object a `material` to render it without its MTL materials"),
                referenced_at: Box::new(referenced_at),
            });
        }
        let models = cached.models.clone();
        let info = cached.info;
        if let Some(mi) = self.mesh_info.get_mut(info) {
            mi.instances += 1;
        }
        for (mesh, mtl) in models {
            let mat = match (material, mtl) {
                (Some(m), _) => m,
                (None, Some(k)) => self.mtl_material(&key, k, p)?,
                (None, None) => self.default_material(),
            };
            self.objects.push(Object::Mesh { mesh, transform });
            self.object_materials.push(mat);
            *self.kinds.entry("mesh".into()).or_default() += 1;
        }
        Ok(())
    }

    /// The prism material for MTL material `k` of the cached mesh `key`.
    fn mtl_material(&mut self, key: &Path, k: usize, p: &Spanned<String>) -> Result<u32> {
        let Some(cached) = self.mesh_cache.get(key) else {
            return Err(self.invalid(&p.span(), "internal error: mesh cache"));
        };
        if let Some(Some(i)) = cached.mtl_materials.get(k) {
            return Ok(*i);
        }
        if let Some(e) = &cached.material_error {
            return Err(SceneError::Asset {
                location: Location::file(&cached.obj_path),
                message: format!("{e}; give the object a `material` to render it without its MTL materials"),
                referenced_at: Box::new(self.loc(&p.span())),
            });
        }
        let Some(raw) = cached.raw_materials.get(k).cloned() else {
            return Err(self.invalid(
                &p.span(),
                format!("the OBJ file uses material {k}, which its MTL file does not define"),
            ));
        };
        let mtl_dir = cached.mtl_dir.clone();
        let obj_name =
            cached.obj_path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let obj_path = cached.obj_path.clone();
        let m = self.convert_mtl(&raw, &mtl_dir, &obj_path, p)?;
        let i = self.add_material(format!("{obj_name}/{}", raw.name), m);
        if let Some(slot) = self.mesh_cache.get_mut(key).and_then(|c| c.mtl_materials.get_mut(k)) {
            *slot = Some(i);
        }
        Ok(i)
    }

    fn convert_mtl(
        &mut self,
        raw: &tobj::Material,
        dir: &Path,
        obj_path: &Path,
        p: &Spanned<String>,
    ) -> Result<Material> {
        let bad = |what: &str| SceneError::Asset {
            location: Location::file(obj_path),
            message: format!("material `{}` in the MTL file: {what} must be finite and >= 0", raw.name),
            referenced_at: Box::new(self.loc(&p.span())),
        };
        let v3 = |a: [f32; 3], what: &str| {
            let v = Vec3::from_array(a);
            if v.is_finite() && v.min_element() >= 0.0 { Ok(v) } else { Err(bad(what)) }
        };
        let scalar = |x: f32, what: &str| if x.is_finite() && x >= 0.0 { Ok(x) } else { Err(bad(what)) };
        let kd = raw.diffuse.map(|c| v3(c, "Kd")).transpose()?;
        let mut m = Material::diffuse(kd.unwrap_or(Vec3::splat(0.8)));
        m.ambient = 0.1;
        m.diffuse = 0.9;
        if let Some(ks) = raw.specular.map(|c| v3(c, "Ks")).transpose()? {
            let peak = ks.max_element();
            m.specular = peak;
            m.specular_color = if peak > 0.0 { ks / peak } else { Vec3::ONE };
        } else {
            m.specular = 0.0;
        }
        if let Some(ns) = raw.shininess {
            m.shininess = scalar(ns, "Ns")?;
        }
        if let Some(ni) = raw.optical_density {
            let ni = scalar(ni, "Ni")?;
            if ni > 0.0 {
                m.ior = ni;
            }
        }
        let illum = raw.illumination_model.unwrap_or(2);
        if matches!(illum, 3 | 5 | 8) {
            m.reflectivity =
                raw.specular.map_or(0.5, |ks| Vec3::from_array(ks).max_element()).clamp(0.0, 1.0);
        }
        // `Tr` (transparency) is the complement of `d`; tobj keeps it as an unknown key.
        let tr = raw.unknown_param.get("Tr").and_then(|t| t.trim().parse::<f32>().ok()).map(|t| 1.0 - t);
        if let Some(d) = raw.dissolve.or(tr) {
            let d = scalar(d, "d")?.min(1.0);
            if d < 1.0 {
                if matches!(illum, 4 | 6 | 7 | 9) {
                    m.transmission = 1.0 - d;
                } else {
                    m.transparency = 1.0 - d;
                }
            }
        }
        let sum = m.reflectivity + m.transparency + m.transmission;
        if sum > 1.0 {
            m.reflectivity /= sum;
            m.transparency /= sum;
            m.transmission /= sum;
        }
        if let Some(tex) = &raw.diffuse_texture {
            let direct = dir.join(tex.trim());
            let name = if direct.is_file() {
                tex.trim().to_string()
            } else {
                // Options such as `-s 1 1 1` come before the file name.
                tex.split_whitespace().last().unwrap_or("").to_string()
            };
            let image = self.load_texture(p, Wrap::Repeat, Some((dir, &name)))?;
            m.texture = Texture::Image {
                image,
                mapping: Mapping::Uv,
                scale: Vec2::ONE,
                tint: kd.unwrap_or(Vec3::ONE),
            };
        }
        m.validate().map_err(|e| SceneError::Asset {
            location: Location::file(obj_path),
            message: format!("material `{}` in the MTL file: {e}", raw.name),
            referenced_at: Box::new(self.loc(&p.span())),
        })?;
        Ok(m)
    }
}

fn vec3_of(v: &[f64; 3]) -> Option<Vec3> {
    let out = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    out.is_finite().then_some(out)
}

/// `other * target / this`, rounded, at least 1: the other side of an
/// image resized to keep its aspect ratio.
fn scaled(other: u64, this: u64, target: u64) -> u64 {
    if this == 0 {
        return other;
    }
    ((other as f64 * target as f64 / this as f64).round() as u64).max(1)
}

fn check_spp(spp: u64, max: u32) -> std::result::Result<u32, String> {
    if spp == 0 {
        Err("spp (samples per pixel) must be at least 1".into())
    } else if spp > u64::from(max) {
        Err(format!("spp {spp} is over the limit of {max} samples per pixel (raise it with --max-spp)"))
    } else {
        Ok(spp as u32)
    }
}

fn check_depth(depth: u64, max: u32) -> std::result::Result<u32, String> {
    if depth > u64::from(max) {
        Err(format!(
            "max_depth {depth} is over the limit of {max} bounces (the renderer never goes deeper than {})",
            prism_shade::MAX_DEPTH_LIMIT
        ))
    } else {
        Ok(depth as u32)
    }
}

fn default_fog_end(eye: Vec3, bounds: Aabb) -> f32 {
    if bounds.is_empty() || !bounds.is_finite() {
        return 100.0;
    }
    let far = bounds.corners().iter().map(|c| c.distance(eye)).fold(0.0_f32, f32::max);
    if far.is_finite() && far > 0.0 { 1.5 * far } else { 100.0 }
}

/// Why a path that is not a regular file cannot be read as one: a
/// directory, or a device (such as `/dev/zero`) or FIFO that could be read
/// forever.
pub(crate) fn not_a_file_reason(meta: &std::fs::Metadata) -> String {
    if meta.is_dir() {
        "it is a directory, expected a file".into()
    } else {
        "it is not a regular file (a device, FIFO or socket?)".into()
    }
}

pub(crate) fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// An error from [`Builder::build_obj_scene`], made to point at the OBJ
/// file `path` (as the user named it; `canonical` is its resolved path):
/// the builder's positions in its (empty) scene text are dropped, and a
/// problem in the OBJ itself is reported at its line, not as an asset
/// "used at" itself.
pub(crate) fn obj_scene_error(e: SceneError, path: &Path, canonical: &Path) -> SceneError {
    let own = |l: Location| if l.file == path { Location::file(path) } else { l };
    match e {
        SceneError::Asset { location, message, .. } if location.file == canonical => {
            SceneError::Invalid { location: Location { file: path.to_path_buf(), ..location }, message }
        }
        SceneError::Asset { location, message, .. } => {
            SceneError::Asset { location, message, referenced_at: Box::new(Location::file(path)) }
        }
        SceneError::Read { location, what, path: p, reason } => {
            SceneError::Read { location: own(location), what, path: p, reason }
        }
        SceneError::Syntax { location, message } => SceneError::Syntax { location: own(location), message },
        SceneError::Invalid { location, message } => SceneError::Invalid { location: own(location), message },
        e @ SceneError::Option { .. } => e,
    }
}
