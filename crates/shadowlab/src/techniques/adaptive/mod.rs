//! `asm`: adaptive shadow maps (Fernando, Fernandez, Bala and Greenberg, "Adaptive Shadow
//! Maps", SIGGRAPH 2001).
//!
//! The light's view is a tree of fixed-resolution depth tiles instead of one flat map: each
//! node's tile is partitioned into cells, and a cell gets a child node (`cells` times finer)
//! where eye pixels that straddle a shadow boundary see texels larger than themselves.
//! Cells are refined in order of benefit over cost until a per-frame time budget is spent,
//! and the tree lives within a memory budget by evicting least recently used nodes, so
//! quality improves progressively over the frames of a still or slowly moving view.
//!
//! # The algorithm, per frame
//! 1. **Roots.** Each light view gets a root node covering its whole frustum at
//!    `root-resolution` (one view for directional and spot lights; for a point light six
//!    cube faces at `root-resolution / 2` each, so that a face texel subtends about the same
//!    angle as a 512² map over the paper's 122° light frustum). Roots are made for the views
//!    that visible receivers fall in, with the paper's top-level frustum culling: one
//!    triangle list per root cell.
//! 2. **Cost-benefit analysis** (Section 3.1) of a share `analysis-fraction` of the eye
//!    pixels (1/8 as in the paper; the share rotates from frame to frame, so a still view
//!    has every pixel analysed once in eight frames). For each, the deepest node covering
//!    it is found and its projected eye-pixel area measured in that node's texels. A pixel
//!    is *resolution-mismatched* when it covers fewer than `oversampling²` texels, and it
//!    *straddles a depth discontinuity* when the 2×2 texels whose centres surround it do
//!    not agree on its shadow test. The benefit of a cell is the number of such pixels in
//!    it; the cost of a new node is `a·N + b` for its `N` texels, with `a` and `b` fixed
//!    nominal units by default (so the result does not depend on the machine), or with
//!    `auto` calibrated at start-up by timing tile renders of the scene on this machine.
//! 3. **Refinement** (Sections 3.1, 3.2): cells are taken by decreasing benefit/cost while
//!    the predicted time fits `time-budget-ms` and at most `max-new-nodes` are made. When
//!    a node would exceed `budget-mb`, a leaf not used in the last frame is evicted, least
//!    recently used first; if every leaf is in use, the leaf with the smallest benefit (the
//!    analysed mismatched boundary pixels it resolves, averaged over the frames of one
//!    analysis period) is replaced only by a cell of greater benefit. New tiles are
//!    rendered in parallel through the shared rasterizer, each with a `clip_from_world`
//!    that maps its square of the root view onto the whole tile, fed only the triangles
//!    whose projection overlaps it.
//! 4. **Queries** descend from the root to the deepest node covering the receiver, starting
//!    from the last leaf found (Section 4.3's cache). The shadow test is Section 4.2's: lit
//!    when the texel holds the receiver's own triangle (the id test), else lit when the
//!    receiver's depth less a bias of the leaf's texel size is not behind the texel's depth.
//!
//! # Invariants
//! - The tree (every node's depth and id tiles and child tables) never holds more than
//!   `budget-mb`; [`ShadowTechnique::render`] fails with [`Error::Limit`](crate::error::Error::Limit) rather than
//!   exceed it when the roots alone do not fit. The per-root-cell triangle lists (4 bytes
//!   per triangle and root cell it overlaps) are counted in `memory_bytes` beside it.
//! - A child node covers exactly one cell of its parent with `cells` times its texel
//!   density; the texel centres of every level coincide with those of a flat map of the
//!   level's effective resolution.
//! - With the default cost terms (fixed `cost-per-texel-ns` and `cost-per-tile-ms`, in
//!   which the time budget is counted) or `time-budget-ms=none`, the result is a function
//!   of the parameters and the frame sequence alone, bit-identical for any thread count
//!   and across runs: the analysis and the look-ups are reduced in pixel order, and tiles
//!   go through the deterministic rasterizer. Only `auto` cost terms measure the machine.
//! - A still view converges: once a whole analysis period makes and evicts no node, every
//!   later frame repeats the last ([`ShadowTechnique::converged`]); the command line runs a
//!   still view until then (or a cap) and reports the frames it took.
//!
//! # Departures from the paper
//! - The paper estimates projected pixel areas with a mip-mapped texture on graphics
//!   hardware (Section 4.1); here they come from the camera pass's screen-space
//!   derivatives projected into the light view, which is what that trick approximates.
//! - "Straddles a depth discontinuity" is judged against the receiver: the texels around
//!   its look-up disagree on the combined id/depth shadow test. A depth step that changes
//!   no shadow answer there gains nothing from refinement.
//! - With fixed-resolution nodes the paper's `N_required` is always the node's own texel
//!   count, so every candidate costs the same and the ranking reduces to benefit; the
//!   cost model decides how many nodes fit in the time budget. The budget is
//!   spent against predicted costs, and the chosen tiles are then rendered together in
//!   parallel, rather than one by one until a clock runs out.
//! - Up to `passes` refinement passes per frame (the paper makes one): after a pass, the
//!   pixels whose cells were refined are analysed again in the new nodes, so a pixel can
//!   descend several levels in the frame it is analysed instead of one level per period
//!   of eight frames. Each pass draws on the same time and node budgets.
//! - `oversampling` (default 16) asks for texels that many times finer than the eye pixel,
//!   where the paper asks for equal size: measured against a ray-traced reference, a texel
//!   as large as a pixel still moves shadow edges by up to half a pixel and flips about a
//!   tenth of the boundary pixels; 16 brings that near one in a hundred.
//! - The default tiles are 32² with 4×4 cells, small so that memory follows the shadow
//!   boundaries closely (the paper does not give its sizes).
//! - Refinement stops at an effective resolution of [`MAX_EFFECTIVE_RESOLUTION`], where the
//!   f32 light-space coordinates of the rasterizer reach a few hundredths of a texel.
//! - Point lights use a cube of six trees (see above) where the paper's walkthrough used a
//!   single 122° frustum. Semi-transparent casters are treated as opaque, as in `sm`.
//! - A leaf's benefit is averaged over one analysis period, because each frame sees only a
//!   share of its pixels; the paper's single-frame count would let a leaf that no analysed
//!   pixel happened to fall in be replaced at once, and rebuilt the next frame.
//!
//! # Known artifacts
//! Casters thinner than a texel of the level a receiver sees can be missed by every texel
//! around it and then never trigger refinement; the discontinuity test is clamped at tile
//! borders, so a boundary that runs along a tile border refines one level later; the depth
//! bias persists at polygon boundaries where the id test fails (as the paper notes);
//! grazing receivers (tiny light-space footprints) draw refinement down to the deepest
//! level; and with `auto` cost terms the number of nodes made per frame depends on the
//! machine's speed and load. A view that moves faster than refinement converges shows the coarser
//! levels' edges for a few frames.

