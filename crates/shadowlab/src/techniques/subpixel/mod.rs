//! `subpixel`: fast sub-pixel anti-aliased shadow maps (Pan, Wang, Chen, Zhou and Bao,
//! "Fast, Sub-pixel Antialiased Shadow Maps", Pacific Graphics 2009).
//!
//! Idea: each pixel is approximated by its *facet*, the quad that the pixel's footprint
//! cuts out of the tangent plane through its centre sample; every blocker triangle that may
//! shadow the facet is turned into a few half-planes on the screen, each half-plane into a
//! bitmask of the pixel's sub-samples by a precomputed look-up table, and the bitmasks are
//! ANDed per triangle and ORed into the pixel's occlusion mask — N samples of shadow for
//! the cost of one evaluation per triangle–pixel pair. A *silhouette mask map* (texels
//! crossed by a visible silhouette edge, with a summed-area table over it) limits that work
//! to pixels near shadow boundaries; every other pixel is wholly lit or wholly shadowed and
//! takes the ordinary depth-map test.
//!
//! Pipeline, as Figure 2 of the paper, with the counters of its Table 1:
//! 1. Light-view depth map (the shared rasterizer, [`render_light_maps`]).
//! 2. Silhouette mask map (`silhouette_edges.rs`, `silhouette_mask_map.rs`, drawn by
//!    `rasterization.rs`): silhouette edges (one adjacent face on each side of the plane
//!    through the edge and the light; boundary and non-manifold edges always count) are
//!    rasterized conservatively — every texel the segment touches — keeping per texel the
//!    nearest edge depth; texels whose edges lie behind the depth map are dropped; then a
//!    summed-area table (`silhouette_texels`).
//! 3. Facets (`facets.rs`): pixels whose projected facet's bounding rectangle holds no
//!    silhouette texel (four SAT look-ups) take the depth-map test. So that this first
//!    filter costs little per pixel, it runs on a box that provably holds the projected
//!    facet — the facet's linearization at the centre, widened by bounds on the two
//!    perspective divisions (see `FrameState::facet_bound`) — and only pixels that pass it
//!    build their exact facet and rectangle. The rest are rasterized conservatively into
//!    pixel–texel pairs (`pairs.rs`; per texel row, the exact span of the projected quad —
//!    the separating-axis test of the paper done row by row); pixels that touch no
//!    silhouette texel after all go back to the depth-map test (`silhouette_pixels` counts
//!    the others).
//! 4. Triangle–texel pairs (`pairs.rs`, blockers set up in `blockers.rs`): every triangle
//!    is rasterized the same way, against the texels that hold pixels only, then sorted by
//!    texel.
//! 5. Visibility evaluation (`visibility_evaluation.rs`; counter `visibility_evaluations`):
//!    for each silhouette pixel, each blocker of its texels is tested once. The three edge
//!    planes of the triangle's shadow volume (through the light) and the triangle's own
//!    plane restrict, on the tangent plane, to the occluded area; each plane maps to a
//!    half-plane on the screen (exactly: the tangent-plane point under image position `s`
//!    is `E + t(s)·d(s)` with `t > 0`, so the sign of a plane's equation there is the sign
//!    of a function linear in `s`). Each half-plane's bitmask comes from the look-up table
//!    (`lookup_table.rs`); their AND is ORed into the occlusion mask. The validity mask of
//!    Section 3.4 drops samples beyond the line where a triangle that cuts the facet
//!    (inside the pixel) rises above it — never the centre sample, and not at convex
//!    creases, where that triangle lies behind the facet from the light. Shadow = 1 −
//!    popcount(occlusion & validity) / popcount(validity).
//!
//! Invariants: every sample pattern holds the pixel centre (see [`crate::sampling`]), so
//! the centre sample is always valid; the pixel–texel and triangle–texel rasterizations are
//! conservative (a blocker whose light-space projection covers any point of a facet is
//! tested against that facet); with one sample per pixel the result is the exact point
//! visibility of the centre sample wherever the silhouette mask routes a pixel to the
//! evaluation. Output is identical for any thread count: parallel stages collect in order,
//! and the only shared writes are integer min/max and mask OR/AND, which do not depend on
//! order.
//!
//! Departures from the paper, and why:
//! - CPU instead of CUDA: scan, compact and sort become rayon collects and parallel sorts;
//!   the paper's atomic per-pixel mask updates become a loop per pixel over the union of
//!   its texels' triangle lists, deduplicated, so each triangle–pixel pair is evaluated
//!   once (the paper evaluates every TT-pair × PT-pair product). `visibility_evaluations`
//!   counts the pairs after deduplication.
//! - A silhouette pixel pairs with *every* texel its facet touches, not only the silhouette
//!   texels as in the paper. Where blockers are finely tessellated against the map, the
//!   triangles over a facet's silhouette texel need not reach its other texels, and the
//!   facet's part there would be left wrongly lit (speckles inside shadows, found by the
//!   brute-force test); the price is more pairs per facet.
//! - Conservative rasterization (of silhouette edges, facets and triangles) uses its own
//!   coverage rule — every texel whose closed square the primitive touches — which the
//!   shared rasterizer's point-sampled top-left rule cannot give; it is written here, per
//!   texel row, instead of the paper's wide lines and points with a fragment-shader test.
//! - Hidden silhouettes: the paper compares the edge depth with the depth map at the one
//!   texel. A texel whose silhouette is covered only in part (the occluder's outline
//!   crosses it, or the edge bounds the very surface the depth map sees) would then be
//!   dropped and its pixels would get a point-sampled, aliased answer; here an edge is
//!   hidden only when the depth map is nearer than it, by [`HIDDEN_SILHOUETTE_BIAS`], at
//!   all 3×3 texel centres around the texel (a planar occluder nearer at those nine points
//!   covers the whole texel).
//! - Edge adjacency comes from welding vertices with bit-identical positions, so triangle
//!   soups work; it is built once per scene and cached. Silhouettes use the plane through
//!   the edge and the light, which needs no consistent winding.
//! - The half-planes are derived in one step (triangle plane → screen, through the facet's
//!   tangent plane) rather than by projecting half-planes onto the tangent plane and then
//!   onto the screen; the regions are the same, and the orientation question of the paper's
//!   Figure 6(b) does not arise. The fourth half-plane (the triangle's plane) is always
//!   applied; where the triangle does not cut the facet's plane it is all or nothing.
//! - Grazing facets: when a corner ray of the pixel meets the tangent plane behind the eye
//!   or more than [`MAX_FACET_STRETCH`] pixel widths away, the facet is the footprint of a
//!   smaller square about the centre (halved up to [`FACET_SHRINK_STEPS`] times, else the
//!   centre point) and samples outside it start invalid.
//! - Point lights: six cube faces, each with its own maps; a pixel's facet is handled in
//!   the face its centre projects to (a facet straddling two faces sees blockers of that
//!   face only).
//! - Semi-transparent casters are treated as opaque (bitmasks hold no transmittance), as in
//!   `sm` and `pcf`.
//! - Alpha-masked casters: every edge of a masked triangle counts as a silhouette (its
//!   cut-out outline may run anywhere inside it), and each sample a masked blocker's
//!   half-planes cover is tested exactly against the mask where its shadow ray meets the
//!   triangle. Pixels whose facets reach no silhouette texel (an outline deep inside a large
//!   masked triangle) take the depth-map test, which drops cut-out texels: there the outline
//!   is as sharp as the map, as in `sm`.
//! - The half-plane table is not the last word: quantized to [`LUT_ANGLES`] ×
//!   [`LUT_DISTANCES`] entries, it moves a half-plane's edge by up to about 0.017 pixel,
//!   and with a grid pattern a nearly horizontal or vertical shadow edge that close to a
//!   row of samples flips the whole row (7 of 32 samples on a pixel of the bunny's shadow).
//!   Each entry therefore also keeps the samples that lie close enough to its line to be on
//!   either side, and those few are tested exactly; the masks are then exact, and still
//!   complementary for adjacent blockers. On planar receivers this brings the error against
//!   the same-pattern reference, on pixels whose sub-samples all see the receiver, from
//!   about 5e-4 to below 1e-5.
//!
//! Known artifacts: the facet approximates the surface inside a pixel by one plane, so
//! pixels whose sub-samples see other surfaces (object outlines in the image) or a strongly
//! curved one get the centre surface's shadow; at concave creases the validity mask lowers
//! the sample count (the paper reports 18.5 valid of 32 on its bumpy receiver; the counter
//! `valid_samples_boundary_mean` gives ours). Non-silhouette pixels keep the depth-map test
//! and its bias. The shared [`crate::light::Light::illuminates`] rule decides whole pixels
//! by their centre, so the rim of a spot light's cone is not anti-aliased.

