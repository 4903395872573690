//! `subpixel`: fast sub-pixel anti-aliased shadow maps (Pan, Wang, Chen, Zhou and Bao,
//! "Fast, Sub-pixel Antialiased Shadow Maps", Pacific Graphics 2009).
//!
//! Idea: each pixel is approximated by its *facet*, the quad that the pixel's footprint cuts
//! out of the tangent plane through its centre sample; every blocker triangle that may shadow
//! the facet is turned into a few half-planes on the screen, each half-plane into a bitmask of
//! the pixel's sub-samples by a precomputed look-up table, and the bitmasks are ANDed per
//! triangle and ORed into the pixel's occlusion mask — N samples of shadow for the cost of
//! one evaluation per triangle–pixel pair. A *silhouette mask map* (texels crossed by a
//! visible silhouette edge, with a summed-area table over it) limits that work to pixels
//! near shadow boundaries; every other pixel is wholly lit or wholly shadowed and takes the
//! ordinary depth-map test.
//!
//! Pipeline, as Figure 2 of the paper, with the counters of its Table 1:
//! 1. Light-view depth map (the shared rasterizer, [`render_light_maps`]).
//! 2. Silhouette mask map: silhouette edges (one adjacent face on each side of the plane
//!    through the edge and the light; boundary and non-manifold edges always count) are
//!    rasterized conservatively — every texel the segment touches — keeping per texel the
//!    nearest edge depth; texels whose edges lie behind the depth map are dropped; then a
//!    summed-area table (`silhouette_texels`).
//! 3. Facets: pixels whose projected facet's bounding rectangle holds no silhouette texel
//!    (four SAT look-ups) take the depth-map test. So that this first filter costs little
//!    per pixel, it runs on a box that provably holds the projected facet — the facet's
//!    linearization at the centre, widened by bounds on the two perspective divisions (see
//!    `facet_bound`) — and only pixels that pass it build their exact facet and rectangle.
//!    The rest are rasterized conservatively into pixel–texel pairs (per texel row, the
//!    exact span of the projected quad — the separating-axis test of the paper done row by
//!    row); pixels that touch no silhouette texel after all go back to the depth-map test
//!    (`silhouette_pixels` counts the others).
//! 4. Triangle–texel pairs: every triangle is rasterized the same way, against the texels
//!    that hold pixels only, then sorted by texel.
//! 5. Visibility evaluation (`visibility_evaluations`): for each silhouette pixel, each
//!    blocker of its texels is tested once. The three edge planes of the triangle's shadow
//!    volume (through the light) and the triangle's own plane restrict, on the tangent plane,
//!    to the occluded area; each plane maps to a half-plane on the screen (exactly: the
//!    tangent-plane point under image position `s` is `E + t(s)·d(s)` with `t > 0`, so the
//!    sign of a plane's equation there is the sign of a function linear in `s`). Each
//!    half-plane's bitmask comes from the look-up table; their AND is ORed into the
//!    occlusion mask. The validity mask of Section 3.4 drops samples beyond the line where a
//!    triangle that cuts the facet (inside the pixel) rises above it — never the centre
//!    sample, and not at convex creases, where that triangle lies behind the facet from the
//!    light. Shadow = 1 − popcount(occlusion & validity) / popcount(validity).
//!
//! Invariants: every sample pattern holds the pixel centre (see [`crate::sampling`]), so the
//! centre sample is always valid; the pixel–texel and triangle–texel rasterizations are
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
//!   texel. A texel whose silhouette is covered only in part (the occluder's outline crosses
//!   it, or the edge bounds the very surface the depth map sees) would then be dropped and
//!   its pixels would get a point-sampled, aliased answer; here an edge is hidden only when
//!   the depth map is nearer than it, by [`HIDDEN_SILHOUETTE_BIAS`], at all 3×3 texel
//!   centres around the texel (a planar occluder nearer at those nine points covers the
//!   whole texel).
//! - Edge adjacency comes from welding vertices with bit-identical positions, so triangle
//!   soups work; it is built once per scene and cached. Silhouettes use the plane through
//!   the edge and the light, which needs no consistent winding.
//! - The half-planes are derived in one step (triangle plane → screen, through the facet's
//!   tangent plane) rather than by projecting half-planes onto the tangent plane and then
//!   onto the screen; the regions are the same, and the orientation question of the
//!   paper's Figure 6(b) does not arise. The fourth half-plane (the triangle's plane) is
//!   always applied; where the triangle does not cut the facet's plane it is all or nothing.
//! - Grazing facets: when a corner ray of the pixel meets the tangent plane behind the eye
//!   or more than [`MAX_FACET_STRETCH`] pixel widths away, the facet is the footprint of a
//!   smaller square about the centre (halved up to [`FACET_SHRINK_STEPS`] times, else the
//!   centre point) and samples outside it start invalid.
//! - Point lights: six cube faces, each with its own maps; a pixel's facet is handled in the
//!   face its centre projects to (a facet straddling two faces sees blockers of that face only).
//! - Semi-transparent casters are treated as opaque (bitmasks hold no transmittance), as in
//!   `sm` and `pcf`.
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
//! Known artifacts: the facet approximates the surface inside a pixel by one plane, so pixels
//! whose sub-samples see other surfaces (object outlines in the image) or a strongly curved
//! one get the centre surface's shadow; at concave creases the validity mask lowers the
//! sample count (the paper reports 18.5 valid of 32 on its bumpy receiver; the counter
//! `valid_samples_boundary_mean` gives ours). Non-silhouette pixels keep the depth-map test
//! and its bias. The
//! shared [`Light::illuminates`] rule decides whole pixels by their centre, so the rim of a
//! spot light's cone is not anti-aliased.

use super::shadow_map::{
    check_resolution, lookup_nearest, receiver_bias, render_light_maps, LightMaps,
    DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS,
};
use super::{
    check_range, parse_value, unknown_param, Frame, ShadowTechnique, Shadows, Stats, Visibility,
};
use crate::error::{Error, Result};
use crate::light::{Light, LightView};
use crate::math::{Mat4, Vec2, Vec3};
use crate::sampling::{centre_index, pattern, PatternKind};
use crate::scene::Scene;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::{BitAnd, BitAndAssign, BitOr, BitOrAssign, Not};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// Default sub-samples per pixel (the paper's usual rate).
pub const DEFAULT_SAMPLES: u32 = 32;
/// The most sub-samples per pixel: occlusion and validity masks are at most 128 bits.
pub const MAX_SAMPLES: u32 = 128;
/// Default side of the depth map and the silhouette mask map. The paper uses 512² at
/// 800×600; a finer map marks fewer pixels as silhouette pixels and puts fewer triangles in
/// each texel, at the cost of more pixel–texel pairs per facet.
pub const DEFAULT_RESOLUTION: u32 = 1024;
/// Angle bins of the half-plane look-up table (over a full turn, in diamond-angle steps).
pub const LUT_ANGLES: usize = 256;
/// Distance bins of the half-plane look-up table, over `±LUT_REACH` pixels from the centre.
/// With [`LUT_ANGLES`] the table moves a half-plane's edge by at most about 0.017 pixel
/// (the samples that close to an entry's line are tested exactly; fewer bins, more of them);
/// finer tables are larger (bins × 16 bytes at 128 samples) and fall out of cache.
pub const LUT_DISTANCES: usize = 128;
/// Beyond this distance from the pixel centre a half-plane's edge misses every sample
/// position in the pixel (half the diagonal, √2/2, plus a margin).
const LUT_REACH: f32 = 0.7072;
/// An edge is hidden in a texel when the depth map is nearer than the edge by this many
/// texels (world size at that depth) at all nine texel centres around it. Larger keeps more
/// hidden silhouettes (more pixels take the exact, slower path; never wrong); smaller drops
/// texels whose edge bounds the very surface the depth map sees, giving those pixels a
/// point-sampled, aliased answer.
pub const HIDDEN_SILHOUETTE_BIAS: f32 = 2.0;
/// Triangle vertices within this fraction of their distance from the pixel's surface point
/// count as lying on its tangent plane. Larger ignores real blockers at extreme grazing
/// light; smaller lets floating-point noise turn coplanar neighbours (a tessellated plane)
/// into triangles that cut the facet and invalidate samples.
pub const COPLANAR_TOLERANCE: f32 = 1e-5;
/// A facet corner may lie at most this many pixel widths (at the pixel's depth, facing the
/// camera) from the centre sample; grazing pixels whose footprint is longer use a smaller
/// facet. Larger gives grazing pixels all their samples but many more texels to visit.
pub const MAX_FACET_STRETCH: f32 = 16.0;
/// How many times a grazing facet is halved before it falls back to the centre point.
pub const FACET_SHRINK_STEPS: u32 = 4;
/// Conservative rasterization widens every primitive by this many texels so that
/// floating-point rounding never drops a texel the primitive touches.
const RASTER_EPS: f32 = 2e-3;
/// Plane normals more nearly parallel than this (sine of the angle) to the direction they
/// are tested against are degenerate: a triangle seen edge-on from the light casts no area.
const EDGE_ON_SINE: f32 = 1e-6;
/// Marks an empty slot.
const NONE: u32 = u32::MAX;

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