//!
//! # Where each stage lives
//! - `tree`: the hierarchical grid (Section 3): nodes, cells, light views, the walk down.
//! - `roots`: step 1, the root of each light view; `culling`: Section 4.3's culling
//!   lists per root cell.
//! - `analysis`: step 2's benefit, the resolution-mismatched pixels that straddle a
//!   discontinuity (Sections 3.1, 4.1, 4.3); `cost`: the cost model, its calibration and
//!   the ranking by benefit over cost (Section 3.1).
//! - `node_creation`: step 3, the refinement passes and the rendering of new tiles
//!   (Section 3.1); `node_removal`: the LRU and benefit eviction (Section 3.2).
//! - `lookup`: step 4, the queries with Section 4.2's id and depth test.
//! - `params`: the parameters; `dump`: the pictures of the tree.

mod analysis;
mod cost;
mod culling;
mod dump;
mod lookup;
mod node_creation;
mod node_removal;
mod params;
mod roots;
#[cfg(test)]
mod test_scenes;
mod tree;

pub use culling::clipped_uv_bounds;
pub use dump::LEVEL_COLOURS;
pub use params::{
    DEFAULT_ANALYSIS_FRACTION, DEFAULT_BUDGET_MB, DEFAULT_CELLS, DEFAULT_COST_PER_TEXEL_NS,
    DEFAULT_COST_PER_TILE_MS, DEFAULT_MAX_NEW_NODES, DEFAULT_OVERSAMPLING, DEFAULT_PASSES,
    DEFAULT_ROOT_RESOLUTION, DEFAULT_TILE_RESOLUTION, DEFAULT_TIME_BUDGET_MS,
};
pub use tree::MAX_EFFECTIVE_RESOLUTION;

