//! Texture filtering for pre-filtered shadow maps: the software equivalent of a GPU's
//! render-target blur, automatic mip-map generation and tri-linear / anisotropic texture
//! look-ups, shared by `csm` and `vsm`.
//!
//! A [`Texture`] holds `channels` values per texel, interleaved, in a [`Channel`] format:
//! `u8` (8-bit unsigned normalized, stored as raw codes 0..=255, rounded on every write as
//! a GPU render target is) or `f32`. Filtering is linear in the stored codes, so a caller
//! that encodes linearly (`code = a·value + b`) decodes the filtered code the same way.
//!
//! - [`blur`]: a separable binomial (discrete Gaussian) kernel of odd side `n`, clamp-to-edge,
//!   each pass written back in the texture's format like a two-pass GPU blur.
//! - [`MipChain::build`]: a full chain down to 1×1, each level the box-filtered previous
//!   level (2×2 average for even sides, area-weighted taps for odd sides), quantized like
//!   `glGenerateMipmap` on an 8-bit texture.
//! - [`MipChain::sample`]: bilinear (level 0 only), tri-linear (level of detail
//!   λ = log2 of the longer screen-space derivative in texels, blended between the two
//!   nearest levels) or anisotropic filtering as `EXT_texture_filter_anisotropic`
//!   describes it: `N = min(⌈Pmax/Pmin⌉, max_aniso)` tri-linear probes spread along the
//!   major axis of the footprint at λ = log2(Pmax/N). Addressing clamps to the edge and
//!   texel centres lie at `(i + 0.5) / side`.
//! - [`light_footprint`]: the screen-space derivatives of light-map coordinates, taken by
//!   projecting the camera pass's `position ± dpdx` and `position ± dpdy` into the light
//!   view and differencing them. For an orthographic light this is exactly the projection
//!   of the world-space step to the next pixel (the GPU's `ddx/ddy`); for a perspective
//!   light the symmetric difference cancels the projection's curvature to first order.
//!
//! - [`ReceiverDepths`] and [`DepthRange::fitted`]: the depth interval a map is normalized
//!   over, fitted to the receivers that may be shadowed (some texel under their filter
//!   support, found with a [`MinPyramid`], is nearer than their own tangent plane there).
//!
//! Invariants: every pass is a pure function of its input, computed per row in parallel
//! and collected in order, so results are bit-identical for any thread count; filter
//! weights of every look-up sum to one, so a constant texture samples to that constant.
//! Known departures from hardware: GPUs approximate λ and the anisotropic probe placement
//! with reduced-precision arithmetic and vendor-specific footprints; here both are exact.

use super::shadow_map::render_light_maps;
use super::{Frame, Stats};
use crate::error::{Error, Result};
use crate::light::{cube_face, Light, LightView};
use crate::math::{Vec2, Vec3};
use crate::raster::DepthBuffer;
use rayon::prelude::*;

/// The largest blur kernel side accepted.
pub const MAX_BLUR: u32 = 63;
/// The largest anisotropy (probes per look-up) accepted, as on GPUs.
pub const MAX_ANISOTROPY: u32 = 16;
/// Default anisotropy: the paper's 16× anisotropic tri-linear filtering.
pub const DEFAULT_ANISOTROPY: u32 = 16;
/// Bytes a filtered map (all views, all levels) may take before a render is refused.
pub const MAX_FILTERED_MAP_BYTES: u64 = 3 << 30;

/// Calls `$f::<N>(args)` with the channel count `$ch` as a constant for the counts the
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
fn chans<const N: usize>(runtime: usize) -> usize {
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

/// Pixels per parallel work item of the per-pixel passes ([`ReceiverDepths::of_frame`],
/// [`FilteredMaps::lookup`]).
const PIXEL_CHUNK: usize = 1024;

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

/// The normalized binomial weights of an `n`-tap kernel (`n` odd): row `n − 1` of Pascal's
/// triangle over `2^(n−1)`, the discrete Gaussian of variance `(n − 1) / 4`.
pub fn binomial_weights(n: u32) -> Vec<f32> {
    let n = n.max(1) as usize;
    let mut w = vec![1.0f64];
    for _ in 1..n {
        let mut next = vec![1.0f64; w.len() + 1];
        for i in 1..w.len() {
            next[i] = w[i - 1] + w[i];
        }
        w = next;
    }
    let sum: f64 = w.iter().sum();
    w.iter().map(|v| (v / sum) as f32).collect()
}

/// Checks a blur kernel side: 0 or 1 for none, otherwise odd and at most [`MAX_BLUR`].
pub fn check_blur(technique: &str, n: u32) -> Result<u32> {
    if n <= 1 {
        return Ok(0);
    }
    if n & 1 == 0 || n > MAX_BLUR {
        return Err(Error::param(format!(
            "{technique}.blur = {n}: the kernel side must be odd and at most {MAX_BLUR} (or `none`)"
        )));
    }
    Ok(n)
}

/// Parses a blur parameter: `none`, `0`, `1`, or an odd kernel side such as `3`, `5`, `7`
/// (`3x3` is accepted too).
pub fn parse_blur(technique: &str, value: &str) -> Result<u32> {
    let v = value.trim().to_ascii_lowercase();
    if v == "none" || v == "off" {
        return Ok(0);
    }
    let side = v.split('x').next().unwrap_or("");
    let n: u32 = super::parse_value(technique, "blur", side)?;
    check_blur(technique, n)
}

/// A separable `n × n` binomial blur with clamp-to-edge addressing; `n ≤ 1` returns a copy.
/// The horizontal pass is written in the texture's format before the vertical pass reads
/// it, as a two-pass blur between 8-bit render targets would be.
pub fn blur<T: Channel>(tex: &Texture<T>, n: u32) -> Texture<T> {
    if n <= 1 || tex.data.is_empty() {
        return tex.clone();
    }
    with_channels!(tex.channels, blur_n::<T>, (tex, n))
}

fn blur_n<T: Channel, const N: usize>(tex: &Texture<T>, n: u32) -> Texture<T> {
    let w = binomial_weights(n);
    let r = (w.len() / 2) as i64;
    let ch = chans::<N>(tex.channels);
    let (tw, th) = (tex.width as i64, tex.height as i64);
    let row_len = tw as usize * ch;
    let mut horizontal = vec![T::default(); tex.data.len()];
    horizontal
        .par_chunks_mut(row_len)
        .enumerate()
        .for_each_init(
            || vec![0.0f32; row_len],
            |sums, (y, out)| {
                let src = &tex.data[y * row_len..(y + 1) * row_len];
                sums.fill(0.0);
                for (x, acc) in (0..tw).zip(sums.chunks_exact_mut(ch)) {
                    for (j, &wj) in w.iter().enumerate() {
                        let sx = (x + j as i64 - r).clamp(0, tw - 1) as usize;
                        let texel = &src[sx * ch..sx * ch + ch];
                        if N > 0 {
                            let acc: &mut [f32; N] = acc.try_into().expect("N channels");
                            T::add_scaled(acc, texel.try_into().expect("N channels"), wj);
                        } else {
                            for (a, s) in acc.iter_mut().zip(texel) {
                                *a += wj * s.to_f32();
                            }
                        }
                    }
                }
                T::store_row(sums, out);
            },
        );
    let mut data = vec![T::default(); tex.data.len()];
    data.par_chunks_mut(row_len).enumerate().for_each_init(
        || vec![0.0f32; row_len],
        |acc, (y, out)| {
            acc.fill(0.0);
            for (j, &wj) in w.iter().enumerate() {
                let sy = (y as i64 + j as i64 - r).clamp(0, th - 1) as usize;
                T::add_scaled_row(acc, &horizontal[sy * row_len..(sy + 1) * row_len], wj);
            }
            T::store_row(acc, out);
        },
    );
    Texture { data, ..*tex }
}

/// Area-weighted taps of a 1D box reduction from `src` texels to `dst`: destination texel
/// `i` covers the source interval `[i·s, (i+1)·s)` with `s = src/dst`.
fn box_taps(src: u32, dst: u32) -> Vec<Vec<(usize, f32)>> {
    let s = src as f64 / dst as f64;
    (0..dst)
        .map(|i| {
            let (a, b) = (i as f64 * s, (i + 1) as f64 * s);
            let mut taps = Vec::new();
            let mut j = a.floor() as u32;
            while (j as f64) < b && j < src {
                let overlap = (b.min(j as f64 + 1.0) - a.max(j as f64)).max(0.0);
                if overlap > 0.0 {
                    taps.push((j as usize, (overlap / s) as f32));
                }
                j += 1;
            }
            taps
        })
        .collect()
}

/// How a look-up filters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Bilinear on level 0 only: no mip-mapping.
    Bilinear,
    /// Tri-linear: bilinear on the two levels around λ, blended.
    Trilinear,
    /// Anisotropic: up to `max_aniso` tri-linear probes along the footprint's major axis.
    Anisotropic,
}

