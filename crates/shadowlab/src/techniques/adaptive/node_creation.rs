//! Creating nodes (Fernando et al. 2001, Section 3.1): "new shadow map nodes are only
//! generated for the most profitable cells from this list until a given time limit has
//! passed." The candidate cells, ranked by benefit over cost ([`super::cost`]), receive
//! child nodes while the predicted time and the node cap allow, evicting within the memory
//! budget ([`super::node_removal`]); the new tiles are then rendered together. Up to
//! `passes` such passes run per frame, each analysing again the pixels whose cells were
//! just refined.

use super::analysis::{cell_benefits, Probe};
use super::cost::{Candidate, CostModel};
use super::culling::tile_triangles;
use super::params::Params;
use super::tree::{Face, Node, Square, Tree, NO_NODE};
use crate::frame::Frame;
use crate::math::Mat4;
use crate::raster;
use crate::raster::NO_TRIANGLE;
use crate::scene::Scene;
use glam::{DMat4, DVec4};
use rayon::prelude::*;
use std::collections::BTreeSet;
use std::time::Instant;

/// What the refinement passes of one frame have used of their budgets.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RefineBudget {
    pub(super) made: u64,
    pub(super) evicted: u64,
    pub(super) spent_ms: f64,
}

/// What the refinement passes of one frame did.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Refinement {
    /// Nodes made and evicted, and their predicted cost.
    pub(super) budget: RefineBudget,
    /// Cells that the first pass's analysis voted for.
    pub(super) candidate_cells: usize,
    /// Passes run.
    pub(super) passes: u32,
    /// Wall time of the analyses after the first, in milliseconds.
    pub(super) analysis_ms: f64,
    /// Wall time of the passes, in milliseconds.
    pub(super) refine_ms: f64,
}

/// The clip-space scale and translation that maps the root-view square onto the whole
/// target.
fn tile_from_root(square: Square) -> DMat4 {
    let Square { u0, v0, size } = square;
    let s = 1.0 / size;
    let cx = 2.0 * (u0 + 0.5 * size) - 1.0;
    let cy = 1.0 - 2.0 * (v0 + 0.5 * size);
    DMat4::from_cols(
        DVec4::new(s, 0.0, 0.0, 0.0),
        DVec4::new(0.0, s, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 1.0, 0.0),
        DVec4::new(-s * cx, -s * cy, 0.0, 1.0),
    )
}

/// Renders `square` of `face` into a `res × res` tile of linear depths and triangle ids,
/// with only the triangles whose projection overlaps it.
pub(super) fn render_tile(
    scene: &Scene,
    face: &Face,
    square: Square,
    res: u32,
) -> (Vec<f32>, Vec<u32>) {
    let m = face.view.clip_from_world;
    let selection = tile_triangles(scene, face, square, res);
    let clip_from_world: Mat4 = (tile_from_root(square) * m.as_dmat4()).as_mat4();
    let light_from_world = face.view.light_from_world;
    let setups = raster::setup(selection.len(), res, res, |i| {
        let t = scene.triangle(selection[i] as usize);
        (
            t.map(|p| clip_from_world * p.extend(1.0)),
            t.map(|p| -light_from_world.transform_point3(p).z),
        )
    });
    let masked = scene.has_alpha_masks();
    let buf = raster::depth_buffer_where(&setups, res, res, |f| {
        !masked || !scene.cut_out(selection[f.id as usize] as usize, f.bary())
    });
    let id = buf
        .id
        .into_iter()
        .map(|i| {
            if i == NO_TRIANGLE {
                i
            } else {
                selection[i as usize]
            }
        })
        .collect();
    (buf.depth, id)
}

impl Tree {
    /// Refinement passes over the analysed `probes` of frame `now`: the most profitable
    /// cells first, within the time and memory budgets; after each pass the pixels whose
    /// cells were refined are analysed again in the new nodes.
    pub(super) fn refine_passes(
        &mut self,
        frame: &Frame,
        p: &Params,
        cost: CostModel,
        mut probes: Vec<Probe>,
        now: u64,
    ) -> Refinement {
        let mut r = Refinement::default();
        while r.passes < p.passes {
            let cells = cell_benefits(&probes);
            if r.passes == 0 {
                r.candidate_cells = cells.len();
            }
            if cells.is_empty() {
                break;
            }
            let t0 = Instant::now();
            let candidates = self.ranked_candidates(&cells, cost, p.tile_resolution);
            let made = self.refine(frame.scene, p, candidates, now, &mut r.budget);
            r.refine_ms += t0.elapsed().as_secs_f64() * 1e3;
            r.passes += 1;
            if made.is_empty() || r.passes == p.passes {
                break;
            }
            let t0 = Instant::now();
            let refined: BTreeSet<(u32, u32)> = made
                .iter()
                .map(|&s| {
                    let n = self.node(s);
                    (n.parent, n.parent_cell)
                })
                .collect();
            let again: Vec<u32> = probes
                .iter()
                .filter(|pr| pr.candidate && refined.contains(&(pr.leaf, pr.cell)))
                .map(|pr| pr.pixel)
                .collect();
            probes = self.analyse(frame, p, &again);
            r.analysis_ms += t0.elapsed().as_secs_f64() * 1e3;
        }
        r
    }

