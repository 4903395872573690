//! Moment-based filtered shadow maps that engines ship: `evsm` (exponential variance shadow
//! maps) and `msm` (moment shadow maps). Both store a few moments of a warped depth per
//! texel, then blur, mip-map and filter them on the chain `vsm` and `csm` use
//! ([`super::filtering`]), and bound the lit fraction of a receiver from the filtered
//! moments.
//!
//! This module holds what the two share: the 16-bit storage formats a GPU would give them
//! ([`F16`], a half float for `evsm`; [`Unorm16`], a 16-bit unsigned normalized value for
//! `msm`) and the storage-size parameter [`Bits`].
//!
//! Invariants: storage rounds to nearest on every write (encode, blur pass, mip level), as
//! a GPU render target does; filtering is linear in what is stored, so an encoder that is
//! affine in its inputs decodes filtered values with the inverse affine map.

pub mod evsm;
pub mod hamburger;
pub mod msm;

use super::filtering::Channel;
use super::technique::{parse_value, ParamSpec};
use crate::error::{Error, Result};

/// Bits per stored moment: a half float / 16-bit normalized format, or 32-bit float.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bits {
    /// 16 bits per moment.
    B16,
    /// 32-bit float per moment.
    B32,
}

/// The storage size of the moments of evsm and msm.
pub const BITS: ParamSpec = ParamSpec::choice(
    "bits",
    &["16", "32"],
    "bits per stored moment: 16 (half float for evsm, quantized unorm for msm) or 32-bit float",
);

impl Bits {
    /// The number of bits.
    pub fn value(self) -> u32 {
        match self {
            Bits::B16 => 16,
            Bits::B32 => 32,
        }
    }

    /// Bytes per stored moment.
    pub fn bytes(self) -> usize {
        self.value() as usize / 8
    }

    /// Parses `16` or `32` for `technique.key`.
    pub fn parse(technique: &str, key: &str, value: &str) -> Result<Self> {
        match parse_value::<u32>(technique, key, value)? {
            16 => Ok(Bits::B16),
            32 => Ok(Bits::B32),
            b => Err(Error::param(format!(
                "parameter {technique}.{key} = {b} is not a storage size: use 16 or 32"
            ))),
        }
    }
}

/// An IEEE 754 half float (binary16) channel: what `R16G16B16A16_FLOAT` stores.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F16(pub half::f16);

/// Largest finite half float.
pub const F16_MAX: f32 = 65504.0;

impl Channel for F16 {
    const BYTES: usize = 2;
    #[inline]
    fn to_f32(self) -> f32 {
        self.0.to_f32()
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        // Render targets clamp to the largest finite value rather than overflowing to
        // infinity (which would turn every filtered value it touches infinite).
        F16(half::f16::from_f32(v.clamp(-F16_MAX, F16_MAX)))
    }
    #[inline]
    fn encode_signed(v: f32) -> f32 {
        v
    }
    #[inline]
    fn decode_signed(raw: f32) -> f32 {
        raw
    }
}

/// A 16-bit unsigned normalized channel (`R16G16B16A16_UNORM`), stored as its raw code
/// 0..=65535: [`Channel::to_f32`] returns the code, so filtered values are codes too.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unorm16(pub u16);

/// The largest code of a [`Unorm16`].
pub const UNORM16_MAX: f32 = 65535.0;

impl Channel for Unorm16 {
    const BYTES: usize = 2;
    #[inline]
    fn to_f32(self) -> f32 {
        self.0 as f32
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        // Round half up; `as` saturates (negatives and NaN give 0, values past the top give
        // 65535), which is the clamp a UNORM render target applies.
        Unorm16((v + 0.5) as u16)
    }
    #[inline]
    fn encode_signed(v: f32) -> f32 {
        (v + 1.0) * (UNORM16_MAX * 0.5)
    }
    #[inline]
    fn decode_signed(raw: f32) -> f32 {
        raw / (UNORM16_MAX * 0.5) - 1.0
    }

    /// The 2×2 mip reduction in integers: `from_f32(sum · 0.25)` rounds half up, and for
    /// sums of four codes (exact in f32) that is `(sum + 2) >> 2`, the same code.
    #[inline]
    fn reduce_row_2x2<const N: usize>(r0: &[Self], r1: &[Self], out: &mut [Self], ch: usize) {
        // The channel count: `N` when known at compile time (so the loop unrolls).
        let ch = if N > 0 { N } else { ch };
        for (x, texel) in out.chunks_exact_mut(ch).enumerate() {
            let i = 2 * x * ch;
            let (a, b) = (&r0[i..i + 2 * ch], &r1[i..i + 2 * ch]);
            for c in 0..ch {
                let sum = a[c].0 as u32 + a[ch + c].0 as u32 + b[c].0 as u32 + b[ch + c].0 as u32;
                texel[c] = Unorm16(((sum + 2) >> 2) as u16);
            }
        }
    }
}

/// The grey of a dumped map texel whose value is `v` (clamped to `[0, 1]`, white = 1).
pub(crate) fn grey(v: f32) -> [u8; 3] {
    let g = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    [g, g, g]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_round_and_clamp() {
        assert_eq!(F16::from_f32(1.0).to_f32(), 1.0);
        assert_eq!(F16::from_f32(1e9).to_f32(), F16_MAX);
        assert_eq!(F16::from_f32(-1e9).to_f32(), -F16_MAX);
        // 11 significant bits: 2049 is halfway between 2048 and 2050, rounds to even.
        assert_eq!(F16::from_f32(2049.0).to_f32(), 2048.0);
    }

    #[test]
    fn unorm16_rounds_and_saturates() {
        assert_eq!(Unorm16::from_f32(0.49).0, 0);
        assert_eq!(Unorm16::from_f32(0.5).0, 1);
        assert_eq!(Unorm16::from_f32(-3.0).0, 0);
        assert_eq!(Unorm16::from_f32(1e9).0, 65535);
        assert_eq!(Unorm16::from_f32(f32::NAN).0, 0);
        let v = 0.3f32;
        let code = Unorm16::from_f32(Unorm16::encode_signed(v)).to_f32();
        assert!((Unorm16::decode_signed(code) - v).abs() < 2.0 / UNORM16_MAX);
    }

    #[test]
    fn unorm16_mip_reduction_equals_the_float_one() {
        let mut rng = crate::math::TestRng(3);
        let mut code = || Unorm16((rng.next() * 65535.99) as u16);
        let r0: Vec<Unorm16> = (0..64).map(|_| code()).chain([Unorm16(65535); 8]).collect();
        let r1: Vec<Unorm16> = (0..64).map(|_| code()).chain([Unorm16(65534); 8]).collect();
        let mut fast = vec![Unorm16(0); 36];
        Unorm16::reduce_row_2x2::<4>(&r0, &r1, &mut fast, 4);
        for (x, texel) in fast.chunks_exact(4).enumerate() {
            for (c, t) in texel.iter().enumerate() {
                let i = 8 * x + c;
                let sum = [r0[i], r0[i + 4], r1[i], r1[i + 4]].map(|v| v.to_f32());
                let float = Unorm16::from_f32((sum[0] + sum[1] + sum[2] + sum[3]) * 0.25);
                assert_eq!(*t, float, "texel {x} channel {c}");
            }
        }
    }
}
