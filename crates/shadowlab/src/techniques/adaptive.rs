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
//!   `budget-mb`; [`ShadowTechnique::render`] fails with [`Error::Limit`] rather than
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

use super::shadow_map::{
    receiver_bias, DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS, DIRECTIONAL_PAD,
};
use super::{
    check_range, parse_value, unknown_param, Frame, ShadowTechnique, Shadows, Stats, Visibility,
};
use crate::error::{Error, Result};
use crate::light::{cube_face, light_views, Light, LightView};
use crate::math::{Aabb, Mat4, Vec3, Vec4};
use crate::raster::{self, DepthBuffer, NO_TRIANGLE};
use crate::scene::Scene;
use glam::{DMat4, DVec4};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::time::Instant;

/// Default side of a root node's tile in texels (the paper's starting resolution).
pub const DEFAULT_ROOT_RESOLUTION: u32 = 512;
/// Default side of every other node's tile in texels.
pub const DEFAULT_TILE_RESOLUTION: u32 = 32;
/// Default number of cells per side of a node: each level refines texels by this factor.
pub const DEFAULT_CELLS: u32 = 4;
/// Default memory budget in MiB (the paper's 16 MB, the size of a 2048² map of 32-bit depths).
pub const DEFAULT_BUDGET_MB: f64 = 16.0;
/// Default share of eye pixels analysed per frame (the paper's one eighth).
pub const DEFAULT_ANALYSIS_FRACTION: f64 = 0.125;
/// Default per-frame budget for new nodes, in the cost model's (nominal) milliseconds.
pub const DEFAULT_TIME_BUDGET_MS: f64 = 40.0;
/// Default cost of a new tile per texel in the cost model (`a`), in nominal nanoseconds:
/// a fixed unit, not a measurement, so that the refinement budget (`time-budget-ms`) buys
/// the same nodes on any machine and under any load and a frame's result depends on its
/// inputs alone. The value is about what a 32² tile costs per texel on a 2-core machine;
/// `cost-per-texel-ns=auto` measures this machine instead (and gives up determinism).
pub const DEFAULT_COST_PER_TEXEL_NS: f64 = 50.0;
/// Default fixed cost of a new tile in the cost model (`b`), in nominal milliseconds (see
/// [`DEFAULT_COST_PER_TEXEL_NS`]); `cost-per-tile-ms=auto` measures it.
pub const DEFAULT_COST_PER_TILE_MS: f64 = 0.2;
/// Default cap on new nodes per frame.
pub const DEFAULT_MAX_NEW_NODES: u32 = 1024;
/// Default number of refinement passes per frame (the paper makes one): each further pass
/// examines again the pixels whose cells were just refined, in the new nodes, so a view
/// reaches its resolution in fewer frames.
pub const DEFAULT_PASSES: u32 = 4;
/// Default linear ratio of shadow-map to eye resolution that refinement aims for. Larger
/// values put shadow edges closer to where a ray-traced reference puts them and spend more
/// memory and time; 1 is the paper's criterion.
pub const DEFAULT_OVERSAMPLING: f32 = 16.0;
/// Refinement stops at this effective resolution (texels across a root view): beyond it
/// the f32 clip coordinates of a tile's triangles and the look-ups' light-space
/// coordinates err by more than a few hundredths of a texel.
pub const MAX_EFFECTIVE_RESOLUTION: u64 = 1 << 20;
/// Bytes per MiB, the unit of `budget-mb`.
const MIB: f64 = 1024.0 * 1024.0;
/// Timed repetitions per calibration tile; the median is kept.
const CALIBRATION_REPEATS: usize = 3;
/// Root cells timed by the calibration (the most populated ones, so the estimate errs on
/// the slow side and the time budget is rarely overrun).
const CALIBRATION_CELLS: usize = 4;
/// Marks an empty cell in a node's child table.
const NO_NODE: u32 = u32::MAX;

/// The technique's parameters.
#[derive(Clone, Debug, PartialEq)]
struct Params {
    root_resolution: u32,
    tile_resolution: u32,
    cells: u32,
    budget_mb: f64,
    analysis_fraction: f64,
    time_budget_ms: Option<f64>,
    max_new_nodes: u32,
    passes: u32,
    oversampling: f32,
    bias: f32,
    slope_bias: f32,
    cost_per_texel_ns: Option<f64>,
    cost_per_tile_ms: Option<f64>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            root_resolution: DEFAULT_ROOT_RESOLUTION,
            tile_resolution: DEFAULT_TILE_RESOLUTION,
            cells: DEFAULT_CELLS,
            budget_mb: DEFAULT_BUDGET_MB,
            analysis_fraction: DEFAULT_ANALYSIS_FRACTION,
            time_budget_ms: Some(DEFAULT_TIME_BUDGET_MS),
            max_new_nodes: DEFAULT_MAX_NEW_NODES,
            passes: DEFAULT_PASSES,
            oversampling: DEFAULT_OVERSAMPLING,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            cost_per_texel_ns: Some(DEFAULT_COST_PER_TEXEL_NS),
            cost_per_tile_ms: Some(DEFAULT_COST_PER_TILE_MS),
        }
    }
}

const KNOWN: &[&str] = &[
    "root-resolution",
    "tile-resolution",
    "cells",
    "budget-mb",
    "analysis-fraction",
    "time-budget-ms",
    "max-new-nodes",
    "passes",
    "oversampling",
    "bias",
    "slope-bias",
    "cost-per-texel-ns",
    "cost-per-tile-ms",
];

impl Params {
    /// Side of a root tile for a light with `views` views.
    fn face_resolution(&self, views: usize) -> u32 {
        if views > 1 {
            (self.root_resolution / 2).max(1)
        } else {
            self.root_resolution
        }
    }

    /// Checks the parameters that constrain one another.
    fn check_structure(&self, views: usize) -> Result<()> {
        let face = self.face_resolution(views);
        let cell = self.tile_resolution / self.cells;
        if cell == 0 || cell * self.cells != self.tile_resolution {
            return Err(Error::param(format!(
                "asm.cells = {} must divide asm.tile-resolution = {}",
                self.cells, self.tile_resolution
            )));
        }
        if face < cell || face / cell * cell != face {
            return Err(Error::param(format!(
                "asm.root-resolution = {} gives root tiles of {face} texels, which the cells of {cell} texels \
                 (asm.tile-resolution / asm.cells) must divide",
                self.root_resolution
            )));
        }
        Ok(())
    }
}