mod blockers;
mod dump;
mod facets;
mod lookup_table;
mod pairs;
mod rasterization;
mod ray_plane;
mod silhouette_edges;
mod silhouette_mask_map;
mod visibility_evaluation;

pub use facets::{FACET_SHRINK_STEPS, MAX_FACET_STRETCH};
pub use lookup_table::{lookup_table, LookupTable, LUT_ANGLES, LUT_DISTANCES};
pub use silhouette_edges::{edge_adjacency, EdgeAdjacency};
pub use silhouette_mask_map::HIDDEN_SILHOUETTE_BIAS;
pub use visibility_evaluation::COPLANAR_TOLERANCE;

use super::shadow_map::{
    check_resolution, lookup_nearest, receiver_bias, render_light_maps, LightMaps,
    DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS,
};
use super::{
    check_range, find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique,
    Shadows, Stats, Visibility, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::Result;
use crate::math::{ndc_to_uv, Vec3};
use crate::sampling::PatternKind;
use blockers::Blocker;
use facets::{non_silhouette_pixels, silhouette_facets, Facet};
use lookup_table::{Lut, LutCache, Mask};
use pairs::Pairs;
use rasterization::Projector;
use ray_plane::RayPlane;
use silhouette_edges::{fingerprint, silhouette_edges, Adjacency, Toward};
use silhouette_mask_map::{silhouette_mask_maps, MaskMap};
use std::collections::BTreeMap;
use std::sync::Arc;
use visibility_evaluation::{combine, evaluate_silhouette_pixels, Totals};

/// Default sub-samples per pixel (the paper's usual rate).
pub const DEFAULT_SAMPLES: u32 = 32;
/// The most sub-samples per pixel: occlusion and validity masks are at most 128 bits.
pub const MAX_SAMPLES: u32 = 128;
/// Default side of the depth map and the silhouette mask map. The paper uses 512² at
/// 800×600; a finer map marks fewer pixels as silhouette pixels and puts fewer triangles in
/// each texel, at the cost of more pixel–texel pairs per facet.
pub const DEFAULT_RESOLUTION: u32 = 1024;

/// The `subpixel` technique.
#[derive(Clone, Debug)]
pub struct Subpixel {
    /// Sub-samples per pixel (1..=[`MAX_SAMPLES`]).
    pub samples: u32,
    /// Sub-sample pattern (one sample always on the pixel centre).
    pub pattern: PatternKind,
    /// Side of the depth and silhouette mask maps in texels.
    pub resolution: u32,
    /// Constant bias of the non-silhouette depth test, in texels (see `sm`).
    pub bias: f32,
    /// Slope-scaled bias of the non-silhouette depth test, in texels per unit of tan θ.
    pub slope_bias: f32,
    adjacency: Option<Arc<Adjacency>>,
    lut: Option<Arc<LutCache>>,
}

impl Default for Subpixel {
    fn default() -> Self {
        Subpixel {
            samples: DEFAULT_SAMPLES,
            pattern: PatternKind::Grid,
            resolution: DEFAULT_RESOLUTION,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            adjacency: None,
            lut: None,
        }
    }
}

/// The parameter table, in key order.
const TABLE: &[ParamSpec] = &[
    BIAS,
    ParamSpec::choice(
        "pattern",
        &["grid", "rotated-grid"],
        "where the sub-samples of a pixel lie: a regular grid or a rotated grid",
    ),
    RESOLUTION,
    ParamSpec::int(
        "samples",
        1,
        MAX_SAMPLES as i64,
        "sub-samples per pixel of a silhouette pixel (the paper's 32)",
    ),
    SLOPE_BIAS,
];

impl ShadowTechnique for Subpixel {
    fn name(&self) -> &'static str {
        "subpixel"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("samples".to_string(), self.samples.into()),
            ("pattern".to_string(), pattern_name(self.pattern).into()),
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        TABLE.to_vec()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "subpixel";
        let spec = find_param(t, TABLE, key)?;
        match key {
            "samples" => self.samples = spec.u32(t, value)?,
            "pattern" => {
                // `rgss` is accepted beside the table's words; anything else gets its error.
                self.pattern = value
                    .trim()
                    .parse()
                    .or_else(|_| spec.word(t, value)?.parse())?
            }
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let n = check_range("subpixel", "samples", self.samples, 1, MAX_SAMPLES)?;
        let res = check_resolution("subpixel", self.resolution)?;
        // The depth maps and as many silhouette mask maps of the same size.
        super::shadow_map::check_light_map_size(
            "subpixel",
            2 * super::shadow_map::light_view_count(frame.light),
            res,
        )?;
        let mut stats = Stats::default();
        let fp = fingerprint(frame.scene);
        if self
            .adjacency
            .as_ref()
            .is_none_or(|a| a.fingerprint != fp || a.triangles != frame.scene.len())
        {
            self.adjacency = Some(Arc::new(
                stats.stage("adjacency", || Adjacency::build(frame.scene, fp)),
            ));
        }
        if self
            .lut
            .as_ref()
            .is_none_or(|l| l.kind != self.pattern || l.samples.len() != n as usize)
        {
            self.lut = Some(Arc::new(LutCache::build(self.pattern, n)?));
        }
        let adjacency = self.adjacency.clone().expect("built above");
        let lut = self.lut.clone().expect("built above");
        let cfg = Config {
            res,
            bias: self.bias,
            slope_bias: self.slope_bias,
        };
        if n <= 32 {
            run::<u32>(frame, &adjacency, &lut, &cfg, &mut stats)
        } else if n <= 64 {
            run::<u64>(frame, &adjacency, &lut, &cfg, &mut stats)
        } else {
            run::<u128>(frame, &adjacency, &lut, &cfg, &mut stats)
        }
        .map(|visibility| Shadows::new(visibility, stats))
    }
}

fn pattern_name(k: PatternKind) -> &'static str {
    match k {
        PatternKind::Grid => "grid",
        PatternKind::RotatedGrid => "rotated-grid",
    }
}

