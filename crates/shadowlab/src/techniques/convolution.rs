//! `csm`: convolution shadow maps (Annen, Mertens, Bekaert, Seidel & Kautz, "Convolution
//! Shadow Maps", EGSR 2007).
//!
//! The binary shadow test `f(d, z) = H(z − d)` is expanded in a truncated Fourier series
//! whose terms separate into functions of the receiver depth `d` and of the map depth `z`
//! (Eq. 13), so the map can be turned into basis images `sin(c_k z)`, `cos(c_k z)` that are
//! filtered *before* the test: blurred, mip-mapped and read with tri-linear or anisotropic
//! filtering, which removes the screen-space aliasing of minified shadows.
//!
//! Pipeline per frame: the light's linear depth map (the shared rasterizer, through
//! `shadow_map::render_light_maps`; six cube faces for a point light, each with its own
//! basis images) → `2M` basis values per texel (8-bit unsigned normalized by default, as
//! in the paper, or f32) → optional separable Gaussian blur → full mip chain → per pixel a
//! filtered look-up whose footprint comes from the camera pass's screen-space derivatives
//! (see [`super::filtering`]) → reconstruction with Eq. 13, clamped to `[0, 1]`.
//!
//! Invariants: `c_k = π(2k − 1)` for `k = 1..=M`; the basis values of texel `p` are
//! `B_{2k−1} = sin(c_k z(p))`, `B_{2k} = cos(c_k z(p))` and the shadow term is
//! `clamp(scale · (½ + Σ_k σ_k (2/c_k)[cos(c_k d′) B_{2k−1} − sin(c_k d′) B_{2k}]), 0, 1)`
//! with `σ_k = exp(−α (k/M)²)` (Section 3.2.1) and `d′ = d − offset` (Section 3.2.2).
//! Filtering the basis equals filtering the shadow test when `d` is constant over the
//! filter's support (Eq. 8), up to the 8-bit quantization.
//!
//! Departures from the paper, and why:
//! - Eq. 11 prints `sin(c_k(d − z))`, which is 1 where the receiver is *behind* the map;
//!   Eq. 13 (implemented) is `sin(c_k(z − d))`, the shadow test the paper defines in Eq. 1.
//! - The paper does not give its offset; here the default (`offset = auto`) is the
//!   smallest `t > 0` where the attenuated reconstruction of the step first comes within
//!   [`OFFSET_PLATEAU_TOLERANCE`] of its plateau (`min(1, max g)`), so a surface that is
//!   its own occluder (`z = d`) is lit, whatever `M` and `α`.
//! - Depths are normalized over the interval from the nearest map texel under the filter
//!   support of a visible receiver that something may shadow to the farthest such receiver
//!   ([`super::filtering::DepthRange::fitted`]; the paper asks for a tightly fitted light
//!   frustum; clamping outside it keeps every receiver's test, and receivers that nothing can
//!   shadow stay lit), into `[0, 1 − 2·offset]` rather than `[0, 1]`:
//!   the series is periodic with period 2 and the offset shifts `z − d` up, so without
//!   that margin a receiver far in front of its neighbours' depths (`z − d + offset` near
//!   or past 1) would fall on the next period's step and turn dark.
//! - The paper's α is not given; [`DEFAULT_ALPHA`] states the trade-off chosen, and
//!   [`DEFAULT_M`] why the default order is the paper's figures' 16 rather than its
//!   recommended 4.
//! - 8-bit maps of at least [`TABLE_MIN_TEXELS`] texels are encoded through a
//!   [`BasisTable`]: the normalized depth is rounded to one of 2¹⁶ levels (as a 16-bit
//!   depth buffer would hold it) and the level's precomputed codes are copied, about a fifth
//!   of the work of evaluating the basis per texel. The rounding moves a code by one, at
//!   most, for 0.3% of the codes at M = 4 and 1.2% at M = 16; 32-bit maps and smaller maps
//!   are encoded directly.
//!
//! Known artifacts (as in the paper): light leaks where an occluder is within about the
//! offset (plus the step's half-width, ≈ 0.07 of the depth range at M = 4) of its receiver
//! — contact shadows fade, more so for small M; ringing leaves shadowed areas slightly
//! uneven; a sloped receiver filtered over a wide footprint shades itself once the depth
//! change across the footprint exceeds the offset; point-light cube faces filter up to their
//! own edges only, so wide filters show seams.

use super::filtering::{check_map_size, Channel, FilterSettings, FilteredMaps};
use super::shadow_map::{check_resolution, DEFAULT_RESOLUTION};
use super::{
    check_range, parse_value, unknown_param, Frame, ShadowTechnique, Shadows, Stats, Visibility,
};
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::f32::consts::PI;