/// Parses `none` (or `auto` for cost terms) or a number in `lo..=hi`.
fn parse_optional(key: &str, value: &str, word: &str, lo: f64, hi: f64) -> Result<Option<f64>> {
    if value.trim().eq_ignore_ascii_case(word) {
        return Ok(None);
    }
    let v: f64 = parse_value("asm", key, value)?;
    Ok(Some(check_range("asm", key, v, lo, hi)?))
}

fn power_of_two(key: &str, value: &str, lo: u32, hi: u32) -> Result<u32> {
    let v: u32 = check_range("asm", key, parse_value("asm", key, value)?, lo, hi)?;
    if !v.is_power_of_two() {
        return Err(Error::param(format!(
            "parameter asm.{key} = {v} must be a power of two"
        )));
    }
    Ok(v)
}

/// What the tree was built for; a different scene or light starts a new tree.
#[derive(Clone, Debug, PartialEq)]
struct Fingerprint {
    name: String,
    triangles: usize,
    revision: u64,
    bounds: Aabb,
    light: Light,
}

impl Fingerprint {
    fn of(frame: &Frame) -> Self {
        Fingerprint {
            name: frame.scene.name.clone(),
            triangles: frame.scene.len(),
            revision: frame.scene.revision,
            bounds: frame.scene.bounds,
            light: *frame.light,
        }
    }
}

/// The calibrated cost of rendering a tile: `a·N + b` milliseconds for `N` texels.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CostModel {
    /// Milliseconds per texel.
    a: f64,
    /// Milliseconds per tile.
    b: f64,
}

impl CostModel {
    fn predict(&self, texels: u64) -> f64 {
        self.a * texels as f64 + self.b
    }
}

/// `x.floor() as i64` without a library call in the per-pixel loops (values far outside
/// the i64 range saturate, as the cast does).
#[inline]
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    t - ((t as f64) > x) as i64
}

/// One node of a tree: a depth and id tile over a square of its light view.
#[derive(Debug)]
struct Node {
    face: u8,
    level: u8,
    /// Origin in texels of this level's effective resolution.
    x0: u32,
    y0: u32,
    /// Tile side in texels.
    res: u32,
    /// Cells per side.
    cells: u32,
    parent: u32,
    parent_cell: u32,
    /// Unique over the tree's life, so a stale reference to a reused slot is detected.
    serial: u64,
    children: Vec<u32>,
    live_children: u32,
    depth: Vec<f32>,
    id: Vec<u32>,
    /// Last frame whose analysis or look-ups used this node or a descendant.
    stamp: u64,
    /// Frame the node was made in.
    created: u64,
    /// Analysed pixels per frame whose mismatch it resolves, averaged over the frames of
    /// one analysis period (each frame sees a different share of the pixels).
    benefit: f32,
}

impl Node {
    fn bytes(res: u32, cells: u32) -> u64 {
        let texels = res as u64 * res as u64;
        texels * 8 + cells as u64 * cells as u64 * 4 + std::mem::size_of::<Node>() as u64
    }

    /// Position of `(u, v)` in this node's texels, given its level's effective resolution.
    #[inline]
    fn local(&self, u: f64, v: f64, scale: f64) -> (f64, f64) {
        (u * scale - self.x0 as f64, v * scale - self.y0 as f64)
    }

    #[inline]
    fn contains(&self, lx: f64, ly: f64) -> bool {
        let r = self.res as f64;
        lx >= 0.0 && ly >= 0.0 && lx < r && ly < r
    }

    #[inline]
    fn texel(&self, lx: f64, ly: f64) -> (u32, u32) {
        let m = self.res as i64 - 1;
        (
            floor_i64(lx).clamp(0, m) as u32,
            floor_i64(ly).clamp(0, m) as u32,
        )
    }

    #[inline]
    fn cell(&self, lx: f64, ly: f64) -> u32 {
        let size = (self.res / self.cells) as f64;
        let m = self.cells as i64 - 1;
        let cx = floor_i64(lx / size).clamp(0, m) as u32;
        let cy = floor_i64(ly / size).clamp(0, m) as u32;
        cy * self.cells + cx
    }

    /// The combined id and depth test of Section 4.2 at one texel.
    #[inline]
    fn lit(&self, tx: u32, ty: u32, own: u32, biased_depth: f32) -> bool {
        let k = (ty * self.res + tx) as usize;
        self.id[k] == own || biased_depth <= self.depth[k]
    }

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

/// One light view and its tree's root.
#[derive(Debug)]
struct Face {
    view: LightView,
    /// `clip_from_world` in f64 for look-ups.
    clip_from_world: DMat4,
    /// Root tile side in texels.
    resolution: u32,
    root: u32,
    /// Root cells per side (the culling grid).
    grid: u32,
    /// Triangles whose projection overlaps each root cell, ascending.
    bins: Vec<Vec<u32>>,
}

impl Face {
    fn bins_bytes(&self) -> u64 {
        self.bins
            .iter()
            .map(|b| b.capacity() as u64 * 4 + std::mem::size_of::<Vec<u32>>() as u64)
            .sum()
    }

    /// Root-view image coordinates (`u, v` in `[0, 1)`) and linear depth of `p`.
    #[inline]
    fn project(&self, p: Vec3) -> (f64, f64, f32) {
        let c = self.clip_from_world * DVec4::new(p.x as f64, p.y as f64, p.z as f64, 1.0);
        let (u, v) = uv_of(c);
        (
            u.clamp(0.0, LAST_UV),
            v.clamp(0.0, LAST_UV),
            self.view.depth(p),
        )
    }
}

/// The largest `u` or `v` kept inside a view.
const LAST_UV: f64 = 1.0 - 1e-12;

#[inline]
fn uv_of(c: DVec4) -> (f64, f64) {
    let inv_w = 1.0 / c.w;
    (c.x * inv_w * 0.5 + 0.5, 0.5 - c.y * inv_w * 0.5)
}

/// The forest of one light: a tree per light view, nodes in a slot arena.
#[derive(Debug)]
struct Tree {
    fingerprint: Fingerprint,
    views: Vec<LightView>,
    faces: Vec<Option<Face>>,
    nodes: Vec<Option<Node>>,
    free: Vec<u32>,
    /// Bytes held by nodes and culling lists.
    bytes: u64,
    next_serial: u64,
    /// Texel refinement per level (`cells`).
    refine: u32,
    /// Tile side of non-root nodes.
    tile: u32,
}

/// What the analysis found at one analysed pixel.
#[derive(Clone, Copy, Debug)]
struct Probe {
    /// The pixel.
    pixel: u32,
    /// The deepest node covering the pixel.
    leaf: u32,
    /// The cell of `leaf` the pixel falls in.
    cell: u32,
    /// Mismatched and straddling at the leaf's resolution: a vote for refining the cell.
    candidate: bool,
    /// Mismatched and straddling at the parent's resolution: the leaf resolves it.
    serves: bool,
}

/// What the refinement passes of one frame have used of their budgets.
#[derive(Clone, Copy, Debug, Default)]
struct RefineBudget {
    made: u64,
    evicted: u64,
    spent_ms: f64,
}

/// A cell that could receive a node this frame.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    node: u32,
    serial: u64,
    cell: u32,
    benefit: u32,
    cost_ms: f64,
}

