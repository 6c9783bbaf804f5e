//! OBJ meshes and their MTL materials, through tobj.
//!
//! Before tobj sees a file, a line-by-line check reports the problems that
//! tobj reports without a place (or not at all): numbers that do not parse
//! or are not finite, faces with fewer than three corners, and face indices
//! that are zero or out of range, each with the OBJ file's line.
//!
//! No I/O here: the OBJ's bytes are given, and its material libraries are
//! read through a function the caller passes (see `read.rs`).

use crate::error::Location;
use crate::wild;
use prism_geometry::TriangleMesh;
use prism_geometry::glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One model of an OBJ file (an `o`/`g` group with one material).
#[derive(Debug)]
pub struct ObjModel {
    /// The geometry.
    pub mesh: Arc<TriangleMesh>,
    /// Index into [`ObjFile::materials`], if the model uses one.
    pub material: Option<usize>,
    /// Faces of zero area (kept but never hit).
    pub degenerate: usize,
}

/// A loaded OBJ file.
#[derive(Debug)]
pub struct ObjFile {
    /// The file (canonical path).
    pub path: PathBuf,
    /// Its models.
    pub models: Vec<ObjModel>,
    /// Materials from its MTL libraries (empty when unavailable).
    pub materials: Vec<tobj::Material>,
    /// Why the MTL libraries could not be used, if they could not.
    pub material_error: Option<String>,
    /// The MTL files it names (the caller canonicalizes those that exist).
    pub mtl_files: Vec<PathBuf>,
    /// What was guessed to read it (`FILE:LINE: ...`), for the user.
    pub warnings: Vec<String>,
    /// `usemtl` lines naming no material of its libraries (`FILE:LINE:
    /// ...`), a warning wherever its MTL materials are used.
    pub unknown_materials: Vec<String>,
    /// Where each of `materials` is defined, in the same order (empty
    /// where they cannot be matched: a library that could not be read).
    pub material_places: Vec<MtlPlace>,
}

/// Where an MTL material is defined: its `newmtl` line, and the lines of
/// its texture maps, for messages that name the MTL file rather than the
/// OBJ file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MtlPlace {
    /// The MTL file: the OBJ file's folder joined with the name its
    /// `mtllib` gives.
    pub file: PathBuf,
    /// The `newmtl` line (1-based).
    pub line: usize,
    /// Each map statement (`map_Kd`, `map_d`, `bump`, ...) with its line,
    /// in the file's order.
    pub maps: Vec<(String, usize)>,
}

impl MtlPlace {
    /// `FILE:LINE` of the material's `newmtl`, or of its last statement
    /// `key` where it has one (the one that counts, as tobj reads it).
    #[must_use]
    pub fn at(&self, key: &str) -> String {
        let line = self.maps.iter().rev().find(|(k, _)| k == key).map_or(self.line, |&(_, l)| l);
        format!("{}:{line}", self.file.display())
    }
}

/// The MTL keys of texture maps (tobj reads some, the rest are other
/// keys to it): `map_` and any suffix but `map_aat` (an on/off switch),
/// and the bare names some exporters write.
fn is_map_key(key: &str) -> bool {
    key.starts_with("map_") && key != "map_aat" || matches!(key, "bump" | "disp" | "decal" | "refl" | "norm")
}

/// The materials the MTL text `text` defines, in order, placed in
/// `file`: each line's key is its first word, as tobj reads it (a `#`
/// stuck to a word is part of it).
fn mtl_places(file: &Path, text: &str) -> Vec<MtlPlace> {
    let mut out: Vec<MtlPlace> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        match line.split_whitespace().next() {
            Some("newmtl") => out.push(MtlPlace { file: file.to_path_buf(), line: i + 1, maps: Vec::new() }),
            Some(key) if is_map_key(key) => {
                if let Some(m) = out.last_mut() {
                    m.maps.push((key.to_owned(), i + 1));
                }
            }
            _ => {}
        }
    }
    out
}

/// How vertex normals are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NormalMode {
    /// The file's normals when every vertex has one, else computed:
    /// welded by position, smooth within the file's smoothing groups
    /// (`s`), hard at edges sharper than the default crease angle
    /// ([`prism_geometry::DEFAULT_CREASE_DEG`]).
    Auto,
    /// [`NormalMode::Auto`] with another crease angle, in hundredths of a
    /// degree (`crease_angle`).
    AutoCrease(u32),
    /// Always computed normals, welded by position and smooth everywhere
    /// (no crease, no smoothing groups).
    Smooth,
    /// No vertex normals: each face shaded with its geometric normal.
    Flat,
}