const PARAMS: &[&str] = &["samples", "pattern", "resolution", "bias", "slope-bias"];

impl ShadowTechnique for Subpixel {
    fn name(&self) -> &'static str {
        "subpixel"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("samples".to_string(), self.samples.into()),
            ("pattern".to_string(), pattern_name(self.pattern).into()),
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), self.bias.into()),
            ("slope-bias".to_string(), self.slope_bias.into()),
        ])
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "subpixel";
        match key {
            "samples" => {
                self.samples = check_range(t, key, parse_value(t, key, value)?, 1, MAX_SAMPLES)?
            }
            "pattern" => {
                self.pattern = value.trim().parse().map_err(|_| {
                    Error::param(format!(
                        "parameter subpixel.pattern = {value:?} is not one of grid, rotated-grid"
                    ))
                })?
            }
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?,
            "slope-bias" => {
                self.slope_bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?
            }
            _ => return Err(unknown_param(t, key, PARAMS)),
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
// Bitmasks and the half-plane look-up table

/// A sample bitmask: bit `i` is sub-sample `i`.
trait Mask:
    Copy
    + Send
    + Sync
    + Eq
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + BitAndAssign
    + BitOrAssign
{
    const ZERO: Self;
    fn from_u128(v: u128) -> Self;
    fn to_u128(self) -> u128;
    fn ones(self) -> u32;
}

macro_rules! impl_mask {
    ($t:ty) => {
        impl Mask for $t {
            const ZERO: Self = 0;
            #[inline]
            fn from_u128(v: u128) -> Self {
                v as $t
            }
            #[inline]
            fn to_u128(self) -> u128 {
                self as u128
            }
            #[inline]
            fn ones(self) -> u32 {
                self.count_ones()
            }
        }
    };
}
impl_mask!(u32);
impl_mask!(u64);
impl_mask!(u128);

/// The pattern and its half-plane table, kept between frames.
#[derive(Debug)]
struct LutCache {
    kind: PatternKind,
    samples: Vec<Vec2>,
    centre: usize,
    /// `LUT_ANGLES × LUT_DISTANCES` masks: samples `s` with `dir·(s − ½) + dist ≥ 0`.
    masks: Vec<u128>,
    /// Per entry, the samples within [`LutCache::uncertain_reach`] of its line: the ones
    /// a half-plane that falls in this entry may put on the other side, which
    /// [`Lut::half_plane`] tests exactly.
    uncertain: Vec<u128>,
}

/// The unit direction at diamond angle `p ∈ [0, 4)` (see [`diamond_angle`]).
fn diamond_direction(p: f32) -> Vec2 {
    let q = p.fract();
    let d = match p as u32 {
        0 => Vec2::new(1.0 - q, q),
        1 => Vec2::new(-q, 1.0 - q),
        2 => Vec2::new(-(1.0 - q), -q),
        _ => Vec2::new(q, -(1.0 - q)),
    };
    d.normalize()
}

/// A monotone stand-in for the angle of `(a, b)` without trigonometry: the quadrant and
/// the fraction `[0, 1]` through it. `(−a, −b)` gives the quadrant two further on and the
/// bit-identical fraction, which keeps opposite half-planes complementary in the table.
#[inline]
fn diamond_angle(a: f32, b: f32) -> (usize, f32) {
    if b >= 0.0 {
        if a >= 0.0 {
            (0, b / (a + b))
        } else {
            (1, (-a) / (b - a))
        }
    } else if a <= 0.0 {
        (2, (-b) / (-a - b))
    } else {
        (3, a / (a - b))
    }
}

impl LutCache {
    fn build(kind: PatternKind, n: u32) -> Result<Self> {
        let samples = pattern(kind, n)?;
        let centre = centre_index(&samples).ok_or_else(|| {
            Error::param(format!(
                "sample pattern {} of {n} samples has no sample on the pixel centre",
                pattern_name(kind)
            ))
        })?;
        let all = if n == 128 {
            u128::MAX
        } else {
            (1u128 << n) - 1
        };
        let half = LUT_ANGLES * LUT_DISTANCES / 2;
        let reach = Self::uncertain_reach(&samples);
        let (mut masks, mut uncertain): (Vec<u128>, Vec<u128>) = (0..half)
            .into_par_iter()
            .with_min_len(256)
            .map(|e| {
                let dir = diamond_direction((e / LUT_DISTANCES) as f32 * 4.0 / LUT_ANGLES as f32);
                let dist = -LUT_REACH
                    + ((e % LUT_DISTANCES) as f32 + 0.5) * (2.0 * LUT_REACH / LUT_DISTANCES as f32);
                let (mut m, mut u) = (0u128, 0u128);
                for (i, s) in samples.iter().enumerate() {
                    let v = dir.dot(*s - Vec2::splat(0.5)) + dist;
                    if v >= 0.0 {
                        m |= 1 << i;
                    }
                    if v.abs() <= reach {
                        u |= 1 << i;
                    }
                }
                (m, u)
            })
            .unzip();
        // The opposite directions are the complements (the half-plane on the other side of
        // the same line), so that two blockers sharing an edge leave no sample between them;
        // their uncertain samples are the same.
        for e in 0..half {
            let (ai, di) = (e / LUT_DISTANCES, e % LUT_DISTANCES);
            let mirror = ai * LUT_DISTANCES + LUT_DISTANCES - 1 - di;
            masks.push(!masks[mirror] & all);
            uncertain.push(uncertain[mirror]);
        }
        Ok(LutCache {
            kind,
            samples,
            centre,
            masks,
            uncertain,
        })
    }

    /// How far (in pixels) a sample may lie from an entry's line and still be on the other
    /// side of a half-plane that falls in that entry: half a distance bin, plus the angle
    /// error (at most half an angle bin of diamond fraction, `2/LUT_ANGLES`, which turns
    /// the direction by at most twice that in radians) times the sample's distance from the
    /// centre, with a quarter more for rounding.
    fn uncertain_reach(samples: &[Vec2]) -> f32 {
        let offset = samples
            .iter()
            .map(|s| (*s - Vec2::splat(0.5)).length())
            .fold(0.0f32, f32::max);
        1.25 * (LUT_REACH / LUT_DISTANCES as f32 + offset * 4.0 / LUT_ANGLES as f32)
    }

    fn bytes(&self, mask_bytes: usize) -> u64 {
        (2 * self.masks.len() * mask_bytes + self.samples.len() * 8) as u64
    }
}

/// The table in the frame's mask width.
struct Lut<M> {
    /// Per entry, its mask and its uncertain samples (side by side: one cache line).
    entries: Vec<[M; 2]>,
    samples: Vec<Vec2>,
    all: M,
}

impl<M: Mask> Lut<M> {
    fn new(c: &LutCache) -> Self {
        let n = c.samples.len();
        let all = if n == 128 {
            u128::MAX
        } else {
            (1u128 << n) - 1
        };
        Lut {
            entries: c
                .masks
                .iter()
                .zip(&c.uncertain)
                .map(|(&m, &u)| [M::from_u128(m), M::from_u128(u)])
                .collect(),
            samples: c.samples.clone(),
            all: M::from_u128(all),
        }
    }

    /// The samples `s` (pixel-local, in `[0, 1)²`) with `a·s.x + b·s.y + c ≥ 0`: the table's
    /// entry, with the samples close enough to its line to be on either side tested exactly.
    #[inline]
    fn half_plane(&self, a: f32, b: f32, c: f32) -> M {
        let v0 = c + 0.5 * (a + b);
        let nn = a * a + b * b;
        if v0 * v0 >= LUT_REACH * LUT_REACH * nn {
            return if v0 >= 0.0 { self.all } else { M::ZERO };
        }
        // Sign-symmetric arithmetic throughout: (−a, −b, −c) lands in the complementary
        // entry (angle + half a turn, mirrored distance bin), so adjacent blockers, whose
        // shared edge plane arrives here exactly negated, cover every sample between them.
        let dist = v0 / nn.sqrt();
        let (quadrant, frac) = diamond_angle(a, b);
        let ai = (quadrant * (LUT_ANGLES / 4) + (frac * (LUT_ANGLES / 4) as f32).round() as usize)
            % LUT_ANGLES;
        let u = (dist * (LUT_DISTANCES as f32 / (2.0 * LUT_REACH))).floor() as i64
            + (LUT_DISTANCES / 2) as i64;
        let di = u.clamp(0, LUT_DISTANCES as i64 - 1) as usize;
        let [mut m, near] = self.entries[ai * LUT_DISTANCES + di];
        if near != M::ZERO {
            // Exactly negated (a, b, c) give exactly negated values here (IEEE rounding is
            // sign-symmetric), so complementary half-planes still cover every sample; one
            // on the line itself is in both.
            m &= !near;
            let mut bits = near.to_u128();
            while bits != 0 {
                let i = bits.trailing_zeros();
                bits &= bits - 1;
                let s = self.samples[i as usize];
                if a * s.x + b * s.y + c >= 0.0 {
                    m |= M::from_u128(1 << i);
                }
            }
        }
        m
    }
}

// ---------------------------------------------------------------------------------------
// Edge adjacency and silhouettes

/// Edges of the scene with the opposite vertex of every face that shares them.
struct Adjacency {
    fingerprint: u64,
    triangles: usize,
    a: Vec<Vec3>,
    b: Vec<Vec3>,
    /// Faces of edge `e` are `opp[opp_start[e]..opp_start[e + 1]]`.
    opp_start: Vec<u32>,
    opp: Vec<Vec3>,
}

impl std::fmt::Debug for Adjacency {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Adjacency {{ edges: {}, triangles: {} }}",
            self.a.len(),
            self.triangles
        )
    }
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// A hash of every vertex position, to tell whether a cached adjacency still fits.
fn fingerprint(scene: &Scene) -> u64 {
    const CHUNK: usize = 4096;
    let n = scene.len();
    let parts: Vec<u64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut h = FNV_OFFSET;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                for p in scene.triangle(i) {
                    for x in p.to_array() {
                        h = (h ^ x.to_bits() as u64).wrapping_mul(FNV_PRIME);
                    }
                }
            }
            h
        })
        .collect();
    parts.iter().fold(FNV_OFFSET ^ n as u64, |h, &p| {
        (h ^ p).wrapping_mul(FNV_PRIME)
    })
}