impl Tree {
    fn new(fingerprint: Fingerprint, views: Vec<LightView>, p: &Params) -> Self {
        Tree {
            fingerprint,
            faces: views.iter().map(|_| None).collect(),
            views,
            nodes: Vec::new(),
            free: Vec::new(),
            bytes: 0,
            next_serial: 0,
            refine: p.cells,
            tile: p.tile_resolution,
        }
    }

    #[inline]
    fn node(&self, s: u32) -> &Node {
        self.nodes[s as usize]
            .as_ref()
            .expect("slot holds a live node")
    }

    #[inline]
    fn node_mut(&mut self, s: u32) -> &mut Node {
        self.nodes[s as usize]
            .as_mut()
            .expect("slot holds a live node")
    }

    /// Effective resolution of `level` in `face`: texels across the whole root view.
    #[inline]
    fn scale(&self, face: &Face, level: u8) -> f64 {
        face.resolution as f64 * (self.refine as f64).powi(level as i32)
    }

    /// The deepest level whose effective resolution stays within the limit.
    fn max_level(&self, face: &Face) -> u8 {
        let mut l = 0u8;
        let mut e = face.resolution as u64;
        while e * self.refine as u64 <= MAX_EFFECTIVE_RESOLUTION {
            e *= self.refine as u64;
            l += 1;
        }
        l
    }

    fn face_of(&self, light: &Light, p: Vec3) -> usize {
        match *light {
            Light::Point { position } if self.views.len() == 6 => cube_face(p - position),
            _ => 0,
        }
    }

    fn insert(&mut self, n: Node) -> u32 {
        self.bytes += Node::bytes(n.res, n.cells);
        match self.free.pop() {
            Some(s) => {
                self.nodes[s as usize] = Some(n);
                s
            }
            None => {
                self.nodes.push(Some(n));
                (self.nodes.len() - 1) as u32
            }
        }
    }

    /// Removes a leaf node.
    fn evict(&mut self, s: u32) {
        let n = self.nodes[s as usize].take().expect("evicting a live node");
        debug_assert_eq!(n.live_children, 0, "only leaves are evicted");
        self.bytes -= Node::bytes(n.res, n.cells);
        let parent = self.node_mut(n.parent);
        parent.children[n.parent_cell as usize] = NO_NODE;
        parent.live_children -= 1;
        self.free.push(s);
    }

    /// Gives `parent`'s empty `cell` a child node (its tile still to be rendered).
    fn add_child(&mut self, parent: u32, cell: u32, now: u64, benefit: f32) -> u32 {
        let (tile, refine) = (self.tile, self.refine);
        let pn = self.node(parent);
        debug_assert_eq!(pn.children[cell as usize], NO_NODE, "the cell is empty");
        let ct = pn.res / pn.cells;
        let (cx, cy) = (cell % pn.cells, cell / pn.cells);
        let node = Node {
            face: pn.face,
            level: pn.level + 1,
            x0: (pn.x0 + cx * ct) * refine,
            y0: (pn.y0 + cy * ct) * refine,
            res: tile,
            cells: refine,
            parent,
            parent_cell: cell,
            serial: self.next_serial,
            children: vec![NO_NODE; (refine * refine) as usize],
            live_children: 0,
            depth: Vec::new(),
            id: Vec::new(),
            stamp: now,
            created: now,
            benefit,
        };
        self.next_serial += 1;
        let s = self.insert(node);
        let pn = self.node_mut(parent);
        pn.children[cell as usize] = s;
        pn.live_children += 1;
        s
    }

    /// The deepest node of `face` covering `(u, v)`.
    fn locate(&self, face: &Face, u: f64, v: f64) -> u32 {
        let mut s = face.root;
        let mut scale = face.resolution as f64;
        loop {
            let n = self.node(s);
            let (lx, ly) = n.local(u, v, scale);
            let c = n.children[n.cell(lx, ly) as usize];
            if c == NO_NODE {
                return s;
            }
            s = c;
            scale *= self.refine as f64;
        }
    }

    /// The leaf to evict so that a new node fits: a leaf unused in the last frame, least
    /// recently used first; else an in-use leaf of smaller benefit than `benefit`.
    fn pick_victim(&self, now: u64, protect: Option<u32>, benefit: Option<f32>) -> Option<u32> {
        let mut unused: Option<(u64, u8, u32)> = None;
        let mut used: Option<(u32, u64, u8, u32)> = None;
        for (s, n) in self.nodes.iter().enumerate() {
            let Some(n) = n else { continue };
            let s = s as u32;
            if n.level == 0 || n.live_children > 0 || n.created == now || Some(s) == protect {
                continue;
            }
            // Deeper nodes first among equals: they hold the least-shared detail.
            let depth_key = u8::MAX - n.level;
            if n.stamp + 1 < now {
                let k = (n.stamp, depth_key, s);
                if unused.is_none_or(|u| k < u) {
                    unused = Some(k);
                }
            } else if let Some(b) = benefit {
                if n.benefit < b {
                    // Non-negative floats order as their bits.
                    let k = (n.benefit.to_bits(), n.stamp, depth_key, s);
                    if used.is_none_or(|u| k < u) {
                        used = Some(k);
                    }
                }
            }
        }
        unused.map(|k| k.2).or(used.map(|k| k.3))
    }

    /// Marks `s` and its ancestors as used in frame `now`.
    fn touch(&mut self, mut s: u32, now: u64) {
        loop {
            let n = self.node_mut(s);
            if n.stamp == now {
                return;
            }
            n.stamp = now;
            if n.level == 0 {
                return;
            }
            s = n.parent;
        }
    }