/// Parses and validates the OBJ file `path` (already read as `bytes`);
/// `read_mtl` gives the bytes of a material library it names (`None`
/// where it cannot be read). An error is the place in the OBJ file and
/// what is wrong.
pub fn load_obj(
    path: &Path,
    bytes: &[u8],
    normals: NormalMode,
    read_mtl: &dyn Fn(&Path) -> Option<Vec<u8>>,
) -> Result<ObjFile, (Location, String)> {
    let (text, decode_warning) = wild::decode_text(bytes).map_err(|(line, m)| {
        (line.map_or_else(|| Location::file(path), |l| Location::at_line(path, l)), m)
    })?;
    let (text, obj_warnings) = wild::fix_obj(&text);
    let text: &str = &text;
    let here = |w: String| format!("{}:{}", path.display(), w.strip_prefix("line ").unwrap_or(&w));
    let mut warnings: Vec<String> = decode_warning.into_iter().chain(obj_warnings).map(here).collect();
    let mtl_warnings: std::cell::RefCell<Vec<String>> = std::cell::RefCell::new(Vec::new());
    let Prechecked { mtllibs, corners } =
        precheck(text).map_err(|(line, m)| (Location::at_line(path, line), m))?;

    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let exists = |name: &str| dir.join(name).exists();
    let mtl_files: Vec<PathBuf> =
        mtllibs.iter().flat_map(|m| library_names(m, exists)).map(|m| dir.join(m)).collect();
    // Polygons are cut here (`polygon_triangles`), not by tobj's fan.
    let options = tobj::LoadOptions { triangulate: false, single_index: true, ..Default::default() };
    // A problem found in an MTL file before tobj sees it, with its place.
    let mtl_problem: std::cell::RefCell<Option<String>> = std::cell::RefCell::new(None);
    let places: std::cell::RefCell<Vec<MtlPlace>> = std::cell::RefCell::new(Vec::new());
    let load_library = |path: &Path| {
        let path = path.to_path_buf();
        let Some(bytes) = read_mtl(&path) else {
            // tobj's own words would be "open file failed".
            let why = if path.exists() { "not a readable file" } else { "no such file" };
            *mtl_problem.borrow_mut() = Some(format!("{}: {why}", path.display()));
            return Err(tobj::LoadError::OpenFileFailed);
        };
        let (text, decode_warning) = match wild::decode_text(&bytes) {
            Ok(t) => t,
            Err((line, m)) => {
                let at = line.map_or_else(String::new, |l| format!(":{l}"));
                *mtl_problem.borrow_mut() = Some(format!("{}{at}: {m}", path.display()));
                return Err(tobj::LoadError::ReadError);
            }
        };
        let (text, fixes) = wild::fix_mtl(&text);
        let at = |w: String| format!("{}:{}", path.display(), w.strip_prefix("line ").unwrap_or(&w));
        mtl_warnings.borrow_mut().extend(decode_warning.into_iter().chain(fixes).map(at));
        let text: &str = &text;
        // tobj panics on some malformed lines (`Kd 1 1`); refuse them first.
        if let Err((line, m)) = precheck_mtl(text) {
            *mtl_problem.borrow_mut() = Some(format!("{}:{line}: {m}", path.display()));
            return Err(tobj::LoadError::MaterialParseError);
        }
        let loaded = tobj::load_mtl_buf(&mut BufReader::new(text.as_bytes()));
        // The places of a library tobj refused would be of no material.
        if loaded.is_ok() {
            places.borrow_mut().extend(mtl_places(&path, text));
        }
        loaded
    };
    // One `mtllib` line may name several libraries.
    let loader = |p: &Path| {
        let name = p.to_string_lossy();
        let mut loaded = None;
        let mut failed = None;
        // As tobj merges the libraries of several `mtllib` lines: those
        // read are used, an error only where none could be.
        for lib in library_names(&name, exists) {
            match (load_library(&dir.join(lib)), &mut loaded) {
                (Ok(first), None) => loaded = Some(first),
                (Ok((mut more, names)), Some((materials, all_names))) => {
                    let offset = materials.len();
                    materials.append(&mut more);
                    all_names.extend(names.into_iter().map(|(k, v)| (k, v + offset)));
                }
                (Err(e), _) => failed = failed.or(Some(e)),
            }
        }
        match (loaded, failed) {
            (Some(l), _) => Ok(l),
            (None, e) => Err(e.unwrap_or(tobj::LoadError::OpenFileFailed)),
        }
    };
    let (models, materials) = tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &options, loader)
        .map_err(|e| (Location::file(path), format!("malformed OBJ: {e}")))?;
    // tobj lists the libraries' materials in the order of their `newmtl`
    // lines, library after library.
    let mut material_places = places.into_inner();
    let (materials, material_error) = match (materials, mtl_problem.into_inner()) {
        (Ok(m), _) => (m, None),
        (Err(_), Some(problem)) => (Vec::new(), Some(format!("cannot use material library {problem}"))),
        (Err(e), None) => {
            let names: Vec<String> = mtl_files.iter().map(|p| p.display().to_string()).collect();
            (Vec::new(), Some(format!("cannot use material library {}: {e}", names.join(", "))))
        }
    };

    // Each model's positions and triangles, its faces cut in file order.
    let cut: Vec<(tobj::Model, Vec<Vec3>, Cut)> = models
        .into_iter()
        .map(|model| {
            let m = &model.mesh;
            let positions: Vec<Vec3> =
                m.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
            let cut = polygon_triangles(&m.indices, &m.face_arities, &positions);
            (model, positions, cut)
        })
        .collect();
    // Smoothing groups per face, if the file has `s` lines and tobj's
    // models hold its faces in file order (else they are not used).
    let total: usize = cut.iter().map(|(_, _, c)| c.faces()).sum();
    let groups = smoothing_groups(text).filter(|g| g.len() == total);
    let mut next_face = 0;
    let mut out = Vec::with_capacity(cut.len());
    let mut pending: Vec<Pending> = Vec::with_capacity(cut.len());
    for (model, positions, Cut { triangles: indices, per_face }) in cut {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let n = m.positions.len() / 3;
        let file_normals = (m.normals.len() == 3 * n)
            .then(|| m.normals.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>());
        // OBJ's v runs upward; prism's image rows run downward from v = 0.
        let mut uvs = (m.texcoords.len() == 2 * n)
            .then(|| m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], 1.0 - c[1])).collect::<Vec<_>>());
        // The smoothing groups of this model's triangles, in file order:
        // each face's for each of its triangles.
        let faces = if per_face.is_empty() { indices.len() } else { per_face.len() };
        let model_groups: Option<Vec<u32>> =
            groups.as_ref().and_then(|g| g.get(next_face..next_face + faces)).map(|g| {
                if per_face.is_empty() {
                    g.to_vec()
                } else {
                    g.iter()
                        .zip(&per_face)
                        .flat_map(|(&group, &n)| std::iter::repeat_n(group, n as usize))
                        .collect()
                }
            });
        let model_groups = model_groups.as_deref();
        let model_faces = next_face..next_face + faces;
        next_face += faces;
        // Texture coordinates at some corners and not at others: tobj
        // gives those it has, which no longer match the vertices.
        if uvs.is_none() && !m.texcoords.is_empty() {
            let mixed = corners.as_ref().and_then(|c| mixed_uvs(c, model_faces, &m.texcoords, n));
            let at = mixed
                .as_ref()
                .map_or_else(|| path.display().to_string(), |(_, line)| format!("{}:{line}", path.display()));
            warnings.push(format!(
                "{at}: model `{}` has faces without texture coordinates (`vt`) beside faces with them; {}",
                model.name,
                if mixed.is_some() {
                    "their corners get uv (0, 0), the image's bottom-left corner point (where its four corner texels meet when it repeats)"
                } else {
                    "its texture coordinates are not used"
                }
            ));
            uvs = mixed.map(|(uvs, _)| uvs);
        }
        // Faces of no area (spikes out and back) give no triangles.
        if indices.is_empty() {
            continue;
        }
        // (file normals, computed with (groups, crease angle)).
        let (given, computed) = match normals {
            NormalMode::Auto | NormalMode::AutoCrease(_) => {
                let crease = match normals {
                    NormalMode::AutoCrease(c) => c as f32 / 100.0,
                    _ => prism_geometry::DEFAULT_CREASE_DEG,
                };
                let computed = file_normals.is_none().then_some((model_groups, crease));
                (file_normals.clone(), computed)
            }
            NormalMode::Smooth => (None, Some((None, 180.0))),
            NormalMode::Flat => (None, None),
        };
        let err =
            |e: prism_geometry::GeometryError| (Location::file(path), format!("model `{}`: {e}", model.name));
        let mut mesh = TriangleMesh::new(positions, given, uvs, indices).map_err(err)?;
        // A solid wound inside out (an exporter's flipped normals) would be
        // glass entered where it is left, absorbing outside itself: each
        // shell is turned to face out (a cavity in), before any normal is
        // computed from the winding.
        let turned = mesh.orient_shells();
        if turned > 0 {
            let (shells, them) =
                if turned == 1 { ("1 shell", "it") } else { (&*format!("{turned} shells"), "them") };
            warnings.push(format!(
                "{}: model `{}` is a closed solid wound inside out ({shells} with face normals pointing into the solid); prism turns {them} the right way out",
                path.display(),
                model.name
            ));
        }
        let computed = computed.map(|(groups, crease)| (groups.map(<[u32]>::to_vec), crease));
        pending.push(Pending { name: model.name, mesh: Some(mesh), material: m.material_id, computed });
    }
    // Normals are computed over the models of one object (`o`/`g` name)
    // together: tobj cuts an object apart where its material changes, and
    // that must not crease a smooth surface.
    let mut objects: HashMap<String, Vec<usize>> = HashMap::new();
    for (k, p) in pending.iter().enumerate().filter(|(_, p)| p.computed.is_some()) {
        objects.entry(p.name.clone()).or_default().push(k);
    }
    let mut meshes: Vec<Option<TriangleMesh>> = (0..pending.len()).map(|_| None).collect();
    for k in 0..pending.len() {
        let Some((_, crease)) = pending[k].computed else {
            meshes[k] = pending[k].mesh.take();
            continue;
        };
        let name = &pending[k].name;
        let Some(together) = objects.remove(name) else { continue };
        let parts: Vec<(&TriangleMesh, Option<&[u32]>)> = together
            .iter()
            .filter_map(|&j| {
                let p = &pending[j];
                Some((p.mesh.as_ref()?, p.computed.as_ref().and_then(|(g, _)| g.as_deref())))
            })
            .collect();
        let done = normals_together(&parts, crease)
            .map_err(|e| (Location::file(path), format!("model `{name}`: {e}")))?;
        for (&j, mesh) in together.iter().zip(done) {
            meshes[j] = Some(mesh);
        }
    }
    for (p, mesh) in pending.iter().zip(meshes) {
        let Some(mesh) = mesh else { continue };
        let degenerate = mesh.degenerate_count();
        out.push(ObjModel { mesh: Arc::new(mesh), material: p.material, degenerate });
    }
    if out.is_empty() {
        return Err((
            Location::file(path),
            "the OBJ file has no faces (lines and points are not rendered, nor faces of no area such as a spike out and back)".into(),
        ));
    }
    // Faces, but none with an area: as good as none (an empty picture with
    // a warning before, where a file of no faces is refused).
    let (triangles, flat) = out.iter().fold((0, 0), |(t, z), m| (t + m.mesh.len(), z + m.degenerate));
    if flat == triangles {
        let what = if triangles == 1 {
            "its one triangle has".to_string()
        } else {
            format!("all {triangles} of its triangles have")
        };
        return Err((
            Location::file(path),
            format!("the OBJ file has nothing to render: {what} zero area (corners repeated or in a line)"),
        ));
    }
    warnings.extend(mtl_warnings.into_inner());
    let mut unknown_materials = Vec::new();
    if mtl_files.is_empty()
        && let Some((line, name)) = unknown_usemtl(text, &[]).first()
    {
        // Materials named, but no library to find them in.
        unknown_materials.push(format!(
            "{}:{line}: `usemtl {name}`, but the file names no material library (`mtllib`); its faces get the default material",
            path.display()
        ));
    }
    if material_error.is_none() && !mtl_files.is_empty() {
        let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        for (line, name) in unknown_usemtl(text, &names) {
            unknown_materials.push(format!(
                "{}:{line}: `usemtl {name}` names no material of {}{} (it defines: {}); those faces get the default material",
                path.display(),
                mtllibs.join(", "),
                prism_shade::did_you_mean(name, &names),
                if names.is_empty() { "none".to_string() } else { names.join(", ") }
            ));
        }
    }
    if material_places.len() != materials.len() {
        material_places.clear();
    }
    Ok(ObjFile {
        path: path.to_path_buf(),
        models: out,
        materials,
        material_error,
        mtl_files,
        warnings,
        unknown_materials,
        material_places,
    })
}

