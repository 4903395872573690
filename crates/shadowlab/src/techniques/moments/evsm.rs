//! `evsm`: exponential variance shadow maps (Lauritzen & McCool, "Layered Variance Shadow
//! Maps", GI 2008, Section 5; the exponential warp of Annen et al.'s exponential shadow
//! maps applied to VSM).
//!
//! The idea: warp the normalized light depth `d` (mapped to `t = 2d − 1 ∈ [−1, 1]`)
//! through `w⁺ = exp(c⁺·t)` and, with four moments, `w⁻ = −exp(−c⁻·t)`, store the first
//! two moments of each warped depth, filter them like `vsm`'s, and take the smaller of the
//! two Chebyshev bounds. The exponential stretches the depths behind an occluder apart from
//! the occluder's, which shrinks the variance a farther surface adds and with it VSM's light
//! bleeding; the negative warp bounds the same leak from the other side.
//!
//! Exponents are clamped to what the storage holds: `exp(2c)` (the second moment of the
//! farthest depth) must stay finite, so `c ≤` [`MAX_EXPONENT_32`] for f32 and
//! [`MAX_EXPONENT_16`] for half floats. The variance floor is `vsm`'s, carried into warped
//! space by the warp's derivative at the receiver (`σ²_w = (dw/dd)²·σ²`), and so is the
//! per-texel slope variance of the encoder; with both, EVSM tends to VSM as `c → 0`
//! (Chebyshev's bound is invariant under an increasing affine map, and `w ≈ 1 + 2c·d`).
//!
//! Invariants: depths are normalized as `vsm`'s; blur, mip chain and look-ups are the
//! shared ones. Departures: the warp acts on `[−1, 1]` as engines do (the paper's
//! `[0, 1]`), which doubles the usable exponent range for the same storage. Known
//! artifacts: bleeding remains where the occluder and a farther surface are close in
//! depth relative to `1/c`; half floats allow only small exponents, so 16-bit EVSM leaks
//! almost as VSM does; very large exponents lose precision for receivers near the far
//! end of the range.

use super::super::filtering::{Channel, FilterSettings, FilteredMaps, MapLayout};
use super::super::shadow_map::{check_resolution, DEFAULT_RESOLUTION};
use super::super::variance::{
    chebyshev, texel_depth_and_variance, BLEED_REDUCTION, DEFAULT_MIN_VARIANCE, MIN_VARIANCE,
};
use super::super::{
    find_param, in_key_order, not_read, param_value, parse_value, Frame, ParamSpec,
    ShadowTechnique, Shadows, Stats, RESOLUTION,
};
use super::{grey, Bits, BITS, F16};
use crate::error::Result;
use crate::math::Vec3;
use std::collections::BTreeMap;

/// Largest exponent for f32 storage: `exp(2·42) ≈ 3·10³⁶`, below f32's 3.4·10³⁸ with room
/// for filter sums.
pub const MAX_EXPONENT_32: f32 = 42.0;
/// Largest exponent for half-float storage: `exp(2·5.54) ≈ 65000`, below the largest half
/// float 65504.
pub const MAX_EXPONENT_16: f32 = 5.54;
/// Default positive exponent: engines' usual 40 (clamped to the storage's maximum).
pub const DEFAULT_EXPONENT_POS: f32 = 40.0;
/// Default negative exponent: engines' usual 5 (clamped to the storage's maximum); larger
/// values trade precision far from the light for less leaking near it.
pub const DEFAULT_EXPONENT_NEG: f32 = 5.0;
/// Default moment count: four (both warps), the usual EVSM4.
pub const DEFAULT_MOMENTS: usize = 4;
/// Default storage: 32-bit floats (half floats cap the exponents at 5.54).
pub const DEFAULT_BITS: Bits = Bits::B32;

/// The `evsm` technique.
#[derive(Clone, Debug)]
pub struct ExponentialVariance {
    /// Map side in texels.
    pub resolution: u32,
    /// 2 (positive warp only) or 4 moments.
    pub moments: usize,
    /// Storage per moment.
    pub bits: Bits,
    /// Positive exponent before clamping.
    pub exponent_pos: f32,
    /// Negative exponent before clamping.
    pub exponent_neg: f32,
    /// Floor on the variance of the normalized depth (as `vsm`'s).
    pub min_variance: f32,
    /// Light-bleeding reduction amount in `[0, 1)`.
    pub bleed_reduction: f32,
    /// Blur, mip-mapping and look-up filter.
    pub filtering: FilterSettings,
}

impl Default for ExponentialVariance {
    fn default() -> Self {
        ExponentialVariance {
            resolution: DEFAULT_RESOLUTION,
            moments: DEFAULT_MOMENTS,
            bits: DEFAULT_BITS,
            exponent_pos: DEFAULT_EXPONENT_POS,
            exponent_neg: DEFAULT_EXPONENT_NEG,
            min_variance: DEFAULT_MIN_VARIANCE,
            bleed_reduction: 0.0,
            filtering: FilterSettings::default(),
        }
    }
}

