//! `gpu:evsm` and `gpu:msm` (and their `-soft` variants): the moment-based filtered maps on
//! the GPU, twins of the library's `evsm` and `msm`, on the shared chain of
//! [`super::filtering`] (whose module doc gives the stages and where the GPU departs).
//!
//! `gpu:evsm` (`evsm_warp.wgsl`, `evsm_bound.wgsl`): the exponential warps' moments in
//! 32-bit floats or half floats (`Rgba16Float`), the exponents clamped to the storage as the
//! library clamps them, and the smaller of the two Chebyshev bounds.
//!
//! `gpu:msm` (`msm_quantize.wgsl`, `hamburger.wgsl`): at 16 bits the paper's optimized
//! quantization Θ into 16-bit normalized texels (`Rgba16Unorm`; on an adapter without
//! 16-bit normalized textures the same codes in 32-bit floats), decoded with Θ⁻¹ after
//! filtering, and the Hamburger 4MSM bound. Departures: Θ's polynomials are evaluated in
//! f32 (the library: f64, then rounded to the code, so a code may differ by one), and the
//! bound is solved in f32 as the paper's shader does (the library: f64).

use super::filtering::{
    Codec, FilteredTwin, Store, ENCODE_SOURCE, FILTERED, LOOKUP_SOURCE, TECH_PARAMS, VIEWS,
};
use super::variance::CHEBYSHEV;
use crate::shader::{Common, Stage, LIGHT, RAY_OFFSET};
use glam::DMat4;
use shadowlab::error::Result;
use shadowlab::techniques::moments::evsm::ExponentialVariance;
use shadowlab::techniques::moments::msm::{MomentShadowMap, THETA, THETA_OFFSET};
use shadowlab::techniques::moments::Bits;
use shadowlab::techniques::shadow_map::check_resolution;

/// `gpu:evsm`'s name.
pub const EVSM: &str = "gpu:evsm";
/// `gpu:evsm-soft`'s name.
pub const EVSM_SOFT: &str = "gpu:evsm-soft";
/// `gpu:msm`'s name.
pub const MSM: &str = "gpu:msm";
/// `gpu:msm-soft`'s name.
pub const MSM_SOFT: &str = "gpu:msm-soft";

const EVSM_WARP: Common = Common {
    name: "moments/evsm_warp.wgsl",
    source: include_str!("evsm_warp.wgsl"),
};
const EVSM_BOUND: Common = Common {
    name: "moments/evsm_bound.wgsl",
    source: include_str!("evsm_bound.wgsl"),
};
const MSM_QUANTIZE: Common = Common {
    name: "moments/msm_quantize.wgsl",
    source: include_str!("msm_quantize.wgsl"),
};
const HAMBURGER: Common = Common {
    name: "moments/hamburger.wgsl",
    source: include_str!("hamburger.wgsl"),
};

const EVSM_ENCODE: Stage = Stage {
    name: "filtering/encode.wgsl (evsm)",
    common: &[FILTERED, EVSM_WARP],
    source: ENCODE_SOURCE,
};
const EVSM_LOOKUP: Stage = Stage {
    name: "filtering/lookup.wgsl (evsm)",
    common: &[
        RAY_OFFSET, LIGHT, VIEWS, FILTERED, EVSM_WARP, CHEBYSHEV, EVSM_BOUND,
    ],
    source: LOOKUP_SOURCE,
};
const MSM_ENCODE: Stage = Stage {
    name: "filtering/encode.wgsl (msm)",
    common: &[FILTERED, MSM_QUANTIZE],
    source: ENCODE_SOURCE,
};
const MSM_LOOKUP: Stage = Stage {
    name: "filtering/lookup.wgsl (msm)",
    common: &[RAY_OFFSET, LIGHT, VIEWS, FILTERED, MSM_QUANTIZE, HAMBURGER],
    source: LOOKUP_SOURCE,
};

impl FilteredTwin for ExponentialVariance {
    fn codec(&self) -> Result<Codec> {
        evsm_codec(self)
    }
}

impl FilteredTwin for MomentShadowMap {
    fn codec(&self) -> Result<Codec> {
        msm_codec(self)
    }
}

/// What `evsm` with `e`'s parameters gives the shared chain.
pub fn evsm_codec(e: &ExponentialVariance) -> Result<Codec> {
    let (cp, cn) = e.exponents();
    let mut tech = [0.0; TECH_PARAMS];
    tech[..5].copy_from_slice(&[cp, cn, e.moments as f32, e.min_variance, e.bleed_reduction]);
    Ok(Codec {
        technique: "evsm",
        resolution: check_resolution("evsm", e.resolution)?,
        channels: e.moments as u32,
        store: match e.bits {
            Bits::B16 => Store::F16,
            Bits::B32 => Store::F32,
        },
        span: 1.0,
        tech,
        encode: EVSM_ENCODE,
        lookup: EVSM_LOOKUP,
        settings: e.filtering,
    })
}

/// What `msm` with `m`'s parameters gives the shared chain.
pub fn msm_codec(m: &MomentShadowMap) -> Result<Codec> {
    let quantized = m.bits == Bits::B16;
    let mut tech = [0.0; TECH_PARAMS];
    tech[0] = if quantized { 1.0 } else { 0.0 };
    tech[1] = m.resolved_moment_bias();
    tech[2] = m.depth_bias;
    tech[3] = THETA_OFFSET as f32;
    for (r, row) in THETA.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            tech[4 + 4 * r + c] = *v as f32;
        }
    }
    // Θ⁻¹ (of Θ acting on column vectors), by columns as WGSL's mat4x4 takes them.
    let inverse = DMat4::from_cols_array_2d(&THETA).transpose().inverse();
    for (i, v) in inverse.to_cols_array().iter().enumerate() {
        tech[20 + i] = *v as f32;
    }
    Ok(Codec {
        technique: "msm",
        resolution: check_resolution("msm", m.resolution)?,
        channels: 4,
        store: if quantized {
            Store::Unorm16
        } else {
            Store::F32
        },
        span: 1.0,
        tech,
        encode: MSM_ENCODE,
        lookup: MSM_LOOKUP,
        settings: m.filtering,
    })
}