struct Config {
    res: u32,
    bias: f32,
    slope_bias: f32,
}

// ---------------------------------------------------------------------------------------
// The frame

/// One frame's light maps, silhouette mask maps, look-up table and camera and light
/// geometry: what the stages after the silhouette mask map read.
struct FrameState<'a, M> {
    frame: &'a Frame<'a>,
    /// Side of the depth and silhouette mask maps.
    res: u32,
    /// Constant bias of the depth-map test, in texels.
    bias: f32,
    /// Slope-scaled bias of the depth-map test, in texels per unit of tan θ.
    slope_bias: f32,
    /// The direction towards the light.
    toward: Toward,
    /// The camera's primary rays.
    rays: RayPlane,
    /// Depth map of each light view (stage 1).
    maps: LightMaps,
    /// Projection into each light view's texels.
    projectors: Vec<Projector>,
    /// Silhouette mask map of each light view (stage 2).
    masks: Vec<MaskMap>,
    /// The sample pattern and its half-plane table.
    lut_cache: &'a LutCache,
    /// That table in masks of type `M`.
    lut: Lut<M>,
    /// The centre sample's bit.
    centre: M,
}

impl<M> FrameState<'_, M> {
    /// The depth-map test of pixel `k` in light view `vi`, at map position `(u, v)` and
    /// light depth `depth`: what non-silhouette pixels get.
    #[inline]
    fn depth_lookup(&self, k: usize, vi: usize, u: f32, v: f32, depth: f32) -> f32 {
        let view = self.frame.view;
        let p = view.position[k];
        let lv = &self.maps.views[vi];
        let (l, _) = self.frame.light.shadow_ray(p);
        let bias = receiver_bias(
            lv.texel_size(self.res, depth),
            view.normal[k],
            l,
            self.bias,
            self.slope_bias,
        );
        lookup_nearest(&self.maps.maps[vi], u, v, depth - bias)
    }

    /// The depth-map test of pixel `k` in light view `vi`.
    fn depth_test(&self, k: usize, vi: usize) -> f32 {
        let p = self.frame.view.position[k];
        let lv = &self.maps.views[vi];
        let (u, v) = ndc_to_uv(lv.clip_from_world * p.extend(1.0));
        self.depth_lookup(k, vi, u, v, lv.depth(p))
    }
}

