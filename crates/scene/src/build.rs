//! The build: a scene description ([`SceneFile`], or the typed values of
//! an OBJ file as a scene) and the files it names, already read
//! ([`Resources`]), to a renderable [`LoadedScene`]. Pure: no I/O, so a
//! scene can be built from a string and in-memory resources.

use crate::check::{Ctx, Result};
use crate::error::{Location, SceneError};
use crate::format::{ObjectDef, SceneFile};
use crate::material::{self, Materials};
use crate::obj::{NormalMode, ObjFile};
use crate::read::{Failure, Resources, TextureFile};
use crate::settings::{self, Defaults, Settings};
use crate::view::{self, CameraSource};
use crate::{LoadOptions, LoadedScene, MeshInfo, Overrides, SceneInfo};
use prism_bvh::{Accel, Object};
use prism_geometry::glam::Vec3;
use prism_geometry::{Aabb, Instance, Transform, TriangleMesh};
use prism_shade::{
    AreaShape, Camera, Fog, FogMode, ImageTexture, Light, LightKind, PointLight, RenderSettings, Scene,
};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

/// Above this depth, a scene with glass and no contribution cut-off is
/// warned about: up to 2^depth rays a sample.
const SPLIT_WARN_DEPTH: u32 = 12;

/// The farthest an OBJ file's framed camera stands from the mesh, in
/// radii of its bounding sphere.
const FRAMING_REACH: f32 = 1e4;

/// The vertical field of view (degrees) of an OBJ file as a scene.
const OBJ_FOV: f32 = 40.0;

/// Builds the scene `file` (whose text and name `ctx` holds) from the
/// files it names, `res`, with `options`.
pub(crate) fn build_scene(
    ctx: Ctx,
    file: &SceneFile,
    res: &Resources,
    options: &LoadOptions,
) -> Result<LoadedScene> {
    let settings =
        settings::resolve(&ctx, file.render.as_ref().map(Spanned::get_ref), Defaults::FILE, options)?;
    let mut b = Build::new(ctx, res, options);
    let lights = file.lights.iter().map(|l| crate::light::light(&ctx, l)).collect::<Result<Vec<_>>>()?;
    let camera_def = view::choose_camera(&ctx, file, options.overrides.camera.as_ref())?;
    if lights.is_empty() {
        b.warn("the scene has no lights; only ambient light will show");
    }
    let fog = file.fog.as_ref().map(|f| view::fog(&ctx, f)).transpose()?;
    for (name, def) in &file.materials {
        let m = material::material(&ctx, def, &mut |p, wrap| b.image(res.texture(p.get_ref(), wrap), p))?;
        b.materials.add_named(&ctx, name, m)?;
    }
    for o in &file.objects {
        b.object(o)?;
    }
    let environment = match file.render.as_ref().and_then(|r| r.get_ref().background.as_ref()) {
        Some(bg) => view::environment(&ctx, bg.get_ref(), &mut |p| {
            b.image(res.texture(p.get_ref(), prism_shade::Wrap::Repeat), p)
        })?,
        None => None,
    };
    let mut loaded = b.finish(settings, &CameraSource::File(camera_def), lights, fog)?;
    loaded.scene.environment = environment;
    Ok(loaded)
}

