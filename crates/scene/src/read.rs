//! Every file a scene names, read once: the scene text itself, OBJ meshes
//! with their MTL libraries, image textures (the scene's and those MTL
//! materials name). The only module of the loader that touches the file
//! system: it checks sizes, that each path is a regular file, resolves
//! canonical paths, and shares what two references name. The result,
//! [`Resources`], is typed in-memory data for the build.
//!
//! A file that cannot be used is not an error here: its [`Failure`] is
//! kept, and the build reports it at the first place that uses it, so a
//! scene's errors come in the order of the scene.

use crate::error::{Location, SceneError};
use crate::format::{ObjectKind, SceneFile, TextureKind};
use crate::mtl_map;
use crate::obj::{self, NormalMode, ObjFile};
use crate::{MAX_SCENE_BYTES, MemoryRoom};
use prism_shade::{ImageTexture, TextureCost, Wrap};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a file named by the scene cannot be used; where it is named is
/// added by [`Failure::at`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Failure {
    /// The path is empty.
    EmptyPath { what: &'static str },
    /// The file cannot be read (missing, a directory, a device, ...).
    Read { what: &'static str, path: PathBuf, reason: String },
    /// The file was read but is malformed, at `location` in it.
    Asset { location: Location, message: String },
}

impl Failure {
    /// The error, for the file named at `named_at`.
    pub fn at(&self, named_at: Location) -> SceneError {
        match self {
            Self::EmptyPath { what } => {
                SceneError::Invalid { location: named_at, message: format!("{what} path is empty") }
            }
            Self::Read { what, path, reason } => {
                SceneError::Read { location: named_at, what, path: path.clone(), reason: reason.clone() }
            }
            Self::Asset { location, message } => SceneError::Asset {
                location: location.clone(),
                message: message.clone(),
                referenced_at: Box::new(named_at),
            },
        }
    }
}

/// An image texture, read.
#[derive(Clone, Debug)]
pub(crate) struct TextureFile {
    /// The file (canonical path).
    pub path: PathBuf,
    /// The image.
    pub image: Arc<ImageTexture>,
}

/// What the files a scene names hold, by the names the scene gives them.
#[derive(Debug, Default)]
pub(crate) struct Resources {
    /// OBJ files by `(path as written, normals)`.
    meshes: HashMap<(String, NormalMode), Result<Arc<ObjFile>, Failure>>,
    /// Image textures by `(path as written, wraps)`.
    textures: HashMap<(String, bool), Result<TextureFile, Failure>>,
    /// Textures of MTL materials by `(OBJ file, material index)`.
    mtl_textures: HashMap<(PathBuf, usize), Result<TextureFile, Failure>>,
}

impl Resources {
    /// The OBJ file written `raw` in the scene, read with `normals`.
    pub fn mesh(&self, raw: &str, normals: NormalMode) -> Option<&Result<Arc<ObjFile>, Failure>> {
        self.meshes.get(&(raw.to_owned(), normals))
    }

    /// The image written `raw` in the scene, read to wrap as `wrap`.
    pub fn texture(&self, raw: &str, wrap: Wrap) -> Option<&Result<TextureFile, Failure>> {
        self.textures.get(&(raw.to_owned(), wrap == Wrap::Repeat))
    }

    /// The texture of MTL material `k` of the OBJ file `obj`.
    pub fn mtl_texture(&self, obj: &Path, k: usize) -> Option<&Result<TextureFile, Failure>> {
        self.mtl_textures.get(&(obj.to_path_buf(), k))
    }

    /// Adds (or replaces) the OBJ file written `raw` with `normals`.
    pub fn insert_mesh(&mut self, raw: &str, normals: NormalMode, mesh: Result<Arc<ObjFile>, Failure>) {
        self.meshes.insert((raw.to_owned(), normals), mesh);
    }

    /// Adds (or replaces) the image written `raw`, to wrap as `wrap`.
    pub fn insert_texture(&mut self, raw: &str, wrap: Wrap, texture: Result<TextureFile, Failure>) {
        self.textures.insert((raw.to_owned(), wrap == Wrap::Repeat), texture);
    }
}

/// Reads every file `file` names, paths relative to `base`.
pub(crate) fn read_resources(file: &SceneFile, base: &Path, room: Option<MemoryRoom>) -> Resources {
    let mut reader = Reader::new(base, room);
    for def in file.materials.values() {
        if let Some(t) = &def.get_ref().texture
            && *t.get_ref().kind.get_ref() == TextureKind::Image
            && let Some(p) = &t.get_ref().path
        {
            reader.texture(p.get_ref(), t.get_ref().wrap(), "texture");
        }
    }
    if let Some(p) = file.render.as_ref().and_then(|r| r.get_ref().background.as_ref()?.get_ref().image()) {
        reader.texture(p.get_ref(), Wrap::Repeat, "background image");
    }
    for o in &file.objects {
        let d = o.get_ref();
        if *d.kind.get_ref() == ObjectKind::Mesh
            && let Some(p) = &d.path
        {
            reader.mesh(p.get_ref(), d.normal_mode(), d.material.is_none());
        }
    }
    reader.res
}

/// Reads the OBJ file `name` in `base` (and its materials' textures) for
/// an OBJ file as a scene.
pub(crate) fn read_obj_alone(base: &Path, name: &str, room: Option<MemoryRoom>) -> Resources {
    let mut reader = Reader::new(base, room);
    reader.mesh(name, NormalMode::Auto, true);
    reader.res
}

/// The reader's state: what is read so far, by canonical path, so that a
/// file named twice (or by two spellings) is read once.
struct Reader<'a> {
    base: &'a Path,
    res: Resources,
    objs: HashMap<(PathBuf, NormalMode), Result<Arc<ObjFile>, Failure>>,
    images: HashMap<(PathBuf, bool), Result<TextureFile, Failure>>,
    /// The memory textures may take in all, if limited.
    room: Option<MemoryRoom>,
    /// Bytes the textures read so far keep.
    kept: u64,
}