/// A model of the OBJ file before its normals are computed.
struct Pending {
    /// Its object's name (`o` or `g`), which the models of one object cut
    /// apart by their materials share.
    name: String,
    mesh: Option<TriangleMesh>,
    material: Option<usize>,
    /// Normals to compute: the smoothing group of each face, and the
    /// crease angle.
    computed: Option<(Option<Vec<u32>>, f32)>,
}

/// `parts` (meshes, with their faces' smoothing groups) with normals
/// computed over all of them as one mesh, welded by position across the
/// parts ([`prism_geometry::with_computed_normals`]), then cut apart again:
/// each part keeps its faces in order, and its uvs if it has them.
fn normals_together(
    parts: &[(&TriangleMesh, Option<&[u32]>)],
    crease: f32,
) -> Result<Vec<TriangleMesh>, prism_geometry::GeometryError> {
    if let [(mesh, groups)] = parts {
        return Ok(vec![prism_geometry::with_computed_normals(mesh, *groups, crease)?]);
    }
    let any_uvs = parts.iter().any(|(m, _)| m.uvs().is_some());
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut indices = Vec::new();
    let mut groups = Vec::new();
    let all_groups = parts.iter().all(|(_, g)| g.is_some());
    for (m, g) in parts {
        let base = u32::try_from(positions.len())
            .map_err(|_| prism_geometry::GeometryError::InvalidMesh("too many vertices".into()))?;
        positions.extend_from_slice(m.positions());
        match m.uvs() {
            Some(u) => uvs.extend_from_slice(u),
            None if any_uvs => uvs.extend(std::iter::repeat_n(Vec2::ZERO, m.positions().len())),
            None => {}
        }
        indices.extend(m.indices().iter().map(|t| t.map(|i| i + base)));
        if let Some(g) = g {
            groups.extend_from_slice(g);
        }
    }
    let whole = TriangleMesh::new(positions, None, any_uvs.then_some(uvs), indices)?;
    let whole = prism_geometry::with_computed_normals(&whole, all_groups.then_some(&groups[..]), crease)?;
    let normals = whole.normals().unwrap_or_default();
    let mut out = Vec::with_capacity(parts.len());
    let mut first = 0;
    for (m, _) in parts {
        let faces = &whole.indices()[first..first + m.len()];
        first += m.len();
        // The part's vertices, in the order its faces first use them.
        let mut new_index: HashMap<u32, u32> = HashMap::new();
        let mut used = Vec::new();
        let indices: Vec<[u32; 3]> = faces
            .iter()
            .map(|t| {
                t.map(|i| {
                    *new_index.entry(i).or_insert_with(|| {
                        used.push(i as usize);
                        (used.len() - 1) as u32
                    })
                })
            })
            .collect();
        let pick = |values: &[Vec3]| used.iter().map(|&i| values[i]).collect::<Vec<_>>();
        let uvs = match (m.uvs(), whole.uvs()) {
            (Some(_), Some(u)) => Some(used.iter().map(|&i| u[i]).collect()),
            _ => None,
        };
        out.push(TriangleMesh::new(pick(whole.positions()), Some(pick(normals)), uvs, indices)?);
    }
    Ok(out)
}

/// The `usemtl` lines of `text` (1-based line, name) whose name is not
/// one of `names`, the first of each name only.
fn unknown_usemtl<'t>(text: &'t str, names: &[&str]) -> Vec<(usize, &'t str)> {
    let mut out: Vec<(usize, &str)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some(name) = line.strip_prefix("usemtl").filter(|r| r.starts_with(char::is_whitespace)) else {
            continue;
        };
        let name = name.trim();
        let known = name.is_empty() || name == wild::UNNAMED || names.contains(&name);
        if !known && !out.iter().any(|(_, n)| *n == name) {
            out.push((i + 1, name));
        }
    }
    out
}