use super::shadow_map::DIRECTIONAL_PAD;
use super::technique::{ParamSpec, ShadowTechnique, Shadows};
use crate::error::Result;
use crate::frame::{Frame, Stats};
use crate::light::light_views;
use cost::{cost_model, CostModel};
use node_creation::Refinement;
use params::{Params, MIB};
use std::collections::BTreeMap;
use std::time::Instant;
use tree::{Fingerprint, Tree};

/// The `asm` technique: adaptive shadow maps. Keeps its tree between frames; a different
/// scene or light, or a change of `root-resolution`, `tile-resolution` or `cells`, starts a
/// new one.
///
/// Parameters (`set_param`):
/// - `root-resolution` (512, a power of two): root tile side; each of a point light's six
///   cube faces gets half of it.
/// - `tile-resolution` (32, a power of two): side of every other node's tile.
/// - `cells` (4, a power of two dividing `tile-resolution`): cells per node side, the
///   refinement factor per level.
/// - `budget-mb` (16): MiB the tree may hold.
/// - `analysis-fraction` (0.125): share of pixels analysed per frame, rounded to `1/n`.
/// - `time-budget-ms` (40, or `none`): predicted milliseconds of new tiles per frame, in
///   the cost model's units (nominal milliseconds unless the cost terms are `auto`).
/// - `max-new-nodes` (1024): new nodes per frame at most.
/// - `passes` (4): refinement passes per frame (1 is the paper's).
/// - `oversampling` (16): texels wanted across an eye pixel's footprint, per axis.
/// - `bias`, `slope-bias` (0.5, 1): depth bias in texels of the leaf, as for `sm`.
/// - `cost-per-texel-ns`, `cost-per-tile-ms` (50 and 0.2, or `auto`): the cost model's
///   `a` and `b` in nominal units; `auto` measures them on this machine at start-up.
#[derive(Debug, Default)]
pub struct Adaptive {
    params: Params,
    tree: Option<Tree>,
    cost: Option<CostModel>,
    /// Frames rendered so far (the clock of the LRU stamps).
    frame: u64,
    /// Frames in a row, up to the last, that made and evicted no node.
    quiet_frames: u32,
    /// Frames in one analysis period (every pixel is analysed once per period).
    period: u32,
}

impl Adaptive {
    /// Bytes the tree and its culling lists hold now (0 before the first frame).
    pub fn memory_bytes(&self) -> u64 {
        self.tree.as_ref().map_or(0, Tree::memory_bytes)
    }

    /// Forgets the tree; the next frame starts from the roots again.
    pub fn reset(&mut self) {
        self.tree = None;
        self.cost = None;
        self.quiet_frames = 0;
    }