/// Default truncation order M: 16, the order of the paper's Figures 4 and 5. The paper
/// finds M = 4 "satisfactory" on its scenes, but the offset that lights a self-occluding
/// surface and the step's half-width are fixed shares of the fitted light-depth range
/// (0.10 and 0.07 of it at M = 4, α = 0.5), so on a real scene metres deep every shadow
/// within that distance of its caster is lost: measured at 480×360 against a 16-sample
/// reference, M = 4 had 1.3–5.4× the mean error of the better of `vsm` and `pcf` on eight
/// real meshes; at the defaults (M = 16, α = 0) it is 1.0–1.9× on eighteen, within 1.3×
/// on eleven (`scripts/verdict-table.sh`). Contact shadows within the offset of their
/// caster and curved receivers shading themselves across a wide footprint remain its
/// largest errors. The price is four times the basis images (memory and encode time)
/// and four times the look-up work of M = 4, and more error under strong minification:
/// on the `fence-far` scene at 160×120, where every look-up spans many texels, M = 16
/// has 0.082 mean error (0.046 with α = 1) against 0.027 at M = 4, α = 0.5, and `pcf`'s
/// 0.029; pass `m=4` and `alpha=0.5` for such views.
pub const DEFAULT_M: u32 = 16;
/// The largest truncation order accepted.
pub const MAX_M: u32 = 16;
/// Default ringing attenuation α: none. At M = 16 the Gibbs overshoot (9%) is clamped away
/// on lit surfaces and the ringing in shadow is confined to |z − d| < a few 1/M; any α > 0
/// flattens the step and needs a larger offset, which fades more contact shadows: at
/// M = 16, α = 0.5 had 5–25% more mean error than α = 0 on every real mesh measured, α = 1
/// 15–65%. At M = 4, α = 0.5 lowers the overshoot to 2.5% and is the better choice there.
pub const DEFAULT_ALPHA: f32 = 0.0;
/// Default scale of the reconstructed step (Section 3.2.2): 1 leaves it as it is; 2 makes it
/// steeper and lights `z = d` without an offset, at the price of sharper (re-aliased) shadows.
pub const DEFAULT_SCALE: f32 = 1.0;
/// Where the attenuated step never overshoots 1 (large α), the automatic offset is where it
/// first comes this close to its maximum: smaller values light self-occluding surfaces more
/// fully but push the offset out (more contact-shadow leaking).
pub const OFFSET_PLATEAU_TOLERANCE: f32 = 0.01;
/// The automatic offset aims the step at `1 + LIT_MARGIN` for a self-occluding surface, so
/// that after clamping it is fully lit despite the 8-bit quantization of the basis (whose
/// reconstruction error stays below about 0.006 at M = 4); a larger margin costs offset.
pub const LIT_MARGIN: f32 = 0.01;
/// The largest offset accepted, in normalized depth: beyond it the margin that keeps
/// `z − d + offset` inside one period of the series vanishes.
pub const MAX_OFFSET: f32 = 0.25;
/// Resolution of the search for the automatic offset, in normalized depth.
const OFFSET_SEARCH_STEP: f32 = 1.0 / 8192.0;

/// The truncated, attenuated Fourier expansion of the shadow test (Eqs. 10–14).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expansion {
    /// Truncation order M: `2M` basis functions.
    pub m: u32,
    /// Ringing attenuation α (0 leaves the series unchanged).
    pub alpha: f32,
}

impl Expansion {
    /// The frequency `c_k = π(2k − 1)` of term `k` (1-based).
    #[inline]
    pub fn c(k: u32) -> f32 {
        PI * (2 * k - 1) as f32
    }

    /// The attenuation `σ_k = exp(−α (k/M)²)` of term `k`.
    #[inline]
    pub fn attenuation(&self, k: u32) -> f32 {
        let r = k as f32 / self.m as f32;
        (-self.alpha * r * r).exp()
    }

    /// Number of basis images, `2M`.
    pub fn channels(&self) -> usize {
        2 * self.m as usize
    }

    /// Writes `sin(c_k x)` into `out[2(k−1)]` and `cos(c_k x)` into `out[2(k−1)+1]` for
    /// `k = 1..=M`, by rotating the angle `πx` in steps of `2πx`.
    #[inline]
    pub fn sin_cos(m: u32, x: f32, out: &mut [f32]) {
        let (s1, c1) = sin_cos_pi(x);
        let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
        let (mut s, mut c) = (s1, c1);
        for pair in out[..2 * m as usize].chunks_exact_mut(2) {
            pair[0] = s;
            pair[1] = c;
            (s, c) = (s * c2 + c * s2, c * c2 - s * s2);
        }
    }

    /// The basis values `B_i(z)` of a map depth `z` (Eq. 14).
    #[inline]
    pub fn basis(&self, z: f32, out: &mut [f32]) {
        Self::sin_cos(self.m, z, out);
    }

    /// The expansion at receiver depth `d` against (filtered) basis values: `½ + Σ a_i(d) B_i`,
    /// attenuated, not offset, not scaled, not clamped.
    pub fn reconstruct(&self, d: f32, basis: &[f32]) -> f32 {
        self.reconstruction().eval(d, basis)
    }

