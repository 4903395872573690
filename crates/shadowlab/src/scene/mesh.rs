//! Scenes from a renderer's indexed meshes, and geometry that changes between frames.
//!
//! [`Scene::from_meshes`] takes each mesh's vertex positions, triangle indices and
//! material as they sit in the caller's buffers; mesh `i`'s triangles follow mesh
//! `i − 1`'s in the scene, so [`Scene::mesh_triangles`] ranges name them later.
//!
//! A scene whose geometry moves is edited in place through [`Scene::replace_mesh`],
//! [`Scene::transform_triangles`] or, after writing `v0`/`v1`/`v2` directly,
//! [`Scene::mark_changed`]. Each bumps [`Scene::revision`] and refreshes the bounds:
//! techniques that keep per-scene state across frames (`asm`'s tile tree) compare the
//! revision and rebuild that state, so a moved object never leaves stale shadows behind.

use super::{Material, Scene};
use crate::error::{Error, Result};
use crate::math::{Mat4, Vec3};

/// One indexed triangle mesh in world space, borrowed from the caller's buffers.
#[derive(Clone, Copy, Debug)]
pub struct IndexedMesh<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Three vertex indices per triangle.
    pub indices: &'a [[u32; 3]],
    /// The material of every triangle of the mesh.
    pub material: &'a Material,
}

impl Scene {
    /// A scene called `name` from indexed meshes (see the [module doc](self)); fails with a
    /// sentence naming the mesh and face of an index out of range, or (as
    /// [`Scene::validate`]) a non-finite vertex, a bad material or no triangles at all.
    ///
    /// ```
    /// use shadowlab::prelude::*;
    /// use shadowlab::scene::mesh::IndexedMesh;
    /// let ground = [vec3(-2.0, 0.0, -2.0), vec3(-2.0, 0.0, 2.0), vec3(2.0, 0.0, 2.0), vec3(2.0, 0.0, -2.0)];
    /// let square = ground.map(|p| p * 0.25 + vec3(0.0, 1.0, 0.0));
    /// let quad = [[0, 1, 2], [0, 2, 3]];
    /// let grey = Material::default();
    /// let scene = Scene::from_meshes("two quads", &[
    ///     IndexedMesh { positions: &ground, indices: &quad, material: &grey },
    ///     IndexedMesh { positions: &square, indices: &quad, material: &grey },
    /// ])
    /// .unwrap();
    /// assert_eq!(scene.len(), 4);
    /// assert_eq!(scene.mesh_triangles(1), 2..4);
    /// ```
    pub fn from_meshes(name: &str, meshes: &[IndexedMesh]) -> Result<Scene> {
        let mut s = Scene::new(name);
        let total: usize = meshes.iter().map(|m| m.indices.len()).sum();
        if total > super::MAX_TRIANGLES {
            return Err(Error::Limit(format!(
                "scene {name} has {total} triangles, more than the limit of {}",
                super::MAX_TRIANGLES
            )));
        }
        s.reserve(total);
        for (i, m) in meshes.iter().enumerate() {
            check_indices(name, i, m.positions.len(), m.indices)?;
            let mat = s.add_material(m.material.clone());
            s.push_indexed(m.positions, m.indices, Mat4::IDENTITY, mat);
            s.mesh_ends.push(s.len());
        }
        s.validate()?;
        Ok(s)
    }

    /// The triangles of mesh `i` of [`Scene::from_meshes`] (or of a mesh added by
    /// [`Scene::add_mesh`]).
    ///
    /// # Panics
    /// When the scene has fewer meshes.
    pub fn mesh_triangles(&self, i: usize) -> std::ops::Range<usize> {
        let start = if i == 0 { 0 } else { self.mesh_ends[i - 1] };
        start..self.mesh_ends[i]
    }

    /// Number of meshes added by [`Scene::from_meshes`] or [`Scene::add_mesh`].
    pub fn mesh_count(&self) -> usize {
        self.mesh_ends.len()
    }