/// The frame flow, stage by stage as Figure 2 of the paper, with masks of type `M`.
fn run<M: Mask>(
    frame: &Frame,
    adj: &Adjacency,
    lut_cache: &LutCache,
    cfg: &Config,
    stats: &mut Stats,
) -> Result<Visibility> {
    let res = cfg.res;
    let toward = Toward::new(frame.light);
    let lut: Lut<M> = Lut::new(lut_cache);
    let centre = M::from_u128(1u128 << lut_cache.centre);

    // 1. Depth maps.
    let maps: LightMaps = stats.stage("depth_map", || render_light_maps(frame, res));
    let projectors: Vec<Projector> = maps.views.iter().map(|v| Projector::new(v, res)).collect();

    // 2. Silhouette mask maps.
    let (masks, n_sil_edges) = stats.stage("silhouette_mask_map", || {
        let edges = silhouette_edges(adj, &toward);
        let masks = silhouette_mask_maps(&edges, adj, &maps, &projectors);
        (masks, edges.len())
    });

    let st = FrameState {
        frame,
        res,
        bias: cfg.bias,
        slope_bias: cfg.slope_bias,
        toward,
        rays: RayPlane::new(&frame.view.camera),
        maps,
        projectors,
        masks,
        lut_cache,
        lut,
        centre,
    };
    // 3–4. Facets, pixel–texel pairs, triangle–texel pairs.
    let mut pairs = stats.stage("pt_tt_pairs", || {
        let mut value = non_silhouette_pixels(&st);
        let facets = silhouette_facets(&st, &mut value);
        pairs::pairs(&st, value, facets)
    });

    // 5. Visibility evaluation of the silhouette pixels.
    let results = stats.stage("shadow_calculation", || {
        evaluate_silhouette_pixels(&st, &pairs)
    });
    let totals = combine(&pairs.facets, &results, &mut pairs.value);
    record_counters(&st, &pairs, &totals, n_sil_edges, adj, stats);

    let (w, h) = (frame.view.width, frame.view.height);
    if frame.dumping() {
        dump::dump(frame, &st.maps, &st.masks, &pairs.facets, w, h)?;
    }
    Ok(Visibility {
        width: w,
        height: h,
        value: pairs.value.into_iter().map(Vec3::splat).collect(),
    })
}