    /// Makes the roots of the views that `frame`'s receivers fall in.
    fn ensure_roots(&mut self, frame: &Frame, p: &Params, now: u64) -> Result<()> {
        let view = frame.view;
        let n = (view.width * view.height) as usize;
        let needed: u32 = if self.views.len() == 1 {
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
        };
        let budget = (p.budget_mb * MIB) as u64;
        let res = p.face_resolution(self.views.len());
        for f in 0..self.views.len() {
            if needed & (1 << f) == 0 || self.faces[f].is_some() {
                continue;
            }
            let lv = self.views[f];
            let mut face = Face {
                view: lv,
                clip_from_world: lv.clip_from_world.as_dmat4(),
                resolution: res,
                root: NO_NODE,
                grid: res / (self.tile / self.refine),
                bins: Vec::new(),
            };
            face.bins = bin_triangles(frame.scene, &face);
            let need = Node::bytes(res, face.grid);
            while self.bytes + need > budget {
                match self.pick_victim(now, None, Some(f32::INFINITY)) {
                    Some(s) => self.evict(s),
                    None => {
                        let faces = needed.count_ones();
                        return Err(Error::Limit(format!(
                            "asm.budget-mb = {} cannot hold the root maps: {faces} light view(s) of {res}² texels \
                             need {:.2} MiB; raise asm.budget-mb or lower asm.root-resolution",
                            p.budget_mb,
                            (self.bytes + need) as f64 / MIB
                        )));
                    }
                }
            }
            let (depth, id) = render_tile(frame.scene, &face, 0.0, 0.0, 1.0, res);
            let root = Node {
                face: f as u8,
                level: 0,
                x0: 0,
                y0: 0,
                res,
                cells: face.grid,
                parent: NO_NODE,
                parent_cell: 0,
                serial: self.next_serial,
                children: vec![NO_NODE; (face.grid * face.grid) as usize],
                live_children: 0,
                depth,
                id,
                stamp: now,
                created: now,
                benefit: 0.0,
            };
            self.next_serial += 1;
            face.root = self.insert(root);
            self.faces[f] = Some(face);
        }
        // A budget lowered since the last frame takes effect at once.
        while self.bytes > budget {
            let victim = self.pick_victim(now, None, Some(f32::INFINITY));
            let Some(s) = victim else {
                return Err(Error::Limit(format!(
                    "asm.budget-mb = {} cannot hold the root maps ({:.2} MiB); raise asm.budget-mb \
                     or lower asm.root-resolution",
                    p.budget_mb,
                    self.bytes as f64 / MIB
                )));
            };
            self.evict(s);
        }
        Ok(())
    }

    /// The depth bias of a receiver at `level`, in world units.
    #[inline]
    fn bias(&self, face: &Face, level: u8, depth: f32, n: Vec3, l: Vec3, p: &Params) -> f32 {
        let e = self.scale(face, level) as u32;
        receiver_bias(face.view.texel_size(e, depth), n, l, p.bias, p.slope_bias)
    }

    /// The pixels analysed in frame `now`: a rotating share of the receivers, so that a
    /// still view has every pixel analysed once per period. Returns them and the period.
    fn analysis_pixels(frame: &Frame, p: &Params, now: u64) -> (Vec<u32>, u64) {
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let period = (1.0 / p.analysis_fraction).round().max(1.0) as u64;
        let phase = now % period;
        let rows: Vec<Vec<u32>> = (0..h)
            .into_par_iter()
            .map(|y| {
                // Consecutive rows shift the pattern by three columns, spreading it evenly.
                (0..w)
                    .filter(|&x| (x as u64 + 3 * y as u64 + phase) % period < 1)
                    .map(|x| y * w + x)
                    .filter(|&k| frame.receiver_lit(k as usize))
                    .collect()
            })
            .collect();
        (rows.concat(), period)
    }

    /// Section 3.1's analysis of `pixels`: for each, the deepest node and cell it falls in,
    /// whether it votes for refining that cell, and whether the node resolves it.
    fn analyse(&self, frame: &Frame, p: &Params, pixels: &[u32]) -> Vec<Probe> {
        let view = frame.view;
        let k2 = (p.oversampling as f64).powi(2);
        let chunks: Vec<Vec<Probe>> = pixels
            .par_chunks(1024)
            .map(|chunk| {
                let mut out = Vec::with_capacity(chunk.len());
                for &k in chunk {
                    let k = k as usize;
                    let pos = view.position[k];
                    let face = self.faces[self.face_of(frame.light, pos)]
                        .as_ref()
                        .expect("roots made for every receiver");
                    let (u, v, depth) = face.project(pos);
                    // The pixel's footprint in root-view coordinates, from the derivatives.
                    let at =
                        |d: Vec3| uv_of(face.clip_from_world * (pos + d).as_dvec3().extend(1.0));
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
                        out.push(probe);
                        continue;
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
                    out.push(probe);
                }
                out
            })
            .collect();
        chunks.concat()
    }

    /// Section 4.2's shadow test for every pixel; returns the visibility and the leaves
    /// each row used.
    fn lookup(&self, frame: &Frame, p: &Params) -> (Vec<Vec3>, Vec<u32>) {
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let rows: Vec<(Vec<Vec3>, Vec<u32>)> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut vals = Vec::with_capacity(w as usize);
                let mut used: Vec<u32> = Vec::new();
                // The last leaf found (Section 4.3): most neighbours fall in it too.
                let mut cache: Option<(usize, u32)> = None;
                for x in 0..w {
                    let k = (y * w + x) as usize;
                    if !frame.receiver_lit(k) {
                        vals.push(if view.covered(k) {
                            Vec3::ZERO
                        } else {
                            Vec3::ONE
                        });
                        continue;
                    }
                    let pos = view.position[k];
                    let f = self.face_of(frame.light, pos);
                    let face = self.faces[f]
                        .as_ref()
                        .expect("roots made for every receiver");
                    let (u, v, depth) = face.project(pos);
                    let cached = cache.filter(|&(cf, s)| {
                        if cf != f {
                            return false;
                        }
                        let n = self.node(s);
                        let (lx, ly) = n.local(u, v, self.scale(face, n.level));
                        n.contains(lx, ly) && n.children[n.cell(lx, ly) as usize] == NO_NODE
                    });
                    let leaf = match cached {
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
            })
            .collect();
        let mut value = Vec::with_capacity((w * h) as usize);
        let mut used = Vec::new();
        for (v, u) in rows {
            value.extend(v);
            used.extend(u);
        }
        (value, used)
    }