impl Filter {
    /// The name the command line uses.
    pub fn name(self) -> &'static str {
        match self {
            Filter::Bilinear => "bilinear",
            Filter::Trilinear => "trilinear",
            Filter::Anisotropic => "anisotropic",
        }
    }

    /// Parses a filter name.
    pub fn parse(technique: &str, value: &str) -> Result<Self> {
        match value.trim().to_ascii_lowercase().as_str() {
            "bilinear" | "none" => Ok(Filter::Bilinear),
            "trilinear" | "mip" => Ok(Filter::Trilinear),
            "anisotropic" | "aniso" => Ok(Filter::Anisotropic),
            _ => Err(Error::param(format!(
                "{technique}.filter = {value:?}: known filters are bilinear, trilinear, anisotropic"
            ))),
        }
    }
}

/// The screen-space derivatives of a look-up's texture coordinates, in map coordinates
/// (`[0, 1]` across the map) per pixel step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// d(u, v)/dx: change per pixel step to the right.
    pub dx: Vec2,
    /// d(u, v)/dy: change per pixel step down.
    pub dy: Vec2,
}

/// The screen-space derivatives of the light-map coordinates of a surface point `p` whose
/// world position changes by `dpdx`, `dpdy` per pixel step: half the differences of the
/// projections of `p ± dpdx` and `p ± dpdy`. Non-finite projections (behind a perspective
/// eye) give a zero derivative.
pub fn light_footprint(view: &LightView, p: Vec3, dpdx: Vec3, dpdy: Vec3) -> Footprint {
    if view.orthographic {
        // The projection is affine: the difference is the linear part applied to the step
        // (one matrix-vector product per axis instead of four projections).
        let m = &view.clip_from_world;
        let lin = |d: Vec3| {
            let c = m.transform_vector3(d);
            let g = Vec2::new(0.5 * c.x, -0.5 * c.y);
            if g.is_finite() {
                g
            } else {
                Vec2::ZERO
            }
        };
        return Footprint {
            dx: lin(dpdx),
            dy: lin(dpdy),
        };
    }
    let uv = |q: Vec3| {
        let s = view.project(q);
        Vec2::new(s.u, s.v)
    };
    let diff = |d: Vec3| {
        let g = (uv(p + d) - uv(p - d)) * 0.5;
        if g.is_finite() {
            g
        } else {
            Vec2::ZERO
        }
    };
    Footprint {
        dx: diff(dpdx),
        dy: diff(dpdy),
    }
}

/// Where a look-up reads: the level of detail and the probes along the major axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lod {
    /// Level of detail λ (log2 of texels per probe step at level 0); ≤ 0 magnifies.
    pub lambda: f32,
    /// Number of probes (1 unless anisotropic).
    pub probes: u32,
    /// The major axis in map coordinates (the probes are spread along it).
    pub axis: Vec2,
}

/// The level of detail of a footprint on a `side`-texel level 0, as the GPU computes it.
pub fn level_of_detail(fp: &Footprint, side: u32, filter: Filter, max_aniso: u32) -> Lod {
    let n = side as f32;
    let px = fp.dx.length() * n;
    let py = fp.dy.length() * n;
    let (pmax, pmin, axis) = if px >= py {
        (px, py, fp.dx)
    } else {
        (py, px, fp.dy)
    };
    match filter {
        Filter::Bilinear => Lod {
            lambda: f32::NEG_INFINITY,
            probes: 1,
            axis: Vec2::ZERO,
        },
        Filter::Trilinear => Lod {
            lambda: pmax.log2(),
            probes: 1,
            axis: Vec2::ZERO,
        },
        Filter::Anisotropic => {
            let max_aniso = max_aniso.clamp(1, MAX_ANISOTROPY);
            // Probes only spread across a footprint longer than one texel; a magnified
            // look-up is one bilinear sample as on hardware.
            let probes = if pmax <= 1.0 {
                1
            } else if pmin > 0.0 {
                // `fast_ceil` saturates like `ceil` then `as` would, past 2³¹ and for NaN.
                (fast_ceil(pmax / pmin) as u32).clamp(1, max_aniso)
            } else {
                max_aniso
            };
            Lod {
                lambda: (pmax / probes as f32).log2(),
                probes,
                axis,
            }
        }
    }
}