impl<'a> Reader<'a> {
    fn new(base: &'a Path, room: Option<MemoryRoom>) -> Self {
        Self { base, res: Resources::default(), objs: HashMap::new(), images: HashMap::new(), room, kept: 0 }
    }

    /// The image written `raw` (a `what`: "texture", "background image").
    fn texture(&mut self, raw: &str, wrap: Wrap, what: &'static str) {
        let key = (raw.to_owned(), wrap == Wrap::Repeat);
        if !self.res.textures.contains_key(&key) {
            let t = regular_file(self.base, raw, what).and_then(|p| self.image(p, wrap, what));
            self.res.insert_texture(raw, wrap, t);
        }
    }

    /// The image `path` (canonical), read once per wrap mode; a failure
    /// names it as `what` ("texture", "background image").
    fn image(&mut self, path: PathBuf, wrap: Wrap, what: &str) -> Result<TextureFile, Failure> {
        let key = (path, wrap == Wrap::Repeat);
        if let Some(t) = self.images.get(&key) {
            return t.clone();
        }
        let (room, kept) = (self.room, self.kept);
        let mut cost = None;
        let t = ImageTexture::load_checked(&key.0, wrap, |c| {
            cost = Some(c.kept);
            fits(room, kept, c)
        })
        .map(|image| TextureFile { path: key.0.clone(), image: Arc::new(image) })
        .map_err(|e| Failure::Asset {
            location: Location::file(&key.0),
            message: match e {
                prism_shade::ShadeError::Texture { reason, .. } => {
                    format!("cannot use this {what}: {reason}")
                }
                other => other.to_string(),
            },
        });
        if t.is_ok() {
            self.kept = self.kept.saturating_add(cost.unwrap_or(0));
        }
        self.images.insert(key, t.clone());
        t
    }

    /// The OBJ file written `raw`; with `needs_mtl` (an object uses its
    /// MTL materials) also the textures of the MTL materials its models use.
    fn mesh(&mut self, raw: &str, normals: NormalMode, needs_mtl: bool) {
        let obj = match self.res.mesh(raw, normals) {
            Some(obj) => obj.clone(),
            None => {
                let obj = regular_file(self.base, raw, "mesh").and_then(|p| self.obj(p, normals));
                self.res.insert_mesh(raw, normals, obj.clone());
                obj
            }
        };
        let Ok(obj) = obj else { return };
        if !needs_mtl || obj.material_error.is_some() {
            return;
        }
        let dir = obj.path.parent().map(Path::to_path_buf).unwrap_or_default();
        for k in obj.models.iter().filter_map(|m| m.material) {
            let key = (obj.path.clone(), k);
            if self.res.mtl_textures.contains_key(&key) {
                continue;
            }
            if let Some(tex) = obj.materials.get(k).and_then(|m| m.diffuse_texture.as_ref()) {
                // Relative to the MTL file (the first library's folder where
                // it is found), else to the OBJ file.
                let dirs = obj.mtl_files.iter().filter_map(|m| m.parent());
                let found = dirs.map(|m| mtl_texture_path(m, tex)).find(Result::is_ok);
                let wrap = if mtl_map::parse(tex).clamp { Wrap::Clamp } else { Wrap::Repeat };
                let t = found
                    .unwrap_or_else(|| mtl_texture_path(&dir, tex))
                    .and_then(|p| self.image(p, wrap, "texture"));
                self.res.mtl_textures.insert(key, t);
            }
        }
    }

