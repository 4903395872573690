//! Filtered look-ups in a mip chain (Annen et al. 2007, Section 4: "mip-mapping, which
//! enables high quality tri-linear and anisotropic filtering"): the level of detail of a
//! footprint, and bilinear, tri-linear or anisotropic samples at it, as
//! `EXT_texture_filter_anisotropic` describes them.

use super::footprint::Footprint;
use super::mip::MipChain;
use super::texture::{chans, fast_ceil, fast_floor, Channel};
use crate::error::{Error, Result};
use crate::math::Vec2;

/// The largest anisotropy (probes per look-up) accepted, as on GPUs.
pub const MAX_ANISOTROPY: u32 = 16;
/// Default anisotropy: the paper's 16× anisotropic tri-linear filtering.
pub const DEFAULT_ANISOTROPY: u32 = 16;

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

impl<T: Channel> MipChain<T> {
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

#[cfg(test)]
mod tests {
    use super::super::mip::tests::ramp;
    use super::*;

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
}
