//! `afsm-soft`: exact soft shadows from the alias-free structure — for every view sample,
//! the visibility of the same `N` light samples the soft reference traces
//! ([`crate::soft_reference`]), found by rasterizing each caster's penumbra into the
//! alias-free BSP of the view samples (Aila & Laine 2004) and classifying the light
//! samples it hides with bitmasks (the idea of Sintorn, Eisemann & Assarsson, "Sample
//! Based Visibility for Soft Shadows using Alias-free Shadow Maps", EGSR 2008, with the
//! sub-pixel paper's bitmask classification applied to the light's samples).
//!
//! Steps of a frame, one module each, in the order a frame runs them:
//! - *light samples* (`samples.rs`): the reference's fixed sample set in the coordinates
//!   of the light's affine frame, where every plane through a view sample is an affine
//!   function.
//! - *transform* (`transform.rs`): each view sample's shadow-ray origin projected from the
//!   light's centre to the hard technique's light image planes (six cube faces, or the
//!   orthographic plane of a distant light), and its lit mask (the light samples in front
//!   of its surface and inside a sized spot's cone).
//! - *bsp*: the hard technique's BSP over each plane (`leaf-size` samples a leaf).
//! - *raster* (`raster.rs`, `footprint.rs`, `classify.rs`): each caster triangle's
//!   conservative penumbra footprint (the cone its vertices span with the light's bounding
//!   corners, narrowed at each BSP node to the depth of its deepest sample) culls nodes and
//!   samples; each (view sample, triangle) pair is decided whole by the light's bounding
//!   square where it can be, else with two bitmasks from four affine functions of the
//!   light samples (a patch of 16 samples at once where a function's sign is the same over
//!   the patch's box), and the light samples within a margin of an
//!   edge take the reference's own ray (watertight test, same origin, direction and
//!   length). Opaque casters set bits of a dark mask; samples and BSP nodes whose light
//!   samples are all dark drop out (the paper's occlusion culling).
//! - `--dump` (`afsm-soft-bsp*.png`): each plane's samples and leaves, as the hard
//!   technique's.
//!
//! Counters: `pairs` (view sample × triangle pairs classified), `pairs_missed` and
//! `pairs_hidden` (decided whole), `pairs_masked` (classified by bitmask),
//! `pairs_grazing` (view sample in the triangle's plane: every ray), `ray_tests`,
//! `nodes_visited`, `nodes_occlusion_culled`, `bsp_nodes`, `light_planes`.
//!
//! Invariants:
//! - Every light sample's verdict is the reference's: certain classifications hold by
//!   margins of [`SOFT_TOLERANCE`] of the magnitudes involved (well beyond the rounding
//!   of both the classification and the watertight test), everything between takes the
//!   reference's ray. Semi-transparent casters multiply a light sample's transmittance in
//!   triangle-index order, alpha-masked ones are decided at the ray's barycentrics, and
//!   the shadow term is the sum in sample order over `N`: the result equals the soft
//!   reference with one primary ray per pixel bit for bit.
//! - Results and counters are the same for any thread count (units own their samples
//!   and take the triangles in index order).
//!
//! Departures and limits:
//! - The view samples are the pixels' centres (the camera pass), so the technique equals
//!   the reference traced with one primary ray per pixel (`compare`'s default for it);
//!   against a supersampled reference it is judged like any other.
//! - At most [`MAX_EXACT_LIGHT_SAMPLES`] light samples (the masks live in fixed arrays);
//!   more is refused with an error naming the count.
//! - No look-up table: evaluating the four planes on the samples directly is exact to
//!   the margin, not to a table's bin, so fewer samples need the ray.
//! - Under a punctual light (no area) it is the hard `afsm`.
//! - Semi-transparent receivers' layers are not shaded (as the soft reference).

mod classify;
mod footprint;
mod raster;
mod samples;
mod transform;