/// The parameters of evsm's own, beside the filtering ones.
const OWN: &[ParamSpec] = &[
    BLEED_REDUCTION,
    BITS,
    ParamSpec::real(
        "exponent-neg",
        1e-6,
        1e3,
        "exponent c₋ of the negative warp −e^(−c₋z) (4 moments only), clamped to the storage's",
    ),
    ParamSpec::real(
        "exponent-pos",
        1e-6,
        1e3,
        "exponent c₊ of the positive warp e^(c₊z), clamped to the storage's: larger bleeds less",
    ),
    MIN_VARIANCE,
    ParamSpec::choice(
        "moments",
        &["2", "4"],
        "2: the positive warp's two moments; 4: both warps, the smaller bound",
    ),
    RESOLUTION,
];

/// The exponential warps of a normalized depth `d`, with exponents `(c⁺, c⁻)`: `(w⁺, w⁻)`.
#[inline]
pub fn warp(d: f32, c: (f32, f32)) -> (f32, f32) {
    let t = 2.0 * d - 1.0;
    ((c.0 * t).exp(), -(-c.1 * t).exp())
}

/// The lit fraction of a receiver at normalized depth `d` from the filtered warped moments
/// `mo` (`[E w⁺, E w⁺²]` or `[E w⁺, E w⁺², E w⁻, E w⁻²]`), exponents `c`, the variance floor
/// of the normalized depth `min_variance` and the bleeding reduction `reduction`.
#[inline]
pub fn lit(d: f32, mo: &[f32], c: (f32, f32), min_variance: f32, reduction: f32) -> f32 {
    let (wp, wn) = warp(d, c);
    // dw/dd at the receiver: 2c·w for both warps (in magnitude).
    let sp = 2.0 * c.0 * wp;
    let p = chebyshev(wp, mo[0], mo[1], min_variance * sp * sp, reduction);
    if mo.len() < 4 {
        return p;
    }
    let sn = 2.0 * c.1 * wn;
    p.min(chebyshev(
        wn,
        mo[2],
        mo[3],
        min_variance * sn * sn,
        reduction,
    ))
}

impl ExponentialVariance {
    /// The exponents in effect: the set ones clamped to the storage's maximum.
    pub fn exponents(&self) -> (f32, f32) {
        let max = match self.bits {
            Bits::B16 => MAX_EXPONENT_16,
            Bits::B32 => MAX_EXPONENT_32,
        };
        (self.exponent_pos.min(max), self.exponent_neg.min(max))
    }

    fn render_with<T: Channel>(&self, frame: &Frame, stats: &mut Stats) -> Result<Vec<Vec3>> {
        let c = self.exponents();
        let n = self.moments;
        let layout = MapLayout {
            technique: "evsm",
            resolution: self.resolution,
            channels: n,
            span: 1.0,
        };
        let (min_var, reduction) = (self.min_variance, self.bleed_reduction);
        let (maps, value) = FilteredMaps::<T>::shade_texels(
            frame,
            &layout,
            &self.filtering,
            stats,
            |m, r, x, y, out| {
                let (z, var) = texel_depth_and_variance(m, r, x, y);
                let (wp, wn) = warp(z, c);
                // Second moments with the texel's own depth variance carried through the
                // warp's derivative.
                let (sp, sn) = (2.0 * c.0 * wp, 2.0 * c.1 * wn);
                out[0] = wp;
                out[1] = wp * wp + sp * sp * var;
                if n == 4 {
                    out[2] = wn;
                    out[3] = wn * wn + sn * sn * var;
                }
            },
            |d, mo| lit(d, mo, c, min_var, reduction),
        )?;
        stats.count("exponent_pos", c.0 as f64);
        stats.count("exponent_neg", c.1 as f64);
        // The positive warp's mean, mapped back to normalized depth.
        maps.dump_level0(
            frame,
            |i| format!("evsm-mean-depth{i}.png"),
            |t| grey((t[0].to_f32().max(1e-30).ln() / c.0.max(1e-6) + 1.0) * 0.5),
        )?;
        Ok(value)
    }
}