    /// One refinement pass over the ranked `candidates`: takes them in order while `budget`
    /// allows, evicting to stay within the memory budget, and renders the new tiles
    /// together. Returns the new nodes.
    fn refine(
        &mut self,
        scene: &Scene,
        p: &Params,
        candidates: Vec<Candidate>,
        now: u64,
        budget: &mut RefineBudget,
    ) -> Vec<u32> {
        let bytes_budget = p.budget_bytes();
        let need = Node::bytes(p.tile_resolution, p.cells);
        let mut pending: Vec<u32> = Vec::new();
        for c in candidates {
            if budget.made >= p.max_new_nodes as u64 {
                break;
            }
            if p.time_budget_ms
                .is_some_and(|b| budget.spent_ms + c.cost_ms > b)
            {
                break;
            }
            // The cell's node may have been evicted for an earlier candidate.
            let alive = self.nodes[c.node as usize]
                .as_ref()
                .is_some_and(|n| n.serial == c.serial && n.children[c.cell as usize] == NO_NODE);
            if !alive {
                continue;
            }
            let (evicted, fits) =
                self.make_room(need, bytes_budget, now, Some(c.node), c.benefit as f32);
            budget.evicted += evicted;
            if !fits {
                // Every later candidate has no greater benefit and the same size.
                break;
            }
            pending.push(self.add_child(c.node, c.cell, now, c.benefit as f32));
            budget.made += 1;
            budget.spent_ms += c.cost_ms;
        }
        self.render_new(scene, &pending, p.tile_resolution);
        pending
    }

    /// Renders the tiles of the new nodes `pending`, `res²` texels each, together.
    fn render_new(&mut self, scene: &Scene, pending: &[u32], res: u32) {
        let jobs: Vec<(&Face, Square)> = pending
            .iter()
            .map(|&s| {
                let n = self.node(s);
                (self.face(n), self.square(n))
            })
            .collect();
        let tiles: Vec<(Vec<f32>, Vec<u32>)> = jobs
            .par_iter()
            .map(|&(face, square)| render_tile(scene, face, square, res))
            .collect();
        for (&s, (depth, id)) in pending.iter().zip(tiles) {
            let n = self.node_mut(s);
            n.depth = depth;
            n.id = id;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_scenes::{face, small_scene};
    use super::*;
    use crate::light::Light;
    use crate::math::{vec3, Vec3};
    use crate::techniques::shadow_map::render_depth_map;

    #[test]
    fn tiles_match_the_flat_map_of_their_level() {
        let scene = small_scene();
        for light in [
            Light::Directional {
                to_light: vec3(-0.3, 1.0, 0.2).normalize(),
            },
            Light::Spot {
                position: vec3(0.5, 6.0, 0.3),
                target: Vec3::ZERO,
                fov_deg: 100.0,
            },
        ] {
            let f = face(&scene, &light, 64, 32, 4);
            // Levels 1 and 2: effective resolutions 256 and 1024.
            for (e, x0, y0) in [(256u32, 96u32, 160u32), (256, 0, 224), (1024, 416, 512)] {
                let flat = render_depth_map(&scene, &f.view, e);
                let square = Square {
                    u0: x0 as f64 / e as f64,
                    v0: y0 as f64 / e as f64,
                    size: 32.0 / e as f64,
                };
                let (depth, id) = render_tile(&scene, &f, square, 32);
                let mut differ = 0;
                for y in 0..32 {
                    for x in 0..32 {
                        let k = (y * 32 + x) as usize;
                        let fk = ((y0 + y) * e + x0 + x) as usize;
                        if id[k] != flat.id[fk] {
                            differ += 1;
                        } else if id[k] != NO_TRIANGLE {
                            let tol = 1e-4 * flat.depth[fk].abs().max(1.0);
                            assert!(
                                (depth[k] - flat.depth[fk]).abs() <= tol,
                                "{light:?} level {e} texel {x},{y}"
                            );
                        }
                    }
                }
                // Snapping to 1/256 texel from different origins may move a texel centre
                // lying exactly on an edge to the neighbouring triangle, nothing more.
                assert!(
                    differ <= 4,
                    "{light:?}: {differ} of 1024 texels differ at {e} ({x0},{y0})"
                );
            }
        }
    }
}