    /// Appends one indexed mesh, returning its mesh number; fails as
    /// [`Scene::from_meshes`] does, leaving the scene as it was. Triangles pushed before
    /// without a mesh belong to the first mesh added.
    pub fn add_mesh(&mut self, mesh: &IndexedMesh) -> Result<usize> {
        let i = self.mesh_ends.len();
        check_indices(&self.name, i, mesh.positions.len(), mesh.indices)?;
        if self.len() + mesh.indices.len() > super::MAX_TRIANGLES {
            return Err(Error::Limit(format!(
                "scene {} would have {} triangles, more than the limit of {}",
                self.name,
                self.len() + mesh.indices.len(),
                super::MAX_TRIANGLES
            )));
        }
        let (triangles, bounds) = (self.len(), self.bounds);
        let mat = self.add_material(mesh.material.clone());
        self.push_indexed(mesh.positions, mesh.indices, Mat4::IDENTITY, mat);
        if let Err(e) = self.validate() {
            for v in [&mut self.v0, &mut self.v1, &mut self.v2] {
                v.truncate(triangles);
            }
            self.material.truncate(triangles);
            self.uv.truncate(triangles);
            self.materials.pop();
            self.bounds = bounds;
            return Err(e);
        }
        self.mesh_ends.push(self.len());
        self.revision += 1;
        Ok(i)
    }

    /// Moves mesh `i` to new vertex positions with the same indices (a deforming or moving
    /// object); fails when the count differs from the mesh's, an index is out of range or
    /// a position is not finite, leaving the scene as it was.
    pub fn replace_mesh(
        &mut self,
        i: usize,
        positions: &[Vec3],
        indices: &[[u32; 3]],
    ) -> Result<()> {
        if i >= self.mesh_ends.len() {
            return Err(Error::param(format!(
                "scene {} has {} meshes, so there is no mesh {i}",
                self.name,
                self.mesh_ends.len()
            )));
        }
        let range = self.mesh_triangles(i);
        if indices.len() != range.len() {
            return Err(Error::param(format!(
                "mesh {i} of scene {} has {} triangles, not {}; add a new mesh to change the count",
                self.name,
                range.len(),
                indices.len()
            )));
        }
        check_indices(&self.name, i, positions.len(), indices)?;
        if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::Scene {
                scene: self.name.clone(),
                what: format!("mesh {i}: vertex {v} is not finite"),
            });
        }
        for (t, tri) in range.zip(indices) {
            let [a, b, c] = tri.map(|j| positions[j as usize]);
            (self.v0[t], self.v1[t], self.v2[t]) = (a, b, c);
        }
        self.mark_changed();
        Ok(())
    }

    /// Applies `world_from_old` to the triangles in `range` (a rigidly moving object).
    pub fn transform_triangles(&mut self, range: std::ops::Range<usize>, world_from_old: Mat4) {
        for t in range {
            self.v0[t] = world_from_old.transform_point3(self.v0[t]);
            self.v1[t] = world_from_old.transform_point3(self.v1[t]);
            self.v2[t] = world_from_old.transform_point3(self.v2[t]);
        }
        self.mark_changed();
    }

    /// Tells the scene its triangles were edited in place: bumps [`Scene::revision`] (so
    /// techniques drop state kept for the old geometry) and recomputes the bounds.
    pub fn mark_changed(&mut self) {
        self.revision += 1;
        self.recompute_bounds();
    }
}

/// Fails naming mesh `mesh`'s first face with an index of `vertices` or more.
fn check_indices(scene: &str, mesh: usize, vertices: usize, indices: &[[u32; 3]]) -> Result<()> {
    match indices
        .iter()
        .enumerate()
        .find(|(_, f)| f.iter().any(|&j| j as usize >= vertices))
    {
        Some((face, f)) => Err(Error::Scene {
            scene: scene.to_string(),
            what: format!(
                "mesh {mesh}: face {face} names vertex {} but the mesh has {vertices} vertices",
                f.iter().copied().max().unwrap_or(0)
            ),
        }),
        None => Ok(()),
    }
}