impl Adjacency {
    fn build(scene: &Scene, fingerprint: u64) -> Self {
        let n = scene.len();
        let corner = |c: usize| scene.triangle(c / 3)[c % 3];
        // Weld corners with bit-identical positions (after folding −0 into +0).
        let key = |p: Vec3| {
            let p = p + Vec3::ZERO;
            [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
        };
        let mut corners: Vec<([u32; 3], u32)> = (0..3 * n)
            .into_par_iter()
            .map(|c| (key(corner(c)), c as u32))
            .collect();
        corners.par_sort_unstable();
        let mut vid = vec![0u32; 3 * n];
        let mut next = 0u32;
        for i in 0..corners.len() {
            if i > 0 && corners[i].0 != corners[i - 1].0 {
                next += 1;
            }
            vid[corners[i].1 as usize] = next;
        }
        // Edges as (low vertex, high vertex, opposite corner), grouped by sorting.
        let mut edges: Vec<(u32, u32, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|t| {
                let vid = &vid;
                (0..3).filter_map(move |e| {
                    let a = vid[3 * t + e];
                    let b = vid[3 * t + (e + 1) % 3];
                    (a != b).then(|| (a.min(b), a.max(b), (3 * t + (e + 2) % 3) as u32))
                })
            })
            .collect();
        edges.par_sort_unstable();
        // The position of a welded vertex: any corner that carries it.
        let mut pos_of = vec![Vec3::ZERO; next as usize + 1];
        for c in 0..3 * n {
            pos_of[vid[c] as usize] = corner(c);
        }
        let mut adj = Adjacency {
            fingerprint,
            triangles: n,
            a: Vec::new(),
            b: Vec::new(),
            opp_start: vec![0],
            opp: Vec::with_capacity(edges.len()),
        };
        let mut i = 0;
        while i < edges.len() {
            let (lo, hi, _) = edges[i];
            adj.a.push(pos_of[lo as usize]);
            adj.b.push(pos_of[hi as usize]);
            while i < edges.len() && edges[i].0 == lo && edges[i].1 == hi {
                adj.opp.push(corner(edges[i].2 as usize));
                i += 1;
            }
            adj.opp_start.push(adj.opp.len() as u32);
        }
        adj
    }

    fn len(&self) -> usize {
        self.a.len()
    }

    fn bytes(&self) -> u64 {
        (self.a.len() * 24 + self.opp_start.len() * 4 + self.opp.len() * 12) as u64
    }

    /// Whether edge `e` is a silhouette seen from the light: its faces all lie on one side
    /// of the plane through the edge and the light (a fold), or it has one face (a mesh
    /// boundary) or more than two (non-manifold). Degenerate cases count as silhouettes.
    fn is_silhouette(&self, e: usize, toward: &Toward) -> bool {
        let faces = &self.opp[self.opp_start[e] as usize..self.opp_start[e + 1] as usize];
        if faces.len() != 2 {
            return true;
        }
        let a = self.a[e];
        let m = (self.b[e] - a).cross(toward.at(a));
        let s0 = m.dot(faces[0] - a);
        let s1 = m.dot(faces[1] - a);
        s0 == 0.0 || s1 == 0.0 || (s0 > 0.0) == (s1 > 0.0)
    }
}

/// The direction towards the light from a point.
#[derive(Clone, Copy)]
enum Toward {
    Direction(Vec3),
    Position(Vec3),
}

impl Toward {
    fn new(light: &Light) -> Self {
        match *light {
            Light::Directional { to_light } => Toward::Direction(to_light.normalize()),
            Light::Spot { position, .. } | Light::Point { position } => Toward::Position(position),
        }
    }