/// A texture and its full chain of box-filtered levels down to 1×1.
#[derive(Clone, Debug)]
pub struct MipChain<T> {
    /// Level 0 first.
    pub levels: Vec<Texture<T>>,
}

impl<T: Channel> MipChain<T> {
    /// Builds the full chain from `base`; each level halves the sides (rounding down, at
    /// least 1) and is written in the texture's format.
    pub fn build(base: Texture<T>) -> Self {
        let mut levels = vec![base];
        loop {
            let prev = levels.last().expect("level 0 exists");
            if prev.width <= 1 && prev.height <= 1 {
                break;
            }
            let next = Self::reduce(prev);
            levels.push(next);
        }
        MipChain { levels }
    }

    /// A chain of level 0 alone (look-ups never leave it).
    pub fn single(base: Texture<T>) -> Self {
        MipChain { levels: vec![base] }
    }

    fn reduce(src: &Texture<T>) -> Texture<T> {
        with_channels!(src.channels, reduce_n::<T>, (src))
    }

    /// Values per texel.
    pub fn channels(&self) -> usize {
        self.levels[0].channels
    }

    /// Bytes held by every level.
    pub fn memory_bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.memory_bytes()).sum()
    }

    /// Adds `weight ×` the bilinear sample of `level` at `(u, v)` to `acc`.
    #[inline]
    pub fn bilinear_add(&self, level: usize, u: f32, v: f32, weight: f32, acc: &mut [f32]) {
        self.bilinear_add_n::<0>(level, u, v, weight, acc)
    }

    /// [`Self::bilinear_add`] for textures of `N` channels (`N = 0`: any count).
    #[inline(always)]
    pub fn bilinear_add_n<const N: usize>(
        &self,
        level: usize,
        u: f32,
        v: f32,
        weight: f32,
        acc: &mut [f32],
    ) {
        let t = &self.levels[level];
        let ch = chans::<N>(t.channels);
        let acc = &mut acc[..ch];
        let fx = u * t.width as f32 - 0.5;
        let fy = v * t.height as f32 - 0.5;
        // Clamp far-off coordinates first so the integer conversion cannot overflow.
        let fx = if fx.is_finite() {
            fx.clamp(-1.0, t.width as f32)
        } else {
            0.0
        };
        let fy = if fy.is_finite() {
            fy.clamp(-1.0, t.height as f32)
        } else {
            0.0
        };
        let (x0, y0) = (fast_floor(fx), fast_floor(fy));
        let (ax, ay) = (fx - x0, fy - y0);
        let (wm, hm) = (t.width as i32 - 1, t.height as i32 - 1);
        let xa = (x0 as i32).clamp(0, wm) as usize;
        let xb = (x0 as i32 + 1).clamp(0, wm) as usize;
        let ya = (y0 as i32).clamp(0, hm) as usize;
        let yb = (y0 as i32 + 1).clamp(0, hm) as usize;
        let w = t.width as usize;
        let taps = [
            (ya * w + xa, (1.0 - ax) * (1.0 - ay)),
            (ya * w + xb, ax * (1.0 - ay)),
            (yb * w + xa, (1.0 - ax) * ay),
            (yb * w + xb, ax * ay),
        ];
        if N > 0 {
            // Fixed-size texels: each tap is a few vector operations.
            let acc: &mut [f32; N] = (&mut acc[..N]).try_into().expect("N channels");
            for (i, tw) in taps {
                let wt = tw * weight;
                if wt == 0.0 {
                    continue;
                }
                let src: &[T; N] = t.data[i * N..i * N + N].try_into().expect("N channels");
                T::add_scaled(acc, src, wt);
            }
            return;
        }
        for (i, tw) in taps {
            let wt = tw * weight;
            if wt == 0.0 {
                continue;
            }
            for (a, s) in acc.iter_mut().zip(&t.data[i * ch..i * ch + ch]) {
                *a += wt * s.to_f32();
            }
        }
    }

    /// Adds `weight ×` the tri-linear sample at level of detail `lambda` to `acc`.
    #[inline]
    pub fn trilinear_add(&self, lambda: f32, u: f32, v: f32, weight: f32, acc: &mut [f32]) {
        self.trilinear_add_n::<0>(lambda, u, v, weight, acc)
    }

    #[inline(always)]
    fn trilinear_add_n<const N: usize>(
        &self,
        lambda: f32,
        u: f32,
        v: f32,
        weight: f32,
        acc: &mut [f32],
    ) {
        let top = (self.levels.len() - 1) as f32;
        let l = if lambda.is_nan() {
            0.0
        } else {
            lambda.clamp(0.0, top)
        };
        let l0 = fast_floor(l);
        let f = l - l0;
        self.bilinear_add_n::<N>(l0 as usize, u, v, weight * (1.0 - f), acc);
        if f > 0.0 {
            self.bilinear_add_n::<N>(l0 as usize + 1, u, v, weight * f, acc);
        }
    }

    /// The filtered values at `(u, v)` for a look-up of footprint `fp`, written into `out`
    /// (of length [`Self::channels`]); returns the level of detail used.
    pub fn sample(
        &self,
        u: f32,
        v: f32,
        fp: &Footprint,
        filter: Filter,
        max_aniso: u32,
        out: &mut [f32],
    ) -> Lod {
        self.sample_n::<0>(u, v, fp, filter, max_aniso, out)
    }

    /// [`Self::sample`] for textures of `N` channels (`N = 0`: any count).
    #[inline(always)]
    pub fn sample_n<const N: usize>(
        &self,
        u: f32,
        v: f32,
        fp: &Footprint,
        filter: Filter,
        max_aniso: u32,
        out: &mut [f32],
    ) -> Lod {
        let lod = level_of_detail(
            fp,
            self.levels[0].width.max(self.levels[0].height),
            filter,
            max_aniso,
        );
        if N > 0 {
            // A local accumulator the compiler keeps in registers; the sums are the same.
            let mut acc = [0.0f32; N];
            self.probes_add_n::<N>(&lod, u, v, &mut acc);
            out[..N].copy_from_slice(&acc);
        } else {
            out.fill(0.0);
            self.probes_add_n::<N>(&lod, u, v, out);
        }
        lod
    }

    /// Adds the probes of a look-up at `(u, v)` with level of detail `lod` to `out`.
    #[inline(always)]
    fn probes_add_n<const N: usize>(&self, lod: &Lod, u: f32, v: f32, out: &mut [f32]) {
        if lod.probes <= 1 {
            self.trilinear_add_n::<N>(lod.lambda, u, v, 1.0, out);
        } else {
            let w = 1.0 / lod.probes as f32;
            for i in 0..lod.probes {
                let s = (i as f32 + 0.5) * w - 0.5;
                let p = Vec2::new(u, v) + lod.axis * s;
                self.trilinear_add_n::<N>(lod.lambda, p.x, p.y, w, out);
            }
        }
    }
}