    /// One refinement pass over the candidate `cells` (with their benefits): takes them by
    /// decreasing benefit over cost while `budget` allows, evicting to stay within the
    /// memory budget, and renders the new tiles together. Returns the new nodes.
    fn refine(
        &mut self,
        frame: &Frame,
        p: &Params,
        cost: CostModel,
        cells: &BTreeMap<(u32, u32), u32>,
        now: u64,
        budget: &mut RefineBudget,
    ) -> Vec<u32> {
        let texels = p.tile_resolution as u64 * p.tile_resolution as u64;
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
            let ra = a.benefit as f64 / a.cost_ms.max(1e-12);
            let rb = b.benefit as f64 / b.cost_ms.max(1e-12);
            rb.total_cmp(&ra)
                .then(b.benefit.cmp(&a.benefit))
                .then(a.node.cmp(&b.node))
                .then(a.cell.cmp(&b.cell))
        });
        let bytes_budget = (p.budget_mb * MIB) as u64;
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
            let mut fits = true;
            while self.bytes + need > bytes_budget {
                match self.pick_victim(now, Some(c.node), Some(c.benefit as f32)) {
                    Some(s) => {
                        self.evict(s);
                        budget.evicted += 1;
                    }
                    None => {
                        fits = false;
                        break;
                    }
                }
            }
            if !fits {
                // Every later candidate has no greater benefit and the same size.
                break;
            }
            pending.push(self.add_child(c.node, c.cell, now, c.benefit as f32));
            budget.made += 1;
            budget.spent_ms += c.cost_ms;
        }
        // Render the new tiles together.
        let jobs: Vec<(u8, f64, f64, f64)> = pending
            .iter()
            .map(|&s| {
                let n = self.node(s);
                let face = self.faces[n.face as usize]
                    .as_ref()
                    .expect("node of a live face");
                let e = self.scale(face, n.level);
                (n.face, n.x0 as f64 / e, n.y0 as f64 / e, n.res as f64 / e)
            })
            .collect();
        let tiles: Vec<(Vec<f32>, Vec<u32>)> = jobs
            .par_iter()
            .map(|&(f, u0, v0, size)| {
                let face = self.faces[f as usize]
                    .as_ref()
                    .expect("node of a live face");
                render_tile(frame.scene, face, u0, v0, size, p.tile_resolution)
            })
            .collect();
        for (&s, (depth, id)) in pending.iter().zip(tiles) {
            let n = self.node_mut(s);
            n.depth = depth;
            n.id = id;
        }
        pending
    }

    /// Bytes held.
    fn memory_bytes(&self) -> u64 {
        self.bytes + self.culling_bytes()
    }

    /// Bytes held by the per-root-cell triangle lists.
    fn culling_bytes(&self) -> u64 {
        self.faces.iter().flatten().map(Face::bins_bytes).sum()
    }

    fn live_nodes(&self) -> impl Iterator<Item = &Node> {
        self.nodes.iter().flatten()
    }
}

/// The root-view image rectangle `[u0, u1] × [v0, v1]` covered by the part of a
/// triangle (clip-space vertices `c`) in front of the near plane, or `None` when no part
/// is; the clipping matches the rasterizer's, so the rectangle bounds what it covers.
fn clipped_uv_bounds(c: [Vec4; 3]) -> Option<[f32; 4]> {
    if !c.iter().all(|c| c.is_finite()) {
        return None;
    }
    let mut pts = [Vec4::ZERO; 4];
    let mut n = 0;
    for i in 0..3 {
        let (a, b) = (c[i], c[(i + 1) % 3]);
        if a.z >= 0.0 {
            pts[n] = a;
            n += 1;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            // Computed from the inside vertex, as the rasterizer does.
            let (i, o) = if a.z >= 0.0 { (a, b) } else { (b, a) };
            pts[n] = i + (o - i) * (i.z / (i.z - o.z));
            n += 1;
        }
    }
    let mut r = [
        f32::INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NEG_INFINITY,
    ];
    for p in &pts[..n] {
        if p.w <= 0.0 {
            // On the light's eye plane itself: unbounded.
            return Some([
                f32::NEG_INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::INFINITY,
            ]);
        }
        let u = p.x / p.w * 0.5 + 0.5;
        let v = 0.5 - p.y / p.w * 0.5;
        r = [r[0].min(u), r[1].min(v), r[2].max(u), r[3].max(v)];
    }
    (n >= 3).then_some(r)
}

/// Lists, per root cell of `face`, the triangles whose projection overlaps it.
fn bin_triangles(scene: &Scene, face: &Face) -> Vec<Vec<u32>> {
    let g = face.grid as usize;
    let m = face.view.clip_from_world;
    let margin = 1.0 / MAX_EFFECTIVE_RESOLUTION as f32;
    // Cell ranges per triangle, computed in parallel and filled in triangle order.
    let ranges: Vec<Option<[u32; 4]>> = (0..scene.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let [u0, v0, u1, v1] = clipped_uv_bounds(scene.triangle(i).map(|p| m * p.extend(1.0)))?;
            if !(u1 >= -margin && v1 >= -margin && u0 <= 1.0 + margin && v0 <= 1.0 + margin) {
                return None;
            }
            let cell = |x: f32| ((x * g as f32).floor() as i64).clamp(0, g as i64 - 1) as u32;
            Some([
                cell(u0 - margin),
                cell(v0 - margin),
                cell(u1 + margin),
                cell(v1 + margin),
            ])
        })
        .collect();
    let mut bins = vec![Vec::new(); g * g];
    for (i, r) in ranges.into_iter().enumerate() {
        if let Some([x0, y0, x1, y1]) = r {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    bins[y as usize * g + x as usize].push(i as u32);
                }
            }
        }
    }
    for b in &mut bins {
        b.shrink_to_fit();
    }
    bins
}