use super::super::{find_param, Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use super::bsp::Bsp;
use super::{AliasFree, Buffers, CULL_TOLERANCE, DEFAULT_LEAF_SIZE, MAX_LEAF_SIZE};
use crate::area_light::check_light_samples;
use crate::error::{Error, Result};
use crate::frame::Visibility;
use crate::math::Vec3;
use raster::{rasterize, Counters, Ctx};
use samples::LightSamples;
use std::collections::BTreeMap;
use transform::transform;

/// The most light samples the exact soft technique takes per view sample.
pub const MAX_EXACT_LIGHT_SAMPLES: u32 = 1024;

/// Margin of every certain classification and every culling bound, relative to the
/// magnitudes involved: the hard technique's [`CULL_TOLERANCE`] (64 ulps, several times
/// the rounding of the watertight test and of the classification). Larger only sends
/// more light samples to the exact ray (slower, never wrong).
pub const SOFT_TOLERANCE: f32 = CULL_TOLERANCE;

/// Exact soft shadows from the alias-free structure.
#[derive(Clone, Debug)]
pub struct SoftAliasFree {
    /// A BSP leaf holds at most this many view samples.
    pub leaf_size: u32,
    buffers: Buffers,
}

impl Default for SoftAliasFree {
    fn default() -> Self {
        SoftAliasFree {
            leaf_size: DEFAULT_LEAF_SIZE,
            buffers: Buffers::default(),
        }
    }
}

impl ShadowTechnique for SoftAliasFree {
    fn name(&self) -> &'static str {
        "afsm-soft"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([("leaf-size".to_string(), self.leaf_size.into())])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::int(
            "leaf-size",
            1,
            MAX_LEAF_SIZE as i64,
            "a BSP leaf holds at most this many view samples (the paper's 64); only the speed changes",
        )]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let spec = find_param("afsm-soft", &self.param_specs(), key)?;
        if key == "leaf-size" {
            self.leaf_size = spec.u32("afsm-soft", value)?;
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let Some(area) = frame.area else {
            let mut hard = AliasFree {
                leaf_size: self.leaf_size,
                ..AliasFree::default()
            };
            return hard.render(frame);
        };
        area.validate()?;
        let n = frame.light_samples;
        check_light_samples(n)?;
        if n > MAX_EXACT_LIGHT_SAMPLES {
            return Err(Error::param(format!(
                "afsm-soft takes at most {MAX_EXACT_LIGHT_SAMPLES} light samples, not {n}"
            )));
        }
        let mut stats = Stats::default();
        let leaf = self.leaf_size.max(1) as usize;
        let buf = &mut self.buffers;
        let ls = stats.stage("light samples", || LightSamples::new(area, n));
        let (planes, lit) = stats.stage("transform", || transform(frame, area, &ls, buf));
        let trees: Vec<Bsp> = stats.stage("bsp", || {
            planes
                .into_iter()
                .map(|p| Bsp::build(p, leaf, buf))
                .collect()
        });
        let view = frame.view;
        let mut out = Visibility::lit(view.width, view.height);
        for (k, v) in out.value.iter_mut().enumerate() {
            if view.covered(k) {
                *v = Vec3::ZERO;
            }
        }
        let ctx = Ctx {
            frame,
            area,
            ls: &ls,
            lit: &lit,
        };
        let counters = stats.stage("raster", || rasterize(&ctx, &trees, &mut out));
        record(&mut stats, &trees, &counters, lit.bits.len());
        for (i, t) in trees.iter().enumerate() {
            frame.dump_image(&format!("afsm-soft-bsp{i}.png"), || {
                super::dump::bsp_picture(t)
            })?;
        }
        for t in trees {
            t.recycle(&mut self.buffers);
        }
        Ok(Shadows::new(out, stats))
    }
}

/// The counters and the memory held, into `stats`.
fn record(stats: &mut Stats, trees: &[Bsp], c: &Counters, mask_words: usize) {
    let nodes: usize = trees.iter().map(|t| t.nodes.len()).sum();
    let samples: usize = trees.iter().map(|t| t.su.len()).sum();
    stats.count("samples", samples as f64);
    stats.count("bsp_nodes", nodes as f64);
    stats.count("light_planes", trees.len() as f64);
    stats.count("nodes_visited", c.nodes_visited as f64);
    stats.count("nodes_occlusion_culled", c.occlusion_culled as f64);
    stats.count("pairs", c.pairs as f64);
    stats.count("pairs_missed", c.pairs_missed as f64);
    stats.count("pairs_hidden", c.pairs_hidden as f64);
    stats.count("pairs_masked", c.pairs_masked as f64);
    stats.count("pairs_grazing", c.pairs_grazing as f64);
    stats.count("ray_tests", c.ray_tests as f64);
    // Coordinates, ray record and lit and dark masks of every sample, and the nodes.
    let per_sample = 3 * 4 + std::mem::size_of::<super::shadow_ray::ShadowRay>();
    stats.memory_bytes = (samples * per_sample
        + 2 * mask_words * 8
        + nodes * std::mem::size_of::<super::bsp::Node>()) as u64;
}
