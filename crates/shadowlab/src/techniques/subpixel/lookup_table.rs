//! The occlusion-mask look-up table of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow
//! Maps", Section 3.4, after Eisemann and Décoret): sample bitmasks, one bit per view
//! sample, and the precomputed table that turns a half-plane on the screen into the
//! bitmask of the samples it covers.

use crate::error::{Error, Result};
use crate::math::Vec2;
use crate::sampling::{centre_index, pattern, PatternKind};
use rayon::prelude::*;
use std::ops::{BitAnd, BitAndAssign, BitOr, BitOrAssign, Not};

use super::pattern_name;

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
/// Factor on the bound of how far a sample may lie from an entry's line and still fall on
/// either side (see [`LutCache::uncertain_reach`]): a quarter more than the bound, so that
/// rounding in the table's arithmetic never leaves a sample wrongly certain.
const UNCERTAIN_MARGIN: f32 = 1.25;

/// A sample bitmask: bit `i` is sub-sample `i`.
pub(super) trait Mask:
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
    /// No sample.
    const ZERO: Self;
    /// The low bits of `v`.
    fn from_u128(v: u128) -> Self;
    /// The mask widened to 128 bits.
    fn to_u128(self) -> u128;
    /// How many samples the mask holds.
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
pub(super) struct LutCache {
    /// The sample pattern.
    pub(super) kind: PatternKind,
    /// Sample positions, pixel-local in `[0, 1)²`.
    pub(super) samples: Vec<Vec2>,
    /// Index of the sample on the pixel centre.
    pub(super) centre: usize,
    /// `LUT_ANGLES × LUT_DISTANCES` masks: samples `s` with `dir·(s − ½) + dist ≥ 0`.
    masks: Vec<u128>,
    /// Per entry, the samples within [`LutCache::uncertain_reach`] of its line: the ones
    /// a half-plane that falls in this entry may put on the other side, which
    /// [`Lut::half_plane`] tests exactly.
    uncertain: Vec<u128>,
}

/// The mask of the first `n` samples (`n ≤ 128`).
fn all_samples(n: usize) -> u128 {
    if n == 128 {
        u128::MAX
    } else {
        (1u128 << n) - 1
    }
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
    /// The pattern of `n` samples of `kind` and its table.
    pub(super) fn build(kind: PatternKind, n: u32) -> Result<Self> {
        let samples = pattern(kind, n)?;
        let centre = centre_index(&samples).ok_or_else(|| {
            Error::param(format!(
                "sample pattern {} of {n} samples has no sample on the pixel centre",
                pattern_name(kind)
            ))
        })?;
        let all = all_samples(n as usize);
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
        UNCERTAIN_MARGIN * (LUT_REACH / LUT_DISTANCES as f32 + offset * 4.0 / LUT_ANGLES as f32)
    }

    /// The entries' masks and their uncertain samples, entry by entry.
    pub(super) fn entries(&self) -> (&[u128], &[u128]) {
        (&self.masks, &self.uncertain)
    }

    /// Bytes held by the table at `mask_bytes` per mask.
    pub(super) fn bytes(&self, mask_bytes: usize) -> u64 {
        (2 * self.masks.len() * mask_bytes + self.samples.len() * 8) as u64
    }
}

/// The table in the frame's mask width.
pub(super) struct Lut<M> {
    /// Per entry, its mask and its uncertain samples (side by side: one cache line).
    entries: Vec<[M; 2]>,
    samples: Vec<Vec2>,
    /// Every sample of the pattern.
    pub(super) all: M,
}

impl<M: Mask> Lut<M> {
    /// The table of `c` in masks of type `M`.
    pub(super) fn new(c: &LutCache) -> Self {
        let all = all_samples(c.samples.len());
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

    /// The sample positions (pixel-local, in `[0, 1)²`), in bit order.
    pub(super) fn samples(&self) -> &[Vec2] {
        &self.samples
    }

    /// The samples `s` (pixel-local, in `[0, 1)²`) with `a·s.x + b·s.y + c ≥ 0`: the table's
    /// entry, with the samples close enough to its line to be on either side tested exactly.
    #[inline]
    pub(super) fn half_plane(&self, a: f32, b: f32, c: f32) -> M {
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

/// A pattern's half-plane look-up table as [`Subpixel`](super::Subpixel) builds it once per pattern and
/// sample count, for a twin that uploads it (the GPU's `gpu:subpixel`).
#[derive(Clone, Debug)]
pub struct LookupTable {
    /// Sample positions, pixel-local in `[0, 1)²`, in bit order.
    pub samples: Vec<Vec2>,
    /// Index of the sample on the pixel centre.
    pub centre: usize,
    /// `LUT_ANGLES × LUT_DISTANCES` entries (angle-major): the samples on the positive side
    /// of the entry's line.
    pub masks: Vec<u128>,
    /// Per entry, the samples close enough to its line to be tested exactly.
    pub uncertain: Vec<u128>,
}

/// The look-up table of `n` samples of `kind` (see [`LookupTable`]).
pub fn lookup_table(kind: PatternKind, n: u32) -> Result<LookupTable> {
    let c = LutCache::build(kind, n)?;
    let (masks, uncertain) = c.entries();
    Ok(LookupTable {
        masks: masks.to_vec(),
        uncertain: uncertain.to_vec(),
        samples: c.samples.clone(),
        centre: c.centre,
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