impl ShadowTechnique for ExponentialVariance {
    fn name(&self) -> &'static str {
        "evsm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let (cp, cn) = self.exponents();
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("moments".to_string(), self.moments.into()),
            ("bits".to_string(), self.bits.value().into()),
            ("exponent-pos".to_string(), param_value(cp)),
            ("exponent-neg".to_string(), param_value(cn)),
            ("min-variance".to_string(), param_value(self.min_variance)),
            (
                "bleed-reduction".to_string(),
                param_value(self.bleed_reduction),
            ),
        ]);
        self.filtering.params(&mut m);
        m
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        in_key_order([OWN, &FilterSettings::SPECS].concat())
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "evsm";
        let spec = find_param(t, &self.param_specs(), key)?;
        if self.filtering.set_param(t, key, value)? {
            return Ok(());
        }
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "moments" => self.moments = parse_value(t, key, spec.word(t, value)?)?,
            "bits" => self.bits = Bits::parse(t, key, spec.word(t, value)?)?,
            "exponent-pos" => self.exponent_pos = spec.f32(t, value)?,
            "exponent-neg" => self.exponent_neg = spec.f32(t, value)?,
            "min-variance" => self.min_variance = spec.f32(t, value)?,
            "bleed-reduction" => self.bleed_reduction = spec.f32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        check_resolution("evsm", self.resolution)?;
        let mut stats = Stats::default();
        let value = match self.bits {
            Bits::B16 => self.render_with::<F16>(frame, &mut stats)?,
            Bits::B32 => self.render_with::<f32>(frame, &mut stats)?,
        };
        Ok(Shadows::of_frame(frame, value, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(E z, E z²)` and the warped moments of a distribution of normalized depths.
    fn moments(points: &[(f32, f32)], c: (f32, f32)) -> ([f32; 2], [f32; 4]) {
        let (mut v, mut e) = ([0.0f64; 2], [0.0f64; 4]);
        for &(z, w) in points {
            let (wp, wn) = warp(z, c);
            let w = w as f64;
            v[0] += w * z as f64;
            v[1] += w * (z as f64).powi(2);
            e[0] += w * wp as f64;
            e[1] += w * (wp as f64).powi(2);
            e[2] += w * wn as f64;
            e[3] += w * (wn as f64).powi(2);
        }
        (v.map(|x| x as f32), e.map(|x| x as f32))
    }

    #[test]
    fn evsm_tends_to_vsm_as_the_exponents_shrink() {
        // An occluder covering 40% of the filter at 0.3, the rest at 0.55 and 0.6 behind it.
        let pts = [(0.3, 0.4), (0.55, 0.3), (0.6, 0.3)];
        for d in [0.58f32, 0.62, 0.75] {
            let (v, _) = moments(&pts, (1.0, 1.0));
            let vsm = chebyshev(d, v[0], v[1], DEFAULT_MIN_VARIANCE, 0.0);
            let mut last = f32::INFINITY;
            for c in [2.0f32, 0.5, 0.1, 0.02] {
                let (_, e) = moments(&pts, (c, c));
                let err = (lit(d, &e, (c, c), DEFAULT_MIN_VARIANCE, 0.0) - vsm).abs();
                let err2 = (lit(d, &e[..2], (c, c), DEFAULT_MIN_VARIANCE, 0.0) - vsm).abs();
                assert!(
                    err <= last + 1e-3 && err2 <= last + 1e-3,
                    "d {d} c {c}: {err} {err2} after {last}"
                );
                last = err.max(err2);
            }
            assert!(last < 5e-3, "d {d}: EVSM at c = 0.02 is {last} from VSM");
        }
    }

    #[test]
    fn large_exponents_cut_the_leak_behind_two_occluders() {
        // VSM's classic leak: half the filter sees an occluder at 0.2, the other half a
        // surface at 0.75, and the receiver at 0.8 lies behind both (truly lit share 0);
        // Chebyshev's bound on the two moments lets 40% of the light through.
        let pts = [(0.2, 0.5), (0.75, 0.5)];
        let (v, _) = moments(&pts, (1.0, 1.0));
        let vsm = chebyshev(0.8, v[0], v[1], DEFAULT_MIN_VARIANCE, 0.0);
        let c = (MAX_EXPONENT_32, 5.0);
        let (_, e) = moments(&pts, c);
        let evsm = lit(0.8, &e, c, DEFAULT_MIN_VARIANCE, 0.0);
        assert!(evsm < vsm - 0.2, "evsm {evsm} vs vsm {vsm}");
    }

    #[test]
    fn exponents_are_clamped_to_the_storage() {
        let mut t = ExponentialVariance::default();
        assert_eq!(t.exponents(), (DEFAULT_EXPONENT_POS, DEFAULT_EXPONENT_NEG));
        t.set_param("bits", "16").unwrap();
        // The positive exponent is clamped; the negative one (5) already fits.
        assert_eq!(t.exponents(), (MAX_EXPONENT_16, DEFAULT_EXPONENT_NEG));
        assert!(warp(1.0, t.exponents()).0.powi(2) < crate::techniques::moments::F16_MAX);
        t.set_param("bits", "32").unwrap();
        t.set_param("exponent-pos", "100").unwrap();
        assert_eq!(t.exponents().0, MAX_EXPONENT_32);
        assert!(warp(1.0, t.exponents()).0.powi(2).is_finite());
        assert!(t.set_param("moments", "3").is_err());
        assert!(t.set_param("bits", "8").is_err());
    }
}
