//! The storage of a filtered map: [`Texture`], `channels` interleaved values per texel in
//! a [`Channel`] format, and the arithmetic every filtering pass shares. This is the
//! "basis textures" storage of the convolution shadow map paper (Annen et al. 2007,
//! Section 4.1: 8-bit fixed point, or 32-bit floats), which the moment maps reuse with
//! their own formats.

use rayon::prelude::*;

/// techniques use (2, 4, …, 32), so per-texel loops are unrolled and vectorized; other
/// counts run the same code with `N = 0` (read at run time).
macro_rules! with_channels {
    ($ch:expr, $f:ident $(::<$t:ty>)?, ($($arg:expr),*)) => {
        match $ch {
            2 => $f::<$($t,)? 2>($($arg),*),
            4 => $f::<$($t,)? 4>($($arg),*),
            6 => $f::<$($t,)? 6>($($arg),*),
            8 => $f::<$($t,)? 8>($($arg),*),
            16 => $f::<$($t,)? 16>($($arg),*),
            32 => $f::<$($t,)? 32>($($arg),*),
            _ => $f::<$($t,)? 0>($($arg),*),
        }
    };
}
pub(crate) use with_channels;

/// The channel count of a texture: the constant `N` when it is known at compile time.
#[inline(always)]
pub(super) fn chans<const N: usize>(runtime: usize) -> usize {
    if N > 0 {
        N
    } else {
        runtime
    }
}

/// `x.floor()` for `|x| < 2³¹`, without the library call that `f32::floor` becomes on
/// x86-64 targets without SSE4.1 (it dominated the per-texel and per-look-up cost).
#[inline(always)]
pub fn fast_floor(x: f32) -> f32 {
    let t = x as i32 as f32;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `x.ceil()` for `|x| < 2³¹` (see [`fast_floor`]).
#[inline(always)]
pub fn fast_ceil(x: f32) -> f32 {
    let t = fast_floor(x);
    if t < x {
        t + 1.0
    } else {
        t
    }
}

/// Storage of one texel channel.
pub trait Channel: Copy + Default + Send + Sync + 'static {
    /// Bytes per stored value.
    const BYTES: usize;
    /// The stored value as a number (raw codes for integer formats).
    fn to_f32(self) -> f32;
    /// Stores a number, rounding to nearest and clamping to the format's range.
    fn from_f32(v: f32) -> Self;
    /// The stored number that represents a value in `[-1, 1]` (linear, so filtered codes
    /// decode with [`Channel::decode_signed`]).
    fn encode_signed(v: f32) -> f32;
    /// The value in `[-1, 1]` that a (filtered) stored number represents.
    fn decode_signed(raw: f32) -> f32;

    /// `acc[c] += w · src[c].to_f32()` for every channel.
    #[inline(always)]
    fn add_scaled<const N: usize>(acc: &mut [f32; N], src: &[Self; N], w: f32) {
        for (a, s) in acc.iter_mut().zip(src) {
            *a += w * s.to_f32();
        }
    }

    /// `acc[i] += w · src[i].to_f32()` along a row.
    #[inline]
    fn add_scaled_row(acc: &mut [f32], src: &[Self], w: f32) {
        for (a, s) in acc.iter_mut().zip(src) {
            *a += w * s.to_f32();
        }
    }

    /// Stores a row of numbers, `dst[i] = from_f32(src[i])`, in a loop the compiler can
    /// vectorize.
    #[inline]
    fn store_row(src: &[f32], dst: &mut [Self]) {
        for (d, s) in dst.iter_mut().zip(src) {
            *d = Self::from_f32(*s);
        }
    }

    /// One row of a 2×2 mip reduction of textures of `N` channels (`N = 0`: `ch` read at run
    /// time): texel `x` of `out` is `from_f32` of a quarter of the sum of texels `2x` and
    /// `2x + 1` of the rows `r0` and `r1`, summed in that order.
    #[inline]
    fn reduce_row_2x2<const N: usize>(r0: &[Self], r1: &[Self], out: &mut [Self], ch: usize) {
        let ch = chans::<N>(ch);
        for (x, texel) in out.chunks_exact_mut(ch).enumerate() {
            let i = 2 * x * ch;
            let (a, b) = (&r0[i..i + 2 * ch], &r1[i..i + 2 * ch]);
            for c in 0..ch {
                let sum = a[c].to_f32() + a[ch + c].to_f32() + b[c].to_f32() + b[ch + c].to_f32();
                texel[c] = Self::from_f32(sum * 0.25);
            }
        }
    }
}