    /// Starts a frame: checks the parameters against `frame`'s light, keeps the tree
    /// unless it was built for another scene or light, and returns the frame's clock.
    fn start_frame(&mut self, frame: &Frame, p: &Params) -> Result<u64> {
        let views = light_views(
            frame.light,
            &frame.scene.bounds,
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        p.check_structure(views.len())?;
        self.frame += 1;
        let fingerprint = Fingerprint::of(frame);
        if self
            .tree
            .as_ref()
            .is_none_or(|t| t.fingerprint != fingerprint)
        {
            self.tree = Some(Tree::new(fingerprint, views, p));
            self.cost = None;
            self.quiet_frames = 0;
        }
        Ok(self.frame)
    }
}

/// What a frame did, for its counters.
struct FrameTally {
    refinement: Refinement,
    cost: CostModel,
    analysed_pixels: usize,
    benefit_pixels: usize,
    /// The finest effective resolution among the leaves the look-ups used.
    used_finest: f64,
}

/// Counts `tree` and what the frame did (`tally`) into `stats`.
fn report(stats: &mut Stats, tree: &Tree, p: &Params, tally: &FrameTally) {
    let mut finest = 0f64;
    let mut per_level: Vec<u64> = Vec::new();
    for n in tree.live_nodes() {
        finest = finest.max(tree.scale(tree.face(n), n.level));
        if per_level.len() <= n.level as usize {
            per_level.resize(n.level as usize + 1, 0);
        }
        per_level[n.level as usize] += 1;
    }
    let levels = per_level.len();
    for (l, &c) in per_level.iter().enumerate() {
        stats.count(&format!("nodes_level_{l}"), c as f64);
    }
    let r = &tally.refinement;
    stats.memory_bytes = tree.memory_bytes();
    stats.count("tree_bytes", tree.bytes as f64);
    stats.count("culling_bytes", tree.culling_bytes() as f64);
    stats.count("nodes", tree.live_nodes().count() as f64);
    stats.count("budget_bytes", (p.budget_mb * MIB).floor());
    stats.count("effective_resolution", finest);
    stats.count("effective_resolution_used", tally.used_finest);
    stats.count("levels", levels as f64);
    stats.count("cells_refined", r.budget.made as f64);
    stats.count("nodes_evicted", r.budget.evicted as f64);
    stats.count("candidate_cells", r.candidate_cells as f64);
    stats.count("refine_passes", r.passes as f64);
    stats.count("analysed_pixels", tally.analysed_pixels as f64);
    stats.count("benefit_pixels", tally.benefit_pixels as f64);
    stats.count("predicted_refine_ms", r.budget.spent_ms);
    if p.time_budget_ms.is_some() {
        stats.count("cost_per_texel_ns", tally.cost.a * 1e6);
        stats.count("cost_per_tile_ms", tally.cost.b);
    }
}

impl ShadowTechnique for Adaptive {
    fn name(&self) -> &'static str {
        "asm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        self.params.to_map()
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        Params::specs()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let mut p = self.params.clone();
        p.set(key, value)?;
        // The tree's shape depends on these; a change starts a new one.
        let reshaped = self.params.reshapes(&p);
        self.params = p;
        if reshaped {
            self.reset();
        }
        Ok(())
    }

