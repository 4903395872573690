//! `gpu:asm`: adaptive shadow maps (Fernando, Fernandez, Bala and Greenberg, SIGGRAPH 2001)
//! as GPUs build them today, as virtual shadow maps: the twin of the library's `asm`.
//!
//! Each light view (one for directional and spot lights, six cube faces for a point light)
//! has a virtual map far larger than memory, whose mip levels play the paper's hierarchy
//! levels: level `levels - 1`, the coarsest, has the CPU's root resolution and is always
//! resident; each finer level doubles it, down to level 0 at [`REFINED_LEVELS`] doublings
//! (65536² texels for a 512² root). Every level is cut into pages of `tile-resolution`
//! texels; a page table (4 bytes a page of every level and view, coarsest level first) maps
//! the resident ones to slots of a physical pool, one atlas of triangle ids within
//! `budget-mb`.
//!
//! # A frame
//! Up to `passes` times:
//! 1. **analysis** (`analysis.wgsl`, the paper's resolution analysis, Sections 3.1, 4.1):
//!    every lit receiver projects its pixel's footprint (the camera pass's derivatives)
//!    into its view and finds the level whose texels are `oversampling` times finer across;
//!    it reads the finest resident page over it, stamps that page's slot with the frame's
//!    clock, and where that page is coarser than wanted and the 2×2 texels around the
//!    receiver disagree on its shadow test (it straddles a boundary), requests the page one
//!    level finer. Requests come back as a set, each with its benefit (the paper's: the
//!    requesting receivers, mismatched pixels that straddle a boundary).
//! 2. **allocate** (`allocate.wgsl` and `pool`): the requests, by decreasing benefit
//!    (ties in table order, coarsest level first), take free slots, then the least
//!    recently read slots not read this frame (LRU eviction; ties by slot), at most
//!    `max-new-nodes` a frame; the page table gets the new entries and loses the evicted
//!    ones, and the new pages are emptied.
//! 3. **render** (`render.wgsl`): the hardware rasterizer draws each new page into its slot
//!    (one render pass, a viewport a page) through the page's own `clip_from_world`,
//!    keeping the nearest triangle's id; a page draws only the triangles of its cell, a
//!    page of the coarsest level, whose list (the paper's culling, Section 4.3) is made
//!    once per map (`culling`).
//!
//! Then **lookup** (`lookup.wgsl`): every receiver reads the finest resident page over it
//! and applies Section 4.2's test: lit when the texel holds its own triangle, else when the
//! texel's triangle lies no more than the bias of that level's texel in front of it along
//! its shadow ray. A pass that allocates nothing ends the frame's refinement.
//!
//! Pages live across frames: a walkthrough (`render --frames N`) starts each frame from the
//! pages the last left, so it refines instead of starting over. A different scene or light,
//! or a change of `root-resolution`, `tile-resolution` or `budget-mb`, empties the map.
//!
//! # Parameters (the CPU `asm`'s table and defaults), read for a virtual map
//! - `root-resolution`: the coarsest level's side (a point light's faces get half, as on
//!   the CPU), always resident: it must fit the budget. `tile-resolution`: the page side,
//!   which must divide it. `budget-mb`: the pool (4 bytes a texel); `memory_bytes` is the
//!   pool. The page table with its request counts, and the render pass's depth buffer (of
//!   the pool's size), are counted apart (`page_table_bytes`, `scratch_bytes`).
//! - `max-new-nodes`: new pages a frame at most; `passes`: analysis rounds a frame;
//!   `oversampling`, `bias`, `slope-bias`: as on the CPU, the bias in texels of the level
//!   read.
//! - Read differently: `cells` only has to divide `tile-resolution` as on the CPU; a level
//!   refines texels by 2 (a mip chain), not by `cells`. `analysis-fraction` is not read:
//!   every pixel is analysed in every pass, one compute dispatch where the CPU spreads its
//!   work over frames. `time-budget-ms` and the cost terms are not read: the GPU draws
//!   every page it allocates (capped by `max-new-nodes`) instead of spending a predicted
//!   time.
//!
//! # Departures from the CPU twin
//! - The hierarchy: mip levels of pages refining by 2 where the CPU's nodes refine by
//!   `cells`; a receiver asks for the page one level finer than it reads, where the CPU
//!   refines cells ranked by benefit over cost; LRU eviction alone, where the CPU also
//!   keeps leaves of greater benefit when all are in use. The finest level is
//!   [`REFINED_LEVELS`] doublings above the root where the CPU goes to 2²⁰ texels: the page
//!   table is dense (4 bytes a page at every level, and as much again for the requests'
//!   counts).
//! - The pool keeps triangle ids alone (4 bytes a texel where the CPU keeps a depth and an
//!   id, 8), so a budget holds twice the texels: a texel's depth is that of its triangle's
//!   plane where the receiver's shadow ray meets it, rather than the depth at the texel's
//!   centre. This drops the depth sampling error of the paper's test (the plane is exact
//!   where the triangle covers the ray) and keeps its bias for the rest.
//! - Every pixel is analysed in each pass, and the pages are drawn by the hardware
//!   rasterizer, which rounds coverage a little differently from the library's.
//!
//! So images differ from the CPU's, and the verdict tests judge the error against the
//! ray-traced reference with the bounds they name. Results are bit-identical across runs:
//! the requests are a set with order-independent counts, and slots are given by benefit,
//! ties in table order.