    /// The OBJ file `path` (canonical), parsed once per normal mode.
    fn obj(&mut self, path: PathBuf, normals: NormalMode) -> Result<Arc<ObjFile>, Failure> {
        let key = (path, normals);
        if let Some(obj) = self.objs.get(&key) {
            return obj.clone();
        }
        let path = &key.0;
        let obj = std::fs::read(path)
            .map_err(|e| Failure::Read { what: "mesh", path: path.clone(), reason: io_reason(&e) })
            .and_then(|bytes| {
                obj::load_obj(path, &bytes, normals, &read_mtl)
                    .map_err(|(location, message)| Failure::Asset { location, message })
            })
            .map(|mut obj| {
                obj.mtl_files = obj.mtl_files.iter().filter_map(|m| std::fs::canonicalize(m).ok()).collect();
                Arc::new(obj)
            });
        self.objs.insert(key, obj.clone());
        obj
    }
}

/// The bytes of a material library, if it is a regular file that can be
/// read (a device such as /dev/zero would be read forever).
fn read_mtl(path: &Path) -> Option<Vec<u8>> {
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return None;
    }
    std::fs::read(path).ok()
}

/// Whether a texture of cost `c` fits in `room` beside the `kept` bytes of
/// the textures read before it; the reason it does not.
fn fits(room: Option<MemoryRoom>, kept: u64, c: &TextureCost) -> Result<(), String> {
    let Some(room) = room else { return Ok(()) };
    let left = room.bytes.saturating_sub(kept);
    if c.peak <= left {
        return Ok(());
    }
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    let others = if kept > 0 {
        format!(" beside the {:.2} GiB of the scene's other textures", gib(kept))
    } else {
        String::new()
    };
    Err(format!(
        "{}×{} texels need about {:.2} GiB to load, and this process may take only {:.2} GiB more{others} ({}); use a smaller image",
        c.width,
        c.height,
        gib(c.peak),
        gib(left),
        room.limit
    ))
}

/// The file an MTL material's `map_Kd` value names in `dir` (the name
/// after its options, [`mtl_map::parse`]), checked to be a regular file.
fn mtl_texture_path(dir: &Path, value: &str) -> Result<PathBuf, Failure> {
    checked(dir.join(mtl_map::parse(value).name), "texture named in a material library")
}

/// `raw` resolved against `base`, checked to be a regular file; its
/// canonical path. Against the current directory (`.`, a scene there or
/// on standard input) `raw` is used as it is, so that a message names
/// `sky.hdr`, as the scene wrote it, not `./sky.hdr`.
fn regular_file(base: &Path, raw: &str, what: &'static str) -> Result<PathBuf, Failure> {
    if raw.trim().is_empty() {
        return Err(Failure::EmptyPath { what });
    }
    checked(if base == Path::new(".") { PathBuf::from(raw) } else { base.join(raw) }, what)
}

/// The canonical path of `path` if it is a regular file.
fn checked(path: PathBuf, what: &'static str) -> Result<PathBuf, Failure> {
    let fail = |reason: String| Failure::Read { what, path: path.clone(), reason };
    let meta = std::fs::metadata(&path).map_err(|e| fail(io_reason(&e)))?;
    if !meta.is_file() {
        return Err(fail(not_a_file_reason(&meta)));
    }
    std::fs::canonicalize(&path).map_err(|e| fail(io_reason(&e)))
}

/// Why a path that is not a regular file cannot be read as one: a
/// directory, or a device (such as `/dev/zero`) or FIFO that could be read
/// forever.
fn not_a_file_reason(meta: &std::fs::Metadata) -> String {
    if meta.is_dir() {
        "it is a directory, expected a file".into()
    } else {
        "it is not a regular file (a device, FIFO or socket?)".into()
    }
}

/// A short reason for an I/O error.
fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".into(),
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// Checks that a file the user named to load (a scene file, or an OBJ
/// file as a scene) exists and is not a directory: `what` names it in
/// messages and `kind` in the message for a directory ("a .toml file").
fn check_named(path: &Path, what: &'static str, kind: &str) -> Result<(), SceneError> {
    let meta = std::fs::metadata(path).map_err(|e| named_error(path, what, io_reason(&e)))?;
    if meta.is_dir() {
        return Err(named_error(path, what, format!("it is a directory, expected {kind}")));
    }
    Ok(())
}