    /// Converged once a whole analysis period (every pixel analysed once) has passed
    /// without a node made or evicted: another frame of the same view would repeat the last.
    fn converged(&self) -> Option<bool> {
        Some(self.tree.is_some() && self.quiet_frames >= self.period.max(1))
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let p = self.params.clone();
        let mut stats = Stats::default();
        let now = self.start_frame(frame, &p)?;
        let tree = self.tree.as_mut().expect("tree made at the start");
        // 1. The roots of the views the receivers fall in.
        stats.stage("roots", || tree.ensure_roots(frame, &p, now))?;
        let tree = self.tree.as_ref().expect("tree made at the start");
        let cost = if p.time_budget_ms.is_some() {
            stats.stage("calibrate", || {
                cost_model(&p, &mut self.cost, frame.scene, tree)
            })
        } else {
            CostModel::FREE
        };
        // 2. The analysis of this frame's share of the pixels.
        let tree = self.tree.as_mut().expect("tree made at the start");
        let t0 = Instant::now();
        let (pixels, period) = Tree::analysis_pixels(frame, &p, now);
        let probes = tree.analyse(frame, &p, &pixels);
        let analysis_ms = t0.elapsed().as_secs_f64() * 1e3;
        tree.update_benefits(&probes, period, now);
        let benefit_pixels = probes.iter().filter(|pr| pr.candidate).count();
        // 3. Refinement: new nodes for the most profitable cells, within the budgets.
        let refinement = tree.refine_passes(frame, &p, cost, probes, now);
        stats
            .stages_ms
            .push(("analysis".into(), analysis_ms + refinement.analysis_ms));
        stats
            .stages_ms
            .push(("refine".into(), refinement.refine_ms));
        self.period = period as u32;
        let quiet = refinement.budget.made == 0 && refinement.budget.evicted == 0;
        self.quiet_frames = if quiet { self.quiet_frames + 1 } else { 0 };
        // 4. The queries.
        let (value, used) = stats.stage("lookup", || tree.lookup(frame, &p));
        let used_finest = tree.mark_used(used, now);
        let tally = FrameTally {
            refinement,
            cost,
            analysed_pixels: pixels.len(),
            benefit_pixels,
            used_finest,
        };
        report(&mut stats, tree, &p, &tally);
        if frame.dumping() {
            dump::write_dump(tree, frame)?;
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::test_scenes::small_scene;
    use super::tree::{Node, NO_NODE};
    use super::*;
    use crate::camera::Camera;
    use crate::light::Light;
    use crate::math::vec3;
    use crate::view::ViewSamples;

    #[test]
    fn frames_keep_the_tree_consistent_and_within_budget() {
        let scene = small_scene();
        let light = Light::Directional {
            to_light: vec3(-0.3, 1.0, 0.2).normalize(),
        };
        let mut t = Adaptive::default();
        for (k, v) in [
            ("root-resolution", "64"),
            ("tile-resolution", "32"),
            ("budget-mb", "0.25"),
            ("time-budget-ms", "none"),
            ("max-new-nodes", "40"),
        ] {
            t.set_param(k, v).unwrap();
        }
        let budget = (0.25 * MIB) as u64;
        let (mut evicted, mut most) = (0.0, 0.0f64);
        for i in 0..12 {
            let a = i as f32 * 0.5;
            let mut camera = Camera::look_at(
                vec3(3.0 * a.cos(), 2.5, 3.0 * a.sin()),
                vec3(0.0, 0.5, 0.0),
                50.0,
                96,
                72,
            );
            camera.fit_depth_range(&scene.bounds);
            let view = ViewSamples::render(&scene, &camera);
            let shadows = t
                .render(&Frame::new(&scene, &camera, &light, &view))
                .unwrap();
            assert!(shadows.stats.counters["tree_bytes"] <= budget as f64);
            evicted += shadows.stats.counters["nodes_evicted"];
            most = most.max(shadows.stats.counters["nodes"]);
            let tree = t.tree.as_ref().unwrap();
            assert_eq!(shadows.stats.counters["tree_bytes"], tree.bytes as f64);
            assert_eq!(
                shadows.stats.memory_bytes,
                tree.bytes + tree.culling_bytes()
            );
            let mut bytes = 0;
            for (s, n) in tree.nodes.iter().enumerate() {
                let Some(n) = n else { continue };
                bytes += Node::bytes(n.res, n.cells);
                assert_eq!(
                    n.depth.len(),
                    (n.res * n.res) as usize,
                    "every tile is rendered"
                );
                let live = n.children.iter().filter(|&&c| c != NO_NODE).count() as u32;
                assert_eq!(live, n.live_children);
                for (cell, &c) in n.children.iter().enumerate() {
                    if c == NO_NODE {
                        continue;
                    }
                    let ch = tree.node(c);
                    assert_eq!(
                        (ch.parent, ch.parent_cell, ch.level),
                        (s as u32, cell as u32, n.level + 1)
                    );
                    // The child covers exactly its cell, `cells` times finer.
                    let ct = n.res / n.cells;
                    let (cx, cy) = (cell as u32 % n.cells, cell as u32 / n.cells);
                    assert_eq!(ch.x0, (n.x0 + cx * ct) * t.params.cells);
                    assert_eq!(ch.y0, (n.y0 + cy * ct) * t.params.cells);
                    assert_eq!(ch.res, ct * t.params.cells);
                }
            }
            assert_eq!(bytes, tree.bytes);
        }
        assert!(
            evicted > 0.0 && most > 10.0,
            "the budget was exercised: {evicted} evictions, {most} nodes"
        );
        // A lowered budget takes effect on the next frame.
        t.set_param("budget-mb", "0.1").unwrap();
        let mut camera = Camera::look_at(vec3(3.0, 2.5, 0.0), vec3(0.0, 0.5, 0.0), 50.0, 96, 72);
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let shadows = t
            .render(&Frame::new(&scene, &camera, &light, &view))
            .unwrap();
        assert!(shadows.stats.counters["tree_bytes"] <= 0.1 * MIB);
        assert_eq!(
            t.tree.as_ref().unwrap().bytes as f64,
            shadows.stats.counters["tree_bytes"]
        );
    }
}