mod culling;
mod dump;
mod passes;
mod pool;
mod run;

use crate::compute::{pipeline, render_pipeline, to_rgb};
use crate::device::{shared, Gpu};
use crate::shader::{Common, Stage, ALPHA_MASK, LIGHT, RAY_OFFSET, TRIANGLES};
use crate::transfer::{output, read_back, storage, Timer};
use crate::upload::{view_buffer, LightU, SceneBuffers, SceneKey};
use pool::{Layout, Pool};
use shadowlab::error::{Error, Result};
use shadowlab::light::{light_views, Light, LightView};
use shadowlab::techniques::adaptive::Adaptive;
use shadowlab::techniques::shadow_map::DIRECTIONAL_PAD;
use shadowlab::techniques::{Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use std::collections::BTreeMap;
use std::sync::Arc;

/// `gpu:asm`'s name.
pub const NAME: &str = "gpu:asm";

/// Mip levels finer than the root: the finest level is the root side times 2^this.
pub const REFINED_LEVELS: u32 = 7;
// `pages.wgsl` keeps each level's first table entry in eight words.
const _: () = assert!(REFINED_LEVELS < 8);

const WORKGROUP: u32 = 64;

/// Bytes of a pool texel: a 32-bit triangle id.
const TEXEL_BYTES: u64 = 4;

// The stage names carry the folder: the device keeps pipelines by stage name and entry
// point, and `gpu:sm` has a `lookup.wgsl` of its own.
const PAGES: Common = Common {
    name: "adaptive/pages.wgsl",
    source: include_str!("pages.wgsl"),
};

const ANALYSIS: Stage = Stage {
    name: "adaptive/analysis.wgsl",
    common: &[RAY_OFFSET, LIGHT, PAGES],
    source: include_str!("analysis.wgsl"),
};

const ALLOCATE: Stage = Stage {
    name: "adaptive/allocate.wgsl",
    common: &[],
    source: include_str!("allocate.wgsl"),
};

const RENDER: Stage = Stage {
    name: "adaptive/render.wgsl",
    common: &[ALPHA_MASK, TRIANGLES],
    source: include_str!("render.wgsl"),
};

const LOOKUP: Stage = Stage {
    name: "adaptive/lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT, PAGES],
    source: include_str!("lookup.wgsl"),
};

/// The scene on one device, with the pipelines.
struct Resident {
    key: SceneKey,
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    analysis: wgpu::ComputePipeline,
    tally: wgpu::ComputePipeline,
    apply: wgpu::ComputePipeline,
    clear: wgpu::ComputePipeline,
    render: wgpu::RenderPipeline,
    lookup: wgpu::ComputePipeline,
}

/// What the virtual map was made for: a change empties it.
#[derive(Clone, Debug, PartialEq)]
struct Shape {
    light: Light,
    views: Vec<LightView>,
    layout: Layout,
    slots: u32,
}

/// The virtual map kept between frames: the page table, the pool and its LRU mirror.
struct State {
    shape: Shape,
    layout: Layout,
    views: Vec<LightView>,
    pool: Pool,
    /// Pages a row of the pool atlas.
    cols: u32,
    faces: wgpu::Buffer,
    table: wgpu::Buffer,
    flags: wgpu::Buffer,
    slot_used: wgpu::Buffer,
    id: wgpu::Texture,
    scratch: wgpu::Texture,
    /// Section 4.3's culling lists: the offsets on the CPU, the triangles uploaded.
    culling: culling::Culling,
    cull: wgpu::Buffer,
    /// Bytes of the table and the requests' counts.
    table_bytes: u64,
}

/// The parameters `gpu:asm` reads, from its twin's table.
struct Params {
    root: u32,
    tile: u32,
    cells: u32,
    budget_mb: f64,
    max_new: u32,
    passes: u32,
    oversampling: f32,
    bias: f32,
    slope_bias: f32,
}

impl Params {
    fn of(cpu: &Adaptive) -> Result<Self> {
        let map = cpu.params();
        let num = |k: &str| {
            map.get(k)
                .and_then(serde_json::Value::as_f64)
                .ok_or_else(|| Error::Internal(format!("{NAME}: asm has no number {k}")))
        };
        Ok(Params {
            root: num("root-resolution")? as u32,
            tile: num("tile-resolution")? as u32,
            cells: num("cells")? as u32,
            budget_mb: num("budget-mb")?,
            max_new: num("max-new-nodes")? as u32,
            passes: num("passes")? as u32,
            oversampling: num("oversampling")? as f32,
            bias: num("bias")? as f32,
            slope_bias: num("slope-bias")? as f32,
        })
    }

    /// The virtual map's layout for `faces` views, checked as the CPU checks its tree.
    fn layout(&self, faces: u32) -> Result<Layout> {
        let root = if faces > 1 {
            (self.root / 2).max(1)
        } else {
            self.root
        };
        if self.cells == 0 || !self.tile.is_multiple_of(self.cells) {
            return Err(Error::param(format!(
                "{NAME}.cells = {} must divide {NAME}.tile-resolution = {}",
                self.cells, self.tile
            )));
        }
        if root < self.tile || !root.is_multiple_of(self.tile) {
            return Err(Error::param(format!(
                "{NAME}.root-resolution = {} gives views of {root} texels, which pages of \
                 {NAME}.tile-resolution = {} texels must divide",
                self.root, self.tile
            )));
        }
        // Every level's pages, a quarter of the finer's: at most 4/3 of the finest's.
        let finest = u64::from(root / self.tile) << REFINED_LEVELS;
        let entries = u64::from(faces) * finest * finest * 4 / 3;
        if entries > u64::from(u32::MAX / 4) {
            return Err(Error::Limit(format!(
                "{NAME}.root-resolution = {} over pages of {NAME}.tile-resolution = {} texels \
                 needs a page table of {entries} entries, past the {} a table may hold; lower \
                 {NAME}.root-resolution or raise {NAME}.tile-resolution",
                self.root,
                self.tile,
                u32::MAX / 4
            )));
        }
        Ok(Layout {
            page: self.tile,
            levels: REFINED_LEVELS + 1,
            side: root << REFINED_LEVELS,
            faces,
        })
    }
}

/// Adaptive shadow maps as a virtual shadow map; the CPU `asm`'s parameters.
#[derive(Default)]
pub struct GpuAdaptive {
    cpu: Adaptive,
    resident: Option<Resident>,
    state: Option<State>,
    /// Frames rendered (the LRU's clock).
    now: u32,
    /// True when the last frame drew and evicted no page.
    quiet: bool,
}
