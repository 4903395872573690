//! `afsm`: alias-free shadow maps (Aila & Laine, "Alias-Free Shadow Maps", EGSR 2004).
//!
//! Idea: the visible samples of the camera pass are transformed to the light's image plane
//! and used as the sampling points of the shadow map, so every sample gets the shadow term
//! of its own shadow ray and there is no map resolution to alias. The samples are organised
//! in an axis-aligned 2D BSP tree and every caster triangle is rasterized hierarchically
//! into it: the traversal descends only into nodes the triangle's light-space footprint
//! overlaps, and in the leaves each sample is tested for coverage and depth, the shadow term
//! going straight to the sample's screen pixel.
//!
//! Steps of a frame, named as the paper names them and timed as its Table 1, one module
//! each (in the order a frame runs them):
//! - *transform* (`transform.rs`, Section 3 "Projection of Sampling Points"): each lit
//!   sample's shadow ray (origin offset by the position's error bound, exactly as the
//!   reference offsets it; `shadow_ray.rs`) is projected to the light's image plane: an
//!   orthographic plane for a directional light, the spot light's own perspective plane, or,
//!   for a point light, the cube face its direction falls on (one BSP per face).
//! - *bsp* (`bsp.rs`, Section 5.1 "Light-Space Hierarchy"): alternating x/y splits at the
//!   median (quickselect, expected linear time) until a leaf holds at most `leaf-size`
//!   samples (64, as in the paper). Every node keeps the tight bounding rectangle of its
//!   samples and their maximum light depth.
//! - *raster* (`raster.rs`, "Rasterization of blockers"): each triangle's footprint
//!   (`setup.rs`: bounding rectangle and three edge functions) and minimum depth cull nodes;
//!   a leaf tests its samples one by one. The paper's occlusion culling: a node whose
//!   samples are all in shadow is skipped by every later triangle, and a triangle beyond a
//!   node's maximum depth skips the node.
//! - `--dump` (`dump.rs`): each plane's samples and BSP leaves, as the paper's Figure 4.
//!
//! The counters follow the paper's Table 1: `bsp_nodes`, `nodes_visited`,
//! `nodes_occlusion_culled`, `samples_tested` (samples not yet dark in the leaves visited),
//! plus `ray_tests` (samples inside a triangle's footprint that took the exact test).
//!
//! Invariants:
//! - The final per-sample decision is the watertight ray–triangle test of
//!   [`crate::math::intersect_triangle`] on the very ray the reference traces (same origin,
//!   direction and length, the sample's own triangle skipped), evaluated with the same
//!   floating-point operations: the answer equals the reference's bit for bit. The
//!   hierarchy only decides which pairs reach that test; every culling test is widened by
//!   [`CULL_TOLERANCE`] so it can never drop a pair the exact test would count.
//! - Semi-transparent casters modulate the sample's RGB transmittance in triangle-index
//!   order and an opaque one sets it to black: the product equals the reference's.
//! - Semi-transparent receivers (Section 4): when the frame carries the layers behind its
//!   semi-transparent surfaces ([`Frame::layers`], every visible surface of each pixel down
//!   to the first opaque one), their samples join the pixels' samples in the same BSP,
//!   each with its own shadow ray and its own shadow term ([`Shadows::layers`]); the image
//!   composites them (`shade::shade_layers`).
//! - The work is split over the subtrees of the BSP (each owns its samples), and each
//!   subtree takes its triangles in index order: results and counters are identical for
//!   any thread count.
//!
//! Departures from the paper:
//! - Coverage in the leaves is decided by the shadow ray's watertight test (the light-space
//!   projection along that very ray) instead of edge functions on the projected image plane,
//!   and the depth comparison by the ray parameter: the paper notes the remaining difference
//!   to shadow rays is only floating-point error; doing the final test on the ray removes it,
//!   so shadows agree with ray tracing exactly and shared edges never leak.
//! - Edge functions are homogeneous (the planes through the light and each triangle edge), so
//!   triangles that cross the plane of a perspective view need no clipping.
//! - This technique does not use the shared rasterizer: its sampling points are irregular,
//!   which is the paper's point; the regular-grid rasterizer cannot sample them.
//! - Point lights get six BSPs (one per cube face); the paper mentions several maps.
//! - A triangle's traversal starts at the deepest node whose subtree holds every sample its
//!   rectangle can contain (found through a uniform grid over the root), not at the root:
//!   small triangles skip the top levels, so fewer nodes are visited than in a root-first
//!   traversal for the same result.
//! - A triangle nearly edge-on from the light, whose orientation rounding could flip, is
//!   bounded by the slab along its longest edge instead of its three edge functions.
//!
//! Known artifacts: none beyond those of the reference (hard shadows only). A triangle
//! lying in the plane of a light ray (edge-on, or a point light on a surface) is decided by
//! floating-point ties exactly as the reference decides it. Cost grows with the number of
//! nodes each triangle visits; large numbers of tiny triangles dominate.

mod bsp;
mod dump;
mod raster;
mod setup;
mod shadow_ray;
pub mod soft;
mod transform;

use super::{find_param, Frame, ParamSpec, ShadowTechnique, Shadows, Stats, Visibility};
use crate::error::Result;
use crate::math::Vec3;
use bsp::{Bsp, Node};
use raster::{rasterize, Counters};
use shadow_ray::ShadowRay;
use std::collections::BTreeMap;
use transform::{transform, Pt};