/// The smoothing group of every face, in file order, or `None` when the
/// file has no `s` lines. `s off` and `s 0` are group 0 (flat), `s N` group `N`,
/// any other `s` value group 1; faces before the first `s` line are flat,
/// as the OBJ format's default is.
fn smoothing_groups(text: &str) -> Option<Vec<u32>> {
    let mut any = false;
    let mut current = 0u32;
    let mut out = Vec::new();
    for raw in text.lines() {
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        match words.next() {
            Some("s") => {
                any = true;
                current = match words.next() {
                    Some("off") | None => 0,
                    Some(w) => w.parse().unwrap_or(1),
                };
            }
            Some("f") => out.push(current),
            _ => {}
        }
    }
    any.then_some(out)
}

/// A model's faces cut into triangles.
struct Cut {
    /// The triangles, face after face in the file's order.
    triangles: Vec<[u32; 3]>,
    /// How many triangles each face gave (empty where every face is a
    /// triangle).
    per_face: Vec<u32>,
}

impl Cut {
    /// The number of faces.
    fn faces(&self) -> usize {
        if self.per_face.is_empty() { self.triangles.len() } else { self.per_face.len() }
    }
}

/// A model's faces as triangles, in the file's order: `indices` holds
/// each face's corners in turn, `arities` how many each face has (empty
/// when every face is a triangle). A polygon of `n` corners gives `n - 2`
/// triangles, cut by [`prism_geometry::triangulate`] (a fan would cover
/// a polygon's notches; an outline cut where it touches itself gives
/// fewer); a point gives `a a a` and a line `a b b` (kept, never hit), as
/// tobj's own triangulation gives them.
fn polygon_triangles(indices: &[u32], arities: &[u32], positions: &[Vec3]) -> Cut {
    if arities.is_empty() {
        let triangles = indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        return Cut { triangles, per_face: Vec::new() };
    }
    let mut out = Vec::with_capacity(indices.len());
    let mut per_face = Vec::with_capacity(arities.len());
    let mut rest = indices;
    let mut corners = Vec::new();
    for &arity in arities {
        let Some((face, tail)) = rest.split_at_checked(arity as usize) else { break };
        rest = tail;
        let before = out.len();
        match *face {
            [a] => out.push([a, a, a]),
            [a, b] => out.push([a, b, b]),
            [a, b, c] => out.push([a, b, c]),
            _ => {
                corners.clear();
                corners
                    .extend(face.iter().map(|&i| positions.get(i as usize).copied().unwrap_or(Vec3::ZERO)));
                let local = prism_geometry::triangulate(&corners);
                out.extend(local.iter().map(|t| t.map(|k| face.get(k as usize).copied().unwrap_or(face[0]))));
            }
        }
        per_face.push(u32::try_from(out.len() - before).unwrap_or(u32::MAX));
    }
    Cut { triangles: out, per_face }
}

/// The largest emission component (`Ke`) an MTL file may give: the
/// scene file's own bound on colours.
const MAX_KE: f32 = crate::check::MAX_COLOR;

/// Checks the MTL lines that tobj would panic on or that prism would
/// refuse later without a line: colours (`Ka`, `Kd`, `Ks`, `Ke`) need
/// three numbers (one is read as grey before this, see `wild.rs`), finite
/// and `>= 0` (`Ke` at most [`MAX_KE`]); `Ns`, `Ni`, `d` and `Tr` a finite
/// number `>= 0`, `Tr` at most 1; `Tf` one or three numbers from 0 to 1;
/// `illum` a whole number 0 to 255; `map_Kd` and the other maps
/// tobj reads a file name (tobj says only "material parse error" for
/// these). Errors carry the 1-based line.
fn precheck_mtl(text: &str) -> Result<(), (usize, String)> {
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let (key, want) = match words.next() {
            Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) => (key, 3),
            Some(key @ ("Ns" | "Ni" | "d" | "Tr")) => (key, 1),
            // tobj refuses these with "material parse error" alone.
            Some(
                key @ ("map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns" | "map_ns"
                | "map_NS" | "bump" | "map_d"),
            ) => {
                if words.next().is_none() {
                    return Err((i + 1, format!("`{key}` needs a file name")));
                }
                continue;
            }
            // The transmission filter: one number or three, each 0 to 1
            // (a filter passes at most all the light); the CIE XYZ and
            // spectral forms are not read (clear, as without one).
            Some("Tf") => {
                let values: Vec<&str> = words.collect();
                if matches!(values.first(), Some(&("xyz" | "spectral"))) {
                    continue;
                }
                if !matches!(values.len(), 1 | 3) {
                    return Err((
                        i + 1,
                        format!(
                            "`Tf` needs one number or three (r g b, the transmission filter), found {}",
                            values.len()
                        ),
                    ));
                }
                if let Some(v) =
                    values.iter().find(|v| !v.parse::<f32>().is_ok_and(|x| (0.0..=1.0).contains(&x)))
                {
                    return Err((
                        i + 1,
                        format!(
                            "`Tf` value `{v}` must be a number from 0 to 1 (the transmission filter passes at most all the light)"
                        ),
                    ));
                }
                continue;
            }
            Some("illum") => {
                let Some(v) = words.next() else {
                    return Err((
                        i + 1,
                        "`illum` needs a whole number (the illumination model, such as 2)".into(),
                    ));
                };
                if v.parse::<u8>().is_err() {
                    return Err((
                        i + 1,
                        format!(
                            "`illum` value `{v}` must be a whole number from 0 to 255 (the illumination model, such as 2)"
                        ),
                    ));
                }
                continue;
            }
            _ => continue,
        };
        let values: Vec<&str> = words.collect();
        if values.len() < want {
            let what = if want == 3 { "3 numbers (r g b)" } else { "a number" };
            return Err((i + 1, format!("`{key}` needs {what}, found {}", values.len())));
        }
        for v in &values[..want] {
            if !v.parse::<f32>().is_ok_and(|x| x.is_finite() && x >= 0.0) {
                return Err((i + 1, format!("`{key}` value `{v}` must be a finite number >= 0")));
            }
            // A pixel sums up to 65 536 samples of an emission, each seen
            // along paths of up to 64 bounces, in 32-bit floats.
            if key == "Ke" && v.parse::<f32>().is_ok_and(|x| x > MAX_KE) {
                return Err((
                    i + 1,
                    format!(
                        "`Ke` value `{v}` must be at most 1e30 (a pixel's sum of its samples must stay finite)"
                    ),
                ));
            }
            // `d` above 1 reads as 1 (opaque); `Tr` is 1 − d, so above 1 it
            // would be a negative opacity.
            if key == "Tr" && v.parse::<f32>().is_ok_and(|x| x > 1.0) {
                return Err((
                    i + 1,
                    format!("`Tr` value `{v}` must be between 0 and 1 (the transparency, 1 − d)"),
                ));
            }
        }
    }
    Ok(())
}