fn named_error(path: &Path, what: &'static str, reason: String) -> SceneError {
    SceneError::Read { location: Location::file(path), what, path: path.to_path_buf(), reason }
}

/// The text of the scene file `path` (at most [`MAX_SCENE_BYTES`], UTF-8,
/// a byte-order mark dropped), and its canonical path if it has one.
///
/// # Errors
/// [`SceneError::Read`] or, for text that is not UTF-8, [`SceneError::Syntax`].
pub(crate) fn read_scene_text(path: &Path) -> Result<(String, Option<PathBuf>), SceneError> {
    check_named(path, "scene file", "a .toml file")?;
    let mut file = std::fs::File::open(path).map_err(|e| named_error(path, "scene file", io_reason(&e)))?;
    let text = scene_text_from(&mut file, path)?;
    Ok((text, std::fs::canonicalize(path).ok()))
}

/// The scene text read from `reader` (named `path` in messages): at most
/// [`MAX_SCENE_BYTES`], UTF-8, a byte-order mark dropped.
///
/// # Errors
/// [`SceneError::Read`] or, for text that is not UTF-8, [`SceneError::Syntax`].
pub(crate) fn scene_text_from(reader: &mut dyn std::io::Read, path: &Path) -> Result<String, SceneError> {
    use std::io::Read;
    let read_err = |reason: String| named_error(path, "scene file", reason);
    let mut bytes = Vec::new();
    reader.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes).map_err(|e| read_err(io_reason(&e)))?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(read_err(format!(
            "it holds more than {} MiB; a scene file is text (is this the right file?)",
            MAX_SCENE_BYTES >> 20
        )));
    }
    let syntax = |location, message: &str| SceneError::Syntax { location, message: message.into() };
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(syntax(Location::file(path), "the file is UTF-16 text; scene files must be UTF-8"));
    }
    let bom = if bytes.starts_with(b"\xEF\xBB\xBF") { 3 } else { 0 };
    let text = std::str::from_utf8(&bytes[bom..]).map_err(|e| {
        let o = bom + e.valid_up_to();
        syntax(
            Location::at_offset(path, std::str::from_utf8(&bytes[..o]).unwrap_or(""), o),
            "invalid UTF-8 here: scene files are UTF-8 TOML text (is this a binary file?)",
        )
    })?;
    // Valid UTF-8, which TOML would refuse at its first NUL as a bad key
    // or value: a file padded with zeros by a crash, or not text at all.
    if let Some(o) = text.find('\0') {
        return Err(syntax(
            Location::at_offset(path, text, o),
            "a NUL byte here: scene files are UTF-8 TOML text (is this a binary file, or one cut short by a crash?)",
        ));
    }
    Ok(text.to_owned())
}

/// For an OBJ file `path` loaded as a scene: its canonical path, its
/// directory and its file name.
///
/// # Errors
/// [`SceneError::Read`] naming `path`.
pub(crate) fn obj_alone_path(path: &Path) -> Result<(PathBuf, PathBuf, String), SceneError> {
    check_named(path, "mesh", "an .obj file")?;
    let canonical = std::fs::canonicalize(path).map_err(|e| named_error(path, "mesh", io_reason(&e)))?;
    let base = canonical.parent().map(Path::to_path_buf).unwrap_or_default();
    let name = canonical.file_name().and_then(|n| n.to_str()).map(str::to_owned).ok_or_else(|| {
        named_error(
            path,
            "mesh",
            "the file name is not valid UTF-8; rename the file or name it from a scene file".into(),
        )
    })?;
    Ok((canonical, base, name))
}

/// A digest of the contents of `files` (in order), such as a loaded
/// scene's [`crate::LoadedScene::inputs`]: 64-bit FNV-1a over each file's
/// length and bytes, as 16 hex digits. Two loads agree on it when they
/// read the same bytes, wherever the files lie (paths do not enter it), so
/// that the tiles of a render farm can show that they rendered one scene.
/// Not a cryptographic hash: it detects mistakes, not forgeries.
///
/// # Errors
/// [`SceneError::Read`] naming a file that cannot be read.
pub fn inputs_digest(files: &[PathBuf]) -> Result<String, SceneError> {
    let mut h: u64 = 0xCBF2_9CE4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01B3);
        }
    };
    for f in files {
        let bytes = std::fs::read(f).map_err(|e| named_error(f, "input file", io_reason(&e)))?;
        eat(&(bytes.len() as u64).to_le_bytes());
        eat(&bytes);
    }
    Ok(format!("{h:016x}"))
}