/// Builds a scene of the OBJ file `name` alone (read into `res`; its
/// canonical path `canonical`): the mesh, a camera framing it, one light
/// (see [`crate::load_obj_scene`] for the placement). `ctx` names the
/// file as the user gave it; problems in the OBJ are reported at its
/// lines, not as an asset "used at" itself.
pub(crate) fn build_obj_scene(
    ctx: Ctx,
    name: &str,
    canonical: &Path,
    res: &Resources,
    options: &LoadOptions,
) -> Result<LoadedScene> {
    let own = |e: SceneError| match e {
        SceneError::Asset { location, message, .. } if location.file == canonical => {
            SceneError::Invalid { location: Location { file: ctx.file.to_path_buf(), ..location }, message }
        }
        e => e,
    };
    let mut b = Build::new(ctx, res, options);
    let named_at = Location::file(ctx.file);
    let obj = b.lookup_mesh(name, NormalMode::Auto, named_at.clone()).map_err(own)?;
    b.register_mesh(&obj, NormalMode::Auto);
    let material = match &obj.material_error {
        Some(e) => {
            b.warnings.push(format!("{}: {e}; rendering the mesh in neutral grey", obj.path.display()));
            Some(b.materials.default_material())
        }
        None => None,
    };
    b.instance_mesh(&obj, NormalMode::Auto, &named_at, Transform::IDENTITY, material).map_err(own)?;

    let bounds = b.meshes.iter().fold(Aabb::EMPTY, |b, m| b.union(Aabb::from_points(m.positions())));
    let (c, r) =
        if bounds.is_empty() { (Vec3::ZERO, 1.0) } else { (bounds.center(), bounds.extent().length() / 2.0) };
    let r = if r > 0.0 { r } else { 1.0 };
    let ov = options.overrides;
    let d = Defaults::OBJ;
    let (w, h) = settings::fit_size(d.width, d.height, ov.width, ov.height);
    let vfov = ov.fov.filter(|f| f.is_finite() && *f > 0.0 && *f < 180.0).unwrap_or(OBJ_FOV);
    let half_v = (vfov / 2.0).to_radians();
    let half_h = (half_v.tan() * w.max(1) as f32 / h.max(1) as f32).atan();
    let framing = crate::obj_view::Framing::new(options.obj.view.unwrap_or_default(), bounds);
    // The eye stands back so the bounding sphere fills the view; a field of
    // view so narrow that it stands more than `FRAMING_REACH` radii away
    // leaves the mesh smaller than 32-bit floats resolve at the eye.
    let away = 1.0 / half_v.min(half_h).sin();
    if let Some(fov) = ov.fov
        && !(away <= FRAMING_REACH)
    {
        return Err(SceneError::Option {
            flag: "--fov",
            message: format!(
                "{fov}° is too narrow to frame the mesh: the camera would stand {away:.1e} times the mesh's radius away (at most {FRAMING_REACH:.0e}); give 0.02° or more"
            ),
        });
    }
    let eye = c + framing.toward_eye * (r * away);
    let light = match options.obj.light {
        Some(l) if l.is_finite() => l,
        Some(l) => {
            return Err(SceneError::Option {
                flag: "--light",
                message: format!("X,Y,Z must be finite numbers, got {l}"),
            });
        }
        None => framing.light(c, r),
    };
    // With the camera given (`--camera-pos` and `--look-at`), the framed
    // eye is not used; the default light still comes from the bounds.
    let given_camera = ov.camera_pos.is_some() && ov.look_at.is_some();
    let point = |v: Vec3| {
        let n = |x: f32| if x.abs() < 1e6 { x.to_string() } else { format!("{x:e}") };
        format!("[{}, {}, {}]", n(v.x), n(v.y), n(v.z))
    };
    if !(given_camera || (c.is_finite() && r.is_finite() && eye.is_finite() && eye != c)) {
        return Err(ctx.invalid_file(format!(
            "cannot frame the mesh, its bounds {} to {} are too large (or too small for their distance from the origin); give --camera-pos and --look-at",
            point(bounds.min),
            point(bounds.max)
        )));
    }
    if !light.is_finite() {
        return Err(ctx.invalid_file(format!(
            "cannot place the default light for the mesh, its bounds {} to {} are too large; give --light X,Y,Z",
            point(bounds.min),
            point(bounds.max)
        )));
    }
    let settings = settings::resolve(&ctx, None, d, options)?;
    let lights = vec![PointLight { position: light, color: Vec3::ONE, intensity: 1.0 }.into()];
    if options.obj.floor && !bounds.is_empty() {
        b.floor(bounds.min.y).map_err(|e| ctx.invalid_file(format!("cannot place the floor: {e}")))?;
    }
    let camera = CameraSource::Framed { eye, look_at: c, fov: OBJ_FOV, up: framing.up };
    b.finish(settings, &camera, lights, None).map_err(own)
}