/// One mip level from the previous: a 2×2 average where both sides are even, else
/// area-weighted box taps.
fn reduce_n<T: Channel, const N: usize>(src: &Texture<T>) -> Texture<T> {
    let (w, h) = ((src.width / 2).max(1), (src.height / 2).max(1));
    let ch = chans::<N>(src.channels);
    let sw = src.width as usize;
    let mut data = vec![T::default(); w as usize * h as usize * ch];
    if src.width & 1 == 0 && src.height & 1 == 0 {
        data.par_chunks_mut(w as usize * ch)
            .enumerate()
            .for_each(|(y, out)| {
                let r0 = &src.data[2 * y * sw * ch..(2 * y + 1) * sw * ch];
                let r1 = &src.data[(2 * y + 1) * sw * ch..(2 * y + 2) * sw * ch];
                T::reduce_row_2x2::<N>(r0, r1, out, ch);
            });
    } else {
        let tx = box_taps(src.width, w);
        let ty = box_taps(src.height, h);
        data.par_chunks_mut(w as usize * ch)
            .enumerate()
            .for_each(|(y, out)| {
                let mut acc = vec![0.0f32; ch];
                for (x, texel) in out.chunks_exact_mut(ch).enumerate() {
                    acc.fill(0.0);
                    for &(sy, wy) in &ty[y] {
                        for &(sx, wx) in &tx[x] {
                            let wgt = wy * wx;
                            let i = (sy * sw + sx) * ch;
                            for (a, s) in acc.iter_mut().zip(&src.data[i..i + ch]) {
                                *a += wgt * s.to_f32();
                            }
                        }
                    }
                    for (d, a) in texel.iter_mut().zip(&acc) {
                        *d = T::from_f32(*a);
                    }
                }
            });
    }
    Texture {
        width: w,
        height: h,
        channels: src.channels,
        data,
    }
}

/// Blur, mip-mapping and look-up settings shared by the filtered techniques.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSettings {
    /// Blur kernel side (0 = none).
    pub blur: u32,
    /// Look-up filter.
    pub filter: Filter,
    /// Most probes of an anisotropic look-up.
    pub max_aniso: u32,
}

impl Default for FilterSettings {
    fn default() -> Self {
        FilterSettings {
            blur: 0,
            filter: Filter::Anisotropic,
            max_aniso: DEFAULT_ANISOTROPY,
        }
    }
}