    /// Eq. 13 with the constant factors `2σ_k / c_k` of its coefficients computed once.
    pub fn reconstruction(&self) -> Reconstruction {
        let mut weight = [0.0; MAX_M as usize];
        for k in 1..=self.m {
            weight[k as usize - 1] = 2.0 * self.attenuation(k) / Self::c(k);
        }
        Reconstruction { m: self.m, weight }
    }

    /// The reconstructed step as a function of `t = z − d`: `½ + Σ σ_k (2/c_k) sin(c_k t)`.
    pub fn step(&self, t: f32) -> f32 {
        0.5 + (1..=self.m)
            .map(|k| 2.0 * self.attenuation(k) / Self::c(k) * (Self::c(k) * t).sin())
            .sum::<f32>()
    }

    /// The automatic offset: the smallest `t > 0` at which [`Self::step`] reaches
    /// `1 + LIT_MARGIN` — so a self-occluding surface clamps to fully lit even with the
    /// 8-bit quantization noise — or, where the step's maximum over `(0, ½]` stays below
    /// that, comes within [`OFFSET_PLATEAU_TOLERANCE`] of its maximum.
    pub fn auto_offset(&self) -> f32 {
        let n = (0.5 / OFFSET_SEARCH_STEP) as u32;
        let values: Vec<f32> = (1..=n)
            .map(|i| self.step(i as f32 * OFFSET_SEARCH_STEP))
            .collect();
        let peak = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let target = if peak >= 1.0 + LIT_MARGIN {
            1.0 + LIT_MARGIN
        } else {
            peak - OFFSET_PLATEAU_TOLERANCE
        };
        let i = values
            .iter()
            .position(|&v| v >= target)
            .unwrap_or(values.len() - 1);
        ((i + 1) as f32 * OFFSET_SEARCH_STEP).min(MAX_OFFSET)
    }
}

/// `sin r` and `cos r` for `r ∈ [−π/2, π/2]` by Taylor polynomials of degree 11 and 12.
#[inline(always)]
fn sin_cos_taylor(r: f32) -> (f32, f32) {
    let r2 = r * r;
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0
                    + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0 + r2 * (-1.0 / 39_916_800.0))))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0
                    + r2 * (1.0 / 40_320.0
                        + r2 * (-1.0 / 3_628_800.0 + r2 * (1.0 / 479_001_600.0))))));
    (s, c)
}

/// `sin(πx)` and `cos(πx)` for `|x| < 2³¹`: reduction to `r = x − round(x)` and Taylor polynomials of
/// degree 11 and 12 on `πr ∈ [−π/2, π/2]` (error below 2·10⁻⁷, several times faster than
/// two library calls; the basis of a 2048² map needs one pair per texel).
#[inline(always)]
pub fn sin_cos_pi(x: f32) -> (f32, f32) {
    let n = super::filtering::fast_floor(x + 0.5);
    let (s, c) = sin_cos_taylor((x - n) * PI);
    // An odd number of half-turns flips both.
    if (n as i64) & 1 == 0 {
        (s, c)
    } else {
        (-s, -c)
    }
}

/// [`sin_cos_pi`] for `|x| < 2²²` in operations that vectorize (no integer conversion):
/// bit-identical results.
#[inline(always)]
fn sin_cos_pi_wide(x: f32) -> (f32, f32) {
    // ⌊x + ½⌋: adding 1.5·2²³ rounds to the nearest integer, one less where that rounded up;
    // the low bit of the sum's mantissa is that integer's parity.
    const MAGIC: f32 = 12_582_912.0;
    let y = x + 0.5;
    let t = y + MAGIC;
    let rounded = t - MAGIC;
    let up = rounded > y;
    let n = if up { rounded - 1.0 } else { rounded };
    let odd = (t.to_bits() ^ u32::from(up)) & 1;
    let (s, c) = sin_cos_taylor((x - n) * PI);
    let flip = odd << 31;
    (
        f32::from_bits(s.to_bits() ^ flip),
        f32::from_bits(c.to_bits() ^ flip),
    )
}

/// Texels per block of [`encode_row`].
const ENCODE_BLOCK: usize = 64;

/// The stored basis values (`T::from_f32` of `T::encode_signed` of [`Expansion::basis`] of
/// the normalized depth) of a row of map depths, `2m` values per texel, into `row`: the same
/// values as the per-texel computation, computed and quantized for blocks of texels at once
/// so the arithmetic vectorizes. `M` is `m` when it is known at compile time, else 0.
fn encode_row<T: Channel, const M: usize>(
    m: u32,
    range: &super::filtering::DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        #[allow(unsafe_code)]
        unsafe {
            encode_row_avx2::<T, M>(m, range, depths, row)
        };
        return;
    }
    encode_row_body::<T, M>(m, range, depths, row);
}

