//! `msm`: moment shadow maps (Peters & Klein, "Moment Shadow Mapping", I3D 2015).
//!
//! The idea: store four power moments `(z, z², z³, z⁴)` of the light depth per texel and
//! filter them like a variance shadow map; a look-up bounds the lit fraction with the
//! sharp lower bound on the occluded share over all distributions with the filtered
//! moments (the Hamburger 4MSM bound, [`super::hamburger`]). Two moments more than VSM
//! let the bound place three depths instead of two, so a receiver behind two occluders at
//! different depths no longer sees the light leak that VSM's Chebyshev bound gives.
//!
//! Storage: at 16 bits the moments go through the paper's optimized quantization (its
//! Section 4.3): the affine map `b' = Θ·b + (0.0359558848, 0, 0, 0)` spreads the four
//! strongly correlated moments over `[0, 1]` so 16-bit normalized storage keeps the bound
//! usable; filtering is linear in `b'`, and a look-up decodes with `Θ⁻¹` (computed here in
//! f64 from `Θ`). At 32 bits the plain moments are stored as f32.
//!
//! Moment bias (Algorithm 3, step 1): `b ← (1 − α)·b + α·(½, ½, ½, ½)` keeps the Hankel
//! matrix invertible under quantization; the paper's α is [`DEFAULT_MOMENT_BIAS_16`] for
//! 16-bit storage. A depth bias `d ← d − depth-bias` (normalized depth) is subtracted from
//! the receiver before the bound.
//!
//! Invariants: depths are the linear light depths normalized to `[0, 1]` over `vsm`'s
//! fitted interval; blur, mip chain and look-ups are [`super::super::filtering`]'s.
//! Departures: the bound is solved in f64 (see [`super::hamburger`]); the moment bias
//! vector is the one for depths in `[0, 1]` (the paper writes it for `[−1, 1]`).
//! Known artifacts: light leaking is reduced, not removed (where the filter region holds
//! more than three distinct depths); the bias slightly lightens contact shadows; 16-bit
//! storage rounds the moments, which the bias hides at the cost of a little leaking.

use super::super::filtering::{Channel, FilterSettings, FilteredMaps, MapLayout};
use super::super::shadow_map::{check_resolution, DEFAULT_RESOLUTION};
use super::super::{
    find_param, in_key_order, not_read, param_value, parse_value, Frame, ParamSpec,
    ShadowTechnique, Shadows, Stats, RESOLUTION,
};
use super::hamburger;
use super::{grey, Bits, Unorm16, BITS, UNORM16_MAX};
use crate::error::Result;
use crate::math::Vec3;
use glam::{DMat4, DVec4};
use std::collections::BTreeMap;

/// The paper's moment bias α for 16-bit storage with optimized quantization.
pub const DEFAULT_MOMENT_BIAS_16: f32 = 3e-5;
/// Moment bias for 32-bit float storage, chosen by measurement (the paper gives the 16-bit
/// value): f32 moments round finer, but the filters' f32 sums of z⁴ still cancel, and
/// 10⁻⁷ left speckled self-shadowing (mean error 0.0107 on `fence-leak`, 0.0069 on
/// `chessboard` at 512×384, against 0.0095 and 0.0046 at 6·10⁻⁶).
pub const DEFAULT_MOMENT_BIAS_32: f32 = 6e-6;
/// Default storage: the paper's 16-bit optimized quantization (64 bits a texel, the same
/// memory as a 32-bit float VSM).
pub const DEFAULT_BITS: Bits = Bits::B16;
/// Default depth bias in normalized depth (5·10⁻⁴ of the fitted depth range): removes the
/// speckled self-shadowing that the rounding of 16-bit moments leaves on lit receivers far
/// from the light, where the moments of one depth are least separable; on `fence-leak` it
/// lowers the mean error from 0.0148 to 0.0119 (larger values, 2·10⁻³ to 5·10⁻³, start to
/// detach contact shadows and the error rises again).
pub const DEFAULT_DEPTH_BIAS: f32 = 5e-4;