/// Where a mesh's models went: their meshes in the acceleration
/// structure, the prism material of each MTL material (converted on first
/// use), and its row of [`SceneInfo::meshes`].
struct MeshSlot {
    /// `(mesh index, MTL material index)` per model.
    models: Vec<(u32, Option<usize>)>,
    mtl_materials: Vec<Option<u32>>,
    info: usize,
}

/// The scene as it is built.
struct Build<'a> {
    ctx: Ctx<'a>,
    res: &'a Resources,
    overrides: Overrides,
    /// Files used (canonical paths), in order of first use.
    inputs: Vec<PathBuf>,
    warnings: Vec<String>,
    materials: Materials,
    meshes: Vec<Arc<TriangleMesh>>,
    slots: HashMap<(PathBuf, NormalMode), MeshSlot>,
    mesh_info: Vec<MeshInfo>,
    objects: Vec<Object>,
    object_materials: Vec<u32>,
    kinds: BTreeMap<String, usize>,
}

impl<'a> Build<'a> {
    fn new(ctx: Ctx<'a>, res: &'a Resources, options: &LoadOptions) -> Self {
        Self {
            ctx,
            res,
            overrides: options.overrides,
            inputs: Vec::new(),
            warnings: Vec::new(),
            materials: Materials::default(),
            meshes: Vec::new(),
            slots: HashMap::new(),
            mesh_info: Vec::new(),
            objects: Vec::new(),
            object_materials: Vec::new(),
            kinds: BTreeMap::new(),
        }
    }

    /// A ground plane (normal +Y) at height `y`, in the default material
    /// (OBJ mode's `--floor`).
    fn floor(&mut self, y: f32) -> std::result::Result<(), prism_geometry::GeometryError> {
        let plane = prism_geometry::Plane::new(Vec3::new(0.0, y, 0.0), Vec3::Y)?;
        let material = self.materials.default_material();
        *self.kinds.entry("plane".into()).or_default() += 1;
        self.objects.push(Object::Shape(Instance::new(plane.into(), Transform::IDENTITY)));
        self.object_materials.push(material);
        Ok(())
    }

    /// A warning, unless the same one was given already (a file used by
    /// several objects, or read once per normals mode).
    fn warn_once(&mut self, w: String) {
        if !self.warnings.contains(&w) {
            self.warnings.push(w);
        }
    }

    /// A warning about the scene file.
    fn warn(&mut self, message: &str) {
        self.warnings.push(format!("{}: {message}", self.ctx.file.display()));
    }

    fn note_input(&mut self, p: &Path) {
        if !self.inputs.iter().any(|q| q == p) {
            self.inputs.push(p.to_path_buf());
        }
    }

    /// The image of `found` (the texture the scene names with `p`), noted
    /// as an input; its failure reported at `p`.
    fn image(
        &mut self,
        found: Option<&std::result::Result<TextureFile, Failure>>,
        p: &Spanned<String>,
    ) -> Result<Arc<ImageTexture>> {
        self.image_at(found, self.ctx.loc(&p.span()), p.get_ref())
    }

    fn image_at(
        &mut self,
        found: Option<&std::result::Result<TextureFile, Failure>>,
        named_at: Location,
        raw: &str,
    ) -> Result<Arc<ImageTexture>> {
        match found {
            Some(Ok(t)) => {
                self.note_input(&t.path);
                Ok(Arc::clone(&t.image))
            }
            Some(Err(f)) => Err(f.at(named_at)),
            None => Err(not_read(named_at, raw)),
        }
    }

    fn object(&mut self, o: &Spanned<ObjectDef>) -> Result<()> {
        let ctx = self.ctx;
        let d = o.get_ref();
        let kind = *d.kind.get_ref();
        crate::object::check_keys(&ctx, d, kind)?;
        let transform = crate::object::transform(&ctx, d)?;
        let material = d.material.as_ref().map(|name| self.materials.named(&ctx, name)).transpose()?;
        let ospan = o.span();
        // No shape: a mesh, instanced from its file.
        let Some(shape) = crate::object::shape(&ctx, d, kind, &ospan)? else {
            let Some(p) = &d.path else {
                return Err(
                    ctx.invalid(&ospan, "a mesh needs `path`, an OBJ file (relative to the scene file)")
                );
            };
            let named_at = ctx.loc(&p.span());
            let obj = self.lookup_mesh(p.get_ref(), d.normal_mode(), named_at.clone())?;
            return self.instance_mesh(&obj, d.normal_mode(), &named_at, transform, material);
        };
        let material = material.unwrap_or_else(|| self.materials.default_material());
        *self.kinds.entry(shape.kind().to_string()).or_default() += 1;
        self.objects.push(Object::Shape(Instance::new(shape, transform)));
        self.object_materials.push(material);
        Ok(())
    }