/// [`encode_row`] compiled for AVX2: twice the vector width for the same operations, so the
/// same results (no fused multiply-adds: those would round differently).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn encode_row_avx2<T: Channel, const M: usize>(
    m: u32,
    range: &super::filtering::DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    encode_row_body::<T, M>(m, range, depths, row);
}

/// The body of [`encode_row`], inlined into each instruction-set variant.
#[inline(always)]
fn encode_row_body<T: Channel, const M: usize>(
    m: u32,
    range: &super::filtering::DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    let m = if M > 0 { M } else { m as usize };
    let ch = 2 * m;
    // Scratch for one block, initialized once per row: lanes past a short last block keep
    // finite values of the previous block and are never stored.
    let mut stored = [[T::default(); ENCODE_BLOCK]; 2 * MAX_M as usize];
    let (mut s, mut c) = ([0.0f32; ENCODE_BLOCK], [0.0f32; ENCODE_BLOCK]);
    let (mut s2, mut c2) = ([0.0f32; ENCODE_BLOCK], [0.0f32; ENCODE_BLOCK]);
    let (mut es, mut ec) = ([0.0f32; ENCODE_BLOCK], [0.0f32; ENCODE_BLOCK]);
    for (block, out) in depths
        .chunks(ENCODE_BLOCK)
        .zip(row.chunks_mut(ENCODE_BLOCK * ch))
    {
        let n = block.len();
        for i in 0..n {
            let (s1, c1) = sin_cos_pi_wide(range.normalize(block[i]));
            s[i] = s1;
            c[i] = c1;
            // As in `Expansion::sin_cos`: the angle steps by 2πx.
            s2[i] = 2.0 * s1 * c1;
            c2[i] = c1 * c1 - s1 * s1;
        }
        for pair in stored[..ch].chunks_exact_mut(2) {
            let [qs, qc] = pair else { unreachable!() };
            for i in 0..ENCODE_BLOCK {
                es[i] = T::encode_signed(s[i]);
                ec[i] = T::encode_signed(c[i]);
                (s[i], c[i]) = (s[i] * c2[i] + c[i] * s2[i], c[i] * c2[i] - s[i] * s2[i]);
            }
            T::store_row(&es[..n], &mut qs[..n]);
            T::store_row(&ec[..n], &mut qc[..n]);
        }
        for (i, texel) in out.chunks_exact_mut(ch).enumerate() {
            for (j, v) in texel.iter_mut().enumerate() {
                *v = stored[j][i];
            }
        }
    }
}

/// [`encode_row`] for a truncation order known at run time, dispatched to the compiled
/// orders.
fn encode_row_any_m<T: Channel>(
    m: u32,
    range: &super::filtering::DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    match m {
        1 => encode_row::<T, 1>(1, range, depths, row),
        2 => encode_row::<T, 2>(2, range, depths, row),
        3 => encode_row::<T, 3>(3, range, depths, row),
        4 => encode_row::<T, 4>(4, range, depths, row),
        8 => encode_row::<T, 8>(8, range, depths, row),
        16 => encode_row::<T, 16>(16, range, depths, row),
        m => encode_row::<T, 0>(m, range, depths, row),
    }
}

/// Levels of normalized depth in a [`BasisTable`]: the depth is rounded to one of 2¹⁶
/// evenly spaced values, as a 16-bit depth buffer would store it. The phase error this adds
/// is at most `c_M · span / (2 · (2¹⁶ − 1))`: 1.7·10⁻⁴ at M = 4 and 7.4·10⁻⁴ at M = 16,
/// below half of an 8-bit code's step (3.9·10⁻³), so a stored code differs by at most one
/// from direct encoding, and only where the exact value lies that close to a rounding
/// boundary.
pub const TABLE_LEVELS: usize = 1 << 16;
/// Maps of at least this many texels are encoded through a [`BasisTable`] (8-bit basis
/// only): building the table costs as much as encoding [`TABLE_LEVELS`] texels directly,
/// a look-up about a fifth of a direct encoding.
pub const TABLE_MIN_TEXELS: usize = 4 * TABLE_LEVELS;

/// The stored basis values of [`TABLE_LEVELS`] evenly spaced normalized depths in
/// `[0, span]`: a texel is encoded by rounding its normalized depth to the nearest level and
/// copying that level's `2M` codes.
pub struct BasisTable<T> {
    /// `2M` stored values per level.
    codes: Vec<T>,
    /// Values per level (`2M`).
    channels: usize,
    /// Levels per unit of normalized depth.
    levels_per_unit: f32,
}

