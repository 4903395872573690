//! glTF meshes: each primitive's positions and indices decoded and assembled into
//! triangles (lists, strips and fans), the modes that make none skipped.

use super::{Loader, ModeName, Skip};
use crate::error::Result;
use crate::math::{vec2, vec3, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::rc::Rc;

/// One decoded primitive, in mesh space.
pub(super) struct Primitive {
    pub(super) positions: Vec<Vec3>,
    pub(super) tris: Vec<[u32; 3]>,
    pub(super) material: u32,
    /// Texture coordinates per vertex, read for alpha-masked materials only.
    pub(super) uv: Option<Vec<Vec2>>,
}

impl Loader<'_> {
    /// The decoded primitives of `mesh`, decoding them on first use.
    pub(super) fn mesh(&mut self, mesh: &gltf::Mesh) -> Result<Rc<Vec<Primitive>>> {
        if let Some(m) = &self.meshes[mesh.index()] {
            return Ok(m.clone());
        }
        let label = match mesh.name() {
            Some(n) => format!("mesh {} ({n:?})", mesh.index()),
            None => format!("mesh {}", mesh.index()),
        };
        let mut prims = Vec::new();
        for prim in mesh.primitives() {
            let at = format!("{label}, primitive {}", prim.index());
            let mode = prim.mode();
            let skip = match mode {
                Mode::Points => Some(ModeName::Points),
                Mode::Lines => Some(ModeName::Lines),
                Mode::LineLoop => Some(ModeName::LineLoop),
                Mode::LineStrip => Some(ModeName::LineStrip),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => None,
            };
            if let Some(m) = skip {
                *self.skipped.entry(Skip::Mode(m)).or_default() += 1;
                continue;
            }
            let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
                *self.skipped.entry(Skip::NoPositions).or_default() += 1;
                continue;
            };
            if prim.morph_targets().next().is_some() {
                *self.skipped.entry(Skip::MorphTargets).or_default() += 1;
            }
            if pos.dimensions() != Dimensions::Vec3 {
                return Err(self.err(format!(
                    "{at}: POSITION accessor {} is not VEC3",
                    pos.index()
                )));
            }
            let raw = self.read_accessor(&pos, &at)?;
            let mut positions = Vec::with_capacity(raw.len() / 3);
            for (v, c) in raw.chunks_exact(3).enumerate() {
                let p = vec3(c[0] as f32, c[1] as f32, c[2] as f32);
                if !p.is_finite() {
                    return Err(self.err(format!("{at}: vertex {v} has a non-finite position")));
                }
                positions.push(p);
            }
            let indices: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    if acc.dimensions() != Dimensions::Scalar
                        || !matches!(
                            acc.data_type(),
                            DataType::U8 | DataType::U16 | DataType::U32
                        )
                    {
                        return Err(self.err(format!(
                            "{at}: index accessor {} is not a scalar of unsigned integers",
                            acc.index()
                        )));
                    }
                    let raw = self.read_accessor(&acc, &at)?;
                    let n = positions.len();
                    let mut out = Vec::with_capacity(raw.len());
                    for (k, &i) in raw.iter().enumerate() {
                        if i >= n as f64 {
                            return Err(self.err(format!(
                                "{at}: index {k} (accessor {}) is out of range for the {n} vertices of POSITION",
                                acc.index()
                            )));
                        }
                        out.push(i as u32);
                    }
                    out
                }
                None => {
                    if positions.len() > u32::MAX as usize {
                        return Err(self.err(format!("{at}: too many vertices")));
                    }
                    (0..positions.len() as u32).collect()
                }
            };
            let tris = match assemble(mode, &indices) {
                Some(t) => t,
                None => {
                    return Err(self.err(format!(
                        "{at}: {} indices do not make whole triangles (TRIANGLES needs a multiple of 3)",
                        indices.len()
                    )))
                }
            };
            let material = self.material(prim.material())?;
            let uv = if self.scene.materials[material as usize].alpha_mask.is_some() {
                Some(self.tex_coords(&prim, positions.len(), &at)?)
            } else {
                None
            };
            prims.push(Primitive {
                positions,
                tris,
                material,
                uv,
            });
        }
        let prims = Rc::new(prims);
        self.meshes[mesh.index()] = Some(prims.clone());
        Ok(prims)
    }
}

impl Loader<'_> {
    /// The texture coordinates of an alpha-masked primitive's `n` vertices, from the set
    /// its base colour texture names (`TEXCOORD_0` by default); without that attribute
    /// every vertex reads the texture at (0, 0), and the warnings say so.
    fn tex_coords(&mut self, prim: &gltf::Primitive, n: usize, at: &str) -> Result<Vec<Vec2>> {
        let set = prim
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
            .map_or(0, |t| t.tex_coord());
        let Some(acc) = prim.get(&gltf::Semantic::TexCoords(set)) else {
            *self.skipped.entry(Skip::NoTexCoords).or_default() += 1;
            return Ok(vec![Vec2::ZERO; n]);
        };
        if acc.dimensions() != Dimensions::Vec2 || acc.count() != n {
            return Err(self.err(format!(
                "{at}: TEXCOORD_{set} accessor {} is not VEC2 with one element per vertex",
                acc.index()
            )));
        }
        let raw = self.read_accessor(&acc, at)?;
        let uv: Vec<Vec2> = raw
            .chunks_exact(2)
            .map(|c| vec2(c[0] as f32, c[1] as f32))
            .collect();
        if let Some(v) = uv.iter().position(|t| !t.is_finite()) {
            return Err(self.err(format!("{at}: vertex {v} has a non-finite TEXCOORD_{set}")));
        }
        Ok(uv)
    }
}

/// The triangles `mesh` adds per instance, from its accessors' counts alone.
pub(super) fn mesh_triangles(mesh: &gltf::Mesh) -> u64 {
    let mut n = 0u64;
    for prim in mesh.primitives() {
        let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
            continue;
        };
        let k = prim.indices().map_or(pos.count(), |a| a.count()) as u64;
        n = n.saturating_add(match prim.mode() {
            Mode::Triangles => k / 3,
            Mode::TriangleStrip | Mode::TriangleFan => k.saturating_sub(2),
            _ => 0,
        });
    }
    n
}

/// Triangles from a primitive's vertex list: `None` when a `TRIANGLES` list is not a
/// whole number of triangles. Strips alternate their winding so every triangle keeps the
/// orientation of the first.
fn assemble(mode: Mode, idx: &[u32]) -> Option<Vec<[u32; 3]>> {
    let n = idx.len();
    match mode {
        Mode::Triangles => {
            let chunks = idx.chunks_exact(3);
            if !chunks.remainder().is_empty() {
                return None;
            }
            Some(chunks.map(|c| [c[0], c[1], c[2]]).collect())
        }
        Mode::TriangleStrip => Some(
            (0..n.saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [idx[i], idx[i + 1], idx[i + 2]]
                    } else {
                        [idx[i + 1], idx[i], idx[i + 2]]
                    }
                })
                .collect(),
        ),
        Mode::TriangleFan => Some(
            (1..n.saturating_sub(1))
                .map(|i| [idx[0], idx[i], idx[i + 1]])
                .collect(),
        ),
        _ => Some(Vec::new()),
    }
}
