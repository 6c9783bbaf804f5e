//! The prism scene loader: reads the TOML scene format documented in
//! `docs/scene-format.md`, with OBJ meshes (and their MTL materials)
//! through tobj, into a renderable [`prism_shade::Scene`].
//!
//! Every error names the file, the line and column where possible, and
//! what was expected; nothing in a scene file, mesh or texture can make
//! the loader panic. Paths in a scene are relative to the scene file.
//!
//! Loading goes parse → read → build (as pbrt-v4's parse → description →
//! build): the text is parsed into the file's description (`format`);
//! every file it names (OBJ meshes, MTL libraries, textures) is read once
//! (`read`, the only module that touches the file system); then a pure
//! build (`build`, with `settings`, `view`, `material`, `object`) makes the
//! [`prism_shade::Scene`]. An OBJ file as a scene ([`load_obj_scene`])
//! enters the build with typed values of its own.
//!
//! # Example
//!
//! ```
//! use prism_scene::parse_scene_str;
//! use std::path::Path;
//!
//! let text = r#"
//! [camera]
//! position = [0, 1, 5]
//! look_at = [0, 1, 0]
//!
//! [[lights]]
//! position = [5, 5, 5]
//!
//! [materials.red]
//! color = [0.8, 0.1, 0.1]
//!
//! [[objects]]
//! type = "sphere"
//! center = [0, 1, 0]
//! radius = 1
//! material = "red"
//! "#;
//! let loaded = parse_scene_str(text, Path::new("."), Path::new("inline.toml"))?;
//! assert_eq!(loaded.info.objects, 1);
//! assert_eq!(loaded.info.materials, ["red"]);
//!
//! let bad = text.replace("radius = 1", "radius = -1");
//! let err = parse_scene_str(&bad, Path::new("."), Path::new("inline.toml")).unwrap_err();
//! assert_eq!(err.to_string(), "inline.toml:15:10: sphere radius must be greater than 0, got -1");
//! # Ok::<(), prism_scene::SceneError>(())
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod build;
mod check;
mod error;
mod format;
mod light;
mod material;
mod mtl_map;
mod obj;
mod obj_view;
mod object;
mod overrides;
mod read;
mod scan;
mod set;
mod settings;
mod suggest;
mod view;
mod wild;

pub use error::{Location, SceneError, line_col};
pub use obj_view::{ObjOptions, ObjView};
#[cfg(feature = "clap")]
pub use overrides::Named;
pub use overrides::{CameraName, Overrides, parse_vec3, whole_number, whole_u32};
pub use read::inputs_digest;
pub use settings::fit_size;

use prism_geometry::Aabb;
use prism_shade::{Aov, Camera, Fog, Light, RenderSettings, Scene};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Limits that protect against absurd (or hostile) scene files. Every
/// limit is checked before anything large is allocated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Largest image width or height in pixels (default 16384).
    pub max_side: u32,
    /// Largest number of pixels (default 100 000 000).
    pub max_pixels: u64,
    /// Largest recursion depth (default [`prism_shade::MAX_DEPTH_LIMIT`], 64;
    /// the renderer never goes deeper).
    pub max_depth: u32,
    /// Largest number of samples per pixel (default 65536).
    pub max_spp: u32,
    /// The memory the scene's image textures may take in all (default:
    /// unchecked). Each texture's cost is checked from its header, before
    /// its pixels are decoded.
    pub memory: Option<MemoryRoom>,
}

/// Memory a process may still take, and what limits it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryRoom {
    /// Bytes left.
    pub bytes: u64,
    /// What sets the limit, for messages (`ulimit -v`, `cgroup memory.max`,
    /// "the machine's memory and swap").
    pub limit: &'static str,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_side: 16_384,
            max_pixels: 100_000_000,
            max_depth: prism_shade::MAX_DEPTH_LIMIT,
            max_spp: 65_536,
            memory: None,
        }
    }
}

/// How to load a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Size limits.
    pub limits: Limits,
    /// Command-line replacements.
    pub overrides: Overrides,
    /// Scene values replaced by their dotted path, each `KEY=VALUE`
    /// (`render.spp=16`, `fog.enabled=false`, `objects.1.radius=2`), in
    /// order, applied to the scene text before it is parsed, so that they
    /// reach every key and are checked like the file's own (`prism render
    /// --set`). A problem in a set value is a [`SceneError::Option`] naming
    /// `--set`; other places keep the file's own lines. Scene files only:
    /// an OBJ file as a scene refuses them.
    pub sets: Vec<String>,
    /// How an OBJ file as a scene is seen and lit (`--view`, `--light`,
    /// `--floor`); a TOML scene refuses them.
    pub obj: ObjOptions,
}

