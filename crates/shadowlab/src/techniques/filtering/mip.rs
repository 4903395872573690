//! Mip-mapping of the pre-filtering stage (Annen et al. 2007, Section 4.1: "we then build
//! a mip-map of this texture (using the auto-mip-map feature of modern GPUs) to prevent
//! minification aliasing"): a full chain of box-filtered levels down to 1×1, quantized like
//! `glGenerateMipmap`.

use super::texture::{chans, with_channels, Channel, Texture};
use rayon::prelude::*;

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

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A 2-channel test texture: `x`, and `3x + 7y`.
    pub(in super::super) fn ramp(w: u32, h: u32) -> Texture<f32> {
        Texture::from_fn(w, h, 2, |x, y, o| {
            o[0] = x as f32;
            o[1] = (x * 3 + y * 7) as f32;
        })
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
}