    /// The OBJ file written `raw`, read with `normals`; its failure
    /// reported at `named_at`.
    fn lookup_mesh(&self, raw: &str, normals: NormalMode, named_at: Location) -> Result<Arc<ObjFile>> {
        match self.res.mesh(raw, normals) {
            Some(Ok(obj)) => Ok(Arc::clone(obj)),
            Some(Err(f)) => Err(f.at(named_at)),
            None => Err(not_read(named_at, raw)),
        }
    }

    /// One instance of every model of `obj`, with `material` or else
    /// each model's MTL material (the default where it has none).
    fn instance_mesh(
        &mut self,
        obj: &ObjFile,
        normals: NormalMode,
        named_at: &Location,
        transform: Transform,
        material: Option<u32>,
    ) -> Result<()> {
        let key = self.register_mesh(obj, normals);
        if let (None, Some(e)) = (material, &obj.material_error) {
            return Err(mtl_unusable(obj, e, named_at));
        }
        if material.is_none() {
            for w in &obj.unknown_materials {
                self.warn_once(w.clone());
            }
        }
        let Some(slot) = self.slots.get_mut(&key) else {
            return Err(not_read(named_at.clone(), &obj.path.display().to_string()));
        };
        if let Some(mi) = self.mesh_info.get_mut(slot.info) {
            mi.instances += 1;
        }
        for (mesh, mtl) in slot.models.clone() {
            let mat = match (material, mtl) {
                (Some(m), _) => m,
                (None, Some(k)) => self.mtl_material(obj, &key, k, named_at)?,
                (None, None) => self.materials.default_material(),
            };
            self.objects.push(Object::Mesh { mesh, transform });
            self.object_materials.push(mat);
            *self.kinds.entry("mesh".into()).or_default() += 1;
        }
        Ok(())
    }

    /// Adds the models of `obj` (read with `normals`) to the scene's
    /// meshes, once: notes its files as inputs, warns of degenerate
    /// triangles. The key of its slot.
    fn register_mesh(&mut self, obj: &ObjFile, normals: NormalMode) -> (PathBuf, NormalMode) {
        let key = (obj.path.clone(), normals);
        if !self.slots.contains_key(&key) {
            self.note_input(&obj.path);
            for m in &obj.mtl_files {
                self.note_input(m);
            }
            // Once, though the file is read again for each normals mode.
            for w in &obj.warnings {
                self.warn_once(w.clone());
            }
            let mut models = Vec::with_capacity(obj.models.len());
            let (mut triangles, mut degenerate) = (0, 0);
            for model in &obj.models {
                triangles += model.mesh.len();
                degenerate += model.degenerate;
                models.push((self.meshes.len() as u32, model.material));
                self.meshes.push(Arc::clone(&model.mesh));
            }
            if degenerate > 0 {
                self.warnings.push(format!(
                    "{}: {degenerate} of {triangles} triangles have zero area and will not be rendered",
                    obj.path.display()
                ));
            }
            let info = self.mesh_info.len();
            self.mesh_info.push(MeshInfo {
                path: obj.path.clone(),
                models: models.len(),
                triangles,
                instances: 0,
                closed_models: obj.models.iter().filter(|m| m.mesh.is_closed()).count(),
            });
            let slot = MeshSlot { models, mtl_materials: vec![None; obj.materials.len()], info };
            self.slots.insert(key.clone(), slot);
        }
        key
    }

