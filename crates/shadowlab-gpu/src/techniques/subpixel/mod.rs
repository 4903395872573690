//! `gpu:subpixel`: fast sub-pixel anti-aliased shadow maps (Pan, Wang, Chen, Zhou and
//! Bao, Pacific Graphics 2009, who ran it on a GPU) as compute shaders, twin of the
//! library's `subpixel` with its parameters, meanings and defaults (`samples` 1–128,
//! default 32; `pattern`; `resolution` 1024; `bias`, `slope-bias`) and every light it
//! supports (directional, spot, a point light's six cube faces).
//!
//! Stages, one WGSL file each, named as the library's modules and the paper name them:
//! `shadow_map` (`gpu:sm`'s depth stage over the library's light views), `silhouette_edges`
//! (the edges seen from the light as silhouettes, rasterized conservatively with their
//! nearest depth per texel), `silhouette_mask_map` (hidden silhouettes dropped, the
//! summed-area table), `facets` (the cheap bound, then the exact facet of each pixel near a
//! silhouette texel; the rest take the depth-map test), `pairs` (pixel–texel and
//! triangle–texel pairs, counted, scanned and filled per texel slot) and
//! `visibility_evaluation` (per facet, every paired blocker's four half-planes as look-up
//! table bitmasks, the validity mask, alpha-masked blockers tested per sample). The common
//! files `bindings.wgsl`, `rasterization.wgsl`, `ray_plane.wgsl` and `lookup_table.wgsl`
//! mirror the library's modules of those names.
//!
//! Built on the CPU, once, as the CPU technique builds them once: the half-plane look-up
//! table of the pattern and sample count (`subpixel::lookup_table`, uploaded per pattern
//! and count) and the scene's edge adjacency (`subpixel::edge_adjacency`, uploaded per
//! scene).
//!
//! The work is cut so that no invocation loops long: a triangle whose texel rows exceed one
//! block of about 32768 texels (a ground plane under the whole map) is rasterized against
//! the pixels' texels by blocks of rows, one invocation each (`pairs.wgsl`, `big_blocks`),
//! and the visibility evaluation runs one invocation per chunk of at most 64 triangles of
//! one texel against one facet, ORing the occluded and the invalidated samples into the facet's masks
//! (`visibility_evaluation.wgsl`). Software adapters end every loop of an invocation once
//! its loops together have turned 65535 times (Mesa llvmpipe's
//! `LP_MAX_TGSI_LOOP_ITERATIONS`, one count for all the loops of a shader): one invocation
//! a triangle lost the ground plane's pairs past that count, and one a facet lost the last
//! blockers of a facet over a finely tessellated caster, both silently, as lit samples
//! (chess pieces standing on the board were lighter at their bases). On a hardware GPU the
//! same cut spreads a large triangle's or a busy facet's work over many threads.
//!
//! Departures from the CPU twin: the depth map is `gpu:sm`'s (hardware rasterization,
//! depths over the far plane), so the non-silhouette pixels' depth-map test and the
//! hidden-silhouette test see its rounding; the GPU's float arithmetic may contract
//! products into fused multiply-adds, so a facet's corners, its projection and a
//! half-plane's coefficients can differ from the CPU's in the last bits, which moves a
//! sample that lies on a shadow edge to the other side now and then (a triangle is paired
//! with a texel when it is nearer than the farthest facet there by a relative margin of
//! 1e-5, so the rounding never drops a pair the CPU makes). Facets are stored at their
//! pixel's index, texel slots are numbered by an atomic counter and filled in whatever
//! order the threads run; each chunk of a slot's triangles ORs its occlusion and its
//! invalid samples into the facet's masks, so neither which chunk holds which triangle
//! nor the order the chunks run changes a bit of the result. A triangle met through
//! several texels of a facet is evaluated once per texel (the CPU deduplicates; OR and
//! AND make the mask the same).
//! The counts of the triangle–texel pairs are scanned in blocks of 256 slots (for the loop
//! count above), and the shaders index no array or vector by a variable where a loop can
//! be unrolled into calls (a software adapter was seen to compile such indexing
//! differently for different invocations).
//!
//! Counters: `samples`, `silhouette_pixels` (facets built, before the pixel–texel pairs
//! send some back to the depth-map test), `tt_pairs`, `large_triangle_blocks` (the blocks
//! of rows of triangles too large for one invocation), `evaluation_items` (chunks of a
//! texel's triangles against a facet), `hardware_raster`, and the GPU time of each stage
//! (`gpu_STAGE_ms`).

mod kit;
mod run;

use super::maps::MapScene;
use shadowlab::error::{Error, Result};
use shadowlab::sampling::PatternKind;
use shadowlab::techniques::subpixel::{lookup_table, LookupTable, Subpixel, MAX_SAMPLES};
use shadowlab::techniques::{check_range, Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use std::collections::BTreeMap;
use std::sync::Arc;

/// `gpu:subpixel`'s name.
pub const NAME: &str = "gpu:subpixel";

/// The scene on one device: its buffers and its edges.
struct Resident {
    ms: MapScene,
    /// The edges' ends, and whether each has two faces with their opposite vertices.
    edges: [wgpu::Buffer; 2],
    edge_count: u32,
}

/// Sub-pixel anti-aliased shadow maps on the GPU; the CPU `subpixel`'s parameters.
#[derive(Default)]
pub struct GpuSubpixel {
    cpu: Subpixel,
    resident: Option<Resident>,
    lut: Option<(PatternKind, u32, Arc<LookupTable>)>,
}

impl GpuSubpixel {
    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&mut Resident> {
        if self.resident.as_ref().is_none_or(|r| !r.ms.holds(frame)) {
            self.resident = None;
            let ms = MapScene::upload(NAME, frame, stats)?;
            let (edges, edge_count) =
                stats.stage("adjacency", || run::upload_edges(&ms.gpu, frame.scene))?;
            self.resident = Some(Resident {
                ms,
                edges,
                edge_count,
            });
        }
        self.resident
            .as_mut()
            .ok_or_else(|| Error::Internal(format!("{NAME}: the scene was not uploaded")))
    }
}

impl ShadowTechnique for GpuSubpixel {
    fn name(&self) -> &'static str {
        NAME
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        self.cpu.params()
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        self.cpu.param_specs()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        crate::twin::set_twin_param(NAME, &mut self.cpu, key, value)
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let n = check_range(NAME, "samples", self.cpu.samples, 1, MAX_SAMPLES)?;
        let res = shadowlab::techniques::shadow_map::check_resolution(NAME, self.cpu.resolution)?;
        let pattern = self.cpu.pattern;
        if self
            .lut
            .as_ref()
            .is_none_or(|(k, m, _)| *k != pattern || *m != n)
        {
            self.lut = Some((pattern, n, Arc::new(lookup_table(pattern, n)?)));
        }
        let lut = self
            .lut
            .as_ref()
            .map(|l| l.2.clone())
            .ok_or_else(|| Error::Internal(format!("{NAME}: no look-up table")))?;
        let mut stats = Stats::default();
        let cpu = self.cpu.clone();
        let r = self.resident(frame, &mut stats)?;
        let value = run::run(r, frame, &cpu, res, &lut, &mut stats)?;
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