impl<T: Channel> BasisTable<T> {
    /// The table of order `m` over `[0, span]`.
    pub fn new(m: u32, span: f32) -> Self {
        use rayon::prelude::*;
        let channels = 2 * m as usize;
        let last = (TABLE_LEVELS - 1) as f32;
        // The identity range maps level j's depth j / (L − 1) to j / (L − 1) · span.
        let unit = super::filtering::DepthRange {
            near: 0.0,
            far: 1.0,
            span,
        };
        let depths: Vec<f32> = (0..TABLE_LEVELS).map(|j| j as f32 / last).collect();
        let mut codes = vec![T::default(); TABLE_LEVELS * channels];
        const CHUNK: usize = 4096;
        codes
            .par_chunks_mut(CHUNK * channels)
            .zip(depths.par_chunks(CHUNK))
            .for_each(|(out, d)| encode_row_any_m(m, &unit, d, out));
        BasisTable {
            codes,
            channels,
            levels_per_unit: if span > 0.0 { last / span } else { 0.0 },
        }
    }

    /// The level a normalized depth `z ∈ [0, span]` rounds to.
    #[inline]
    pub fn level(&self, z: f32) -> usize {
        // Clamped in floating point first, so the conversion cannot saturate (and
        // vectorizes); `z` is finite and non-negative (see `DepthRange::normalize`).
        let x = (z * self.levels_per_unit + 0.5).min((TABLE_LEVELS - 1) as f32);
        x as i32 as usize
    }

    /// Encodes a row of map depths, normalized by `range`, into `row`.
    pub fn encode_row(&self, range: &super::filtering::DepthRange, depths: &[f32], row: &mut [T]) {
        super::filtering::with_channels!(
            self.channels,
            table_encode_row_n::<T>,
            (self, range, depths, row)
        )
    }
}

/// [`BasisTable::encode_row`] for `N` values per level known at compile time (0: read at run
/// time), so that a texel is one fixed-size copy.
#[inline(always)]
fn table_encode_row_n<T: Channel, const N: usize>(
    table: &BasisTable<T>,
    range: &super::filtering::DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    let ch = if N > 0 { N } else { table.channels };
    // Levels for a block first (arithmetic that vectorizes), then the copies.
    let mut level = [0u32; ENCODE_BLOCK];
    for (block, out) in depths
        .chunks(ENCODE_BLOCK)
        .zip(row.chunks_mut(ENCODE_BLOCK * ch))
    {
        for (l, &d) in level.iter_mut().zip(block) {
            *l = table.level(range.normalize(d)) as u32;
        }
        for (texel, &j) in out.chunks_exact_mut(ch).zip(&level) {
            let j = j as usize * ch;
            texel.copy_from_slice(&table.codes[j..j + ch]);
        }
    }
}

/// Eq. 13 ready to evaluate per pixel (see [`Expansion::reconstruction`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reconstruction {
    m: u32,
    weight: [f32; MAX_M as usize],
}

impl Reconstruction {
    /// `½ + Σ_k (2σ_k/c_k)[cos(c_k d) B_{2k−1} − sin(c_k d) B_{2k}]` (unclamped).
    #[inline]
    pub fn eval(&self, d: f32, basis: &[f32]) -> f32 {
        let mut sc = [0.0f32; 2 * MAX_M as usize];
        Expansion::sin_cos(self.m, d, &mut sc);
        let m = self.m as usize;
        let mut sum = 0.0;
        for ((w, t), b) in self.weight[..m]
            .iter()
            .zip(sc[..2 * m].chunks_exact(2))
            .zip(basis[..2 * m].chunks_exact(2))
        {
            sum += w * (t[1] * b[0] - t[0] * b[1]);
        }
        0.5 + sum
    }

    /// [`Self::eval`] of the basis values `scale · raw + bias` (a linear decoding of filtered
    /// stored codes), without decoding each channel: the sum is linear in the basis, so it is
    /// `scale · Σ(raw) + bias · Σ(1)` with both sums taken in one pass.
    #[inline]
    pub fn eval_encoded(&self, d: f32, raw: &[f32], scale: f32, bias: f32) -> f32 {
        let mut sc = [0.0f32; 2 * MAX_M as usize];
        Expansion::sin_cos(self.m, d, &mut sc);
        let m = self.m as usize;
        let (mut sum, mut ones) = (0.0, 0.0);
        for ((w, t), b) in self.weight[..m]
            .iter()
            .zip(sc[..2 * m].chunks_exact(2))
            .zip(raw[..2 * m].chunks_exact(2))
        {
            sum += w * (t[1] * b[0] - t[0] * b[1]);
            ones += w * (t[1] - t[0]);
        }
        0.5 + scale * sum + bias * ones
    }
}

/// Storage of the basis images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// 8-bit unsigned normalized, `[-1, 1] → 0..=255` (the paper's setting).
    U8,
    /// 32-bit float.
    F32,
}

/// The `csm` technique.
#[derive(Clone, Debug)]
pub struct Convolution {
    /// Map side in texels.
    pub resolution: u32,
    /// Truncation order M.
    pub m: u32,
    /// Ringing attenuation α.
    pub alpha: f32,
    /// Offset subtracted from the receiver depth, in normalized depth; `None` = automatic.
    pub offset: Option<f32>,
    /// Scale of the reconstructed step before clamping.
    pub scale: f32,
    /// Storage of the basis images.
    pub precision: Precision,
    /// Blur, mip-mapping and look-up filter.
    pub filtering: FilterSettings,
}