impl Channel for f32 {
    const BYTES: usize = 4;
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        v
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

impl Channel for u8 {
    const BYTES: usize = 1;
    #[inline]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline]
    fn from_f32(v: f32) -> Self {
        // Round half up: `as` truncates towards zero and saturates, so values below 0 give 0,
        // above 255 give 255, NaN gives 0, and the rest round to nearest — what clamping first
        // would give, without the clamp's NaN handling (this runs once per channel per texel).
        (v + 0.5) as u8
    }
    #[inline]
    fn encode_signed(v: f32) -> f32 {
        (v + 1.0) * 127.5
    }
    #[inline]
    fn decode_signed(raw: f32) -> f32 {
        raw / 127.5 - 1.0
    }
    #[inline]
    fn store_row(src: &[f32], dst: &mut [Self]) {
        for (d, s) in dst.iter_mut().zip(src) {
            // `from_f32` in operations that vectorize (the saturating cast does not): `v > 0`
            // is false for NaN, so NaN and negatives give 0 and values past 255 give 255, as
            // the cast saturates; in between, the cast truncates, which for `v ≥ 0` is
            // `floor(v)`: adding 2²³ rounds `v` to the nearest integer in the low mantissa
            // bits, and one less is taken where that rounded up.
            let v = *s + 0.5;
            let v = if v > 0.0 { v } else { 0.0 };
            let v = if v < 255.0 { v } else { 255.0 };
            let t = v + 8_388_608.0;
            let up = u32::from(t - 8_388_608.0 > v);
            *d = t.to_bits().wrapping_sub(up) as u8;
        }
    }
    #[inline(always)]
    fn add_scaled<const N: usize>(acc: &mut [f32; N], src: &[Self; N], w: f32) {
        // Widened to i32 first: a signed conversion that vectorizes on every x86-64.
        let v: [f32; N] = std::array::from_fn(|c| i32::from(src[c]) as f32);
        for c in 0..N {
            acc[c] += w * v[c];
        }
    }
    #[inline]
    fn add_scaled_row(acc: &mut [f32], src: &[Self], w: f32) {
        for (a, s) in acc.iter_mut().zip(src) {
            *a += w * i32::from(*s) as f32;
        }
    }
    #[inline]
    fn reduce_row_2x2<const N: usize>(r0: &[Self], r1: &[Self], out: &mut [Self], ch: usize) {
        // The sum of four codes is an integer below 2¹⁰, so `from_f32(sum / 4)` (exact in f32,
        // then rounded half up) is `(sum + 2) >> 2`: the same codes in integer arithmetic.
        let ch = chans::<N>(ch);
        for (x, texel) in out.chunks_exact_mut(ch).enumerate() {
            let i = 2 * x * ch;
            let (a, b) = (&r0[i..i + 2 * ch], &r1[i..i + 2 * ch]);
            for c in 0..ch {
                let sum = a[c] as u16 + a[ch + c] as u16 + b[c] as u16 + b[ch + c] as u16;
                texel[c] = ((sum + 2) >> 2) as u8;
            }
        }
    }
}

/// A 2D image of `channels` interleaved values per texel, row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture<T> {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Values per texel.
    pub channels: usize,
    /// `width × height × channels` values.
    pub data: Vec<T>,
}

impl<T: Channel> Texture<T> {
    /// A texture whose texel `(x, y)` gets the values `f(x, y, out)` writes into `out`
    /// (of length `channels`, zeroed before each call), stored in the format `T`.
    pub fn from_fn(
        width: u32,
        height: u32,
        channels: usize,
        f: impl Fn(u32, u32, &mut [f32]) + Sync,
    ) -> Self {
        Self::from_rows(width, height, channels, |y, row| {
            for (x, texel) in row.chunks_exact_mut(channels).enumerate() {
                f(x as u32, y, texel);
            }
        })
    }

