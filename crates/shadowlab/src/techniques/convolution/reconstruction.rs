//! The shadow reconstruction (Annen et al. 2007, Eq. 13, Section 4.1: "we evaluate a
//! weighted sum at each pixel of the filtered basis functions multiplied by coefficients
//! a_i(d)"): the per-pixel sum against filtered basis values, decoded or still encoded.

use super::expansion::{Expansion, MAX_M};

impl Expansion {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::filtering::Channel;

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
}