    /// The prism material for MTL material `k` of `obj` (slot `key`).
    fn mtl_material(
        &mut self,
        obj: &ObjFile,
        key: &(PathBuf, NormalMode),
        k: usize,
        named_at: &Location,
    ) -> Result<u32> {
        if let Some(Some(i)) = self.slots.get(key).and_then(|s| s.mtl_materials.get(k)) {
            return Ok(*i);
        }
        let Some(raw) = obj.materials.get(k) else {
            return Err(SceneError::Invalid {
                location: named_at.clone(),
                message: format!("the OBJ file uses material {k}, which its MTL file does not define"),
            });
        };
        let obj_name = obj.path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        // Messages name the MTL file and line where the material is known
        // to be defined, else the OBJ file.
        let place = obj.material_places.get(k);
        let at = |key: &str| place.map_or_else(|| obj.path.display().to_string(), |p| p.at(key));
        let res = self.res;
        let found = res.mtl_texture(&obj.path, k);
        // A texture file that is missing (or not a file): the material's
        // colour, with a warning, as for a missing MTL file.
        let without_texture;
        let raw = match found {
            Some(Err(Failure::Read { what, path, reason })) => {
                let w = format!(
                    "{}: material `{}`: cannot read {what} {}: {reason}; using its colour (Kd) instead",
                    at("map_Kd"),
                    raw.name,
                    path.display()
                );
                self.warn_once(w);
                without_texture = tobj::Material { diffuse_texture: None, ..raw.clone() };
                &without_texture
            }
            _ => raw,
        };
        // A texture that cannot be decoded: which material names it, where.
        let named_by = match place {
            Some(p) => format!("the map_Kd of material `{}` at {}", raw.name, p.at("map_Kd")),
            None => format!("the map_Kd of material `{}` in {obj_name}'s MTL", raw.name),
        };
        let image = || {
            self.image_at(found, named_at.clone(), raw.diffuse_texture.as_deref().unwrap_or("")).map_err(
                |e| match e {
                    SceneError::Asset { location, message, referenced_at } => SceneError::Asset {
                        location,
                        message: format!("{message} ({named_by})"),
                        referenced_at,
                    },
                    other => other,
                },
            )
        };
        let m = material::from_mtl(raw, &Location::file(&obj.path), named_at, image)?;
        if let Some(value) = &raw.diffuse_texture {
            for option in crate::mtl_map::parse(value).ignored {
                let w = format!(
                    "{}: material `{}`: map_Kd option {option} is not applied",
                    at("map_Kd"),
                    raw.name
                );
                self.warn_once(w);
            }
        }
        // The other maps, which prism does not use, once each.
        for (key, _) in place.map_or(&[][..], |p| &p.maps) {
            if key != "map_Kd" {
                let w = format!(
                    "{}: material `{}`: `{key}` is not used by prism (of the texture maps it reads only map_Kd); {}",
                    at(key),
                    raw.name,
                    unused_map(key)
                );
                self.warn_once(w);
            }
        }
        let i = self.materials.add(format!("{obj_name}/{}", raw.name), m);
        if let Some(slot) = self.slots.get_mut(key).and_then(|s| s.mtl_materials.get_mut(k)) {
            *slot = Some(i);
        }
        Ok(i)
    }