/// The counters of the paper's Table 1 and ours, and the memory held.
fn record_counters<M: Mask>(
    st: &FrameState<'_, M>,
    pairs: &Pairs,
    totals: &Totals,
    n_sil_edges: usize,
    adj: &Adjacency,
    stats: &mut Stats,
) {
    let samples = &st.lut_cache.samples;
    let Pairs {
        facets, blockers, ..
    } = pairs;
    let boundary = totals.boundary;
    let sil_texels: usize = st.masks.iter().map(|m| m.texels()).sum();
    stats.count("samples", samples.len() as f64);
    stats.count("silhouette_edges", n_sil_edges as f64);
    stats.count("silhouette_texels", sil_texels as f64);
    stats.count("silhouette_pixels", facets.len() as f64);
    stats.count("pt_pairs", pairs.pt_texels.len() as f64);
    stats.count("tt_pairs", pairs.tt_blocker.len() as f64);
    stats.count("blockers", blockers.len() as f64);
    stats.count("visibility_evaluations", totals.evaluations as f64);
    stats.count("boundary_pixels", boundary as f64);
    stats.count(
        "valid_samples_mean",
        if facets.is_empty() {
            samples.len() as f64
        } else {
            totals.valid as f64 / facets.len() as f64
        },
    );
    stats.count(
        "valid_samples_boundary_mean",
        if boundary == 0 {
            samples.len() as f64
        } else {
            totals.boundary_valid as f64 / boundary as f64
        },
    );
    stats.memory_bytes = st.maps.memory_bytes()
        + st.masks.iter().map(|m| m.bytes()).sum::<u64>()
        + adj.bytes()
        + st.lut_cache.bytes(std::mem::size_of::<M>())
        + (pairs.slot.len() * 4
            + pairs.pt_texels.len() * 4
            + pairs.pt_start.len() * 4
            + pairs.tt_start.len() * 4
            + pairs.tt_blocker.len() * 12) as u64
        + (facets.len() * std::mem::size_of::<Facet>()
            + blockers.len() * std::mem::size_of::<Option<Blocker>>()) as u64;
}