/// Checks every line that tobj would read; returns the `mtllib` names.
/// Errors carry the 1-based line.
fn precheck(text: &str) -> Result<Prechecked, (usize, String)> {
    let (mut nv, mut nvt, mut nvn, mut faces) = (0_i64, 0_i64, 0_i64, 0_usize);
    let (mut with_vt, mut without_vt) = (false, false);
    let mut mtllibs = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        let numbers = |min: usize, max: usize, what: &str| -> Result<(), (usize, String)> {
            let vals: Vec<&str> = line.split_whitespace().skip(1).collect();
            if vals.len() < min || vals.len() > max {
                let want = if min == max { format!("{min}") } else { format!("{min} to {max}") };
                return Err((
                    line_no,
                    format!("`{key}` needs {want} numbers ({what}), found {}", vals.len()),
                ));
            }
            for v in vals {
                match v.parse::<f32>() {
                    Ok(x) if x.is_finite() => {}
                    // Finite as written (1e39) but past f32, in which the
                    // file is read: said as the TOML reader says it.
                    Ok(_) if v.parse::<f64>().is_ok_and(f64::is_finite) => {
                        return Err((
                            line_no,
                            format!("`{key}` value `{v}` must lie within ±{:e} (single precision)", f32::MAX),
                        ));
                    }
                    Ok(_) => return Err((line_no, format!("`{key}` value `{v}` is not finite"))),
                    Err(_) => return Err((line_no, format!("`{key}` value `{v}` is not a number"))),
                }
            }
            Ok(())
        };
        match key {
            "v" => {
                // x y z, x y z w, or x y z r g b (vertex colours, which
                // `wild::fix_obj` has dropped by now unless one is bad).
                let vals: Vec<&str> = words.collect();
                if !matches!(vals.len(), 3 | 4 | 6) {
                    return Err((
                        line_no,
                        format!(
                            "`v` needs 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b), found {}",
                            vals.len()
                        ),
                    ));
                }
                if vals.len() == 6 {
                    numbers(6, 6, "x y z r g b")?;
                }
                numbers(3, 4, "x y z [w]")?;
                // tobj divides x, y and z by w.
                if let [x, y, z, w] = vals.as_slice() {
                    let n = |s: &str| s.parse::<f32>().unwrap_or(f32::NAN);
                    let w = n(w);
                    if w == 0.0 {
                        return Err((line_no, "`v` weight w is 0; x, y and z are divided by it".into()));
                    }
                    if ![x, y, z].iter().all(|c| (n(c) / w).is_finite()) {
                        return Err((
                            line_no,
                            format!("`v` x, y and z divided by the weight w = {w:e} are not all finite"),
                        ));
                    }
                }
                nv += 1;
            }
            "vt" => {
                numbers(1, 3, "u [v [w]]")?;
                nvt += 1;
            }
            "vn" => {
                numbers(3, 3, "x y z")?;
                nvn += 1;
            }
            "f" => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err((
                        line_no,
                        format!("a face needs at least 3 corners, found {}", corners.len()),
                    ));
                }
                for c in corners {
                    let parts: Vec<&str> = c.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err((line_no, format!("face corner `{c}` is not v, v/vt, v//vn or v/vt/vn")));
                    }
                    if parts.get(1).is_some_and(|vt| !vt.is_empty()) {
                        with_vt = true;
                    } else {
                        without_vt = true;
                    }
                    for (k, (part, count, what)) in [
                        (parts[0], nv, "vertex"),
                        (parts.get(1).copied().unwrap_or(""), nvt, "texture coordinate"),
                        (parts.get(2).copied().unwrap_or(""), nvn, "normal"),
                    ]
                    .into_iter()
                    .enumerate()
                    {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let idx: i64 = part.parse().map_err(|_| {
                            (line_no, format!("face corner `{c}`: `{part}` is not an integer index"))
                        })?;
                        let resolved = resolve_index(idx, count);
                        if idx == 0 {
                            return Err((
                                line_no,
                                format!(
                                    "face corner `{c}`: {what} index 0 is invalid (OBJ indices start at 1)"
                                ),
                            ));
                        }
                        if resolved < 1 || resolved > count {
                            return Err((
                                line_no,
                                format!(
                                    "face corner `{c}`: {what} index {idx} is out of range ({count} defined before this line)"
                                ),
                            ));
                        }
                    }
                }
                faces += 1;
            }
            "mtllib" => {
                let name = line["mtllib".len()..].trim();
                if !name.is_empty() {
                    mtllibs.push(name.to_string());
                }
            }
            _ => {}
        }
    }
    if faces == 0 {
        return Err((
            text.lines().count().max(1),
            "the OBJ file has no faces (`f` lines); lines and points are not rendered".into(),
        ));
    }
    let corners = (with_vt && without_vt).then(|| FaceCorners::of(text));
    Ok(Prechecked { mtllibs, corners })
}

/// An OBJ index as written (`idx`; negative: relative to the `count`
/// elements of its kind defined before its line), counted from 1.
fn resolve_index(idx: i64, count: i64) -> i64 {
    if idx < 0 { count + idx + 1 } else { idx }
}

/// The material libraries an `mtllib` line's `name` (the rest of its
/// line) names: `name` itself where a file is called that (`exists`), as
/// tobj reads it (a name with spaces), else each of its words, where there
/// are several and each ends in `.mtl` (the OBJ format allows several
/// libraries on one line).
fn library_names(name: &str, exists: impl Fn(&str) -> bool) -> Vec<&str> {
    let words: Vec<&str> = name.split_whitespace().collect();
    let several = words.len() > 1
        && words.iter().all(|w| {
            w.len() > 4 && w.is_char_boundary(w.len() - 4) && w[w.len() - 4..].eq_ignore_ascii_case(".mtl")
        });
    if several && !exists(name) { words } else { vec![name] }
}

/// What [`precheck`] gathers for the load.
#[derive(Debug)]
struct Prechecked {
    /// The names each `mtllib` line gives (the rest of its line).
    mtllibs: Vec<String>,
    /// Every face's corners, where some corners have texture coordinates
    /// and some have none ([`mixed_uvs`]).
    corners: Option<FaceCorners>,
}

/// Every face's corners in the file's order, as `(v, vt, vn)` indices
/// resolved to count from 1 (0: none given), the key by which tobj makes
/// one vertex of each distinct corner.
#[derive(Debug)]
struct FaceCorners {
    /// The corners, face after face.
    keys: Vec<[i64; 3]>,
    /// Where each face's corners start in `keys`, and its line; one more
    /// entry than there are faces, for the end.
    faces: Vec<(usize, usize)>,
}

impl FaceCorners {
    /// The corners of `text`, which [`precheck`] has accepted.
    fn of(text: &str) -> Self {
        let mut counts = [0_i64; 3];
        let mut keys = Vec::new();
        let mut faces = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("");
            let mut words = line.split_whitespace();
            let slot = match words.next() {
                Some("v") => 0,
                Some("vt") => 1,
                Some("vn") => 2,
                Some("f") => {
                    faces.push((keys.len(), i + 1));
                    for corner in words {
                        let mut key = [0_i64; 3];
                        for (k, part) in corner.split('/').enumerate().take(3) {
                            let idx: i64 = part.parse().unwrap_or(0);
                            key[k] = resolve_index(idx, counts[k]);
                        }
                        keys.push(key);
                    }
                    continue;
                }
                _ => continue,
            };
            counts[slot] += 1;
        }
        faces.push((keys.len(), 0));
        Self { keys, faces }
    }
}