    #[inline]
    fn at(&self, p: Vec3) -> Vec3 {
        match *self {
            Toward::Direction(d) => d,
            Toward::Position(l) => l - p,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Conservative rasterization in light space

const MAX_POLY: usize = 12;

/// A small convex polygon: light-texel `x`, `y` and a depth key `z` that is linear in
/// texel space (depth for orthographic views, 1/depth for perspective ones).
#[derive(Clone, Copy, Debug)]
struct Poly {
    v: [Vec3; MAX_POLY],
    n: usize,
}

impl Poly {
    const EMPTY: Poly = Poly {
        v: [Vec3::ZERO; MAX_POLY],
        n: 0,
    };

    #[inline]
    fn push(&mut self, p: Vec3) {
        if self.n < MAX_POLY {
            self.v[self.n] = p;
            self.n += 1;
        }
    }

    #[inline]
    fn verts(&self) -> &[Vec3] {
        &self.v[..self.n]
    }

    /// The part where `f ≥ 0` (Sutherland–Hodgman; a two-vertex polygon is a segment).
    #[inline]
    fn clip(&self, f: impl Fn(Vec3) -> f32) -> Poly {
        let mut out = Poly::EMPTY;
        for i in 0..self.n {
            let a = self.v[i];
            let b = self.v[(i + 1) % self.n];
            let (fa, fb) = (f(a), f(b));
            if fa >= 0.0 {
                out.push(a);
            }
            if (fa >= 0.0) != (fb >= 0.0) {
                out.push(a + (b - a) * (fa / (fa - fb)));
            }
        }
        out
    }

    /// Bounds `(min, max)` of the vertices.
    #[inline]
    fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in self.verts() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        (lo, hi)
    }
}

/// Projects world polygons into one light view's texel grid.
struct Projector {
    light_from_world: Mat4,
    clip_from_light: Mat4,
    ortho: bool,
    near: f32,
    res: f32,
}

impl Projector {
    fn new(view: &LightView, res: u32) -> Self {
        Projector {
            light_from_world: view.light_from_world,
            clip_from_light: view.clip_from_light,
            ortho: view.orthographic,
            near: view.near,
            res: res as f32,
        }
    }

    /// The polygon (or segment) in texel space, clipped to the near plane of a perspective
    /// view. Empty when nothing is in front of the light.
    fn project(&self, world: &[Vec3]) -> Poly {
        let mut p = Poly::EMPTY;
        for w in world {
            p.push(self.light_from_world.transform_point3(*w));
        }
        if !self.ortho {
            let near = self.near;
            p = p.clip(|q| -q.z - near);
        }
        let mut out = Poly::EMPTY;
        for q in p.verts() {
            let c = self.clip_from_light * q.extend(1.0);
            let depth = -q.z;
            let key = if self.ortho { depth } else { 1.0 / depth };
            let t = Vec3::new(
                (c.x / c.w * 0.5 + 0.5) * self.res,
                (0.5 - c.y / c.w * 0.5) * self.res,
                key,
            );
            if t.is_finite() {
                out.push(t);
            }
        }
        out
    }

    /// The depth range `(min, max)` of depth keys `k0 ≤ k1`.
    #[inline]
    fn depth_span(&self, k0: f32, k1: f32) -> (f32, f32) {
        if self.ortho {
            (k0, k1)
        } else {
            (1.0 / k1, 1.0 / k0)
        }
    }
}

/// Calls `f(y, x0, x1, key_min, key_max)` for every texel row the polygon touches, with the
/// inclusive column span of the texels it touches in that row (conservative by
/// [`RASTER_EPS`]) and the range of its depth key over that row.
#[inline]
fn row_spans(poly: &Poly, res: u32, mut f: impl FnMut(u32, u32, u32, f32, f32)) {
    if poly.n == 0 {
        return;
    }
    let (lo, hi) = poly.bounds();
    let r = res as f32;
    if !(lo.is_finite() && hi.is_finite())
        || hi.x < -RASTER_EPS
        || hi.y < -RASTER_EPS
        || lo.x > r + RASTER_EPS
        || lo.y > r + RASTER_EPS
    {
        return;
    }
    let cols = |x0: f32, x1: f32| -> Option<(u32, u32)> {
        let a = (x0 - RASTER_EPS).floor().max(0.0);
        let b = (x1 + RASTER_EPS).floor().min(r - 1.0);
        (a <= b).then_some((a as u32, b as u32))
    };
    let y0 = (lo.y - RASTER_EPS).floor().max(0.0) as u32;
    let y1 = (hi.y + RASTER_EPS).floor().min(r - 1.0) as u32;
    if y0 == y1 {
        if let Some((a, b)) = cols(lo.x, hi.x) {
            f(y0, a, b, lo.z, hi.z);
        }
        return;
    }
    for y in y0..=y1 {
        let top = y as f32 - RASTER_EPS;
        let bottom = y as f32 + 1.0 + RASTER_EPS;
        let band = poly.clip(|q| q.y - top).clip(|q| bottom - q.y);
        if band.n == 0 {
            continue;
        }
        let (blo, bhi) = band.bounds();
        if let Some((a, b)) = cols(blo.x, bhi.x) {
            f(y, a, b, blo.z, bhi.z);
        }
    }
}

/// Float bits that order like the (non-negative) float.
#[inline]
fn depth_bits(d: f32) -> u32 {
    d.max(0.0).to_bits()
}

// ---------------------------------------------------------------------------------------
// The silhouette mask map

/// The silhouette mask map of one light view and its summed-area table.
struct MaskMap {
    res: u32,
    /// 1 for a silhouette texel, 2 for a texel whose silhouettes are all hidden, else 0.
    mask: Vec<u8>,
    /// `(res + 1)²` prefix sums of silhouette texels.
    sat: Vec<u32>,
}

impl MaskMap {
    fn build(
        edges: &[u32],
        adj: &Adjacency,
        proj: &Projector,
        view: &LightView,
        depth: &[f32],
        res: u32,
    ) -> Self {
        let r = res as usize;
        let nearest: Vec<AtomicU32> = (0..r * r)
            .map(|_| AtomicU32::new(f32::INFINITY.to_bits()))
            .collect();
        edges.par_iter().with_min_len(64).for_each(|&e| {
            let poly = proj.project(&[adj.a[e as usize], adj.b[e as usize]]);
            row_spans(&poly, res, |y, x0, x1, k0, k1| {
                let d = depth_bits(proj.depth_span(k0, k1).0);
                for x in x0..=x1 {
                    nearest[y as usize * r + x as usize].fetch_min(d, Ordering::Relaxed);
                }
            });
        });
        let mask: Vec<u8> = (0..r)
            .into_par_iter()
            .flat_map_iter(|y| {
                let nearest = &nearest;
                (0..r).map(move |x| {
                    let e = f32::from_bits(nearest[y * r + x].load(Ordering::Relaxed));
                    if !e.is_finite() {
                        return 0;
                    }
                    let bias = HIDDEN_SILHOUETTE_BIAS * view.texel_size(res, e);
                    // Hidden only if the map is nearer at all nine texel centres around.
                    let mut far = f32::NEG_INFINITY;
                    for yy in y.saturating_sub(1)..(y + 2).min(r) {
                        for xx in x.saturating_sub(1)..(x + 2).min(r) {
                            far = far.max(depth[yy * r + xx]);
                        }
                    }
                    let border = x == 0 || y == 0 || x + 1 == r || y + 1 == r;
                    if !border && far < e - bias {
                        2
                    } else {
                        1
                    }
                })
            })
            .collect();
        let w = r + 1;
        let mut sat = vec![0u32; w * w];
        for y in 0..r {
            let mut row = 0u32;
            for x in 0..r {
                row += (mask[y * r + x] == 1) as u32;
                sat[(y + 1) * w + x + 1] = sat[y * w + x + 1] + row;
            }
        }
        MaskMap { res, mask, sat }
    }

    /// Silhouette texels in the inclusive rectangle.
    #[inline]
    fn count(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> u32 {
        let w = self.res as usize + 1;
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize + 1, y1 as usize + 1);
        self.sat[y1 * w + x1] + self.sat[y0 * w + x0]
            - self.sat[y0 * w + x1]
            - self.sat[y1 * w + x0]
    }

    /// Silhouette texels touched by the box `(tx ± ex, ty ± ey)` in texel coordinates
    /// (widened by [`RASTER_EPS`]); 0 when the box misses the map.
    #[inline]
    fn count_around(&self, tx: f32, ty: f32, ex: f32, ey: f32) -> u32 {
        let r = self.res as f32;
        let (x0, x1) = (tx - ex - RASTER_EPS, tx + ex + RASTER_EPS);
        let (y0, y1) = (ty - ey - RASTER_EPS, ty + ey + RASTER_EPS);
        if !(x1 >= 0.0 && y1 >= 0.0 && x0 < r && y0 < r) {
            return 0;
        }
        let c = |v: f32| v.clamp(0.0, r - 1.0) as u32;
        self.count(c(x0), c(y0), c(x1), c(y1))
    }

    #[inline]
    fn is_silhouette(&self, x: u32, y: u32) -> bool {
        self.mask[(y * self.res + x) as usize] == 1
    }

    fn texels(&self) -> usize {
        self.sat[self.sat.len() - 1] as usize
    }

    fn bytes(&self) -> u64 {
        (self.mask.len() + self.sat.len() * 4 + self.mask.len() * 4) as u64
    }
}

// ---------------------------------------------------------------------------------------
// Facets and blockers

/// The camera's primary ray directions as an affine function of image position:
/// `d(x, y) = d0 + dx·x + dy·y` (pixel centres at +0.5).
struct RayPlane {
    eye: Vec3,
    d0: Vec3,
    dx: Vec3,
    dy: Vec3,
}

impl RayPlane {
    fn new(c: &crate::camera::Camera) -> Self {
        let (r, u, f) = c.basis();
        let th = (c.fov_y_deg.to_radians() * 0.5).tan();
        let asp = c.aspect();
        RayPlane {
            eye: c.eye,
            d0: f - r * (th * asp) + u * th,
            dx: r * (2.0 * th * asp / c.width as f32),
            dy: -u * (2.0 * th / c.height as f32),
        }
    }

    #[inline]
    fn at(&self, x: f32, y: f32) -> Vec3 {
        self.d0 + self.dx * x + self.dy * y
    }
}

/// A silhouette pixel's facet and what its visibility evaluation needs.
struct Facet {
    /// Pixel index.
    k: u32,
    x: f32,
    y: f32,
    /// Light view the facet is handled in.
    view: u32,
    /// Own triangle (never a blocker of its own facet).
    own: u32,
    p: Vec3,
    n: Vec3,
    /// `−n·d` for the pixel-corner ray and its per-pixel steps: the facet-plane part of
    /// every half-plane.
    an: f32,
    bn: f32,
    cn: f32,
    /// `−n·(p − eye)` (positive: the facet faces the camera).
    beta: f32,
    /// Samples inside the facet (all unless a grazing facet was shrunk).
    valid: u128,
    /// Largest light depth over the facet.
    depth_max: f32,
    /// The projected facet in texel space.
    poly: Poly,
}

/// One blocker triangle with its four planes in screen-ready form.
struct Blocker {
    tri: u32,
    v: [Vec3; 3],
    /// Per plane `(α, m·dx, m·dy, m·d0)` with `α = m·(eye − q)` for the plane
    /// `m·(X − q) ≥ 0`: three shadow-volume edge planes (inside ≥ 0), then the triangle's
    /// plane (≥ 0 behind the triangle as seen from the light).
    planes: [[f32; 4]; 4],
}

impl Blocker {
    /// `None` for a triangle that casts no area (degenerate, or edge-on to the light).
    fn new(tri: u32, v: [Vec3; 3], toward: &Toward, rays: &RayPlane) -> Option<Self> {
        let plane = |m: Vec3, q: Vec3| {
            [
                m.dot(rays.eye - q),
                m.dot(rays.dx),
                m.dot(rays.dy),
                m.dot(rays.d0),
            ]
        };
        let [a, b, c] = v;
        let mut m4 = (b - a).cross(c - a);
        let ta = toward.at(a);
        let side = m4.dot(ta);
        if side.is_nan() || side.abs() <= EDGE_ON_SINE * m4.length() * ta.length() {
            return None;
        }
        if side > 0.0 {
            m4 = -m4;
        }
        let mut planes = [[0.0; 4]; 4];
        for (j, (p, q, r)) in [(a, b, c), (b, c, a), (c, a, b)].into_iter().enumerate() {
            // The neighbour across this edge must get the bit-identical plane, negated: derive
            // it from the edge's endpoints in a fixed order, whichever triangle asks.
            let (p, q) = if p.to_array() < q.to_array() {
                (p, q)
            } else {
                (q, p)
            };
            let mut m = (q - p).cross(toward.at(p));
            let s = m.dot(r - p);
            if s.is_nan() || s.abs() <= EDGE_ON_SINE * m.length() * (r - p).length() {
                return None;
            }
            if s < 0.0 {
                m = -m;
            }
            planes[j] = plane(m, p);
        }
        planes[3] = plane(m4, a);
        Some(Blocker { tri, v, planes })
    }
}

/// The clip-space-to-pixel mapping of the camera, for the validity test's segments.
struct ScreenMap {
    clip_from_world: Mat4,
    w: f32,
    h: f32,
}

impl ScreenMap {
    #[inline]
    fn pixel(&self, p: Vec3) -> Option<Vec2> {
        let c = self.clip_from_world * p.extend(1.0);
        (c.w > 0.0).then(|| {
            Vec2::new(
                (c.x / c.w * 0.5 + 0.5) * self.w,
                (0.5 - c.y / c.w * 0.5) * self.h,
            )
        })
    }
}

/// Whether the segment `a–b` meets the square `[x, x+1] × [y, y+1]` (Liang–Barsky).
fn segment_meets_pixel(a: Vec2, b: Vec2, x: f32, y: f32) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d.x, a.x - x),
        (d.x, x + 1.0 - a.x),
        (-d.y, a.y - y),
        (d.y, y + 1.0 - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// Half-extents `(ex, ey)` in texels of a box about the pixel centre's light-space position
/// that holds the pixel's whole projected facet, or `None` when the pixel is too grazing
/// (to the camera or the light) for the bound and needs the exact facet.
///
/// The tangent-plane point under image offset `o` from the centre is
/// `p + k(o)·(o.x·jx + o.y·jy)`, with `jx`, `jy` the derivatives at the centre and
/// `k(o) = g(0)/g(o) ≤ 1/(1 − r)` where `g(o) = n·d(o)` is affine and
/// `r = ½(|∂g/∂x| + |∂g/∂y|)/|g(0)|`; the light projection adds a factor `1/(1 − ρ)` of the
/// same kind for its division by `w`. Both factors multiply the linearized box.
#[allow(clippy::too_many_arguments)]
#[inline]
fn facet_bound(
    rays: &RayPlane,
    p: Vec3,
    n: Vec3,
    x: f32,
    y: f32,
    lv: &LightView,
    c: crate::math::Vec4,
    res: u32,
) -> Option<(f32, f32)> {
    let dc = rays.at(x + 0.5, y + 0.5);
    let (gc, gx, gy) = (n.dot(dc), n.dot(rays.dx), n.dot(rays.dy));
    let r = 0.5 * (gx.abs() + gy.abs()) / gc.abs();
    if r.is_nan() || r >= 0.5 {
        return None;
    }
    let beta = n.dot(p - rays.eye);
    let s = beta / (gc * gc);
    let jx = (rays.dx * gc - dc * gx) * s;
    let jy = (rays.dy * gc - dc * gy) * s;
    let f = 1.0 / (1.0 - r);
    let mx = lv.clip_from_world * jx.extend(0.0);
    let my = lv.clip_from_world * jy.extend(0.0);
    let rho = f * 0.5 * (mx.w.abs() + my.w.abs()) / c.w.abs();
    if rho.is_nan() || rho >= 0.5 {
        return None;
    }
    let scale = f / (1.0 - rho) * 0.5 * (0.5 * res as f32) / (c.w * c.w);
    let du = |m: crate::math::Vec4| (m.x * c.w - c.x * m.w).abs();
    let dv = |m: crate::math::Vec4| (m.y * c.w - c.y * m.w).abs();
    let ex = (du(mx) + du(my)) * scale;
    let ey = (dv(mx) + dv(my)) * scale;
    (ex.is_finite() && ey.is_finite()).then_some((ex, ey))
}

/// What one silhouette pixel's evaluation produced.
#[derive(Clone, Copy)]
struct Evaluated {
    lit: f32,
    evaluations: u32,
    valid: u32,
    boundary: bool,
}

/// Occlusion and validity of one facet against its candidate blockers.
fn evaluate<M: Mask>(
    f: &Facet,
    blockers: &[u32],
    all: &[Option<Blocker>],
    lut: &Lut<M>,
    centre: M,
    screen: &ScreenMap,
) -> Evaluated {
    let mut occ = M::ZERO;
    let mut valid = M::from_u128(f.valid) & lut.all;
    let half = |pl: &[f32; 4]| {
        let a = pl[0] * f.an + f.beta * pl[1];
        let b = pl[0] * f.bn + f.beta * pl[2];
        let c = pl[0] * f.cn + f.beta * (pl[3] + f.x * pl[1] + f.y * pl[2]);
        lut.half_plane(a, b, c)
    };
    let mut evaluations = 0;
    for &bi in blockers {
        let Some(bl) = &all[bi as usize] else {
            continue;
        };
        if bl.tri == f.own {
            continue;
        }
        evaluations += 1;
        // Signed heights of the vertices above the tangent plane (the light's side).
        let rel = bl.v.map(|v| v - f.p);
        let d = rel.map(|r| f.n.dot(r));
        let scale = rel.iter().fold(0.0f32, |s, r| s.max(r.abs().max_element()));
        let eps = COPLANAR_TOLERANCE * scale;
        let dmax = d[0].max(d[1]).max(d[2]);
        if dmax <= eps {
            // On or below the facet's plane: the segment from any facet point to the light
            // stays above it.
            continue;
        }
        let mut behind: Option<M> = None;
        if d[0].min(d[1]).min(d[2]) <= eps {
            // The triangle cuts (or touches along an edge) the facet's plane: samples past
            // the cut line, where it rises above the facet, are invalid (Section 3.4).
            let mut pts = [Vec3::ZERO; 3];
            let mut np = 0;
            for i in 0..3 {
                let j = (i + 1) % 3;
                if d[i].abs() <= eps {
                    pts[np.min(2)] = bl.v[i];
                    np += 1;
                } else if d[j].abs() > eps && (d[i] > 0.0) != (d[j] > 0.0) {
                    pts[np.min(2)] = bl.v[i] + (bl.v[j] - bl.v[i]) * (d[i] / (d[i] - d[j]));
                    np += 1;
                }
            }
            if np >= 2 {
                if let (Some(a), Some(b)) = (screen.pixel(pts[0]), screen.pixel(pts[1])) {
                    if segment_meets_pixel(a, b, f.x, f.y) {
                        let m = half(&bl.planes[3]);
                        behind = Some(m);
                        // The centre sample is valid by definition; the other side of the
                        // line holds the invalid samples, unless the triangle lies behind the
                        // facet from the light there (a convex crease).
                        if m & centre == M::ZERO {
                            valid &= !m;
                        }
                    }
                }
            }
        }
        let mut m = lut.all;
        for pl in &bl.planes[..3] {
            m &= half(pl);
            if m == M::ZERO {
                break;
            }
        }
        if m != M::ZERO {
            m &= behind.unwrap_or_else(|| half(&bl.planes[3]));
        }
        occ |= m;
    }
    let nv = valid.ones();
    let shadowed = (occ & valid).ones();
    Evaluated {
        lit: 1.0 - shadowed as f32 / nv as f32,
        evaluations,
        valid: nv,
        boundary: shadowed > 0 && shadowed < nv,
    }
}

// ---------------------------------------------------------------------------------------
// The frame

#[allow(clippy::too_many_lines)]
fn run<M: Mask>(
    frame: &Frame,
    adj: &Adjacency,
    lut_cache: &LutCache,
    cfg: &Config,
    stats: &mut Stats,
) -> Result<Visibility> {
    let view = frame.view;
    let (w, h) = (view.width, view.height);
    let res = cfg.res;
    let r2 = res as usize * res as usize;
    let light = frame.light;
    let toward = Toward::new(light);
    let lut: Lut<M> = Lut::new(lut_cache);
    let centre = M::from_u128(1u128 << lut_cache.centre);
    let samples = &lut_cache.samples;

    // 1. Depth maps.
    let maps: LightMaps = stats.stage("depth_map", || render_light_maps(frame, res));
    let projectors: Vec<Projector> = maps.views.iter().map(|v| Projector::new(v, res)).collect();

    // 2. Silhouette mask maps.
    let (masks, n_sil_edges) = stats.stage("silhouette_mask_map", || {
        let edges: Vec<u32> = (0..adj.len() as u32)
            .into_par_iter()
            .with_min_len(1024)
            .filter(|&e| adj.is_silhouette(e as usize, &toward))
            .collect();
        let masks: Vec<MaskMap> = maps
            .views
            .iter()
            .enumerate()
            .map(|(i, v)| MaskMap::build(&edges, adj, &projectors[i], v, &maps.maps[i].depth, res))
            .collect();
        (masks, edges.len())
    });

    // 3–4. Facets, pixel–texel pairs, triangle–texel pairs.
    let rays = RayPlane::new(&view.camera);
    let pixel_width = rays.dx.length();
    let (bias, slope) = (cfg.bias, cfg.slope_bias);
    let depth_test = |k: usize, vi: usize| -> f32 {
        let p = view.position[k];
        let lv = &maps.views[vi];
        let s = lv.project(p);
        let (l, _) = light.shadow_ray(p);
        let d =
            s.depth - receiver_bias(lv.texel_size(res, s.depth), view.normal[k], l, bias, slope);
        lookup_nearest(&maps.maps[vi], s.u, s.v, d)
    };
    let pairs = stats.stage("pt_tt_pairs", || {
        // First pass, every pixel: the depth-map test unless a bound of the projected facet
        // holds a silhouette texel (NaN marks those candidates).
        let mut value = vec![1.0f32; (w * h) as usize];
        value
            .par_chunks_mut(w as usize)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, out) in row.iter_mut().enumerate() {
                    let k = y * w as usize + x;
                    *out = if !view.covered(k) {
                        1.0
                    } else if !frame.receiver_lit(k) {
                        0.0
                    } else {
                        let p = view.position[k];
                        let vi = maps.select(light, p);
                        let (lv, map) = (&maps.views[vi], &maps.maps[vi]);
                        let c = lv.clip_from_world * p.extend(1.0);
                        let (u, v) = (c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
                        match facet_bound(&rays, p, view.normal[k], x as f32, y as f32, lv, c, res)
                        {
                            Some((ex, ey))
                                if masks[vi].count_around(
                                    u * res as f32,
                                    v * res as f32,
                                    ex,
                                    ey,
                                ) == 0 =>
                            {
                                let depth = lv.depth(p);
                                let (l, _) = light.shadow_ray(p);
                                let d = depth
                                    - receiver_bias(
                                        lv.texel_size(res, depth),
                                        view.normal[k],
                                        l,
                                        bias,
                                        slope,
                                    );
                                lookup_nearest(map, u, v, d)
                            }
                            _ => f32::NAN,
                        }
                    };
                }
            });
        // Second pass, the candidates: their exact facets (the paper's bounding-rectangle
        // test on the projected quad).
        let candidates: Vec<u32> = (0..value.len() as u32)
            .into_par_iter()
            .filter(|&k| value[k as usize].is_nan())
            .collect();
        let built: Vec<Result<Facet, f32>> = candidates
            .par_iter()
            .with_min_len(64)
            .map(|&k| {
                let k = k as usize;
                let p = view.position[k];
                let vi = maps.select(light, p);
                let (x, y) = ((k as u32 % w) as f32, (k as u32 / w) as f32);
                let n = view.normal[k];
                let beta = n.dot(p - rays.eye);
                let cap = MAX_FACET_STRETCH * pixel_width * view.depth[k].max(0.0);
                // The footprint on the tangent plane of a square of side `s` about the centre.
                let footprint = |s: f32| -> Option<[Vec3; 4]> {
                    let mut c = [Vec3::ZERO; 4];
                    for (i, (ox, oy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                        .into_iter()
                        .enumerate()
                    {
                        let d = rays.at(x + 0.5 + 0.5 * s * ox, y + 0.5 + 0.5 * s * oy);
                        let nd = n.dot(d);
                        if nd.is_nan() || nd >= 0.0 {
                            return None;
                        }
                        c[i] = rays.eye + d * (beta / nd);
                        let dist = (c[i] - p).length();
                        if dist.is_nan() || dist > cap {
                            return None;
                        }
                    }
                    Some(c)
                };
                let mut scale = 0.0;
                let mut corners = [p; 4];
                let mut s = 1.0;
                for _ in 0..=FACET_SHRINK_STEPS {
                    if let Some(c) = footprint(s) {
                        scale = s;
                        corners = c;
                        break;
                    }
                    s *= 0.5;
                }
                let proj = &projectors[vi];
                let poly = proj.project(&corners);
                if poly.n == 0 {
                    return Err(depth_test(k, vi));
                }
                let (lo, hi) = poly.bounds();
                let rf = res as f32;
                let clampf = |v: f32| v.clamp(0.0, rf - 1.0) as u32;
                if hi.x < 0.0 || hi.y < 0.0 || lo.x >= rf || lo.y >= rf {
                    return Err(depth_test(k, vi));
                }
                let count = masks[vi].count(
                    clampf(lo.x - RASTER_EPS),
                    clampf(lo.y - RASTER_EPS),
                    clampf(hi.x + RASTER_EPS),
                    clampf(hi.y + RASTER_EPS),
                );
                if count == 0 {
                    return Err(depth_test(k, vi));
                }
                let mut valid = 0u128;
                for (i, s) in samples.iter().enumerate() {
                    let o = (*s - Vec2::splat(0.5)).abs();
                    if i == lut_cache.centre || (o.x <= 0.5 * scale && o.y <= 0.5 * scale) {
                        valid |= 1 << i;
                    }
                }
                let dc = rays.at(x, y);
                Ok(Facet {
                    k: k as u32,
                    x,
                    y,
                    view: vi as u32,
                    own: view.triangle[k],
                    p,
                    n,
                    an: -n.dot(rays.dx),
                    bn: -n.dot(rays.dy),
                    cn: -n.dot(dc),
                    beta: -beta,
                    valid,
                    depth_max: proj.depth_span(lo.z, hi.z).1,
                    poly,
                })
            })
            .collect();
        let mut facets: Vec<Facet> = Vec::with_capacity(built.len());
        for (&k, b) in candidates.iter().zip(built) {
            match b {
                Ok(f) => facets.push(f),
                Err(v) => value[k as usize] = v,
            }
        }

        // Pixel–texel pairs: every texel a facet touches, kept per facet, for facets that
        // touch a silhouette texel at all.
        let max_depth: Vec<AtomicU32> = (0..r2 * maps.views.len())
            .map(|_| AtomicU32::new(0))
            .collect();
        let pt: Vec<Vec<u32>> = facets
            .par_iter()
            .with_min_len(64)
            .map(|f| {
                let mut out = Vec::new();
                let mm = &masks[f.view as usize];
                let base = f.view as usize * r2;
                let mut touches = false;
                row_spans(&f.poly, res, |y, x0, x1, _, _| {
                    for x in x0..=x1 {
                        touches |= mm.is_silhouette(x, y);
                        out.push((base + (y * res + x) as usize) as u32);
                    }
                });
                if !touches {
                    return Vec::new();
                }
                let dbits = depth_bits(f.depth_max);
                for &g in &out {
                    max_depth[g as usize].fetch_max(dbits, Ordering::Relaxed);
                }
                out
            })
            .collect();
        // Compaction: facets that touch no silhouette texel take the depth-map test.
        let mut kept = Vec::with_capacity(facets.len());
        let mut pt_start = vec![0u32];
        let mut pt_texels = Vec::new();
        for (f, list) in facets.into_iter().zip(pt) {
            if list.is_empty() {
                value[f.k as usize] = depth_test(f.k as usize, f.view as usize);
            } else {
                pt_texels.extend_from_slice(&list);
                pt_start.push(pt_texels.len() as u32);
                kept.push(f);
            }
        }
        // Texels with pixels get slots, in texel order.
        let mut slot: Vec<u32> = max_depth.into_iter().map(AtomicU32::into_inner).collect();
        let mut slot_depth = Vec::new();
        for d in slot.iter_mut() {
            if *d == 0 {
                *d = NONE;
            } else {
                slot_depth.push(f32::from_bits(*d));
                *d = slot_depth.len() as u32 - 1;
            }
        }

        // Triangle–texel pairs for those texels, sorted by texel.
        let scene = frame.scene;
        let ntri = scene.len();
        const CHUNK: usize = 1024;
        let mut tt: Vec<u64> = Vec::new();
        if !slot_depth.is_empty() {
            for (vi, proj) in projectors.iter().enumerate() {
                let base = vi * r2;
                let slot = &slot;
                let slot_depth = &slot_depth;
                let parts: Vec<Vec<u64>> = (0..ntri.div_ceil(CHUNK))
                    .into_par_iter()
                    .map(|c| {
                        let mut out = Vec::new();
                        for i in c * CHUNK..((c + 1) * CHUNK).min(ntri) {
                            let poly = proj.project(&scene.triangle(i));
                            row_spans(&poly, res, |y, x0, x1, k0, k1| {
                                let dmin = proj.depth_span(k0, k1).0;
                                let row = base + (y * res) as usize;
                                for x in x0..=x1 {
                                    let s = slot[row + x as usize];
                                    if s != NONE && dmin < slot_depth[s as usize] {
                                        out.push((s as u64) << 32 | i as u64);
                                    }
                                }
                            });
                        }
                        out
                    })
                    .collect();
                tt.extend(parts.into_iter().flatten());
            }
            tt.par_sort_unstable();
        }
        // Blockers: every triangle in a pair, in triangle order, set up once.
        let mut used = vec![NONE; ntri];
        for &e in &tt {
            used[(e & 0xffff_ffff) as usize] = 0;
        }
        let mut ids = Vec::new();
        for (i, u) in used.iter_mut().enumerate() {
            if *u == 0 {
                *u = ids.len() as u32;
                ids.push(i as u32);
            }
        }
        let blockers: Vec<Option<Blocker>> = ids
            .par_iter()
            .with_min_len(256)
            .map(|&i| Blocker::new(i, scene.triangle(i as usize), &toward, &rays))
            .collect();
        let mut tt_start = vec![0u32; slot_depth.len() + 1];
        for &e in &tt {
            tt_start[(e >> 32) as usize + 1] += 1;
        }
        for s in 0..slot_depth.len() {
            tt_start[s + 1] += tt_start[s];
        }
        let tt_blocker: Vec<u32> = tt
            .iter()
            .map(|&e| used[(e & 0xffff_ffff) as usize])
            .collect();
        Pairs {
            value,
            facets: kept,
            pt_start,
            pt_texels,
            slot,
            tt_start,
            tt_blocker,
            blockers,
        }
    });

    // 5. Visibility evaluation of the silhouette pixels.
    let screen = ScreenMap {
        clip_from_world: view.camera.clip_from_world(),
        w: w as f32,
        h: h as f32,
    };
    let Pairs {
        mut value,
        facets,
        pt_start,
        pt_texels,
        slot,
        tt_start,
        tt_blocker,
        blockers,
    } = pairs;
    let results: Vec<Evaluated> = stats.stage("shadow_calculation", || {
        facets
            .par_iter()
            .enumerate()
            .with_min_len(16)
            .map_init(Vec::new, |cand: &mut Vec<u32>, (fi, f)| {
                cand.clear();
                for &g in &pt_texels[pt_start[fi] as usize..pt_start[fi + 1] as usize] {
                    let s = slot[g as usize] as usize;
                    cand.extend_from_slice(
                        &tt_blocker[tt_start[s] as usize..tt_start[s + 1] as usize],
                    );
                }
                cand.sort_unstable();
                cand.dedup();
                evaluate(f, cand, &blockers, &lut, centre, &screen)
            })
            .collect()
    });
    let mut evaluations = 0u64;
    let mut valid_sum = 0u64;
    let mut boundary = 0u64;
    let mut boundary_valid = 0u64;
    for (f, e) in facets.iter().zip(&results) {
        value[f.k as usize] = e.lit;
        evaluations += e.evaluations as u64;
        valid_sum += e.valid as u64;
        if e.boundary {
            boundary += 1;
            boundary_valid += e.valid as u64;
        }
    }

    let sil_texels: usize = masks.iter().map(|m| m.texels()).sum();
    stats.count("samples", samples.len() as f64);
    stats.count("silhouette_edges", n_sil_edges as f64);
    stats.count("silhouette_texels", sil_texels as f64);
    stats.count("silhouette_pixels", facets.len() as f64);
    stats.count("pt_pairs", pt_texels.len() as f64);
    stats.count("tt_pairs", tt_blocker.len() as f64);
    stats.count("blockers", blockers.len() as f64);
    stats.count("visibility_evaluations", evaluations as f64);
    stats.count("boundary_pixels", boundary as f64);
    stats.count(
        "valid_samples_mean",
        if facets.is_empty() {
            samples.len() as f64
        } else {
            valid_sum as f64 / facets.len() as f64
        },
    );
    stats.count(
        "valid_samples_boundary_mean",
        if boundary == 0 {
            samples.len() as f64
        } else {
            boundary_valid as f64 / boundary as f64
        },
    );
    stats.memory_bytes = maps.memory_bytes()
        + masks.iter().map(|m| m.bytes()).sum::<u64>()
        + adj.bytes()
        + lut_cache.bytes(std::mem::size_of::<M>())
        + (slot.len() * 4
            + pt_texels.len() * 4
            + pt_start.len() * 4
            + tt_start.len() * 4
            + tt_blocker.len() * 12) as u64
        + (facets.len() * std::mem::size_of::<Facet>()
            + blockers.len() * std::mem::size_of::<Option<Blocker>>()) as u64;

    if frame.dumping() {
        dump(frame, &maps, &masks, &facets, w, h)?;
    }
    Ok(Visibility {
        width: w,
        height: h,
        value: value.into_iter().map(Vec3::splat).collect(),
    })
}

struct Pairs {
    value: Vec<f32>,
    facets: Vec<Facet>,
    pt_start: Vec<u32>,
    pt_texels: Vec<u32>,
    slot: Vec<u32>,
    tt_start: Vec<u32>,
    tt_blocker: Vec<u32>,
    blockers: Vec<Option<Blocker>>,
}

/// Writes the depth maps, the silhouette mask maps (white: silhouette texel, grey: hidden
/// silhouette) and the silhouette pixels.
fn dump(
    frame: &Frame,
    maps: &LightMaps,
    masks: &[MaskMap],
    facets: &[Facet],
    w: u32,
    h: u32,
) -> Result<()> {
    for (i, (m, mm)) in maps.maps.iter().zip(masks).enumerate() {
        frame.dump_depth(&format!("subpixel-depth{i}.png"), m)?;
        frame.dump_grey(&format!("subpixel-silhouette-mask{i}.png"), || {
            image::GrayImage::from_fn(mm.res, mm.res, |x, y| {
                image::Luma([match mm.mask[(y * mm.res + x) as usize] {
                    1 => 255,
                    2 => 96,
                    _ => 0,
                }])
            })
        })?;
    }
    frame.dump_grey("subpixel-silhouette-pixels.png", || {
        let mut img = image::GrayImage::new(w, h);
        for f in facets {
            img.put_pixel(f.k % w, f.k / w, image::Luma([255]));
        }
        img
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::TestRng;

    /// The table's masks equal the exact half-planes, including lines that pass within the
    /// table's quantization of a sample, and a half-plane and its negation cover every sample.
    #[test]
    fn half_planes_are_exact_and_complementary() {
        let mut rng = TestRng(7);
        for (kind, n) in [
            (PatternKind::Grid, 32),
            (PatternKind::RotatedGrid, 64),
            (PatternKind::Grid, 128),
        ] {
            let cache = LutCache::build(kind, n).unwrap();
            let lut: Lut<u128> = Lut::new(&cache);
            let mut near_lines = 0;
            for trial in 0..20_000 {
                let angle = rng.next() * std::f32::consts::TAU;
                let (a, b) = (angle.cos(), angle.sin());
                // Half the lines pass through a sample, nudged by less than the table's error.
                let c = if trial % 2 == 0 {
                    let s = cache.samples[(rng.next() * n as f32) as usize % n as usize];
                    near_lines += 1;
                    -(a * s.x + b * s.y) + (rng.next() - 0.5) * 0.03
                } else {
                    -(a + b) * 0.5 + (rng.next() - 0.5) * 1.6
                };
                let scale = 0.01 + rng.next() * 10.0;
                let (a, b, c) = (a * scale, b * scale, c * scale);
                let m = lut.half_plane(a, b, c);
                let mut exact = 0u128;
                for (i, s) in cache.samples.iter().enumerate() {
                    if a * s.x + b * s.y + c >= 0.0 {
                        exact |= 1 << i;
                    }
                }
                assert_eq!(m, exact, "{kind:?} {n}: ({a}, {b}, {c})");
                assert_eq!(m | lut.half_plane(-a, -b, -c), lut.all);
            }
            assert!(near_lines > 0);
        }
    }
}
