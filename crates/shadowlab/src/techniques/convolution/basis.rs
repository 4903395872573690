//! The basis images (Annen et al. 2007, Section 4.1: "we evaluate the basis functions
//! (sin(c_k z) and cos(c_k z), see Eq. 14) using the current z-values at each texel and
//! store the result"): the `2M` stored basis values of each texel of a light's depth map,
//! computed a row at a time in operations that vectorize, with an AVX2 variant chosen at
//! run time (same operations, so bit-identical codes), or through a [`BasisTable`] of
//! precomputed codes for large 8-bit maps.

use super::expansion::{sin_cos_pi_wide, MAX_M};
use crate::techniques::filtering::{with_channels, Channel, DepthRange};

/// Texels per block of [`encode_row`].
const ENCODE_BLOCK: usize = 64;

/// The stored basis values (`T::from_f32` of `T::encode_signed` of [`Expansion::basis`] of
/// the normalized depth) of a row of map depths, `2m` values per texel, into `row`: the same
/// values as the per-texel computation, computed and quantized for blocks of texels at once
/// so the arithmetic vectorizes. `M` is `m` when it is known at compile time, else 0.
fn encode_row<T: Channel, const M: usize>(
    m: u32,
    range: &DepthRange,
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
    range: &DepthRange,
    depths: &[f32],
    row: &mut [T],
) {
    encode_row_body::<T, M>(m, range, depths, row);
}

/// The body of [`encode_row`], inlined into each instruction-set variant.
#[inline(always)]
fn encode_row_body<T: Channel, const M: usize>(
    m: u32,
    range: &DepthRange,
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
pub(super) fn encode_row_any_m<T: Channel>(
    m: u32,
    range: &DepthRange,
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
        let unit = DepthRange {
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
    pub fn encode_row(&self, range: &DepthRange, depths: &[f32], row: &mut [T]) {
        with_channels!(
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
    range: &DepthRange,
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

#[cfg(test)]
mod tests {
    use super::super::expansion::Expansion;
    use super::*;

    #[test]
    fn encoded_rows_match_per_texel_basis() {
        let range = DepthRange {
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
        let range = DepthRange {
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
        let range = DepthRange {
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
            let unit = DepthRange {
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
}
