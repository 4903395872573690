//! The benefit side of adaptive shadow maps' cost-benefit analysis (Fernando et al. 2001,
//! Sections 3.1, 4.1 and 4.3): "the number of transformed eye pixels within the cell that
//! straddle a depth discontinuity and whose shadow map resolution is lower than the eye
//! view resolution", counted on "a fraction of the transformed pixels" per frame. The
//! projected pixel area that the paper estimates by mip-mapping (Section 4.1) comes here
//! from the camera pass's screen-space derivatives projected into the light view.

use super::params::Params;
use super::tree::{floor_i64, uv_of, Node, Tree, NO_NODE};
use crate::frame::Frame;
use crate::math::Vec3;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Analysed pixels per parallel work item.
const ANALYSIS_CHUNK: usize = 1024;
/// Columns by which the analysed pattern shifts from one row to the next, spreading a
/// frame's share evenly over the image.
const ROW_SHIFT: u64 = 3;

/// What the analysis found at one analysed pixel.
#[derive(Clone, Copy, Debug)]
pub(super) struct Probe {
    /// The pixel.
    pub(super) pixel: u32,
    /// The deepest node covering the pixel.
    pub(super) leaf: u32,
    /// The cell of `leaf` the pixel falls in.
    pub(super) cell: u32,
    /// Mismatched and straddling at the leaf's resolution: a vote for refining the cell.
    pub(super) candidate: bool,
    /// Mismatched and straddling at the parent's resolution: the leaf resolves it.
    pub(super) serves: bool,
}

impl Node {
    /// True when the 2×2 texels whose centres surround the local position `(lx, ly)` do
    /// not agree on the shadow test: a shadow boundary passes within a texel of the
    /// point, so finer texels would place it more exactly.
    fn straddles(&self, lx: f64, ly: f64, own: u32, biased_depth: f32) -> bool {
        let m = self.res as i64 - 1;
        let x0 = floor_i64(lx - 0.5).clamp(0, m) as u32;
        let y0 = floor_i64(ly - 0.5).clamp(0, m) as u32;
        let x1 = (x0 + 1).min(m as u32);
        let y1 = (y0 + 1).min(m as u32);
        let a = self.lit(x0, y0, own, biased_depth);
        a != self.lit(x1, y0, own, biased_depth)
            || a != self.lit(x0, y1, own, biased_depth)
            || a != self.lit(x1, y1, own, biased_depth)
    }
}

/// The benefit of each candidate cell, keyed by node and cell: the probes that vote for
/// refining it.
pub(super) fn cell_benefits(probes: &[Probe]) -> BTreeMap<(u32, u32), u32> {
    let mut cells: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for pr in probes.iter().filter(|pr| pr.candidate) {
        *cells.entry((pr.leaf, pr.cell)).or_default() += 1;
    }
    cells
}

impl Tree {
    /// The pixels analysed in frame `now`: a rotating share of the receivers, so that a
    /// still view has every pixel analysed once per period. Returns them and the period.
    pub(super) fn analysis_pixels(frame: &Frame, p: &Params, now: u64) -> (Vec<u32>, u64) {
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let period = (1.0 / p.analysis_fraction).round().max(1.0) as u64;
        let phase = now % period;
        let rows: Vec<Vec<u32>> = (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .filter(|&x| (x as u64 + ROW_SHIFT * y as u64 + phase) % period < 1)
                    .map(|x| y * w + x)
                    .filter(|&k| frame.receiver_lit(k as usize))
                    .collect()
            })
            .collect();
        (rows.concat(), period)
    }

    /// Section 3.1's analysis of `pixels`: for each, the deepest node and cell it falls in,
    /// whether it votes for refining that cell, and whether the node resolves it.
    pub(super) fn analyse(&self, frame: &Frame, p: &Params, pixels: &[u32]) -> Vec<Probe> {
        let k2 = (p.oversampling as f64).powi(2);
        let chunks: Vec<Vec<Probe>> = pixels
            .par_chunks(ANALYSIS_CHUNK)
            .map(|chunk| {
                chunk
                    .iter()
                    .map(|&k| self.probe(frame, p, k2, k as usize))
                    .collect()
            })
            .collect();
        chunks.concat()
    }

    /// The analysis of pixel `k`; `k2` is the number of texels a pixel's footprint should
    /// cover (`oversampling²`).
    #[inline]
    fn probe(&self, frame: &Frame, p: &Params, k2: f64, k: usize) -> Probe {
        let view = frame.view;
        let pos = view.position[k];
        let face = self.faces[self.face_of(frame.light, pos)]
            .as_ref()
            .expect("roots made for every receiver");
        let (u, v, depth) = face.project(pos);
        // The pixel's footprint in root-view coordinates, from the derivatives.
        let at = |d: Vec3| uv_of(face.clip_from_world * (pos + d).as_dvec3().extend(1.0));
        let (ux, vx) = at(view.dpdx[k]);
        let (uy, vy) = at(view.dpdy[k]);
        let area = ((ux - u) * (vy - v) - (uy - u) * (vx - v)).abs();
        let leaf = self.locate(face, u, v);
        let node = self.node(leaf);
        let scale = self.scale(face, node.level);
        let (lx, ly) = node.local(u, v, scale);
        let mut probe = Probe {
            pixel: k as u32,
            leaf,
            cell: node.cell(lx, ly),
            candidate: false,
            serves: false,
        };
        if !(area > 0.0 && area.is_finite()) {
            // No footprint where the neighbouring rays miss the plane.
            return probe;
        }
        let own = view.triangle[k];
        let nrm = view.normal[k];
        let (l, _) = frame.light.shadow_ray(pos);
        // Mismatched: the pixel covers fewer than oversampling² texels.
        if area * scale * scale < k2 && node.level < self.max_level(face) {
            let d = depth - self.bias(face, node.level, depth, nrm, l, p);
            probe.candidate = node.straddles(lx, ly, own, d);
        }
        if node.level > 0 {
            let parent = self.node(node.parent);
            let ps = scale / self.refine as f64;
            if area * ps * ps < k2 {
                let (plx, ply) = parent.local(u, v, ps);
                let d = depth - self.bias(face, parent.level, depth, nrm, l, p);
                probe.serves = parent.straddles(plx, ply, own, d);
            }
        }
        probe
    }

    /// Each leaf's benefit: the analysed mismatches it resolves (the `probes` it serves),
    /// averaged over an analysis `period`. Then marks the analysed leaves used in `now`.
    pub(super) fn update_benefits(&mut self, probes: &[Probe], period: u64, now: u64) {
        let mut served = vec![0u32; self.nodes.len()];
        for pr in probes.iter().filter(|pr| pr.serves) {
            served[pr.leaf as usize] += 1;
        }
        for (n, &c) in self.nodes.iter_mut().zip(&served) {
            if let Some(n) = n {
                n.benefit += (c as f32 - n.benefit) / period as f32;
            }
        }
        let mut last = NO_NODE;
        for pr in probes {
            if pr.leaf != last {
                self.touch(pr.leaf, now);
                last = pr.leaf;
            }
        }
    }
}