impl Default for Convolution {
    fn default() -> Self {
        Convolution {
            resolution: DEFAULT_RESOLUTION,
            m: DEFAULT_M,
            alpha: DEFAULT_ALPHA,
            offset: None,
            scale: DEFAULT_SCALE,
            precision: Precision::U8,
            filtering: FilterSettings::default(),
        }
    }
}

const KEYS: &[&str] = &[
    "resolution",
    "m",
    "alpha",
    "offset",
    "scale",
    "precision",
    "blur",
    "filter",
    "max-aniso",
];

impl Convolution {
    /// The expansion in effect.
    pub fn expansion(&self) -> Expansion {
        Expansion {
            m: self.m,
            alpha: self.alpha,
        }
    }

    /// The offset in effect, in normalized depth.
    pub fn resolved_offset(&self) -> f32 {
        self.offset
            .unwrap_or_else(|| self.expansion().auto_offset())
    }

    fn run<T: Channel>(&self, frame: &Frame, stats: &mut Stats) -> Result<Vec<crate::math::Vec3>> {
        let exp = self.expansion();
        let offset = self.resolved_offset();
        let span = 1.0 - 2.0 * offset;
        let ch = exp.channels();
        let views = if matches!(frame.light, crate::light::Light::Point { .. }) {
            6
        } else {
            1
        };
        check_map_size("csm", views, self.resolution, ch, T::BYTES)?;
        let maps = FilteredMaps::<T>::build_rows(
            frame,
            self.resolution,
            ch,
            span,
            &self.filtering,
            stats,
            |r| {
                let r = *r;
                let texels = self.resolution as usize * self.resolution as usize;
                // 8-bit maps much larger than the table are encoded through it.
                let table = (T::BYTES == 1 && texels >= TABLE_MIN_TEXELS)
                    .then(|| BasisTable::<T>::new(exp.m, r.span));
                move |m: &crate::raster::DepthBuffer, y: u32, row: &mut [T]| {
                    let w = m.width as usize;
                    let depths = &m.depth[y as usize * w..(y as usize + 1) * w];
                    match &table {
                        Some(t) => t.encode_row(&r, depths, row),
                        None => encode_row_any_m(exp.m, &r, depths, row),
                    }
                }
            },
        );
        let scale = self.scale;
        let rec = exp.reconstruction();
        // The decoding is linear: decode(raw) = raw · (decode(1) − decode(0)) + decode(0).
        let (bias, unit) = (T::decode_signed(0.0), T::decode_signed(1.0));
        let value = maps.lookup(frame, &self.filtering, stats, |d, raw| {
            (scale * rec.eval_encoded(d - offset, raw, unit - bias, bias)).clamp(0.0, 1.0)
        });
        stats.memory_bytes = maps.memory_bytes();
        stats.count("depth_map_bytes", maps.depth_bytes as f64);
        stats.count("basis_images", (ch * maps.chains.len()) as f64);
        stats.count("offset", offset as f64);
        if let Some(r) = maps.ranges.first() {
            // The offset in world units: how far in front of a receiver an occluder must be
            // before its shadow starts to show.
            stats.count("depth_range", (r.far - r.near) as f64);
            stats.count("offset_world", (offset / span * (r.far - r.near)) as f64);
        }
        stats.count(
            "mip_levels",
            maps.chains.first().map_or(0, |c| c.levels.len()) as f64,
        );
        for (i, c) in maps.chains.iter().enumerate() {
            frame.dump_image(&format!("csm-basis{i}-sin1.png"), || {
                let t = &c.levels[0];
                crate::picture::RgbImage::from_fn(t.width, t.height, |x, y| {
                    let b = T::decode_signed(t.texel(x, y)[0].to_f32());
                    // sin(c_1 z): blue where positive, red where negative, as in the paper's Figure 5.
                    let g = (b.abs() * 255.0) as u8;
                    if b >= 0.0 {
                        image::Rgb([0, 0, g])
                    } else {
                        image::Rgb([g, 0, 0])
                    }
                })
            })?;
        }
        Ok(value)
    }
}

