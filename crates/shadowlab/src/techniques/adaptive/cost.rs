//! The cost-benefit metric of adaptive shadow maps (Fernando et al. 2001, Section 3.1):
//! the cost of a new node, `cost = a·N_required + b` for its `N` texels, with `a` and `b`
//! fixed nominal units or, as the paper's "calibration test as a preprocess", measured by
//! timing tile renders of the scene; and the candidate cells "sorted according to this
//! ratio" of benefit over cost.

use super::node_creation::render_tile;
use super::params::Params;
use super::tree::{Square, Tree};
use crate::raster;
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::time::Instant;

/// Timed repetitions per calibration tile; the median is kept.
const CALIBRATION_REPEATS: usize = 3;
/// Root cells timed by the calibration (the most populated ones, so the estimate errs on
/// the slow side and the time budget is rarely overrun).
const CALIBRATION_CELLS: usize = 4;
/// The smallest cost the ranking divides by, in milliseconds: keeps the benefit/cost
/// ratio finite when both cost terms are 0 (then every candidate ties on the ratio and
/// the ranking falls back to benefit).
const MIN_COST_MS: f64 = 1e-12;

/// The calibrated cost of rendering a tile: `a·N + b` milliseconds for `N` texels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct CostModel {
    /// Milliseconds per texel.
    pub(super) a: f64,
    /// Milliseconds per tile.
    pub(super) b: f64,
}

impl CostModel {
    /// The model of a free tile: the cost of a frame without a time budget.
    pub(super) const FREE: CostModel = CostModel { a: 0.0, b: 0.0 };

    fn predict(&self, texels: u64) -> f64 {
        self.a * texels as f64 + self.b
    }
}

/// A cell that could receive a node this frame.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub(super) node: u32,
    pub(super) serial: u64,
    pub(super) cell: u32,
    pub(super) benefit: u32,
    pub(super) cost_ms: f64,
}

impl Tree {
    /// The candidate `cells` (keyed by node and cell, with their benefits), each costing a
    /// `tile²`-texel node, by decreasing benefit over cost.
    pub(super) fn ranked_candidates(
        &self,
        cells: &BTreeMap<(u32, u32), u32>,
        cost: CostModel,
        tile: u32,
    ) -> Vec<Candidate> {
        let texels = tile as u64 * tile as u64;
        let mut candidates: Vec<Candidate> = cells
            .iter()
            .map(|(&(node, cell), &benefit)| Candidate {
                node,
                serial: self.node(node).serial,
                cell,
                benefit,
                cost_ms: cost.predict(texels),
            })
            .collect();
        candidates.sort_by(|a, b| {
            let ra = a.benefit as f64 / a.cost_ms.max(MIN_COST_MS);
            let rb = b.benefit as f64 / b.cost_ms.max(MIN_COST_MS);
            rb.total_cmp(&ra)
                .then(b.benefit.cmp(&a.benefit))
                .then(a.node.cmp(&b.node))
                .then(a.cell.cmp(&b.cell))
        });
        candidates
    }
}

/// The cost model of `p`: its fixed terms, with those set to `auto` taken from the
/// calibration of `tree`'s scene (`measured`, made on first use).
pub(super) fn cost_model(
    p: &Params,
    measured: &mut Option<CostModel>,
    scene: &Scene,
    tree: &Tree,
) -> CostModel {
    if let (Some(a), Some(b)) = (p.cost_per_texel_ns, p.cost_per_tile_ms) {
        return CostModel { a: a * 1e-6, b };
    }
    let measured = *measured.get_or_insert_with(|| calibrate(scene, tree));
    CostModel {
        a: p.cost_per_texel_ns.map_or(measured.a, |a| a * 1e-6),
        b: p.cost_per_tile_ms.unwrap_or(measured.b),
    }
}

/// Times tile renders of the busiest root cells of the first root at two resolutions and
/// fits `a·N + b`.
fn calibrate(scene: &Scene, tree: &Tree) -> CostModel {
    let Some(face) = tree.faces.iter().flatten().next() else {
        return CostModel::FREE;
    };
    let mut cells: Vec<(usize, usize)> = face
        .bins
        .iter()
        .enumerate()
        .map(|(i, b)| (b.len(), i))
        .collect();
    cells.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let g = face.grid as usize;
    let small = (tree.tile / 2).max(8);
    let large = (tree.tile * 2).min(raster::MAX_RASTER_SIDE);
    let time = |res: u32| {
        let mut t = Vec::new();
        for &(_, i) in cells.iter().take(CALIBRATION_CELLS) {
            let (gx, gy) = ((i % g) as f64, (i / g) as f64);
            let square = Square {
                u0: gx / g as f64,
                v0: gy / g as f64,
                size: 1.0 / g as f64,
            };
            for _ in 0..CALIBRATION_REPEATS {
                let t0 = Instant::now();
                std::hint::black_box(render_tile(scene, face, square, res));
                t.push(t0.elapsed().as_secs_f64() * 1e3);
            }
        }
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    let (t1, t2) = (time(small), time(large));
    let (n1, n2) = ((small as f64).powi(2), (large as f64).powi(2));
    let a = ((t2 - t1) / (n2 - n1)).max(0.0);
    CostModel {
        a,
        b: (t1 - a * n1).max(0.0),
    }
}