/// One OBJ file used by the scene (stored once however many objects use it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshInfo {
    /// The file (canonical path).
    pub path: PathBuf,
    /// Models (groups with one material each) in the file.
    pub models: usize,
    /// Triangles in the file.
    pub triangles: usize,
    /// Objects of the scene that use it.
    pub instances: usize,
    /// Of `models`, those that are closed (watertight and consistently
    /// oriented, [`prism_geometry::TriangleMesh::is_closed`]): solids for
    /// refraction, absorption and shadows; the others are open surfaces.
    pub closed_models: usize,
}

/// What a scene holds, for `prism info` and for checking.
#[derive(Clone, Debug)]
pub struct SceneInfo {
    /// The scene file.
    pub file: PathBuf,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum recursion depth.
    pub max_depth: u32,
    /// Contribution cut-off.
    pub min_contribution: f32,
    /// Objects in the acceleration structure (a mesh file with several
    /// models counts once per model and instance).
    pub objects: usize,
    /// Objects by kind (`sphere`, `mesh`, ...).
    pub objects_by_kind: BTreeMap<String, usize>,
    /// The mesh files.
    pub meshes: Vec<MeshInfo>,
    /// Triangles stored (each mesh once).
    pub stored_triangles: usize,
    /// Triangles as rays see them (each instance counted).
    pub instanced_triangles: usize,
    /// Material names, in index order (MTL materials as `file.obj/name`).
    pub materials: Vec<String>,
    /// The lights.
    pub lights: Vec<Light>,
    /// Bounds of every bounded object (planes excluded).
    pub bounds: Aabb,
    /// The fog, if any.
    pub fog: Option<Fog>,
    /// The camera.
    pub camera: Camera,
}

/// A loaded scene, ready to render.
#[derive(Debug)]
pub struct LoadedScene {
    /// The scene data (immutable while rendered; the fog's medium, if any,
    /// is here).
    pub scene: Scene,
    /// The per-render choices: the file's camera (at the image size), fog
    /// on/off (`[fog] enabled`), samples, depth and cut-off, with the
    /// [`Overrides`] applied once (`threads` comes from them only).
    pub settings: RenderSettings,
    /// A description.
    pub info: SceneInfo,
    /// Every file read (canonical paths): the scene, meshes, material
    /// libraries, textures. A renderer must not write over them.
    pub inputs: Vec<PathBuf>,
    /// Problems that did not stop the load (no lights, degenerate
    /// triangles, ...), each starting with the file it is about.
    pub warnings: Vec<String>,
    /// AOV passes the scene asks for (`aov` in `[render]`), in order,
    /// repeats dropped; empty if none.
    pub aovs: Vec<Aov>,
    /// Whether the scene asks for PNG previews of its AOV passes
    /// (`aov_preview` in `[render]`).
    pub aov_preview: bool,
}

/// Loads the scene file `path` with default limits.
///
/// # Errors
/// A [`SceneError`] naming the file, the place and the problem.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene_with(path, &LoadOptions::default())
}

/// Loads the scene file `path` with `options`.
///
/// # Errors
/// A [`SceneError`] naming the file, the place and the problem.
pub fn load_scene_with(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let (text, canonical) = read::read_scene_text(path)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let base = if base.as_os_str().is_empty() { PathBuf::from(".") } else { base };
    let mut loaded = parse_scene_str_with(&text, &base, path, options)?;
    if let Some(c) = canonical {
        loaded.inputs.insert(0, c);
    }
    Ok(loaded)
}

/// The largest scene file read (256 MiB): a device such as `/dev/zero`
/// would otherwise be read until memory runs out. (A pipe, as in
/// `prism render <(generate-scene)`, is read like a file.)
pub const MAX_SCENE_BYTES: u64 = 256 << 20;

/// Loads a scene from `path`, whatever its kind: `-` is a TOML scene read
/// from standard input ([`load_scene_from_reader`]); an OBJ mesh (extension
/// `.obj`, any case) becomes a scene of its own ([`load_obj_scene`]);
/// any other file is read as a TOML scene ([`load_scene_with`]).
///
/// # Errors
/// A [`SceneError`] naming the file, the place and the problem.
pub fn load_path(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    if is_stdin_path(path) {
        return load_scene_from_reader(&mut std::io::stdin().lock(), options);
    }
    if is_obj_path(path) { load_obj_scene(path, options) } else { load_scene_with(path, options) }
}