impl ShadowTechnique for Convolution {
    fn name(&self) -> &'static str {
        "csm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("m".to_string(), self.m.into()),
            ("alpha".to_string(), self.alpha.into()),
            ("offset".to_string(), self.resolved_offset().into()),
            ("scale".to_string(), self.scale.into()),
            (
                "precision".to_string(),
                match self.precision {
                    Precision::U8 => "u8",
                    Precision::F32 => "f32",
                }
                .into(),
            ),
        ]);
        self.filtering.params(&mut m);
        m
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "csm";
        if self.filtering.set_param(t, key, value)? {
            return Ok(());
        }
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "m" => self.m = check_range(t, key, parse_value(t, key, value)?, 1, MAX_M)?,
            "alpha" => self.alpha = check_range(t, key, parse_value(t, key, value)?, 0.0, 100.0)?,
            "offset" => {
                self.offset = if value.trim().eq_ignore_ascii_case("auto") {
                    None
                } else {
                    Some(check_range(
                        t,
                        key,
                        parse_value(t, key, value)?,
                        0.0,
                        MAX_OFFSET,
                    )?)
                }
            }
            "scale" => self.scale = check_range(t, key, parse_value(t, key, value)?, 0.01, 100.0)?,
            "precision" => {
                self.precision = match value.trim().to_ascii_lowercase().as_str() {
                    "u8" | "8" | "8bit" => Precision::U8,
                    "f32" | "32" | "float" => Precision::F32,
                    _ => {
                        return Err(Error::param(format!(
                    "csm.precision = {value:?}: use u8 (8-bit basis images, the paper's) or f32"
                )))
                    }
                }
            }
            _ => return Err(unknown_param(t, key, KEYS)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        check_resolution("csm", self.resolution)?;
        let mut stats = Stats::default();
        let value = match self.precision {
            Precision::U8 => self.run::<u8>(frame, &mut stats)?,
            Precision::F32 => self.run::<f32>(frame, &mut stats)?,
        };
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

    #[test]
    fn sin_cos_recurrence_matches_direct_evaluation() {
        let mut out = [0.0; 32];
        for x in [0.0, 0.13, 0.5, 0.77, 1.0] {
            Expansion::sin_cos(16, x, &mut out);
            for k in 1..=16u32 {
                let a = Expansion::c(k) * x;
                assert!(
                    (out[2 * (k - 1) as usize] - a.sin()).abs() < 2e-5,
                    "x {x} k {k}"
                );
                assert!(
                    (out[2 * (k - 1) as usize + 1] - a.cos()).abs() < 2e-5,
                    "x {x} k {k}"
                );
            }
        }
    }

    #[test]
    fn wide_sin_cos_pi_is_bit_identical() {
        let mut xs: Vec<f32> = (-40_000..=40_000).map(|i| i as f32 / 8192.0).collect();
        xs.extend((0..=2000).map(|i| i as f32 * 0.5 - 500.0));
        xs.extend([
            0.5f32,
            -0.5,
            1.5,
            0.49999997,
            0.50000006,
            -0.0,
            1e-30,
            1_000_000.5,
        ]);
        for x in xs {
            let (a, b) = sin_cos_pi(x);
            let (c, d) = sin_cos_pi_wide(x);
            assert_eq!(
                (a.to_bits(), b.to_bits()),
                (c.to_bits(), d.to_bits()),
                "x {x}"
            );
        }
    }

    #[test]
    fn encoded_rows_match_per_texel_basis() {
        let range = super::super::filtering::DepthRange {
            near: 2.0,
            far: 7.0,
            span: 0.77,
        };
        let depths: Vec<f32> = (0..150)
            .map(|i| match i {
                3 => f32::INFINITY,
                4 => f32::NAN,
                _ => 1.5 + i as f32 * 0.041,
            })
            .collect();
        for m in [1, 4, 7, 16] {
            let ch = 2 * m as usize;
            let mut row = vec![0u8; depths.len() * ch];
            let mut row_f = vec![0.0f32; depths.len() * ch];
            match m {
                4 => {
                    encode_row::<u8, 4>(m, &range, &depths, &mut row);
                    encode_row::<f32, 4>(m, &range, &depths, &mut row_f);
                }
                _ => {
                    encode_row::<u8, 0>(m, &range, &depths, &mut row);
                    encode_row::<f32, 0>(m, &range, &depths, &mut row_f);
                }
            }
            let mut b = vec![0.0f32; ch];
            for (x, &d) in depths.iter().enumerate() {
                Expansion::sin_cos(m, range.normalize(d), &mut b);
                for (j, v) in b.iter().enumerate() {
                    let want = <u8 as Channel>::encode_signed(*v);
                    assert_eq!(row[x * ch + j], u8::from_f32(want), "m {m} x {x} j {j}");
                    assert_eq!(
                        row_f[x * ch + j].to_bits(),
                        v.to_bits(),
                        "m {m} x {x} j {j}"
                    );
                }
            }
        }
    }

    #[test]
    fn every_instruction_set_variant_encodes_the_same_codes() {
        let range = super::super::filtering::DepthRange {
            near: -1.0,
            far: 3.0,
            span: 0.8,
        };
        let depths: Vec<f32> = (0..1000).map(|i| -1.3 + i as f32 * 0.0047).collect();
        for m in [1u32, 4, 5, 16] {
            let ch = 2 * m as usize;
            let (mut dispatched, mut baseline) =
                (vec![0u8; depths.len() * ch], vec![0u8; depths.len() * ch]);
            let (mut dispatched_f, mut baseline_f) =
                (vec![0f32; depths.len() * ch], vec![0f32; depths.len() * ch]);
            encode_row_any_m(m, &range, &depths, &mut dispatched);
            encode_row_body::<u8, 0>(m, &range, &depths, &mut baseline);
            encode_row_any_m(m, &range, &depths, &mut dispatched_f);
            encode_row_body::<f32, 0>(m, &range, &depths, &mut baseline_f);
            assert_eq!(dispatched, baseline, "m {m}");
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&dispatched_f), bits(&baseline_f), "m {m}");
        }
    }

    #[test]
    fn table_encoding_is_direct_encoding_within_one_code() {
        let range = super::super::filtering::DepthRange {
            near: 2.0,
            far: 7.0,
            span: 0.77,
        };
        // Depths on a fine irregular grid across (and past) the range, plus the empty texel.
        let mut depths: Vec<f32> = (0..20_000)
            .map(|i| 1.9 + 5.2 * ((i as f32 * 0.618_034).fract() + i as f32) / 20_000.0)
            .collect();
        depths.extend([f32::INFINITY, f32::NAN, 2.0, 7.0]);
        for m in [1, 3, 4, 8, 16] {
            let ch = 2 * m as usize;
            let table = BasisTable::<u8>::new(m, range.span);
            let mut direct = vec![0u8; depths.len() * ch];
            let mut tabled = vec![0u8; depths.len() * ch];
            encode_row_any_m(m, &range, &depths, &mut direct);
            table.encode_row(&range, &depths, &mut tabled);
            let mut differ = 0;
            for (i, (a, b)) in direct.iter().zip(&tabled).enumerate() {
                assert!(a.abs_diff(*b) <= 1, "m {m} value {i}: {a} vs {b}");
                differ += usize::from(a != b);
            }
            // Only values within the phase error of a rounding boundary differ: a small
            // share, growing with the highest frequency (see `TABLE_LEVELS`).
            let share = differ as f64 / direct.len() as f64;
            eprintln!("m {m}: {share:.4} of the codes differ by one");
            assert!(share < 0.02 * m as f64, "m {m}: {share}");
            // The table's own levels are exact.
            let last = (TABLE_LEVELS - 1) as f32;
            let unit = super::super::filtering::DepthRange {
                near: 0.0,
                far: 1.0,
                span: range.span,
            };
            let levels: Vec<f32> = (0..TABLE_LEVELS)
                .step_by(997)
                .map(|j| j as f32 / last)
                .collect();
            let mut a = vec![0u8; levels.len() * ch];
            let mut b = vec![0u8; levels.len() * ch];
            encode_row_any_m(m, &unit, &levels, &mut a);
            table.encode_row(&unit, &levels, &mut b);
            assert_eq!(a, b, "m {m}");
        }
    }

    #[test]
    fn fast_sin_cos_pi_is_accurate() {
        for i in -3000..=3000 {
            let x = i as f32 / 1000.0;
            let (s, c) = sin_cos_pi(x);
            let (rs, rc) = (std::f64::consts::PI * x as f64).sin_cos();
            assert!(
                (s as f64 - rs).abs() < 5e-7 && (c as f64 - rc).abs() < 5e-7,
                "x {x}"
            );
        }
    }

    #[test]
    fn reconstruction_is_the_step_of_z_minus_d() {
        let e = Expansion { m: 8, alpha: 0.5 };
        let mut b = [0.0; 16];
        for (z, d) in [(0.2, 0.7), (0.7, 0.2), (0.4, 0.41), (0.9, 0.1)] {
            e.basis(z, &mut b);
            assert!((e.reconstruct(d, &b) - e.step(z - d)).abs() < 1e-4);
        }
    }

    #[test]
    fn evaluating_encoded_basis_equals_decoding_first() {
        let e = Expansion { m: 4, alpha: 0.5 };
        let rec = e.reconstruction();
        let mut b = [0.0f32; 8];
        e.basis(0.37, &mut b);
        let raw: Vec<f32> = b
            .iter()
            .map(|v| <u8 as Channel>::encode_signed(*v))
            .collect();
        let (bias, unit) = (u8::decode_signed(0.0), u8::decode_signed(1.0));
        for d in [0.1f32, 0.36, 0.5, 0.8] {
            let a = rec.eval_encoded(d, &raw, unit - bias, bias);
            assert!((a - rec.eval(d, &b)).abs() < 1e-5, "d {d}");
        }
    }

    #[test]
    fn auto_offset_lights_self_occluders() {
        for m in [4, 8, 16] {
            let e = Expansion {
                m,
                alpha: DEFAULT_ALPHA,
            };
            let o = e.auto_offset();
            assert!(o > 0.0 && o <= MAX_OFFSET);
            assert!(e.step(o) >= 0.97, "m {m}: step(offset {o}) = {}", e.step(o));
        }
        assert!(
            Expansion { m: 16, alpha: 0.5 }.auto_offset()
                < Expansion { m: 4, alpha: 0.5 }.auto_offset()
        );
    }
}