impl FilterSettings {
    /// The parameter keys these settings answer to.
    pub const KEYS: [&'static str; 3] = ["blur", "filter", "max-aniso"];

    /// Adds the settings to a technique's parameter list.
    pub fn params(&self, m: &mut std::collections::BTreeMap<String, serde_json::Value>) {
        let blur = if self.blur == 0 {
            serde_json::Value::from("none")
        } else {
            self.blur.into()
        };
        m.insert("blur".into(), blur);
        m.insert("filter".into(), self.filter.name().into());
        m.insert("max-aniso".into(), self.max_aniso.into());
    }

    /// Sets one of the keys in [`Self::KEYS`]; `Ok(false)` when `key` is not one of them.
    pub fn set_param(&mut self, technique: &str, key: &str, value: &str) -> Result<bool> {
        match key {
            "blur" => self.blur = parse_blur(technique, value)?,
            "filter" => self.filter = Filter::parse(technique, value)?,
            "max-aniso" => {
                let v = super::parse_value(technique, key, value)?;
                self.max_aniso = super::check_range(technique, key, v, 1, MAX_ANISOTROPY)?;
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// Blurs `base` and builds the chain the look-up filter needs.
    pub fn prefilter<T: Channel>(&self, base: Texture<T>) -> MipChain<T> {
        let base = if self.blur > 1 {
            blur(&base, self.blur)
        } else {
            base
        };
        match self.filter {
            Filter::Bilinear => MipChain::single(base),
            _ => MipChain::build(base),
        }
    }
}

/// Refuses a filtered map larger than [`MAX_FILTERED_MAP_BYTES`] before anything is
/// allocated: `views` maps of `side²` texels with `channels` values of `bytes` each, plus
/// a third for the mip levels.
pub fn check_map_size(
    technique: &str,
    views: usize,
    side: u32,
    channels: usize,
    bytes: usize,
) -> Result<()> {
    let total = views as u64 * (side as u64).pow(2) * channels as u64 * bytes as u64 * 4 / 3;
    if total > MAX_FILTERED_MAP_BYTES {
        return Err(Error::Limit(format!(
            "{technique}: {views} filtered map(s) of {side}² texels × {channels} channels would take {} MiB, more than {} MiB; lower --param resolution (or m)",
            total >> 20,
            MAX_FILTERED_MAP_BYTES >> 20
        )));
    }
    crate::limits::check_bytes(
        || format!("{technique}: {views} filtered map(s) of {side}² texels × {channels} channels"),
        total,
    )
}

/// The depth interval a map's texels span, for normalizing linear depths into `[0, span]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthRange {
    /// Nearest rasterized depth.
    pub near: f32,
    /// Farthest rasterized depth.
    pub far: f32,
    /// The normalized value of `far`.
    pub span: f32,
}

impl DepthRange {
    /// The range of the finite depths of `map` (the light view's own range when the map
    /// is empty), normalized to `[0, span]`. Fitting the range to what was rasterized
    /// rather than to the light frustum spends the normalized interval where casters are.
    pub fn of_map(map: &DepthBuffer, view: &LightView, span: f32) -> Self {
        let (mut near, mut far) = (f32::INFINITY, f32::NEG_INFINITY);
        for &d in &map.depth {
            if d.is_finite() {
                near = near.min(d);
                far = far.max(d);
            }
        }
        if near > far {
            (near, far) = (view.near, view.far);
        }
        let far = far.max(near + Self::min_width(near, far));
        DepthRange { near, far, span }
    }

    /// The narrowest interval `[near, far]` may be: [`MIN_RANGE_RELATIVE`] of the larger
    /// depth magnitude (a tiny absolute floor for depths near zero).
    #[inline]
    fn min_width(near: f32, far: f32) -> f32 {
        MIN_RANGE_RELATIVE * near.abs().max(far.abs()).max(f32::MIN_POSITIVE.sqrt())
    }

    /// The depth interval that matters to the receivers this frame shades (see
    /// [`ReceiverDepths`]): from the nearest map texel under the filter support of a receiver
    /// that something may shadow to the farthest such receiver. Normalizing with clamping is
    /// monotone, so the shadow test `z < d` of every such receiver keeps its sign: no texel
    /// under its support is nearer than `near`, and a texel farther than `far` lies behind it
    /// and stays behind. A receiver left out has no texel under its support nearer than its
    /// own surface there, so it is lit, and stays lit after clamping: beyond `far` it and its
    /// whole support clamp onto `span` (`z − d = 0`, lit once offset); before `near` it clamps
    /// onto 0 and its support to `≥ 0`. The tighter interval is what the convolution shadow
    /// map paper asks of the light frustum ("tightly fitted"): it shrinks the offset and the
    /// smooth step's half-width in world units. It is never narrower than
    /// [`MIN_RANGE_RELATIVE`] of the depths, so receivers at a single light depth (a point
    /// light's cube face looking straight down at a floor) are not normalized by their
    /// rounding error. Where no receiver may be shadowed, it spans every receiver and its
    /// support; it falls back to [`Self::of_map`] when the view shades no receiver.
    pub fn fitted(
        map: &DepthBuffer,
        view: &LightView,
        receivers: &ReceiverDepths,
        span: f32,
    ) -> Self {
        let (near, far) = if receivers.shadowable > 0 {
            (receivers.shadowable_near, receivers.shadowable_far)
        } else {
            (receivers.near, receivers.far)
        };
        if receivers.count == 0 || !near.is_finite() || !far.is_finite() || near > far {
            return Self::of_map(map, view, span);
        }
        // Receivers that all lie at one light depth (a plane facing the light head-on) give
        // an interval as thin as the depths' rounding; widen it towards the light so that
        // rounding stays far below the filters' offsets and transition widths.
        let near = near.min(far - Self::min_width(near, far));
        // A sliver of slack on both sides so the nearest occluder and the farthest receiver
        // are not both clamped onto the ends.
        let slack = (far - near) * FITTED_RANGE_SLACK;
        DepthRange {
            near: near - slack,
            far: far + slack,
            span,
        }
    }

    /// `depth` mapped to `[0, span]`, clamped; empty texels (`+inf`) map to `span`.
    #[inline]
    pub fn normalize(&self, depth: f32) -> f32 {
        if depth.is_nan() {
            return self.span;
        }
        ((depth - self.near) / (self.far - self.near)).clamp(0.0, 1.0) * self.span
    }
}

/// Narrowest depth interval a map is normalized over, as a fraction of the depths' magnitude
/// (see [`DepthRange::fitted`]). Rasterized and projected depths of the same point differ by
/// a few units in the last place (about 10⁻⁷ relative); normalized over an interval that
/// thin, that rounding fills the whole `[0, span]` and flat receivers shadow themselves. At
/// 10⁻³ the rounding is 10⁻⁴ of the interval, far below `csm`'s offset and `vsm`'s variance
/// floor, while receivers a thousandth of their light distance apart still separate.
pub const MIN_RANGE_RELATIVE: f32 = 1e-3;

/// Fraction of the fitted depth interval added on each side (see [`DepthRange::fitted`]):
/// keeps the extreme depths off the clamped ends at the cost of 1% of the precision.
pub const FITTED_RANGE_SLACK: f32 = 0.005;

/// Steepest receiver slope (tangent of its angle to the light's image plane) whose own
/// depth change across its filter support [`ReceiverDepths`] accounts for; a steeper
/// receiver always counts as one that may be shadowed (conservative: it only widens the
/// fitted interval).
pub const MAX_RECEIVER_SLOPE: f32 = 8.0;

/// A min-depth pyramid of a depth map: level `l` texel `(i, j)` is the nearest depth of the
/// level-0 texels `[i·2^l, (i+1)·2^l) × [j·2^l, (j+1)·2^l)` (`+inf` where empty), so the
/// nearest depth of any texel rectangle is bounded from below by at most 2×2 reads. Level 0
/// is the map itself, borrowed.
#[derive(Clone, Debug)]
pub struct MinPyramid<'a> {
    /// `(width, height, depths)` of each level, level 0 (the map's depths) first.
    pub levels: Vec<(u32, u32, std::borrow::Cow<'a, [f32]>)>,
}

impl<'a> MinPyramid<'a> {
    /// The pyramid of `map`, down to 1×1 (each level `⌈side / 2⌉`).
    pub fn build(map: &'a DepthBuffer) -> Self {
        let mut levels = vec![(
            map.width,
            map.height,
            std::borrow::Cow::Borrowed(&map.depth[..]),
        )];
        loop {
            let (w, h, prev) = levels.last().expect("level 0 exists");
            let (w, h) = (*w as usize, *h as usize);
            if w <= 1 && h <= 1 {
                break;
            }
            let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
            let mut next = vec![f32::INFINITY; nw * nh];
            if nw > 0 {
                next.par_chunks_mut(nw).enumerate().for_each(|(y, row)| {
                    let r0 = &prev[2 * y * w..(2 * y + 1) * w];
                    // The last row of an odd height has no partner: it pairs with itself.
                    let r1 = if 2 * y + 1 < h {
                        &prev[(2 * y + 1) * w..(2 * y + 2) * w]
                    } else {
                        r0
                    };
                    // Pairs of columns (min is exact in any order; the final `min` with +inf
                    // turns an all-NaN block into +inf), then an odd last column.
                    for ((o, a), b) in row
                        .iter_mut()
                        .zip(r0.chunks_exact(2))
                        .zip(r1.chunks_exact(2))
                    {
                        *o = a[0].min(a[1]).min(b[0].min(b[1])).min(f32::INFINITY);
                    }
                    if w & 1 == 1 {
                        row[nw - 1] = r0[w - 1].min(r1[w - 1]).min(f32::INFINITY);
                    }
                });
            }
            levels.push((nw as u32, nh as u32, std::borrow::Cow::Owned(next)));
        }
        MinPyramid { levels }
    }

    /// The nearest depth of a block of texels that contains the texel rectangle `[x0, x1] ×
    /// [y0, y1]` (inclusive, inside level 0): at most 2×2 texels of the finest level whose
    /// texels cover it so. Returns the depth and the block read, as level-0 texel bounds
    /// `(x_begin, x_end, y_begin, y_end)` (end exclusive, clamped to the map).
    pub fn min_in(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> (f32, [u32; 4]) {
        // No level finer than ⌊log2(extent)⌋ holds the rectangle in 2 texels a side, and the
        // test below only turns true once: start there.
        let extent = (x1 - x0).max(y1 - y0);
        let mut l = if extent > 1 {
            (31 - extent.leading_zeros() as usize).min(self.levels.len() - 1)
        } else {
            0
        };
        while l + 1 < self.levels.len() && ((x1 >> l) - (x0 >> l) > 1 || (y1 >> l) - (y0 >> l) > 1)
        {
            l += 1;
        }
        let (w, h, d) = &self.levels[l];
        let (w, h) = (*w as usize, *h as usize);
        let (xa, xb) = ((x0 >> l) as usize, ((x1 >> l) as usize).min(w - 1));
        let (ya, yb) = ((y0 >> l) as usize, ((y1 >> l) as usize).min(h - 1));
        let mut m = f32::INFINITY;
        for y in ya..=yb {
            for x in xa..=xb {
                m = m.min(d[y * w + x]);
            }
        }
        let (w0, h0) = (self.levels[0].0, self.levels[0].1);
        let block = [
            (xa as u32) << l,
            (((xb + 1) as u32) << l).min(w0),
            (ya as u32) << l,
            (((yb + 1) as u32) << l).min(h0),
        ];
        (m, block)
    }
}

/// The light depths that matter to the receivers of one light view, from which
/// [`DepthRange::fitted`] takes its interval.
///
/// A receiver *may be shadowed* when some map texel under its filter support (the texels its
/// look-up can read: the footprint's parallelogram, the bilinear and mip-level spill of the
/// level of detail it uses, and `pad` texels more for the blur) is nearer than its own surface
/// there: nearer than its depth minus the depth change of its tangent plane across the
/// support and one texel. A receiver that cannot be shadowed is lit whatever the interval
/// (see [`DepthRange::fitted`]), so the interval need only cover the others: on a wide
/// ground under a low sun this is the ground round the casters, not the whole visible ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReceiverDepths {
    /// Nearest texel under the support of any receiver.
    pub near: f32,
    /// Farthest receiver.
    pub far: f32,
    /// Nearest texel under the support of a receiver that may be shadowed.
    pub shadowable_near: f32,
    /// Farthest receiver that may be shadowed.
    pub shadowable_far: f32,
    /// Number of receivers.
    pub count: u64,
    /// Number of receivers that may be shadowed.
    pub shadowable: u64,
}

impl ReceiverDepths {
    const EMPTY: ReceiverDepths = ReceiverDepths {
        near: f32::INFINITY,
        far: f32::NEG_INFINITY,
        shadowable_near: f32::INFINITY,
        shadowable_far: f32::NEG_INFINITY,
        count: 0,
        shadowable: 0,
    };

    fn merge(self, o: Self) -> Self {
        ReceiverDepths {
            near: self.near.min(o.near),
            far: self.far.max(o.far),
            shadowable_near: self.shadowable_near.min(o.shadowable_near),
            shadowable_far: self.shadowable_far.max(o.shadowable_far),
            count: self.count + o.count,
            shadowable: self.shadowable + o.shadowable,
        }
    }

    /// The depths of each light view for the pixels of `frame` the light reaches (the point
    /// light's cube faces each get the pixels whose direction selects them), with `maps` the
    /// views' depth maps and `settings` the look-up filter whose support is checked. Minima
    /// and maxima are exact in any order, so the result does not depend on the thread count.
    pub fn of_frame(
        frame: &Frame,
        views: &[LightView],
        maps: &[DepthBuffer],
        settings: &FilterSettings,
    ) -> Vec<Self> {
        let n = views.len();
        let pyramids: Vec<MinPyramid<'_>> = maps.iter().map(MinPyramid::build).collect();
        let view = frame.view;
        let pad = settings.blur / 2 + 1;
        // One pixel's receiver depths into `acc`; pixels are visited in chunks so the many
        // pixels the light does not reach cost a test each, not a call each.
        let visit = |acc: &mut Vec<Self>, k: usize| {
            if !frame.receiver_lit(k) {
                return;
            }
            let p = view.position[k];
            let i = match *frame.light {
                Light::Point { position } => cube_face(p - position),
                _ => 0,
            };
            let (Some(lv), Some(map), Some(pyr)) = (views.get(i), maps.get(i), pyramids.get(i))
            else {
                return;
            };
            if map.width == 0 || map.height == 0 {
                return;
            }
            let s = lv.project(p);
            if !(s.u.is_finite() && s.v.is_finite() && s.depth.is_finite()) {
                return;
            }
            let fp = light_footprint(lv, p, view.dpdx[k], view.dpdy[k]);
            let (w, h) = (map.width as f32, map.height as f32);
            let lod = level_of_detail(
                &fp,
                map.width.max(map.height),
                settings.filter,
                settings.max_aniso,
            );
            // Half-extents of the support in texels: the probes' parallelogram, the
            // bilinear taps of the coarser of the two levels blended (within two of
            // its texels, 2^⌈λ⌉ level-0 texels each), the blur.
            let level = if lod.lambda.is_finite() {
                fast_ceil(lod.lambda.clamp(0.0, 30.0)) as u32
            } else {
                0
            };
            let spill = (2u32 << level) as f32 + pad as f32;
            let (ex, ey) = if settings.filter == Filter::Anisotropic {
                (
                    0.5 * (fp.dx.x.abs() + fp.dy.x.abs()) * w,
                    0.5 * (fp.dx.y.abs() + fp.dy.y.abs()) * h,
                )
            } else {
                (0.0, 0.0)
            };
            let (hx, hy) = (ex + spill, ey + spill);
            let (cx, cy) = (s.u * w, s.v * h);
            let clampx = |t: f32| t.clamp(0.0, w - 1.0) as u32;
            let clampy = |t: f32| t.clamp(0.0, h - 1.0) as u32;
            let (zmin, b) = pyr.min_in(
                clampx(fast_floor(cx - hx)),
                clampx(fast_floor(cx + hx)),
                clampy(fast_floor(cy - hy)),
                clampy(fast_floor(cy + hy)),
            );
            // The receiver's own depth change across the block read (which holds the
            // support), from its tangent plane in light space, plus one texel.
            let bx = (cx - b[0] as f32).max(b[1] as f32 - cx).max(0.0);
            let by = (cy - b[2] as f32).max(b[3] as f32 - cy).max(0.0);
            let texel = lv.texel_size(map.width.max(map.height), s.depth);
            let nl = lv.light_from_world.transform_vector3(view.normal[k]);
            let slope = (nl.x.abs() * bx + nl.y.abs() * by) * texel;
            let own = if nl.z.abs() * MAX_RECEIVER_SLOPE >= nl.x.abs().max(nl.y.abs()) {
                slope / nl.z.abs() + texel
            } else {
                f32::NEG_INFINITY
            };
            let a = &mut acc[i];
            a.count += 1;
            a.far = a.far.max(s.depth);
            a.near = a.near.min(zmin.min(s.depth));
            if zmin < s.depth - own {
                a.shadowable += 1;
                a.shadowable_far = a.shadowable_far.max(s.depth);
                a.shadowable_near = a.shadowable_near.min(zmin);
            }
        };
        let len = view.position.len();
        (0..len.div_ceil(PIXEL_CHUNK))
            .into_par_iter()
            .fold(
                || vec![Self::EMPTY; n],
                |mut acc, c| {
                    for k in c * PIXEL_CHUNK..((c + 1) * PIXEL_CHUNK).min(len) {
                        visit(&mut acc, k);
                    }
                    acc
                },
            )
            .reduce(
                || vec![Self::EMPTY; n],
                |a, b| a.into_iter().zip(b).map(|(x, y)| x.merge(y)).collect(),
            )
    }
}

/// Pre-filtered light maps of one frame: per light view, the encoded map with its mip
/// chain and the depth range it was normalized with.
#[derive(Clone, Debug)]
pub struct FilteredMaps<T> {
    /// The light views (one, or six cube faces).
    pub views: Vec<LightView>,
    /// Encoded, blurred and mip-mapped map of each view.
    pub chains: Vec<MipChain<T>>,
    /// Depth normalization of each view.
    pub ranges: Vec<DepthRange>,
    /// Bytes of the depth maps the chains were computed from.
    pub depth_bytes: u64,
}

impl<T: Channel> FilteredMaps<T> {
    /// Renders the light's depth maps at `res`, encodes each texel with `encode(map, range,
    /// x, y, out)`, then blurs and mip-maps as `settings` says; records the stages
    /// `shadow_map`, `encode`, `blur` and `mipmap` in `stats`. `span` is the normalized
    /// depth of the farthest texel.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        frame: &Frame,
        res: u32,
        channels: usize,
        span: f32,
        settings: &FilterSettings,
        stats: &mut Stats,
        encode: impl Fn(&DepthBuffer, &DepthRange, u32, u32, &mut [f32]) + Sync,
    ) -> Self {
        let encode = &encode;
        Self::build_rows(frame, res, channels, span, settings, stats, |r| {
            let r = *r;
            move |m: &DepthBuffer, y: u32, row: &mut [T]| {
                let mut v = vec![0.0f32; row.len()];
                for (x, texel) in v.chunks_exact_mut(channels).enumerate() {
                    encode(m, &r, x as u32, y, texel);
                }
                T::store_row(&v, row);
            }
        })
    }

    /// [`Self::build`] with an encoder of whole rows that stores the texture's format itself:
    /// `encoder(range)` is called once per view, inside the `encode` stage (so it may
    /// prepare tables for that view's depth range), and returns `encode(map, y, row)`, which
    /// writes the `width × channels` stored values of row `y` into `row` (which holds
    /// `T::default()` before the call).
    #[allow(clippy::too_many_arguments)]
    pub fn build_rows<E: Fn(&DepthBuffer, u32, &mut [T]) + Sync>(
        frame: &Frame,
        res: u32,
        channels: usize,
        span: f32,
        settings: &FilterSettings,
        stats: &mut Stats,
        encoder: impl Fn(&DepthRange) -> E,
    ) -> Self {
        let maps = stats.stage("shadow_map", || render_light_maps(frame, res));
        let receivers = stats.stage("fit", || {
            ReceiverDepths::of_frame(frame, &maps.views, &maps.maps, settings)
        });
        let (count, shadowable) = receivers
            .iter()
            .fold((0, 0), |(c, s), r| (c + r.count, s + r.shadowable));
        stats.count("shadowable_share", shadowable as f64 / count.max(1) as f64);
        if let Some(r) = receivers.first() {
            stats.count("fit_near", r.shadowable_near as f64);
            stats.count("fit_far", r.shadowable_far as f64);
            stats.count("receivers_near", r.near as f64);
            stats.count("receivers_far", r.far as f64);
        }
        let ranges: Vec<DepthRange> = maps
            .maps
            .iter()
            .zip(&maps.views)
            .zip(&receivers)
            .map(|((m, v), r)| DepthRange::fitted(m, v, r, span))
            .collect();
        let encoded: Vec<Texture<T>> = stats.stage("encode", || {
            maps.maps
                .iter()
                .zip(&ranges)
                .map(|(m, r)| {
                    let encode = encoder(r);
                    Texture::from_stored_rows(m.width, m.height, channels, |y, row| {
                        encode(m, y, row)
                    })
                })
                .collect()
        });
        let blurred: Vec<Texture<T>> = if settings.blur > 1 {
            stats.stage("blur", || {
                encoded.iter().map(|t| blur(t, settings.blur)).collect()
            })
        } else {
            encoded
        };
        let chains = stats.stage("mipmap", || {
            blurred
                .into_iter()
                .map(|t| match settings.filter {
                    Filter::Bilinear => MipChain::single(t),
                    _ => MipChain::build(t),
                })
                .collect()
        });
        let depth_bytes = maps.memory_bytes();
        FilteredMaps {
            views: maps.views,
            chains,
            ranges,
            depth_bytes,
        }
    }

    /// Bytes held by the filtered maps (every level of every view).
    pub fn memory_bytes(&self) -> u64 {
        self.chains.iter().map(|c| c.memory_bytes()).sum()
    }

    /// The shadow term of every pixel of `frame`: for each pixel the light can reach, the
    /// filtered values at its light-map position are passed, with its normalized light
    /// depth, to `test(d, values)`. Pixels the light cannot reach get 0, uncovered ones 1.
    /// Records the stage `lookup` and the counters `mean_probes` and `minified_share`.
    pub fn lookup(
        &self,
        frame: &Frame,
        settings: &FilterSettings,
        stats: &mut Stats,
        test: impl Fn(f32, &[f32]) -> f32 + Sync,
    ) -> Vec<Vec3> {
        let ch = self.chains.first().map_or(1, |c| c.channels());
        let (values, codes) = stats.stage("lookup", || {
            with_channels!(ch, lookup_n::<T>, (self, frame, settings, &test))
        });
        // Counters summed in pixel order, so they do not depend on the thread count.
        let (mut lit, mut probes, mut minified) = (0u64, 0u64, 0u64);
        for &c in &codes {
            if c & 0x7f > 0 {
                lit += 1;
                probes += (c & 0x7f) as u64;
                minified += (c >> 7) as u64;
            }
        }
        let lit = lit.max(1) as f64;
        stats.count("mean_probes", probes as f64 / lit);
        stats.count("minified_share", minified as f64 / lit);
        values
    }
}

/// The per-pixel look-ups of [`FilteredMaps::lookup`] for maps of `N` channels: each
/// pixel's shadow term and, in a second vector, a byte packing its probe count (low 7 bits,
/// 0 when the light cannot reach it) and whether it was minified (high bit).
fn lookup_n<T: Channel, const N: usize>(
    maps: &FilteredMaps<T>,
    frame: &Frame,
    settings: &FilterSettings,
    test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
) -> (Vec<Vec3>, Vec<u8>) {
    let view = frame.view;
    let n = (view.width * view.height) as usize;
    let ch = chans::<N>(maps.chains.first().map_or(1, |c| c.channels()));
    let mut values = vec![Vec3::ONE; n];
    let mut codes = vec![0u8; n];
    values
        .par_chunks_mut(PIXEL_CHUNK)
        .zip(codes.par_chunks_mut(PIXEL_CHUNK))
        .enumerate()
        .for_each_init(
            || vec![0.0f32; ch],
            |buf, (c, (values, codes))| {
                let chunk = LookupChunk {
                    maps,
                    frame,
                    settings,
                    first: c * PIXEL_CHUNK,
                };
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2, checked just above.
                    #[allow(unsafe_code)]
                    unsafe {
                        chunk.run_avx2::<N>(test, buf, values, codes)
                    };
                    return;
                }
                chunk.run::<N>(test, buf, values, codes);
            },
        );
    (values, codes)
}

/// One chunk of pixels of [`lookup_n`], starting at pixel `first`.
struct LookupChunk<'a, 'f, T> {
    maps: &'a FilteredMaps<T>,
    frame: &'a Frame<'f>,
    settings: &'a FilterSettings,
    first: usize,
}

impl<T: Channel> LookupChunk<'_, '_, T> {
    /// [`Self::run`] compiled for AVX2: twice the vector width for the same operations, so
    /// the same results (no fused multiply-adds: those would round differently).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2<const N: usize>(
        &self,
        test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
        buf: &mut [f32],
        values: &mut [Vec3],
        codes: &mut [u8],
    ) {
        self.run::<N>(test, buf, values, codes);
    }