/// Whether `path` names standard input (`-`) for [`load_path`].
#[must_use]
pub fn is_stdin_path(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The name a scene read from standard input has in messages.
pub const STDIN_NAME: &str = "<stdin>";

/// The scene `path` as messages and reports name it: [`STDIN_NAME`] for
/// standard input (`-`).
#[must_use]
pub fn scene_name(path: &Path) -> String {
    if is_stdin_path(path) { STDIN_NAME.to_owned() } else { path.display().to_string() }
}

/// Loads a TOML scene read from `reader` (standard input for `prism
/// render -`): at most [`MAX_SCENE_BYTES`], UTF-8. Its messages name it
/// [`STDIN_NAME`], and the paths it holds (meshes, textures) are relative
/// to the current directory, as there is no scene file to be relative to.
///
/// # Errors
/// A [`SceneError`] naming [`STDIN_NAME`], the place and the problem.
pub fn load_scene_from_reader(
    reader: &mut dyn std::io::Read,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    let name = Path::new(STDIN_NAME);
    let text = read::scene_text_from(reader, name)?;
    parse_scene_str_with(&text, Path::new("."), name, options)
}

/// Whether [`load_path`] reads `path` as an OBJ mesh (its extension is
/// `obj`, in any case).
#[must_use]
pub fn is_obj_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// Makes a scene of the OBJ mesh `path` alone, so that a mesh can be
/// looked at without writing a scene file (`docs/scene-format.md`, "An
/// OBJ file as a scene"):
///
/// - the mesh, with its MTL materials (where a model has none, or the
///   material library cannot be read, a neutral grey: colour 0.8, diffuse
///   0.9, specular 0.3; a library that cannot be read is also warned
///   about), vertex normals as `normals = "auto"`;
/// - a camera that frames the mesh's bounding sphere: with `c` the centre
///   of the bounding box and `r = |max − min| / 2`, the eye at
///   `c + e · r / sin(θ/2)` looking at `c`, where θ is the narrower of the
///   vertical and horizontal fields of view (the vertical field of view is
///   40°, or `--fov`) and `e` the unit direction of the view
///   ([`ObjOptions::view`], [`ObjView`]): +Z for `front` (up +Y), −Z
///   `back`, −X `left`, +X `right`, +Y `top` (up −Z), (1, 1, 1)/√3 `iso`;
///   automatically `front` if the box is at least as wide (X) as it is
///   deep (Z), else `right`, so that the camera faces the larger side;
///   camera overrides replace any of this;
/// - one white point light of intensity 1 at `c + r · (1·right + 2·up +
///   1.5·e)` in the view's frame (above, right of and in front of the mesh
///   as seen; `c + r · (1, 2, 1.5)` for `front`), or at
///   [`ObjOptions::light`]; ambient `[1, 1, 1]`, a dark grey-blue
///   background `[0.05, 0.05, 0.07]`;
/// - with [`ObjOptions::floor`], an infinite ground plane (normal +Y, the
///   neutral grey material) at the bottom of the mesh's bounding box,
///   which catches its shadow;
/// - 640×480 pixels, 4 samples per pixel, max depth 8 (overrides apply).
///
/// Errors in the OBJ name its line; errors in its material library or
/// textures name that file and the OBJ.
///
/// # Errors
/// A [`SceneError`] naming the file, the place and the problem.
pub fn load_obj_scene(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    if let Some(set) = options.sets.first() {
        return Err(SceneError::Option {
            flag: "--set",
            message: format!("{set}: --set changes a scene file's values; an OBJ file as a scene has none"),
        });
    }
    if let Some(camera) = options.overrides.camera {
        return Err(SceneError::Option {
            flag: "--camera",
            message: format!(
                "`{camera}`: an OBJ file as a scene has one framed camera and no named ones; choose its side with --view"
            ),
        });
    }
    let (canonical, base, name) = read::obj_alone_path(path)?;
    let res = read::read_obj_alone(&base, &name, options.limits.memory);
    let lines = error::Lines::new("");
    build::build_obj_scene(check::Ctx::new(path, &lines), &name, &canonical, &res, options)
}

/// Parses a scene from `text` as if read from `file_name` (used in
/// messages), resolving relative paths against `base_dir`. Default limits.
///
/// # Errors
/// A [`SceneError`] naming `file_name`, the place and the problem.
pub fn parse_scene_str(text: &str, base_dir: &Path, file_name: &Path) -> Result<LoadedScene, SceneError> {
    parse_scene_str_with(text, base_dir, file_name, &LoadOptions::default())
}

/// [`parse_scene_str`] with `options`.
///
/// # Errors
/// A [`SceneError`] naming `file_name`, the place and the problem.
pub fn parse_scene_str_with(
    text: &str,
    base_dir: &Path,
    file_name: &Path,
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    options.obj.refuse_for_toml()?;
    if !options.sets.is_empty() {
        let edited = set::apply(text, &options.sets, file_name)?;
        let plain = LoadOptions { sets: Vec::new(), ..options.clone() };
        let mut loaded = parse_scene_str_with(&edited.text, base_dir, file_name, &plain)
            .map_err(|e| edited.remap(e, file_name))?;
        loaded.warnings = loaded.warnings.into_iter().map(|w| edited.remap_warning(w, file_name)).collect();
        return Ok(loaded);
    }
    let file = format::SceneFile::parse(text, file_name)?;
    let res = read::read_resources(&file, base_dir, options.limits.memory);
    let notes = std::cell::RefCell::new(Vec::new());
    let lines = error::Lines::new(text);
    let mut loaded =
        build::build_scene(check::Ctx::new(file_name, &lines).noting(&notes), &file, &res, options)?;
    loaded.warnings.extend(notes.into_inner());
    Ok(loaded)
}

#[cfg(test)]
mod tests;
