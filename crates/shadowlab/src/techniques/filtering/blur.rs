//! The blur of the pre-filtering stage (Annen et al. 2007, Section 4.1: "we apply a
//! separable Gaussian filter kernel on the textures to hide aliasing from discretization"):
//! a binomial kernel, each pass written back in the texture's format.

use super::texture::{chans, with_channels, Channel, Texture};
use crate::error::{Error, Result};
use rayon::prelude::*;

/// The largest blur kernel side accepted.
pub const MAX_BLUR: u32 = 63;

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
    let n: u32 = super::super::technique::parse_value(technique, "blur", side)?;
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
