//! The node hierarchy of a glTF scene, walked depth-first with each node's transform
//! composed onto its parent's: mesh instances, camera nodes and the first light node, under
//! the limits on visits and instances.

use super::{Loader, Skip, MAX_CAMERAS, MAX_MESH_INSTANCES, MAX_NODE_VISITS};
use crate::error::{Error, Result};
use crate::math::Mat4;

impl Loader<'_> {
    /// Walks the scene's hierarchy depth-first, in file order, adding each mesh instance;
    /// with `plan`, only counts the triangles the instances would add (from the
    /// accessors' counts, nothing decoded) and returns the total.
    pub(super) fn walk(&mut self, plan: bool) -> Result<u64> {
        let doc = self.doc;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let node_count = doc.nodes().len();
        let mut stack: Vec<(gltf::Node, Mat4, usize)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, 0))
            .collect();
        let mut visits = 0usize;
        let mut instances = 0usize;
        let mut planned = 0u64;
        while let Some((node, parent, depth)) = stack.pop() {
            visits += 1;
            if depth > node_count {
                return Err(self.err(format!(
                    "node {} is its own ancestor: the node hierarchy has a cycle",
                    node.index()
                )));
            }
            if visits > MAX_NODE_VISITS {
                return Err(Error::Limit(format!(
                    "{}: the node hierarchy needs more node visits than the limit of {MAX_NODE_VISITS}",
                    self.path.display()
                )));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            if !local.is_finite() {
                return Err(self.err(format!("node {} has a non-finite transform", node.index())));
            }
            let world = parent * local;
            if let Some(c) = node.camera() {
                if self.cameras.len() < MAX_CAMERAS {
                    self.cameras.push((c.index(), world));
                }
            }
            if node.skin().is_some() && node.mesh().is_some() {
                *self.skipped.entry(Skip::Skin).or_default() += 1;
            }
            if self.light.is_none() {
                if let Some(l) = node.light() {
                    self.light = Some((l.index(), world));
                }
            }
            if let Some(mesh) = node.mesh() {
                instances += 1;
                if instances > MAX_MESH_INSTANCES {
                    return Err(Error::Limit(format!(
                        "{}: the node hierarchy places more mesh instances than the limit of {MAX_MESH_INSTANCES}",
                        self.path.display()
                    )));
                }
                if plan {
                    planned = planned.saturating_add(super::meshes::mesh_triangles(&mesh));
                } else {
                    let prims = self.mesh(&mesh)?;
                    let added: usize = prims.iter().map(|p| p.tris.len()).sum();
                    crate::scene::check_triangle_count(
                        self.path,
                        (self.scene.len() + added) as u64,
                    )?;
                    for p in prims.iter() {
                        match &p.uv {
                            None => {
                                self.scene
                                    .push_indexed(&p.positions, &p.tris, world, p.material)
                            }
                            Some(uv) => {
                                for t in &p.tris {
                                    let v =
                                        t.map(|i| world.transform_point3(p.positions[i as usize]));
                                    self.scene.push_textured(
                                        v,
                                        t.map(|i| uv[i as usize]),
                                        p.material,
                                    );
                                }
                            }
                        }
                    }
                }
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for c in children.into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }
        Ok(planned)
    }
}