/// The paper's leaf size: a leaf holds at most this many samples.
pub const DEFAULT_LEAF_SIZE: u32 = 64;
/// The largest leaf size accepted.
pub const MAX_LEAF_SIZE: u32 = 1 << 20;

/// Widening of every hierarchical culling test, in relative floating-point error: vertices
/// and samples are treated as uncertain by 64 ulps of the scene's size (directional light)
/// or of the distances to the light (point and spot lights), several times what the
/// shadow-ray test's rounding can move them. Larger values only send more samples to the
/// exact per-sample test (slower, never wrong); a value below the rounding error of the
/// shadow-ray test would let the hierarchy skip a sample the ray test counts as shadowed.
pub const CULL_TOLERANCE: f32 = 64.0 * f32::EPSILON;

/// Alias-free shadow maps: exact hard shadows by irregular rasterization.
#[derive(Clone, Debug)]
pub struct AliasFree {
    /// A BSP leaf holds at most this many samples.
    pub leaf_size: u32,
    /// The per-sample buffers of the last frame, kept so the next frame writes into memory
    /// that is already mapped instead of page-faulting tens of megabytes in again.
    buffers: Buffers,
}

impl Default for AliasFree {
    fn default() -> Self {
        AliasFree {
            leaf_size: DEFAULT_LEAF_SIZE,
            buffers: Buffers::default(),
        }
    }
}

/// Spare vectors of one element type, handed out emptied and taken back after the frame.
#[derive(Clone, Debug)]
struct Pool<T>(Vec<Vec<T>>);

impl<T> Default for Pool<T> {
    fn default() -> Self {
        Pool(Vec::new())
    }
}

impl<T> Pool<T> {
    /// An empty vector, with the capacity of one given back earlier when there is one.
    pub(super) fn take(&mut self) -> Vec<T> {
        let mut v = self.0.pop().unwrap_or_default();
        v.clear();
        v
    }

    /// Takes `v` back for a later [`Pool::take`].
    pub(super) fn give(&mut self, v: Vec<T>) {
        self.0.push(v);
    }
}

/// The per-frame buffers, one pool per element type.
#[derive(Clone, Debug, Default)]
struct Buffers {
    rays: Pool<ShadowRay>,
    pts: Pool<Pt>,
    /// Cube faces of the samples.
    bytes: Pool<u8>,
    /// Sample coordinates in leaf order.
    coords: Pool<f32>,
    /// Sample transmittances.
    vis: Pool<Vec3>,
    /// Samples not yet dark.
    flags: Pool<bool>,
}

impl ShadowTechnique for AliasFree {
    fn name(&self) -> &'static str {
        "afsm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([("leaf-size".to_string(), self.leaf_size.into())])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::int(
            "leaf-size",
            1,
            MAX_LEAF_SIZE as i64,
            "a BSP leaf holds at most this many samples (the paper's 64); only the speed changes",
        )]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let spec = find_param("afsm", &self.param_specs(), key)?;
        if key == "leaf-size" {
            self.leaf_size = spec.u32("afsm", value)?;
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        frame.light.validate()?;
        let mut stats = Stats::default();
        let leaf = self.leaf_size.max(1) as usize;
        let buf = &mut self.buffers;
        let planes = stats.stage("transform", || transform(frame, buf));
        let trees: Vec<Bsp> = stats.stage("bsp", || {
            planes
                .into_iter()
                .map(|p| Bsp::build(p, leaf, buf))
                .collect()
        });
        let (visibility, layers, counters) =
            stats.stage("raster", || rasterize(frame, &trees, buf));
        record(&mut stats, &trees, &counters);
        for (i, t) in trees.iter().enumerate() {
            frame.dump_image(&format!("afsm-bsp{i}.png"), || dump::bsp_picture(t))?;
        }
        for t in trees {
            t.recycle(&mut self.buffers);
        }
        Ok(Shadows {
            layers,
            ..Shadows::new(visibility, stats)
        })
    }
}

/// The paper's Table 1 counters and the memory held, into `stats`.
fn record(stats: &mut Stats, trees: &[Bsp], counters: &Counters) {
    let nodes: usize = trees.iter().map(|t| t.nodes.len()).sum();
    let samples: usize = trees.iter().map(|t| t.su.len()).sum();
    stats.count("samples", samples as f64);
    stats.count("bsp_nodes", nodes as f64);
    stats.count("light_planes", trees.len() as f64);
    stats.count("nodes_visited", counters.nodes_visited as f64);
    stats.count("nodes_occlusion_culled", counters.occlusion_culled as f64);
    stats.count("samples_tested", counters.samples_tested as f64);
    stats.count("ray_tests", counters.ray_tests as f64);
    stats.count("triangles_binned", counters.triangles_binned as f64);
    // Coordinates, shadow ray, transmittance and flag of every sample.
    let per_sample = 3 * 4 + std::mem::size_of::<ShadowRay>() + std::mem::size_of::<Vec3>() + 1;
    stats.memory_bytes =
        (samples * per_sample + nodes * std::mem::size_of::<Node>() + counters.setup_bytes) as u64;
}
