//! The roots of adaptive shadow maps (Fernando et al. 2001, Sections 3 and 5): each light
//! view gets a root node covering its whole frustum at the starting resolution, made for
//! the views that visible receivers fall in, with its top-level culling lists
//! ([`super::culling`]). Roots are never evicted; a budget too small for them is an error.

use super::node_creation::render_tile;
use super::params::{Params, MIB};
use super::tree::{Face, Node, RootTile, Square, Tree};
use crate::error::{Error, Result};
use crate::frame::Frame;
use rayon::prelude::*;

/// The root-view square of a whole view.
const WHOLE_VIEW: Square = Square {
    u0: 0.0,
    v0: 0.0,
    size: 1.0,
};

impl Tree {
    /// Makes the roots of the views that `frame`'s receivers fall in.
    pub(super) fn ensure_roots(&mut self, frame: &Frame, p: &Params, now: u64) -> Result<()> {
        let needed = self.needed_views(frame);
        let budget = p.budget_bytes();
        let res = p.face_resolution(self.views.len());
        for f in 0..self.views.len() {
            if needed & (1 << f) == 0 || self.faces[f].is_some() {
                continue;
            }
            let grid = res / (self.tile / self.refine);
            let mut face = Face::new(frame.scene, self.views[f], res, grid);
            let need = Node::bytes(res, face.grid);
            if !self.make_room(need, budget, now, None, f32::INFINITY).1 {
                let faces = needed.count_ones();
                return Err(Error::Limit(format!(
                    "asm.budget-mb = {} cannot hold the root maps: {faces} light view(s) of {res}² texels \
                     need {:.2} MiB; raise asm.budget-mb or lower asm.root-resolution",
                    p.budget_mb,
                    (self.bytes + need) as f64 / MIB
                )));
            }
            let (depth, id) = render_tile(frame.scene, &face, WHOLE_VIEW, res);
            face.root = self.add_root(f as u8, face.grid, now, RootTile { res, depth, id });
            self.faces[f] = Some(face);
        }
        // A budget lowered since the last frame takes effect at once.
        if !self.make_room(0, budget, now, None, f32::INFINITY).1 {
            return Err(Error::Limit(format!(
                "asm.budget-mb = {} cannot hold the root maps ({:.2} MiB); raise asm.budget-mb \
                 or lower asm.root-resolution",
                p.budget_mb,
                self.bytes as f64 / MIB
            )));
        }
        Ok(())
    }

    /// The views (one bit each) that `frame`'s lit receivers fall in: the only view of a
    /// single-view light, and none to look for when every view has its root already.
    fn needed_views(&self, frame: &Frame) -> u32 {
        let view = frame.view;
        let n = (view.width * view.height) as usize;
        if self.views.len() == 1 {
            1
        } else if self.faces.iter().all(Option::is_some) {
            0
        } else {
            (0..n)
                .into_par_iter()
                .with_min_len(4096)
                .map(|k| {
                    if frame.receiver_lit(k) {
                        1u32 << self.face_of(frame.light, view.position[k])
                    } else {
                        0
                    }
                })
                .reduce(|| 0, |a, b| a | b)
        }
    }
}
