//! Scene acceleration for prism: closest-hit and occlusion queries over a
//! mix of analytic shapes and instanced triangle meshes.
//!
//! (This first version tests every object; the obvhs-backed hierarchy
//! replaces the internals without changing this API.)

#![warn(missing_docs)]

use prism_geometry::{Aabb, Hit, Instance, Intersect, Ray, Shape, Transform, TriangleMesh, TriangleRay};
use std::ops::ControlFlow;
use std::sync::Arc;

/// One object of the scene: an analytic shape or an instance of a mesh.
#[derive(Clone, Debug)]
pub enum Object {
    /// An analytic shape placed by a transform.
    Shape(Instance<Shape>),
    /// Mesh number `mesh` (an index into the meshes given to
    /// [`Accel::build`]) placed by `transform`. Many instances may share
    /// one mesh; it is stored once.
    Mesh {
        /// Index into the mesh list.
        mesh: u32,
        /// Object (mesh) space to world.
        transform: Transform,
    },
}

/// A hit on the scene: which object (and triangle) and the geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneHit {
    /// Index of the object in the list given to [`Accel::build`].
    pub object: u32,
    /// Triangle index within the mesh, or [`SceneHit::NO_TRIANGLE`] for
    /// analytic shapes.
    pub triangle: u32,
    /// World-space hit (normals outward, see [`Hit`]). For meshes, its uv
    /// is the interpolated vertex uv (or the barycentrics without uvs).
    pub hit: Hit,
}

impl SceneHit {
    /// The `triangle` value of hits on analytic shapes.
    pub const NO_TRIANGLE: u32 = u32::MAX;
}

/// Figures about a built structure.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Wall time of the build in seconds.
    pub build_seconds: f64,
    /// Bytes held by the acceleration structures (not the meshes).
    pub bvh_bytes: usize,
    /// Triangles stored (each mesh counted once).
    pub stored_triangles: usize,
    /// Triangles as seen by rays (each instance counted).
    pub instanced_triangles: usize,
}

/// Why a scene could not be accelerated.
#[derive(Debug, Clone, PartialEq)]
pub enum BuildError {
    /// An object names a mesh that was not supplied.
    NoSuchMesh {
        /// The object's index.
        object: usize,
        /// The mesh index it named.
        mesh: u32,
    },
}

impl std::fmt::Display for BuildError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NoSuchMesh { object, mesh } => {
                write!(f, "object {object} names mesh {mesh}, which does not exist")
            }
        }
    }
}

impl std::error::Error for BuildError {}

/// The acceleration structure over a whole scene.
#[derive(Debug)]
pub struct Accel {
    meshes: Vec<Arc<TriangleMesh>>,
    objects: Vec<Object>,
    bounds: Aabb,
    stats: BuildStats,
}

impl Accel {
    /// Builds the structure over `objects`, whose mesh instances index
    /// `meshes`.
    ///
    /// # Errors
    /// [`BuildError::NoSuchMesh`] if an object names a missing mesh.
    pub fn build(meshes: Vec<Arc<TriangleMesh>>, objects: Vec<Object>) -> Result<Self, BuildError> {
        let start = std::time::Instant::now();
        let mut bounds = Aabb::EMPTY;
        let mut instanced = 0;
        for (i, o) in objects.iter().enumerate() {
            match o {
                Object::Shape(s) => {
                    if s.shape.is_bounded() {
                        bounds = bounds.union(s.bounds());
                    }
                }
                Object::Mesh { mesh, transform } => {
                    let m = meshes
                        .get(*mesh as usize)
                        .ok_or(BuildError::NoSuchMesh { object: i, mesh: *mesh })?;
                    instanced += m.len();
                    bounds = bounds.union(transform.aabb(&m.bounds()));
                }
            }
        }
        let stats = BuildStats {
            build_seconds: start.elapsed().as_secs_f64(),
            bvh_bytes: 0,
            stored_triangles: meshes.iter().map(|m| m.len()).sum(),
            instanced_triangles: instanced,
        };
        Ok(Self { meshes, objects, bounds, stats })
    }

    /// The objects, in the order given.
    #[must_use]
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The meshes, in the order given.
    #[must_use]
    pub fn meshes(&self) -> &[Arc<TriangleMesh>] {
        &self.meshes
    }

    /// Bounds of every bounded object (infinite planes excluded).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Build figures.
    #[must_use]
    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    fn hit_object(&self, i: usize, ray: &Ray) -> Option<SceneHit> {
        match &self.objects[i] {
            Object::Shape(s) => s.intersect(ray).map(|hit| SceneHit {
                object: i as u32,
                triangle: SceneHit::NO_TRIANGLE,
                hit,
            }),
            Object::Mesh { mesh, transform } => {
                let m = &self.meshes[*mesh as usize];
                let local = transform.ray_to_object(ray);
                let (f, t, b1, b2) = m.intersect_brute_force(&local)?;
                let hit = transform.hit_to_world(&m.hit(f, t, b1, b2, local.dir));
                Some(SceneHit { object: i as u32, triangle: f as u32, hit })
            }
        }
    }

    /// The nearest hit in `[ray.t_min, ray.t_max]`.
    #[must_use]
    pub fn closest_hit(&self, ray: &Ray) -> Option<SceneHit> {
        let mut ray = *ray;
        let mut best = None;
        for i in 0..self.objects.len() {
            if let Some(h) = self.hit_object(i, &ray) {
                ray.t_max = h.hit.t;
                best = Some(h);
            }
        }
        best
    }

    /// Whether anything lies in `[ray.t_min, ray.t_max]` (early exit).
    #[must_use]
    pub fn occluded(&self, ray: &Ray) -> bool {
        (0..self.objects.len()).any(|i| self.hit_object(i, ray).is_some())
    }

    /// Calls `f` for every surface crossing along the ray's interval, in no
    /// particular order, until `f` breaks. A closed shape crossed twice
    /// (entering and leaving) is reported at each crossing; `SceneHit::hit`
    /// says which by `front_face`. Used for coloured shadows behind
    /// transparent objects.
    pub fn for_each_hit(&self, ray: &Ray, mut f: impl FnMut(&SceneHit) -> ControlFlow<()>) {
        for i in 0..self.objects.len() {
            let mut r = *ray;
            while let Some(h) = self.hit_object(i, &r) {
                if f(&h).is_break() {
                    return;
                }
                // Continue past this crossing.
                let next = h.hit.t.next_up_f32();
                if !(next <= r.t_max) {
                    break;
                }
                r.t_min = next;
            }
        }
    }
}

trait NextUp {
    fn next_up_f32(self) -> f32;
}

impl NextUp for f32 {
    fn next_up_f32(self) -> f32 {
        // Smallest step past a crossing that still orders distinct hits.
        self + self.abs().max(1e-6) * 1e-5
    }
}

#[allow(unused_imports)]
use TriangleRay as _;