/// The clip-space scale and translation that maps the root-view square
/// `[u0, u0 + size] × [v0, v0 + size]` onto the whole target.
fn tile_from_root(u0: f64, v0: f64, size: f64) -> DMat4 {
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

/// Renders the root-view square `[u0, u0 + size] × [v0, v0 + size]` of `face` into a
/// `res × res` tile of linear depths and triangle ids, with only the triangles whose
/// projection overlaps it.
fn render_tile(
    scene: &Scene,
    face: &Face,
    u0: f64,
    v0: f64,
    size: f64,
    res: u32,
) -> (Vec<f32>, Vec<u32>) {
    let m = face.view.clip_from_world;
    let selection: Vec<u32> = if size >= 1.0 {
        (0..scene.len() as u32).collect()
    } else {
        // A non-root node lies inside one root cell.
        let g = face.grid as f64;
        let gx = (((u0 + 0.5 * size) * g).floor() as i64).clamp(0, face.grid as i64 - 1) as usize;
        let gy = (((v0 + 0.5 * size) * g).floor() as i64).clamp(0, face.grid as i64 - 1) as usize;
        // One texel of margin: the rasterizer samples texel centres, so a triangle whose
        // box ends outside the square by less than that cannot cover one, but rounding can.
        let margin = size / res as f64;
        let (lo_u, hi_u, lo_v, hi_v) = (
            u0 - margin,
            u0 + size + margin,
            v0 - margin,
            v0 + size + margin,
        );
        face.bins[gy * face.grid as usize + gx]
            .iter()
            .copied()
            .filter(|&t| {
                clipped_uv_bounds(scene.triangle(t as usize).map(|p| m * p.extend(1.0)))
                    .is_some_and(|[u0, v0, u1, v1]| {
                        u1 as f64 >= lo_u
                            && u0 as f64 <= hi_u
                            && v1 as f64 >= lo_v
                            && v0 as f64 <= hi_v
                    })
            })
            .collect()
    };
    let clip_from_world: Mat4 = (tile_from_root(u0, v0, size) * m.as_dmat4()).as_mat4();
    let light_from_world = face.view.light_from_world;
    let setups = raster::setup(selection.len(), res, res, |i| {
        let t = scene.triangle(selection[i] as usize);
        (
            t.map(|p| clip_from_world * p.extend(1.0)),
            t.map(|p| -light_from_world.transform_point3(p).z),
        )
    });
    let buf = raster::depth_buffer(&setups, res, res);
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

/// Times tile renders of the busiest root cells of the first root at two resolutions and
/// fits `a·N + b`.
fn calibrate(scene: &Scene, tree: &Tree) -> CostModel {
    let Some(face) = tree.faces.iter().flatten().next() else {
        return CostModel { a: 0.0, b: 0.0 };
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
            for _ in 0..CALIBRATION_REPEATS {
                let t0 = Instant::now();
                std::hint::black_box(render_tile(
                    scene,
                    face,
                    gx / g as f64,
                    gy / g as f64,
                    1.0 / g as f64,
                    res,
                ));
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

    fn cost_model(&mut self, scene: &Scene) -> CostModel {
        let p = &self.params;
        if let (Some(a), Some(b)) = (p.cost_per_texel_ns, p.cost_per_tile_ms) {
            return CostModel { a: a * 1e-6, b };
        }
        let measured = match self.cost {
            Some(c) => c,
            None => {
                let c = calibrate(
                    scene,
                    self.tree.as_ref().expect("tree made before calibration"),
                );
                self.cost = Some(c);
                c
            }
        };
        CostModel {
            a: p.cost_per_texel_ns.map_or(measured.a, |a| a * 1e-6),
            b: p.cost_per_tile_ms.unwrap_or(measured.b),
        }
    }

    fn write_dump(&self, frame: &Frame) -> Result<()> {
        let Some(tree) = &self.tree else {
            return Ok(());
        };
        for (f, face) in tree.faces.iter().enumerate() {
            let Some(face) = face else { continue };
            let root = tree.node(face.root);
            let map = DepthBuffer {
                width: root.res,
                height: root.res,
                depth: root.depth.clone(),
                id: root.id.clone(),
            };
            frame.dump_depth(&format!("asm-face{f}-root.png"), &map)?;
            // The tile tree: node outlines over the root map, brighter for deeper levels.
            const SIDE: u32 = 1024;
            let mut img = crate::picture::RgbImage::from_fn(SIDE, SIDE, |x, y| {
                let tx = (x as u64 * root.res as u64 / SIDE as u64) as u32;
                let ty = (y as u64 * root.res as u64 / SIDE as u64) as u32;
                let g = if root.depth[(ty * root.res + tx) as usize].is_finite() {
                    60
                } else {
                    20
                };
                image::Rgb([g, g, g])
            });
            for n in tree
                .live_nodes()
                .filter(|n| n.face as usize == f && n.level > 0)
            {
                let e = tree.scale(face, n.level);
                let to_px = |t: u32| ((t as f64 / e) * SIDE as f64) as u32;
                let (x0, y0) = (to_px(n.x0).min(SIDE - 1), to_px(n.y0).min(SIDE - 1));
                let (x1, y1) = (
                    to_px(n.x0 + n.res).min(SIDE - 1),
                    to_px(n.y0 + n.res).min(SIDE - 1),
                );
                let c = LEVEL_COLOURS[(n.level as usize - 1) % LEVEL_COLOURS.len()];
                crate::picture::outline_rect(&mut img, x0, y0, x1, y1, c);
            }
            frame.dump_image(&format!("asm-face{f}-tree.png"), || img)?;
        }
        Ok(())
    }
}

/// Outline colours of the tree picture, by level.
const LEVEL_COLOURS: [[u8; 3]; 6] = [
    [70, 130, 255],
    [60, 200, 90],
    [240, 220, 60],
    [255, 140, 40],
    [240, 50, 50],
    [230, 80, 230],
];

impl ShadowTechnique for Adaptive {
    fn name(&self) -> &'static str {
        "asm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let p = &self.params;
        let opt = |v: Option<f64>, word: &str| {
            v.map_or(serde_json::Value::from(word), serde_json::Value::from)
        };
        BTreeMap::from([
            ("root-resolution".to_string(), p.root_resolution.into()),
            ("tile-resolution".to_string(), p.tile_resolution.into()),
            ("cells".to_string(), p.cells.into()),
            ("budget-mb".to_string(), p.budget_mb.into()),
            ("analysis-fraction".to_string(), p.analysis_fraction.into()),
            ("time-budget-ms".to_string(), opt(p.time_budget_ms, "none")),
            ("max-new-nodes".to_string(), p.max_new_nodes.into()),
            ("passes".to_string(), p.passes.into()),
            ("oversampling".to_string(), p.oversampling.into()),
            ("bias".to_string(), p.bias.into()),
            ("slope-bias".to_string(), p.slope_bias.into()),
            (
                "cost-per-texel-ns".to_string(),
                opt(p.cost_per_texel_ns, "auto"),
            ),
            (
                "cost-per-tile-ms".to_string(),
                opt(p.cost_per_tile_ms, "auto"),
            ),
        ])
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "asm";
        let mut p = self.params.clone();
        match key {
            "root-resolution" => {
                p.root_resolution = power_of_two(key, value, 16, raster::MAX_RASTER_SIDE)?
            }
            "tile-resolution" => p.tile_resolution = power_of_two(key, value, 8, 2048)?,
            "cells" => p.cells = power_of_two(key, value, 2, 64)?,
            "budget-mb" => {
                p.budget_mb = check_range(t, key, parse_value(t, key, value)?, 0.01, 1.0e6)?
            }
            "analysis-fraction" => {
                let f: f64 = parse_value(t, key, value)?;
                if !(f > 0.0 && f <= 1.0) {
                    return Err(Error::param(format!(
                        "parameter asm.{key} = {value} is outside its range (0, 1]"
                    )));
                }
                p.analysis_fraction = f;
            }
            "time-budget-ms" => p.time_budget_ms = parse_optional(key, value, "none", 0.0, 1.0e7)?,
            "max-new-nodes" => {
                p.max_new_nodes = check_range(t, key, parse_value(t, key, value)?, 0, 1_000_000)?
            }
            "passes" => p.passes = check_range(t, key, parse_value(t, key, value)?, 1, 64)?,
            "oversampling" => {
                p.oversampling = check_range(t, key, parse_value(t, key, value)?, 0.01, 1024.0)?
            }
            "bias" => p.bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?,
            "slope-bias" => {
                p.slope_bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?
            }
            "cost-per-texel-ns" => {
                p.cost_per_texel_ns = parse_optional(key, value, "auto", 0.0, 1.0e9)?
            }
            "cost-per-tile-ms" => {
                p.cost_per_tile_ms = parse_optional(key, value, "auto", 0.0, 1.0e7)?
            }
            _ => return Err(unknown_param(t, key, KNOWN)),
        }
        // The tree's shape depends on these; a change starts a new one.
        let reshaped = p.root_resolution != self.params.root_resolution
            || p.tile_resolution != self.params.tile_resolution
            || p.cells != self.params.cells;
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
        let views = light_views(
            frame.light,
            &frame.scene.bounds,
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        p.check_structure(views.len())?;
        let mut stats = Stats::default();
        self.frame += 1;
        let now = self.frame;
        let fingerprint = Fingerprint::of(frame);
        if self
            .tree
            .as_ref()
            .is_none_or(|t| t.fingerprint != fingerprint)
        {
            self.tree = Some(Tree::new(fingerprint, views, &p));
            self.cost = None;
            self.quiet_frames = 0;
        }
        {
            let tree = self.tree.as_mut().expect("tree made above");
            stats.stage("roots", || tree.ensure_roots(frame, &p, now))?;
        }
        let cost = if p.time_budget_ms.is_some() {
            stats.stage("calibrate", || self.cost_model(frame.scene))
        } else {
            CostModel { a: 0.0, b: 0.0 }
        };
        let tree = self.tree.as_mut().expect("tree made above");
        let (mut analysis_ms, mut refine_ms) = (0.0, 0.0);
        let t0 = Instant::now();
        let (pixels, period) = Tree::analysis_pixels(frame, &p, now);
        let mut probes = tree.analyse(frame, &p, &pixels);
        analysis_ms += t0.elapsed().as_secs_f64() * 1e3;

        // Each leaf's benefit: the analysed mismatches it resolves, averaged over a period.
        let mut served = vec![0u32; tree.nodes.len()];
        for pr in probes.iter().filter(|pr| pr.serves) {
            served[pr.leaf as usize] += 1;
        }
        for (n, &c) in tree.nodes.iter_mut().zip(&served) {
            if let Some(n) = n {
                n.benefit += (c as f32 - n.benefit) / period as f32;
            }
        }
        let mut last = NO_NODE;
        for pr in &probes {
            if pr.leaf != last {
                tree.touch(pr.leaf, now);
                last = pr.leaf;
            }
        }
        let benefit_pixels = probes.iter().filter(|pr| pr.candidate).count();

        // Refinement passes: the most profitable cells first, within the time and memory
        // budgets; the pixels whose cells were refined are examined again in the new nodes.
        let mut budget = RefineBudget::default();
        let mut candidate_cells = 0;
        let mut passes = 0;
        while passes < p.passes {
            let mut cells: BTreeMap<(u32, u32), u32> = BTreeMap::new();
            for pr in probes.iter().filter(|pr| pr.candidate) {
                *cells.entry((pr.leaf, pr.cell)).or_default() += 1;
            }
            if passes == 0 {
                candidate_cells = cells.len();
            }
            if cells.is_empty() {
                break;
            }
            let t0 = Instant::now();
            let made = tree.refine(frame, &p, cost, &cells, now, &mut budget);
            refine_ms += t0.elapsed().as_secs_f64() * 1e3;
            passes += 1;
            if made.is_empty() || passes == p.passes {
                break;
            }
            let t0 = Instant::now();
            let refined: std::collections::BTreeSet<(u32, u32)> = made
                .iter()
                .map(|&s| {
                    let n = tree.node(s);
                    (n.parent, n.parent_cell)
                })
                .collect();
            let again: Vec<u32> = probes
                .iter()
                .filter(|pr| pr.candidate && refined.contains(&(pr.leaf, pr.cell)))
                .map(|pr| pr.pixel)
                .collect();
            probes = tree.analyse(frame, &p, &again);
            analysis_ms += t0.elapsed().as_secs_f64() * 1e3;
        }
        stats.stages_ms.push(("analysis".into(), analysis_ms));
        stats.stages_ms.push(("refine".into(), refine_ms));
        let (made, evicted, predicted_ms) = (budget.made, budget.evicted, budget.spent_ms);
        self.period = period as u32;
        self.quiet_frames = if made == 0 && evicted == 0 {
            self.quiet_frames + 1
        } else {
            0
        };

        let (value, used) = stats.stage("lookup", || tree.lookup(frame, &p));
        let mut used_finest = 0f64;
        for s in used {
            tree.touch(s, now);
            let n = tree.node(s);
            let face = tree.faces[n.face as usize]
                .as_ref()
                .expect("node of a live face");
            used_finest = used_finest.max(tree.scale(face, n.level));
        }

        let mut finest = 0f64;
        let mut per_level: Vec<u64> = Vec::new();
        for n in tree.live_nodes() {
            let face = tree.faces[n.face as usize]
                .as_ref()
                .expect("node of a live face");
            finest = finest.max(tree.scale(face, n.level));
            if per_level.len() <= n.level as usize {
                per_level.resize(n.level as usize + 1, 0);
            }
            per_level[n.level as usize] += 1;
        }
        let levels = per_level.len();
        for (l, &c) in per_level.iter().enumerate() {
            stats.count(&format!("nodes_level_{l}"), c as f64);
        }
        stats.memory_bytes = tree.memory_bytes();
        stats.count("tree_bytes", tree.bytes as f64);
        stats.count("culling_bytes", tree.culling_bytes() as f64);
        stats.count("nodes", tree.live_nodes().count() as f64);
        stats.count("budget_bytes", (p.budget_mb * MIB).floor());
        stats.count("effective_resolution", finest);
        stats.count("effective_resolution_used", used_finest);
        stats.count("levels", levels as f64);
        stats.count("cells_refined", made as f64);
        stats.count("nodes_evicted", evicted as f64);
        stats.count("candidate_cells", candidate_cells as f64);
        stats.count("refine_passes", passes as f64);
        stats.count("analysed_pixels", pixels.len() as f64);
        stats.count("benefit_pixels", benefit_pixels as f64);
        stats.count("predicted_refine_ms", predicted_ms);
        if p.time_budget_ms.is_some() {
            stats.count("cost_per_texel_ns", cost.a * 1e6);
            stats.count("cost_per_tile_ms", cost.b);
        }
        if frame.dumping() {
            self.write_dump(frame)?;
        }
        Ok(Shadows {
            visibility: Visibility {
                width: frame.view.width,
                height: frame.view.height,
                value,
            },
            stats,
            layers: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::math::vec3;
    use crate::scene::Material;
    use crate::techniques::shadow_map::render_depth_map;
    use crate::view::ViewSamples;

    /// A ground quad under a few tilted triangles at different heights.
    fn small_scene() -> Scene {
        let mut tris = vec![
            [
                vec3(-4.0, 0.0, -4.0),
                vec3(4.0, 0.0, 4.0),
                vec3(4.0, 0.0, -4.0),
            ],
            [
                vec3(-4.0, 0.0, -4.0),
                vec3(-4.0, 0.0, 4.0),
                vec3(4.0, 0.0, 4.0),
            ],
        ];
        for i in 0..12 {
            let a = i as f32 * 0.7;
            let c = vec3(2.0 * a.cos(), 0.5 + 0.15 * i as f32, 2.0 * a.sin());
            tris.push([c, c + vec3(0.9, 0.2, 0.1), c + vec3(0.2, -0.1, 0.8)]);
        }
        Scene::from_triangles(tris, Material::default()).unwrap()
    }

    fn face(scene: &Scene, light: &Light, res: u32, tile: u32, cells: u32) -> Face {
        let lv = light_views(light, &scene.bounds, &scene.bounds, DIRECTIONAL_PAD)[0];
        let mut f = Face {
            view: lv,
            clip_from_world: lv.clip_from_world.as_dmat4(),
            resolution: res,
            root: NO_NODE,
            grid: res / (tile / cells),
            bins: Vec::new(),
        };
        f.bins = bin_triangles(scene, &f);
        f
    }

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
                let (depth, id) = render_tile(
                    &scene,
                    &f,
                    x0 as f64 / e as f64,
                    y0 as f64 / e as f64,
                    32.0 / e as f64,
                    32,
                );
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

    #[test]
    fn locate_finds_the_deepest_node_covering_a_point() {
        let scene = small_scene();
        let light = Light::Directional { to_light: Vec3::Y };
        let p = Params {
            root_resolution: 64,
            tile_resolution: 32,
            cells: 4,
            ..Params::default()
        };
        let fp = Fingerprint {
            name: String::new(),
            triangles: scene.len(),
            revision: scene.revision,
            bounds: scene.bounds,
            light,
        };
        let views = light_views(&light, &scene.bounds, &scene.bounds, DIRECTIONAL_PAD);
        let mut tree = Tree::new(fp, views, &p);
        let mut f = face(&scene, &light, 64, 32, 4);
        f.root = tree.insert(Node {
            face: 0,
            level: 0,
            x0: 0,
            y0: 0,
            res: 64,
            cells: f.grid,
            parent: NO_NODE,
            parent_cell: 0,
            serial: 0,
            children: vec![NO_NODE; (f.grid * f.grid) as usize],
            live_children: 0,
            depth: Vec::new(),
            id: Vec::new(),
            stamp: 0,
            created: 0,
            benefit: 0.0,
        });
        // A pseudo-random refinement, three levels deep.
        let mut state = 12345u64;
        let mut next = |n: u32| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) % n as u64) as u32
        };
        let mut frontier = vec![f.root];
        for _ in 0..3 {
            let mut children = Vec::new();
            for &s in &frontier {
                let cells = tree.node(s).cells;
                for _ in 0..3 {
                    let c = next(cells * cells);
                    if tree.node(s).children[c as usize] == NO_NODE {
                        children.push(tree.add_child(s, c, 0, 0.0));
                    }
                }
            }
            frontier = children;
        }
        tree.faces[0] = Some(f);
        let f = tree.faces[0].as_ref().unwrap();
        for _ in 0..20000 {
            let (u, v) = (
                next(1 << 20) as f64 / (1 << 20) as f64,
                next(1 << 20) as f64 / (1 << 20) as f64,
            );
            let mut best: Option<(u8, u32)> = None;
            for (s, n) in tree.nodes.iter().enumerate() {
                let Some(n) = n else { continue };
                let e = tree.scale(f, n.level);
                let (lx, ly) = n.local(u, v, e);
                if n.contains(lx, ly) && best.is_none_or(|b| n.level > b.0) {
                    best = Some((n.level, s as u32));
                }
            }
            assert_eq!(tree.locate(f, u, v), best.unwrap().1, "at ({u}, {v})");
        }
    }

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