    /// The look-ups of the chunk's pixels into `values` and `codes` (see [`lookup_n`]).
    #[inline(always)]
    fn run<const N: usize>(
        &self,
        test: &(impl Fn(f32, &[f32]) -> f32 + Sync),
        buf: &mut [f32],
        values: &mut [Vec3],
        codes: &mut [u8],
    ) {
        let (maps, frame, settings) = (self.maps, self.frame, self.settings);
        let view = frame.view;
        let ch = buf.len();
        for (j, (value, code)) in values.iter_mut().zip(codes).enumerate() {
            let k = self.first + j;
            if !frame.receiver_lit(k) {
                if view.covered(k) {
                    *value = Vec3::ZERO;
                }
                continue;
            }
            let p = view.position[k];
            let i = match *frame.light {
                Light::Point { position } => cube_face(p - position),
                _ => 0,
            };
            let lv = &maps.views[i];
            let s = lv.project(p);
            let fp = light_footprint(lv, p, view.dpdx[k], view.dpdy[k]);
            let lod = maps.chains[i].sample_n::<N>(
                s.u,
                s.v,
                &fp,
                settings.filter,
                settings.max_aniso,
                buf,
            );
            let d = maps.ranges[i].normalize(s.depth);
            let minified = u8::from(lod.lambda > 0.0);
            *value = Vec3::splat(test(d, &buf[..ch]));
            *code = lod.probes.clamp(1, 127) as u8 | minified << 7;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: u32, h: u32) -> Texture<f32> {
        Texture::from_fn(w, h, 2, |x, y, o| {
            o[0] = x as f32;
            o[1] = (x * 3 + y * 7) as f32;
        })
    }

    #[test]
    fn binomial_weights_sum_to_one() {
        for n in [1, 3, 5, 7, 15] {
            let w = binomial_weights(n);
            assert_eq!(w.len(), n as usize);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
        assert_eq!(binomial_weights(3), vec![0.25, 0.5, 0.25]);
    }

    #[test]
    fn blur_keeps_constants_and_linear_ramps_inside() {
        let t = Texture::<f32>::from_fn(16, 9, 1, |x, _, o| o[0] = x as f32 * 2.0 + 1.0);
        let b = blur(&t, 5);
        for y in 0..9 {
            for x in 2..14 {
                assert!((b.texel(x, y)[0] - t.texel(x, y)[0]).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn mip_levels_average_their_children() {
        let c = MipChain::build(ramp(8, 6));
        assert_eq!(c.levels.len(), 4); // 8×6, 4×3, 2×1, 1×1
        assert_eq!((c.levels[1].width, c.levels[1].height), (4, 3));
        assert_eq!((c.levels[2].width, c.levels[2].height), (2, 1));
        let t0 = &c.levels[0];
        let avg =
            (t0.texel(2, 2)[1] + t0.texel(3, 2)[1] + t0.texel(2, 3)[1] + t0.texel(3, 3)[1]) / 4.0;
        assert!((c.levels[1].texel(1, 1)[1] - avg).abs() < 1e-5);
        // The mean is preserved down to the last level, odd sides included.
        let mean: f32 = t0.data.iter().skip(1).step_by(2).sum::<f32>() / 48.0;
        assert!(
            (c.levels.last().unwrap().data[1] - mean).abs() < 1e-3,
            "{:?}",
            c.levels.last()
        );
    }

    #[test]
    fn bilinear_hits_texel_centres_and_interpolates() {
        let c = MipChain::single(ramp(8, 8));
        let mut o = [0.0; 2];
        c.sample(
            2.5 / 8.0,
            4.5 / 8.0,
            &Footprint::default(),
            Filter::Bilinear,
            1,
            &mut o,
        );
        assert_eq!(o[0], 2.0);
        c.sample(
            3.0 / 8.0,
            4.5 / 8.0,
            &Footprint::default(),
            Filter::Bilinear,
            1,
            &mut o,
        );
        assert!((o[0] - 2.5).abs() < 1e-6);
    }

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