    /// A texture whose row `y` gets the values `f(y, row)` writes into `row` (of length
    /// `width × channels`, zeroed before each call), stored in the format `T` with
    /// [`Channel::store_row`].
    pub fn from_rows(
        width: u32,
        height: u32,
        channels: usize,
        f: impl Fn(u32, &mut [f32]) + Sync,
    ) -> Self {
        let row_len = width as usize * channels;
        let mut data = vec![T::default(); row_len * height as usize];
        if row_len > 0 {
            data.par_chunks_mut(row_len).enumerate().for_each_init(
                || vec![0.0f32; row_len],
                |v, (y, row)| {
                    v.fill(0.0);
                    f(y as u32, v);
                    T::store_row(v, row);
                },
            );
        }
        Texture {
            width,
            height,
            channels,
            data,
        }
    }

    /// A texture whose row `y` gets the stored values `f(y, row)` writes into `row` (of
    /// length `width × channels`, holding `T::default()` before the call).
    pub fn from_stored_rows(
        width: u32,
        height: u32,
        channels: usize,
        f: impl Fn(u32, &mut [T]) + Sync,
    ) -> Self {
        let row_len = width as usize * channels;
        let mut data = vec![T::default(); row_len * height as usize];
        if row_len > 0 {
            data.par_chunks_mut(row_len)
                .enumerate()
                .for_each(|(y, row)| f(y as u32, row));
        }
        Texture {
            width,
            height,
            channels,
            data,
        }
    }

    /// The values of texel `(x, y)`.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> &[T] {
        let i = (y as usize * self.width as usize + x as usize) * self.channels;
        &self.data[i..i + self.channels]
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> u64 {
        (self.data.len() * T::BYTES) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn u8_rows_store_as_single_values() {
        let mut src = vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            0.0,
            -0.5,
            -0.49,
            0.4999999,
            0.5,
            254.5,
            254.49998,
            255.0,
            255.49,
            255.5,
            256.0,
            1e30,
            -1e30,
            f32::MIN_POSITIVE,
        ];
        for i in -4000..=300_000 {
            src.push(i as f32 / 1024.0);
            src.push(i as f32 * 0.5 + 0.5);
        }
        let mut seed = 12345u32;
        for _ in 0..100_000 {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            src.push((seed >> 8) as f32 / (1 << 24) as f32 * 270.0 - 5.0);
        }
        let mut dst = vec![0u8; src.len()];
        u8::store_row(&src, &mut dst);
        for (s, d) in src.iter().zip(&dst) {
            assert_eq!(*d, u8::from_f32(*s), "{s}");
        }
    }

    #[test]
    fn u8_mip_rows_round_like_float_average() {
        let ch = 2;
        let r0: Vec<u8> = (0..64u32).map(|i| (i * 37 % 256) as u8).collect();
        let r1: Vec<u8> = (0..64u32).map(|i| (i * 101 % 256) as u8).collect();
        let mut a = vec![0u8; 32];
        let mut b = vec![0u8; 32];
        u8::reduce_row_2x2::<2>(&r0, &r1, &mut a, ch);
        for (x, texel) in b.chunks_exact_mut(ch).enumerate() {
            for (c, t) in texel.iter_mut().enumerate() {
                let i = 2 * x * ch + c;
                let sum = r0[i] as f32 + r0[i + ch] as f32 + r1[i] as f32 + r1[i + ch] as f32;
                *t = u8::from_f32(sum * 0.25);
            }
        }
        assert_eq!(a, b);
        for sum in 0..=1020u16 {
            assert_eq!(
                ((sum + 2) >> 2) as u8,
                u8::from_f32(sum as f32 * 0.25),
                "{sum}"
            );
        }
    }

    #[test]
    fn u8_rounds_and_saturates() {
        assert_eq!(u8::from_f32(127.5), 128);
        assert_eq!(u8::from_f32(-3.0), 0);
        assert_eq!(u8::from_f32(300.0), 255);
        assert_eq!(u8::from_f32(f32::NAN), 0);
        assert_eq!(u8::from_f32(-0.7), 0);
        assert_eq!(u8::from_f32(254.6), 255);
        assert_eq!(u8::from_f32(0.49), 0);
        assert_eq!(u8::from_f32(f32::INFINITY), 255);
        assert_eq!(u8::from_f32(f32::NEG_INFINITY), 0);
    }
}