/// The texture coordinates of a model whose faces `faces` (numbered in the
/// file's order) have them at some corners and not at others, where tobj
/// gives only those it has, one per distinct corner with them: each
/// distinct corner in tobj's order, `uv` from the file where it has one,
/// else the OBJ format's (0, 0) (the image's bottom-left corner, as
/// Blender reads such corners). With the line of the model's first face
/// that lacks them, or `None` where the counts do not match tobj's.
fn mixed_uvs(
    corners: &FaceCorners,
    faces: std::ops::Range<usize>,
    texcoords: &[f32],
    n: usize,
) -> Option<(Vec<Vec2>, usize)> {
    let (start, _) = *corners.faces.get(faces.start)?;
    let (end, _) = *corners.faces.get(faces.end)?;
    let mut seen = std::collections::HashSet::with_capacity(n);
    let mut given = texcoords.chunks_exact(2);
    let mut uvs = Vec::with_capacity(n);
    for key in corners.keys.get(start..end)? {
        if seen.insert(*key) {
            // OBJ's v runs upward; prism's image rows run downward from v = 0.
            uvs.push(if key[1] > 0 { given.next().map(|c| Vec2::new(c[0], 1.0 - c[1]))? } else { Vec2::Y });
        }
    }
    let first_bare = corners.faces[faces.start..faces.end]
        .iter()
        .zip(&corners.faces[faces.start + 1..])
        .find(|((from, _), (to, _))| corners.keys[*from..*to].iter().any(|k| k[1] == 0))?;
    (uvs.len() == n && given.next().is_none()).then_some((uvs, first_bare.0.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each material's place, in tobj's order across two libraries, a name
    /// defined in both included (tobj lists both; the OBJ file uses the
    /// second).
    #[test]
    fn materials_are_placed_in_their_mtl_files() {
        let obj = "mtllib a.mtl\nmtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wood\nf 1 2 3\n";
        let a =
            "# first\nnewmtl wood\nKd 1 0 0\nmap_Kd w.png\nmap_aat on\nnewmtl stone\nbump s.png\n#newmtl x\n";
        let b = "newmtl leaf\nmap_d  leaf.png # cut-out\nmap_Kd leaf.png\nnewmtl wood\nmap_Ks k.png\n";
        let read = |p: &Path| Some(if p.ends_with("a.mtl") { a } else { b }.as_bytes().to_vec());
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &read).unwrap();
        let names: Vec<&str> = file.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["wood", "stone", "leaf", "wood"]);
        let place = |file: &str, line, maps: &[(&str, usize)]| MtlPlace {
            file: PathBuf::from(file),
            line,
            maps: maps.iter().map(|&(k, l)| (k.to_owned(), l)).collect(),
        };
        assert_eq!(
            file.material_places,
            [
                place("/s/a.mtl", 2, &[("map_Kd", 4)]),
                place("/s/a.mtl", 6, &[("bump", 7)]),
                place("/s/b.mtl", 1, &[("map_d", 2), ("map_Kd", 3)]),
                place("/s/b.mtl", 4, &[("map_Ks", 5)]),
            ]
        );
        assert_eq!(file.models[0].material, Some(3));
        assert_eq!(file.material_places[2].at("map_Kd"), "/s/b.mtl:3");
        assert_eq!(file.material_places[3].at("map_Kd"), "/s/b.mtl:4");
    }

    /// A comment stuck to a value (`Kd 1 0 0#red`), which tobj would read
    /// as part of the number and so refuse the whole library, silently
    /// (its materials then missing, the other library's places cleared):
    /// the comment is cut, both libraries are read, and every material is
    /// placed.
    #[test]
    fn a_comment_stuck_to_a_value_keeps_its_library() {
        let obj = "mtllib a.mtl\nmtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl leaf\nf 1 2 3\n";
        let a = "newmtl wood\nKd 1 0 0#red\n";
        let b = "newmtl leaf\nKd 0 1 0\nmap_d cut.png\n";
        let read = |p: &Path| Some(if p.ends_with("a.mtl") { a } else { b }.as_bytes().to_vec());
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &read).unwrap();
        let names: Vec<&str> = file.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["wood", "leaf"]);
        assert_eq!(file.materials[0].diffuse, Some([1.0, 0.0, 0.0]));
        assert_eq!(file.material_places.len(), 2);
        assert_eq!(file.material_places[1].at("map_d"), "/s/b.mtl:3");
    }

    /// Each triangle's corners as (position, uv) of a loaded model.
    fn corners(model: &ObjModel) -> Vec<[(Vec3, Vec2); 3]> {
        let m = &model.mesh;
        let uvs = m.uvs().expect("the model has texture coordinates");
        m.indices().iter().map(|t| t.map(|i| (m.positions()[i as usize], uvs[i as usize]))).collect()
    }

    /// Faces with texture coordinates beside faces without, in one model
    /// (tobj then gives only the ones it has, no longer matching the
    /// vertices): each corner with `vt` keeps its own uv (v turned down),
    /// one without gets the OBJ format's (0, 0), also where it shares its
    /// position with a corner that has one; relative indices and a second
    /// model that has them all are read as usual. A warning names the
    /// first face without them.
    #[test]
    fn faces_without_texture_coordinates_leave_the_others_theirs() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.25 0.75\n\
                   o a\nf 1 2 3\nf 1/1 2/2 3/3 4/4\nf 3 4 1\nf -4/-4 -2/-2 -1/-1\n\
                   o b\nf 1/4 2/3 3/2\n";
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        assert_eq!(file.models.len(), 2);
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let uv = |u: f32, v: f32| Vec2::new(u, 1.0 - v);
        let bare = Vec2::Y;
        let quad = [(p[0], uv(0.0, 0.0)), (p[1], uv(1.0, 0.0)), (p[2], uv(1.0, 1.0)), (p[3], uv(0.25, 0.75))];
        assert_eq!(
            corners(&file.models[0]),
            [
                [(p[0], bare), (p[1], bare), (p[2], bare)],
                // The quad, cut into two triangles.
                [quad[0], quad[1], quad[2]],
                [quad[0], quad[2], quad[3]],
                [(p[2], bare), (p[3], bare), (p[0], bare)],
                [quad[0], quad[2], quad[3]],
            ]
        );
        assert_eq!(
            corners(&file.models[1]),
            [[(p[0], uv(0.25, 0.75)), (p[1], uv(1.0, 1.0)), (p[2], uv(1.0, 0.0))]]
        );
        assert_eq!(file.warnings.len(), 1, "{:?}", file.warnings);
        assert!(
            file.warnings[0].starts_with("/s/m.obj:10: model `a` has faces without texture coordinates"),
            "{:?}",
            file.warnings
        );
    }

    /// `usemtl` in a file without `mtllib`: one warning, at the first.
    #[test]
    fn materials_named_without_a_library_are_warned_about() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl wood\nf 1 2 3\nusemtl stone\nf 3 2 1\n";
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        assert_eq!(
            file.unknown_materials,
            [
                "/s/m.obj:4: `usemtl wood`, but the file names no material library (`mtllib`); its faces get the default material"
            ]
        );
        let plain = load_obj(
            Path::new("/s/m.obj"),
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            NormalMode::Flat,
            &|_| None,
        );
        assert!(plain.unwrap().unknown_materials.is_empty());
    }

    /// One `mtllib` line may name several libraries (the OBJ format's
    /// `mtllib a.mtl b.mtl`); a name with spaces that is not a list of
    /// `.mtl` files stays one name, and a comment after it is not part
    /// of it.
    #[test]
    fn one_mtllib_line_names_several_libraries() {
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let read = |p: &Path| {
            let text = match p.to_str()? {
                "/s/a.mtl" => "newmtl red\nKd 1 0 0\n",
                "/s/b.mtl" => "newmtl green\nKd 0 1 0\n",
                "/s/my mats.mtl" => "newmtl blue\nKd 0 0 1\n",
                _ => return None,
            };
            Some(text.as_bytes().to_vec())
        };
        let obj = format!("mtllib a.mtl b.mtl\n{v}usemtl red\nf 1 2 3\nusemtl green\nf 3 2 1\n");
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &read).unwrap();
        let names: Vec<&str> = file.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["red", "green"]);
        assert_eq!(file.mtl_files, [PathBuf::from("/s/a.mtl"), PathBuf::from("/s/b.mtl")]);
        let used: Vec<Option<usize>> = file.models.iter().map(|m| m.material).collect();
        assert_eq!(used, [Some(0), Some(1)]);
        assert!(file.material_error.is_none() && file.unknown_materials.is_empty());
        assert_eq!(file.material_places.len(), 2);
        let obj = format!("mtllib my mats.mtl # the blues\n{v}usemtl blue\nf 1 2 3\n");
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &read).unwrap();
        assert_eq!(file.materials[0].name, "blue");
        assert_eq!(file.mtl_files, [PathBuf::from("/s/my mats.mtl")]);
        assert_eq!(file.models[0].material, Some(0));
        // One of two missing: the other's materials, as with two lines.
        let obj = format!("mtllib a.mtl gone.mtl\n{v}usemtl red\nf 1 2 3\n");
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &read).unwrap();
        assert_eq!(file.materials.len(), 1);
        assert_eq!(file.models[0].material, Some(0));
    }

    /// A comment after a statement, and a statement continued on the
    /// next line with `\\`, as the OBJ format allows: read as meant, each
    /// later line's number kept for messages.
    #[test]
    fn comments_after_statements_and_continued_lines_are_read() {
        let obj = "v 0 0 0 # origin\nv 1 0 0\nv 1 1 0#corner\nv 0 1 0\nf 1 2 \\\n 3 4 # a quad\nf 1 2 \\\n\\\n 3\nf 1 2 9\n";
        let err = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap_err();
        assert_eq!(err.0, Location::at_line(Path::new("/s/m.obj"), 10));
        assert!(err.1.contains("index 9 is out of range"), "{}", err.1);
        let obj = obj.replace("f 1 2 9\n", "");
        let file = load_obj(Path::new("/s/m.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        assert_eq!(file.models[0].mesh.len(), 3);
        assert!(file.warnings.is_empty(), "{:?}", file.warnings);
    }

    /// A face that is a spike out and back (`f 1 2 3 2`) has no area and
    /// gives no triangles (a fan made it a triangle seen from both sides);
    /// a file of nothing else has no faces to render.
    #[test]
    fn a_spike_face_gives_no_triangles() {
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\n";
        let obj = format!("{v}f 1 2 3 2\nf 4 5 6\n");
        let file = load_obj(Path::new("/s/k.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        assert_eq!(file.models.len(), 1);
        assert_eq!(file.models[0].mesh.indices(), [[3, 4, 5]]);
        let obj = format!("{v}g spike\nf 1 2 3 2\ng tri\nf 4 5 6\n");
        let file = load_obj(Path::new("/s/k.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        assert_eq!(file.models.len(), 1);
        let obj = format!("{v}f 1 2 3 2\n");
        let err = load_obj(Path::new("/s/k.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap_err();
        assert!(err.1.contains("no faces") && err.1.contains("spike"), "{}", err.1);
    }

    /// A U-shaped floor polygon (seen from above, its notch around
    /// x = 1.5, z = 2) and a triangle, loaded from an OBJ.
    #[test]
    fn polygons_are_cut_by_ear_clipping_not_fanned() {
        let obj = "v 0 0 0\nv 3 0 0\nv 3 0 3\nv 2 0 3\nv 2 0 1\nv 1 0 1\nv 1 0 3\nv 0 0 3\n\
                   f 1 2 3 4 5 6 7 8\nf 1 2 3\n";
        let file = load_obj(Path::new("/s/u.obj"), obj.as_bytes(), NormalMode::Flat, &|_| None).unwrap();
        let mesh = &file.models[0].mesh;
        // 6 from the polygon, then the triangle.
        assert_eq!(mesh.len(), 7);
        assert_eq!(file.models[0].degenerate, 0);
        let idx = mesh.indices();
        assert_eq!(idx[6], [0, 1, 2]);
        // Straight down onto the notch, and onto the U's arms and base.
        let down = |x: f32, z: f32| prism_geometry::Ray::new(Vec3::new(x, 1.0, z), Vec3::NEG_Y);
        let polygon = TriangleMesh::new(mesh.positions().to_vec(), None, None, idx[..6].to_vec()).unwrap();
        assert!(polygon.intersect_brute_force(&down(1.5, 2.0)).is_none(), "the notch is covered");
        for (x, z) in [(0.5, 2.5), (2.5, 2.5), (1.5, 0.5), (0.1, 0.1), (2.9, 2.9)] {
            assert!(polygon.intersect_brute_force(&down(x, z)).is_some(), "({x}, {z}) is not covered");
        }
    }

    #[test]
    fn faces_of_every_arity_keep_their_order() {
        let positions: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f32, (i * i) as f32, 0.0)).collect();
        // A triangle, a convex quad (cut as a fan would cut it), a point.
        let idx = [0, 1, 2, 0, 1, 2, 3, 4];
        let arities = [3, 4, 1];
        let cut = polygon_triangles(&idx, &arities, &positions);
        assert_eq!(cut.triangles, vec![[0, 1, 2], [0, 1, 2], [0, 2, 3], [4, 4, 4]]);
        assert_eq!(cut.per_face, [1, 2, 1]);
        let cut = polygon_triangles(&[0, 1, 2, 2, 3, 4], &[], &positions);
        assert_eq!(cut.triangles, vec![[0, 1, 2], [2, 3, 4]]);
        assert!(cut.per_face.is_empty());
        assert_eq!(cut.faces(), 2);
    }

    #[test]
    fn precheck_reports_lines() {
        assert_eq!(precheck("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").map(|p| p.mtllibs.len()), Ok(0));
        let e = precheck("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
        assert_eq!(e.0, 4);
        assert!(e.1.contains("out of range"), "{}", e.1);
        let e = precheck("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err();
        assert_eq!(e.0, 3);
        let e = precheck("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err();
        assert!(e.1.contains("index 0"));
        let e = precheck("v 0 nan 0\n").unwrap_err();
        assert!(e.1.contains("not finite"));
        let e = precheck("v 0 0 0\nv 1 0 0\nl 1 2\n").unwrap_err();
        assert!(e.1.contains("no faces"));
        assert!(precheck("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n").is_ok());
        assert!(precheck("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 -2 -1\n").is_err());
        assert_eq!(
            precheck("mtllib my lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").map(|p| p.mtllibs),
            Ok(vec!["my lib.mtl".to_string()])
        );
    }

    #[test]
    fn short_mtl_colours_are_refused_with_their_line() {
        assert_eq!(precheck_mtl("newmtl a\nKd 1 1 1\n"), Ok(()));
        let e = precheck_mtl("newmtl a\n\nKd 0.75 0.975\n").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("`Kd` needs 3 numbers"), "{}", e.1);
        assert!(precheck_mtl("Ke\n").is_err());
        let e = precheck_mtl("newmtl a\nKd 1 -1 1\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("`-1`"), "{}", e.1);
        assert_eq!(precheck_mtl("Ns nan\n").unwrap_err().0, 1);
        assert!(precheck_mtl("d 0.5 # half\nNs 10\n").is_ok());
        // `Tr` above 1 would be a negative opacity; `d` above 1 reads as 1.
        assert_eq!(
            precheck_mtl("newmtl a\nTr 1.5\n"),
            Err((2, "`Tr` value `1.5` must be between 0 and 1 (the transparency, 1 − d)".into()))
        );
        assert!(precheck_mtl("Tr 1\nTr 0.25\nd 1.5\n").is_ok());
        // `Tf`: one number or three, each 0 to 1; its XYZ and spectral forms pass.
        assert!(precheck_mtl("Tf 0.5\nTf 0 0.25 1\nTf xyz 1 1 1\nTf spectral f.rfl\n").is_ok());
        for (tf, what) in [("2 2 2", "`2`"), ("nan", "`nan`"), ("0.5 -0.1 0", "`-0.1`"), ("1 1", "found 2")] {
            let e = precheck_mtl(&format!("newmtl g\nTf {tf}\n")).unwrap_err();
            assert_eq!(e.0, 2, "{tf}");
            assert!(e.1.starts_with("`Tf`") && e.1.contains(what), "{tf}: {}", e.1);
        }
        // An emission whose samples' sum would overflow.
        assert!(precheck_mtl("Ke 1e30 0 1\n").is_ok());
        let e = precheck_mtl("newmtl a\nKe 1e38 1e38 1e38\n").unwrap_err();
        assert_eq!(
            e,
            (
                2,
                "`Ke` value `1e38` must be at most 1e30 (a pixel's sum of its samples must stay finite)"
                    .into()
            )
        );
    }

    #[test]
    fn mtl_lines_tobj_refuses_without_a_place_are_refused_with_their_line() {
        let obj = b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        let error = |mtl: &'static str| {
            let file =
                load_obj(Path::new("/s/m.obj"), obj, NormalMode::Auto, &|_| Some(mtl.as_bytes().to_vec()))
                    .unwrap();
            file.material_error.unwrap_or_default()
        };
        for (mtl, words) in [
            (
                "newmtl a\nillum x\n",
                "/s/m.mtl:2: `illum` value `x` must be a whole number from 0 to 255 (the illumination model, such as 2)",
            ),
            (
                "newmtl a\nKd 1 1 1\nillum\n",
                "/s/m.mtl:3: `illum` needs a whole number (the illumination model, such as 2)",
            ),
            (
                "newmtl a\nillum 300\n",
                "/s/m.mtl:2: `illum` value `300` must be a whole number from 0 to 255 (the illumination model, such as 2)",
            ),
            ("newmtl a\nKd 1 0 0\nmap_Kd\n", "/s/m.mtl:3: `map_Kd` needs a file name"),
            ("newmtl a\nmap_Kd   # no file\n", "/s/m.mtl:2: `map_Kd` needs a file name"),
        ] {
            let e = error(mtl);
            assert_eq!(e, format!("cannot use material library {words}"), "{mtl}");
        }
        for key in ["map_Ka", "map_Ks", "map_Bump", "map_bump", "map_Ns", "map_ns", "map_NS", "bump", "map_d"]
        {
            let e = error(Box::leak(format!("newmtl a\n{key}\n").into_boxed_str()));
            assert_eq!(e, format!("cannot use material library /s/m.mtl:2: `{key}` needs a file name"));
        }
        // What tobj reads stays readable.
        assert_eq!(error("newmtl a\nillum 2\nmap_Kd tex.png\nbump -bm 1 n.png\n"), "");
        assert_eq!(error("newmtl a\nmap_Kd -s 2 2 1 -o 0.5 0 0 -mm 0 1 t.png # tiles\n"), "");
    }

    #[test]
    fn usemtl_names_missing_from_the_library_are_found_once() {
        let text =
            "usemtl a\nf 1 2 3\nusemtl b # typo\nf 1 2 3\nusemtl b\nusemtl\nusemtl_x c\n  usemtl  c \n";
        assert_eq!(unknown_usemtl(text, &["a"]), [(3, "b"), (8, "c")]);
        assert!(unknown_usemtl(text, &["a", "b", "c"]).is_empty());
    }

    #[test]
    fn smoothing_groups_per_face() {
        assert_eq!(smoothing_groups("v 0 0 0\nf 1 2 3\n"), None);
        let text = "f 1 2 3\ns 1\nf 1 2 3 4\ns off\nf 1 2 3\ns 7 # comment\nf 1 2 3\ns 0\nf 3 2 1\n";
        assert_eq!(smoothing_groups(text), Some(vec![0, 1, 0, 7, 0]));
    }

    /// A face cut at a pinch gives fewer than `n - 2` triangles; the
    /// smoothing groups of the faces after it still reach their own
    /// triangles: two triangles folded by 30° (under the crease angle) in
    /// `s off` stay flat.
    #[test]
    fn smoothing_groups_hold_after_a_face_cut_at_a_pinch() {
        // A triangle with a spike (corner 3 passed twice), then the fold.
        let obj = "v -2 -2 0\nv 2 -2 0\nv 0 0 0\nv 0 2 0\nv -2 2 0\n\
                   v 5 0 0\nv 6 0 0\nv 5 1 0\nv 6 1 0.57735\n\
                   s 1\nf 1 2 3 4 3 5\ns off\nf 6 7 8\nf 8 7 9\n";
        let file = load_obj(Path::new("/s/p.obj"), obj.as_bytes(), NormalMode::Auto, &|_| None).unwrap();
        let mesh = &file.models[0].mesh;
        // The spiked triangle: 2 triangles (not 4), then the two.
        assert_eq!(mesh.len(), 4);
        let normals = mesh.normals().unwrap();
        for f in 2..4 {
            let [a, b, c] = mesh.triangle(f);
            let face = (b - a).cross(c - a).normalize();
            for &i in &mesh.indices()[f] {
                let n = normals[i as usize];
                assert!(n.dot(face) > 0.9999, "face {f}: vertex normal {n} against the face's {face}");
            }
        }
    }
}