/// The paper's optimized quantization matrix Θ (rows: the stored channels; columns: the
/// moments z, z², z³, z⁴).
pub const THETA: [[f64; 4]; 4] = [
    [-2.07224649, 32.23703778, -68.571074599, 39.3703274134],
    [13.7948857237, -59.4683975703, 82.0359750338, -35.364903257],
    [0.105877704, -1.9077466311, 9.3496555107, -6.6543490743],
    [9.7924062118, -33.7652110555, 47.9456096605, -23.9728048165],
];
/// The offset added to the first quantized channel.
pub const THETA_OFFSET: f64 = 0.035955884801;

/// Θ as a matrix acting on column vectors.
fn theta() -> DMat4 {
    DMat4::from_cols_array_2d(&THETA).transpose()
}

/// The quantized channels `Θ·b + offset` of depth `z`, each row of Θ evaluated by
/// Horner's rule as the polynomial `z·(Θ₀ + z·(Θ₁ + z·(Θ₂ + z·Θ₃)))` in f64 (it runs for
/// every texel).
#[inline]
pub fn quantize(z: f32) -> [f32; 4] {
    let z = z as f64;
    let q = THETA.map(|[t0, t1, t2, t3]| z * (t0 + z * (t1 + z * (t2 + z * t3))));
    [
        (q[0] + THETA_OFFSET) as f32,
        q[1] as f32,
        q[2] as f32,
        q[3] as f32,
    ]
}

/// The moments that quantized channels `q` stand for: `Θ⁻¹ (q − offset)`.
pub fn dequantize(inverse: &DMat4, q: [f64; 4]) -> [f64; 4] {
    let b = *inverse * DVec4::new(q[0] - THETA_OFFSET, q[1], q[2], q[3]);
    b.to_array()
}

/// The lit fraction of a receiver at normalized depth `d` from moments `b`, with moment
/// bias `alpha` and depth bias `depth_bias`.
#[inline]
pub fn lit(b: [f64; 4], d: f32, alpha: f32, depth_bias: f32) -> f32 {
    if !b.iter().all(|m| m.is_finite()) || !d.is_finite() {
        return 1.0;
    }
    let a = alpha as f64;
    let b = b.map(|m| (1.0 - a) * m + a * 0.5);
    let zf = (d - depth_bias) as f64;
    match hamburger::bound(b, zf) {
        Some(bound) => (1.0 - bound.intensity) as f32,
        // B singular: every moment is that of one depth; lit unless it is in front.
        None => {
            if zf <= b[0] {
                1.0
            } else {
                0.0
            }
        }
    }
}

/// The `msm` technique.
#[derive(Clone, Debug)]
pub struct MomentShadowMap {
    /// Map side in texels.
    pub resolution: u32,
    /// Storage per moment.
    pub bits: Bits,
    /// Moment bias α; `None` for the default of the storage size.
    pub moment_bias: Option<f32>,
    /// Depth bias in normalized depth.
    pub depth_bias: f32,
    /// Blur, mip-mapping and look-up filter.
    pub filtering: FilterSettings,
}

impl Default for MomentShadowMap {
    fn default() -> Self {
        MomentShadowMap {
            resolution: DEFAULT_RESOLUTION,
            bits: DEFAULT_BITS,
            moment_bias: None,
            depth_bias: DEFAULT_DEPTH_BIAS,
            filtering: FilterSettings::default(),
        }
    }
}

/// The parameters of msm's own, beside the filtering ones.
const OWN: &[ParamSpec] = &[
    BITS,
    ParamSpec::real(
        "depth-bias",
        0.0,
        1.0,
        "normalized depth subtracted from the receiver's before the Hamburger bound",
    ),
    ParamSpec::real(
        "moment-bias",
        0.0,
        0.5,
        "weight α of the blend towards a fixed distribution; the default depends on bits",
    ),
    RESOLUTION,
];

impl MomentShadowMap {
    /// The moment bias in effect.
    pub fn resolved_moment_bias(&self) -> f32 {
        self.moment_bias.unwrap_or(match self.bits {
            Bits::B16 => DEFAULT_MOMENT_BIAS_16,
            Bits::B32 => DEFAULT_MOMENT_BIAS_32,
        })
    }