    /// The scene of what was added, with `settings`, the camera of
    /// `camera`, `lights` and `fog`.
    fn finish(
        mut self,
        settings: Settings,
        camera: &CameraSource,
        lights: Vec<Light>,
        fog: Option<(Option<Fog>, bool)>,
    ) -> Result<LoadedScene> {
        if self.objects.is_empty() {
            self.warn("the scene has no objects");
        }
        // A dielectric splits each ray it meets in two; without a cut-off
        // only the depth limit ends the doubling.
        let list = &self.materials.list;
        let splits =
            self.object_materials.iter().any(|&m| list.get(m as usize).is_some_and(|m| m.transmission > 0.0));
        if settings.min_contribution == 0.0 && settings.max_depth > SPLIT_WARN_DEPTH && splits {
            let d = settings.max_depth;
            self.warn(&format!(
                "min_contribution = 0 with max_depth {d}: a glass surface splits each ray in two (reflected and refracted), so a pixel may trace up to 2^{d} rays; a cut-off such as 0.001 (the default) ends the paths that no longer change the picture"
            ));
        }
        let objects_len = self.objects.len();
        let accel = Accel::build(std::mem::take(&mut self.meshes), std::mem::take(&mut self.objects))
            .map_err(|e| self.ctx.invalid_file(format!("internal error: {e}")))?;
        let bounds = accel.bounds();
        let (camera, fog, fog_on) =
            self.camera_and_fog(camera, fog, (settings.width, settings.height), bounds)?;
        if let Some(w) = far_warning(&camera, &lights) {
            self.warn(&w);
        }
        if let Some(w) = offset_warning(bounds) {
            self.warn(&w);
        }
        let stats = accel.stats();
        let Settings {
            width,
            height,
            spp,
            max_depth,
            min_contribution,
            background,
            ambient,
            aovs,
            aov_preview,
            antialias,
        } = settings;
        let info = SceneInfo {
            file: self.ctx.file.to_path_buf(),
            width,
            height,
            spp,
            max_depth,
            min_contribution,
            objects: objects_len,
            objects_by_kind: self.kinds,
            meshes: self.mesh_info,
            stored_triangles: stats.stored_triangles,
            instanced_triangles: stats.instanced_triangles,
            materials: self.materials.names,
            lights: lights.clone(),
            bounds,
            fog,
            camera,
        };
        let scene = Scene {
            accel,
            object_materials: self.object_materials,
            materials: self.materials.list,
            lights,
            ambient,
            background,
            environment: None,
            fog,
        };
        let settings = RenderSettings {
            camera,
            fog: fog_on,
            spp,
            max_depth,
            min_contribution,
            threads: self.overrides.threads,
            antialias,
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

    /// The camera, the fog's medium and the fog on/off bit, with the
    /// overrides applied: the camera overrides (see [`view::camera`]) and
    /// `--fog`/`--no-fog`, which replace the file's `enabled`; on, in a
    /// scene without `[fog]`, adds linear white fog reaching total at
    /// [`view::default_fog_end`] (1.5 times the distance to the farthest
    /// corner of `bounds`, or 3 times the distance to the look-at point
    /// where only planes are), with a warning. `fog` is the file's medium
    /// and its `enabled`.
    fn camera_and_fog(
        &mut self,
        camera: &CameraSource,
        fog: Option<(Option<Fog>, bool)>,
        (width, height): (u32, u32),
        bounds: Aabb,
    ) -> Result<(Camera, Option<Fog>, bool)> {
        let camera = view::camera(&self.ctx, camera, &self.overrides, width, height)?;
        let table = fog.is_some();
        let (mut medium, file_on) = fog.unwrap_or((None, false));
        let on = self.overrides.fog.unwrap_or(file_on);
        if on && medium.is_none() {
            let end = view::default_fog_end(camera.position(), camera.look_at(), bounds);
            let why = if table { "[fog] gives only `enabled`" } else { "the scene has no [fog]" };
            let by = if self.overrides.fog == Some(true) { "--fog uses" } else { "using" };
            self.warn(&format!("{why}; {by} linear white fog from 0 to {end:.1}"));
            medium = Some(Fog { color: Vec3::ONE, mode: FogMode::Linear { start: 0.0, end } });
        }
        Ok((camera, medium, on))
    }
}

/// How far from the origin the camera, its focus and the lights may stand
/// before the squared distances between them and the scene (past about
/// 1.8e19, the square root of the largest `f32`) may overflow.
const FAR: f32 = 1e18;

/// A warning naming the camera, its focus or the lights (numbered from 1)
/// that stand more than [`FAR`] from the origin, if any: past about 1.8e19
/// from what they light or see, their squared distances overflow 32-bit
/// floats and the picture comes out black (prism renders it anyway: a
/// scene whose objects are as far keeps working where it can).
fn far_warning(camera: &Camera, lights: &[Light]) -> Option<String> {
    let reach = |points: &[Vec3]| points.iter().map(|p| p.abs().max_element()).fold(0.0f32, f32::max);
    let mut far = Vec::new();
    let mut farthest = 0.0f32;
    let mut note = |what: String, r: f32| {
        if r > FAR {
            far.push(what);
            farthest = farthest.max(r);
        }
    };
    note("the camera".into(), reach(&[camera.position(), camera.look_at()]));
    if camera.aperture() > 0.0 {
        let focus = camera.position() + camera.forward() * camera.focus_distance();
        note("the camera's focus point".into(), reach(&[focus]));
        // Lens points lie up to the aperture away from the eye.
        note("the camera's lens".into(), reach(&[camera.position()]) + camera.aperture());
    }
    for (k, l) in lights.iter().enumerate() {
        let points = match l.kind {
            LightKind::Point { position, .. } | LightKind::Spot { position, .. } => vec![position],
            LightKind::Directional { .. } => vec![],
            LightKind::Area(a) => match a.shape {
                AreaShape::Quad { corner, edge_u, edge_v } => {
                    vec![corner, corner + edge_u, corner + edge_v, corner + edge_u + edge_v]
                }
                AreaShape::Disk { center, radius, .. } | AreaShape::Sphere { center, radius } => {
                    vec![center - Vec3::splat(radius), center + Vec3::splat(radius)]
                }
            },
        };
        note(format!("light {}", k + 1), reach(&points));
    }
    (!far.is_empty()).then(|| {
        format!(
            "{} {} more than {FAR:.0e} from the origin (up to {farthest:.1e}): 32-bit floats square \
             distances past about 1.8e19 to infinity, and the picture may come out black; scale the scene down",
            far.join(", "),
            if far.len() == 1 { "lies" } else { "lie" }
        )
    })
}

/// How many times their own size the objects may lie from the origin
/// before a warning: 32-bit floats there are spaced a ten-thousandth of
/// that size apart or more. (A scene ten units across renders 1 % of its
/// pixels differently 1000 from the origin and loses every shadow at 10⁵.)
const OFFSET_RATIO: f32 = 1000.0;

/// A warning for bounded objects (`bounds`) that lie more than
/// [`OFFSET_RATIO`] times their extent from the origin, where 32-bit
/// floats are too coarse for their detail.
fn offset_warning(bounds: Aabb) -> Option<String> {
    if bounds.is_empty() {
        return None;
    }
    let reach = bounds.min.abs().max(bounds.max.abs()).max_element();
    let size = (bounds.max - bounds.min).max_element();
    if !(size > 0.0 && reach.is_finite() && reach > OFFSET_RATIO * size) {
        return None;
    }
    let c = bounds.center();
    Some(format!(
        "the objects lie up to {reach:.1e} from the origin but span only {size:.1e}: 32-bit floats there are about \
         {:.0e} apart, too coarse for the scene's detail, and shadows, reflections and refractions speckle or \
         vanish; move the scene near the origin (its centre is at ({:.3e}, {:.3e}, {:.3e}))",
        reach * f32::EPSILON,
        c.x,
        c.y,
        c.z
    ))
}

/// The error for an OBJ file whose material library cannot be used, for
/// an object that gives no `material`.
fn mtl_unusable(obj: &ObjFile, e: &str, named_at: &Location) -> SceneError {
    SceneError::Asset {
        location: Location::file(&obj.path),
        message: format!("{e}; give the object a `material` to render it without its MTL materials"),
        referenced_at: Box::new(named_at.clone()),
    }
}

/// A file the build needs that the resources do not hold (an internal
/// error of the loader, or resources given by hand that lack it).
fn not_read(named_at: Location, raw: &str) -> SceneError {
    SceneError::Invalid { location: named_at, message: format!("internal error: `{raw}` was not read") }
}

/// What a material looks like without its MTL map `key`, which prism
/// does not use.
fn unused_map(key: &str) -> &'static str {
    match key.to_ascii_lowercase().as_str() {
        "map_d" => "its d applies all over, so nothing is cut out",
        "bump" | "map_bump" | "norm" | "map_norm" | "disp" | "map_disp" => "the surface is shaded without it",
        "map_ks" => "its Ks applies all over",
        "map_ns" => "its Ns applies all over",
        "map_ke" => "its Ke applies all over",
        _ => "the material is rendered without it",
    }
}
