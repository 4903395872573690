//! The Fourier expansion of the shadow test (Annen et al. 2007, Section 3.1, Eqs. 10–14)
//! and its ringing attenuation (Section 3.2.1): the frequencies `c_k = π(2k − 1)`, the
//! weights `σ_k = exp(−α (k/M)²)`, the reconstructed step, and the fast `sin(πx)`,
//! `cos(πx)` the basis functions of Eq. 14 are evaluated with.

use std::f32::consts::PI;

/// Default truncation order M: 16, the order of the paper's Figures 4 and 5. The paper
/// finds M = 4 "satisfactory" on its scenes, but the offset that lights a self-occluding
/// surface and the step's half-width are fixed shares of the fitted light-depth range
/// (0.10 and 0.07 of it at M = 4, α = 0.5, unscaled), so on a real scene metres deep every
/// shadow within that distance of its caster is lost: measured at 480×360 against a
/// 16-sample reference, M = 4 had 1.3–5.4× the mean error of the better of `vsm` and `pcf`
/// on eight real meshes. At the defaults (M = 16, α = 0, the step scaled by 2 about 0.1,
/// see [`super::DEFAULT_SCALE`]) it is 0.81–1.09× on the twenty of
/// `scripts/verdict-table.sh`, at most both on fifteen; M = 8 with the same scale had more
/// error than M = 16 on 19 of them (4–71% more; 3% less on the teapot). Contact shadows
/// within the offset of their caster and curved receivers shading themselves across a
/// wide footprint remain its largest errors. The price is four times the basis images
/// (memory and encode time) and four times the look-up work of M = 4, and more error
/// under strong minification: on the `fence-far` scene at 160×120, where every look-up
/// spans many texels, M = 16 has 0.037 mean error against 0.022 at M = 4, α = 0.5, and
/// `pcf`'s 0.029 (16-sample reference); pass `m=4` and `alpha=0.5` for such views.
pub const DEFAULT_M: u32 = 16;
/// The largest truncation order accepted.
pub const MAX_M: u32 = 16;
/// Default ringing attenuation α: none. At M = 16 the Gibbs overshoot (9%) is clamped away
/// on lit surfaces, and in shadow by the scale's pivot ([`super::DEFAULT_PIVOT`]); any
/// α > 0 flattens the step and needs a larger offset, which fades more contact shadows: at
/// M = 16 with the default scale, α = 0.5 had 1–11% more mean error than α = 0 on 19 of
/// the 20 real meshes measured (3% less on the teapot). At M = 4, α = 0.5 lowers the overshoot to 2.5% and is the better
/// choice there.
pub const DEFAULT_ALPHA: f32 = 0.0;

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

    /// The reconstructed step as a function of `t = z − d`: `½ + Σ σ_k (2/c_k) sin(c_k t)`.
    pub fn step(&self, t: f32) -> f32 {
        0.5 + (1..=self.m)
            .map(|k| 2.0 * self.attenuation(k) / Self::c(k) * (Self::c(k) * t).sin())
            .sum::<f32>()
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
    let n = super::super::filtering::fast_floor(x + 0.5);
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
pub(super) fn sin_cos_pi_wide(x: f32) -> (f32, f32) {
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
}
