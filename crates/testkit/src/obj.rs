//! Reading a Wavefront OBJ file as one triangle mesh, positions only: the
//! shared meshes of the tests and benchmarks. (The renderer's own scene
//! loader, with normals, uvs and materials, is prism-scene's.)

use prism_geometry::glam::Vec3;
use prism_geometry::{GeometryError, TriangleMesh};
use std::path::{Path, PathBuf};

/// Why an OBJ file could not be read as a mesh.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// tobj could not read or parse the file.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What tobj said.
        source: tobj::LoadError,
    },
    /// The faces do not make a valid mesh (an index out of range, a
    /// non-finite position).
    #[error("{}: {source}", path.display())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// What prism-geometry said.
        source: GeometryError,
    },
}

/// Every shape of the OBJ at `path` as one mesh: positions only, polygons
/// triangulated, shapes appended in file order.
///
/// # Errors
/// [`ObjError`] if the file cannot be read or its faces are invalid.
pub fn load_obj(path: &Path) -> Result<TriangleMesh, ObjError> {
    let opts = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) =
        tobj::load_obj(path, &opts).map_err(|source| ObjError::Read { path: path.into(), source })?;
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        positions.extend(m.mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        indices.extend(m.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
    }
    TriangleMesh::new(positions, None, None, indices)
        .map_err(|source| ObjError::Mesh { path: path.into(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_shapes_into_one_mesh_and_reports_errors() {
        let dir = std::env::temp_dir().join(format!("prism-testkit-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("two.obj");
        std::fs::write(
            &good,
            "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n",
        )
        .unwrap();
        let m = load_obj(&good).unwrap();
        assert_eq!(m.len(), 3, "a quad (two triangles) and a triangle");
        assert_eq!(m.triangle(2), [Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]);
        assert!(matches!(load_obj(&dir.join("missing.obj")), Err(ObjError::Read { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