    fn render_with<T: Channel>(
        &self,
        frame: &Frame,
        stats: &mut Stats,
        quantized: bool,
    ) -> Result<Vec<Vec3>> {
        let layout = MapLayout {
            technique: "msm",
            resolution: self.resolution,
            channels: 4,
            span: 1.0,
        };
        let inverse = theta().inverse();
        // The moments that filtered stored values stand for.
        let moments = |raw: [f64; 4]| {
            if quantized {
                dequantize(&inverse, raw.map(|v| v / UNORM16_MAX as f64))
            } else {
                raw
            }
        };
        let (alpha, depth_bias) = (self.resolved_moment_bias(), self.depth_bias);
        let (maps, value) = FilteredMaps::<T>::shade_texels(
            frame,
            &layout,
            &self.filtering,
            stats,
            |m, r, x, y, out| {
                let z = r.normalize(m.depth[(y * m.width + x) as usize]);
                if quantized {
                    let q = quantize(z);
                    for (o, q) in out.iter_mut().zip(q) {
                        *o = q * UNORM16_MAX;
                    }
                } else {
                    let z2 = z * z;
                    out.copy_from_slice(&[z, z2, z2 * z, z2 * z2]);
                }
            },
            |d, mo| {
                let raw = [mo[0], mo[1], mo[2], mo[3]].map(|v| v as f64);
                lit(moments(raw), d, alpha, depth_bias)
            },
        )?;
        // The first moment (the mean depth), recovered from what was stored.
        maps.dump_level0(
            frame,
            |i| format!("msm-mean-depth{i}.png"),
            |t| grey(moments([0, 1, 2, 3].map(|c| t[c].to_f32() as f64))[0] as f32),
        )?;
        Ok(value)
    }
}

impl ShadowTechnique for MomentShadowMap {
    fn name(&self) -> &'static str {
        "msm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("bits".to_string(), self.bits.value().into()),
            (
                "moment-bias".to_string(),
                param_value(self.resolved_moment_bias()),
            ),
            ("depth-bias".to_string(), param_value(self.depth_bias)),
        ]);
        self.filtering.params(&mut m);
        m
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        in_key_order([OWN, &FilterSettings::SPECS].concat())
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "msm";
        let spec = find_param(t, &self.param_specs(), key)?;
        if self.filtering.set_param(t, key, value)? {
            return Ok(());
        }
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bits" => self.bits = Bits::parse(t, key, spec.word(t, value)?)?,
            "moment-bias" => self.moment_bias = Some(spec.f32(t, value)?),
            "depth-bias" => self.depth_bias = spec.f32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        check_resolution("msm", self.resolution)?;
        let mut stats = Stats::default();
        let value = match self.bits {
            Bits::B16 => self.render_with::<Unorm16>(frame, &mut stats, true)?,
            Bits::B32 => self.render_with::<f32>(frame, &mut stats, false)?,
        };
        Ok(Shadows::of_frame(frame, value, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantization_round_trips_and_fits_unit_range() {
        let inv = theta().inverse();
        for i in 0..=100 {
            let z = i as f32 / 100.0;
            let q = quantize(z);
            assert!(
                q.iter().all(|&c| (-1e-6..=1.0 + 1e-6).contains(&c)),
                "{z}: {q:?}"
            );
            let b = dequantize(&inv, q.map(|c| c as f64));
            let z = z as f64;
            for (k, m) in b.iter().enumerate() {
                assert!(
                    (m - z.powi(k as i32 + 1)).abs() < 1e-5,
                    "{z} moment {k}: {m}"
                );
            }
        }
    }

    #[test]
    fn lit_in_front_and_shadowed_behind_one_occluder() {
        let z = 0.4f64;
        let b = [z, z * z, z.powi(3), z.powi(4)];
        assert!(lit(b, 0.2, DEFAULT_MOMENT_BIAS_16, 0.0) > 0.99);
        assert!(lit(b, 0.9, DEFAULT_MOMENT_BIAS_16, 0.0) < 0.01);
    }
}
