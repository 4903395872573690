//! The shadow query of adaptive shadow maps (Fernando et al. 2001, Sections 4.2 and 4.3):
//! each receiver descends from its view's root to the deepest node covering it, starting
//! from "a cache storing the most recently queried leaf node", and is tested there with
//! the combination of per-polygon ids and depth comparisons: lit when the texel holds the
//! receiver's own triangle, else lit when the receiver's depth less a bias of the leaf's
//! texel size is not behind the texel's depth.

use super::params::Params;
use super::tree::{Face, Node, Tree, NO_NODE};
use crate::frame::Frame;
use crate::math::Vec3;
use crate::techniques::shadow_map::receiver_bias;
use rayon::prelude::*;

impl Node {
    /// The combined id and depth test of Section 4.2 at one texel.
    #[inline]
    pub(super) fn lit(&self, tx: u32, ty: u32, own: u32, biased_depth: f32) -> bool {
        let k = (ty * self.res + tx) as usize;
        self.id[k] == own || biased_depth <= self.depth[k]
    }
}

impl Tree {
    /// The depth bias of a receiver at `level`, in world units.
    #[inline]
    pub(super) fn bias(
        &self,
        face: &Face,
        level: u8,
        depth: f32,
        n: Vec3,
        l: Vec3,
        p: &Params,
    ) -> f32 {
        let e = self.scale(face, level) as u32;
        receiver_bias(face.view.texel_size(e, depth), n, l, p.bias, p.slope_bias)
    }

    /// Section 4.2's shadow test for every pixel; returns the visibility and the leaves
    /// each row used.
    pub(super) fn lookup(&self, frame: &Frame, p: &Params) -> (Vec<Vec3>, Vec<u32>) {
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let rows: Vec<(Vec<Vec3>, Vec<u32>)> = (0..h)
            .into_par_iter()
            .map(|y| self.lookup_row(frame, p, y))
            .collect();
        let mut value = Vec::with_capacity((w * h) as usize);
        let mut used = Vec::new();
        for (v, u) in rows {
            value.extend(v);
            used.extend(u);
        }
        (value, used)
    }

    /// The shadow test for the pixels of row `y`, and the leaves it used.
    fn lookup_row(&self, frame: &Frame, p: &Params, y: u32) -> (Vec<Vec3>, Vec<u32>) {
        let view = frame.view;
        let w = view.width;
        let mut vals = Vec::with_capacity(w as usize);
        let mut used: Vec<u32> = Vec::new();
        // The last leaf found (Section 4.3): most neighbours fall in it too.
        let mut cache: Option<(usize, u32)> = None;
        for x in 0..w {
            let k = (y * w + x) as usize;
            if let Some(v) = frame.unreached(k) {
                vals.push(v);
                continue;
            }
            let pos = view.position[k];
            let f = self.face_of(frame.light, pos);
            let face = self.faces[f]
                .as_ref()
                .expect("roots made for every receiver");
            let (u, v, depth) = face.project(pos);
            let leaf = match cache.filter(|&(cf, s)| cf == f && self.is_leaf_at(face, s, u, v)) {
                Some((_, s)) => s,
                None => self.locate(face, u, v),
            };
            cache = Some((f, leaf));
            if used.last() != Some(&leaf) {
                used.push(leaf);
            }
            let n = self.node(leaf);
            let (lx, ly) = n.local(u, v, self.scale(face, n.level));
            let (tx, ty) = n.texel(lx, ly);
            let (l, _) = frame.light.shadow_ray(pos);
            let d = depth - self.bias(face, n.level, depth, view.normal[k], l, p);
            vals.push(if n.lit(tx, ty, view.triangle[k], d) {
                Vec3::ONE
            } else {
                Vec3::ZERO
            });
        }
        (vals, used)
    }

    /// Marks the leaves that the look-ups `used` (and their ancestors) as used in frame
    /// `now`; returns the finest effective resolution among them.
    pub(super) fn mark_used(&mut self, used: Vec<u32>, now: u64) -> f64 {
        let mut used_finest = 0f64;
        for s in used {
            self.touch(s, now);
            let n = self.node(s);
            used_finest = used_finest.max(self.scale(self.face(n), n.level));
        }
        used_finest
    }

    /// True when node `s` of `face` covers `(u, v)` with no child there: the answer
    /// [`Tree::locate`] would give.
    #[inline]
    fn is_leaf_at(&self, face: &Face, s: u32, u: f64, v: f64) -> bool {
        let n = self.node(s);
        let (lx, ly) = n.local(u, v, self.scale(face, n.level));
        n.contains(lx, ly) && n.children[n.cell(lx, ly) as usize] == NO_NODE
    }
}
