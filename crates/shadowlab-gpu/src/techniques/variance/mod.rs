//! `gpu:vsm` and `gpu:vsm-soft`: variance shadow maps (Donnelly & Lauritzen 2006) on the
//! GPU, twins of the library's `vsm` and `vsm-soft`, on the shared chain of
//! [`super::filtering`] (whose module doc gives the stages and where the GPU departs).
//!
//! Encoder (`moments.wgsl`): the depth and its square plus the depth variance across the
//! texel, in 32-bit floats (`Rg32Float`, which needs an adapter that filters it). Test
//! (`reconstruct.wgsl` over `chebyshev.wgsl`): the one-tailed Chebyshev bound with the
//! variance floor and the light-bleeding reduction, as the library's.

use super::filtering::{
    Codec, FilteredTwin, Store, ENCODE_SOURCE, FILTERED, LOOKUP_SOURCE, TECH_PARAMS, VIEWS,
};
use crate::shader::{Common, Stage, LIGHT, RAY_OFFSET};
use shadowlab::error::Result;
use shadowlab::techniques::shadow_map::check_resolution;
use shadowlab::techniques::variance::Variance;

/// `gpu:vsm`'s name.
pub const VSM: &str = "gpu:vsm";
/// `gpu:vsm-soft`'s name.
pub const VSM_SOFT: &str = "gpu:vsm-soft";

/// `variance/moments.wgsl`: vsm's encoder.
const MOMENTS: Common = Common {
    name: "variance/moments.wgsl",
    source: include_str!("moments.wgsl"),
};
/// `variance/chebyshev.wgsl`: the Chebyshev bound, shared with `gpu:evsm`.
pub const CHEBYSHEV: Common = Common {
    name: "variance/chebyshev.wgsl",
    source: include_str!("chebyshev.wgsl"),
};
const RECONSTRUCT: Common = Common {
    name: "variance/reconstruct.wgsl",
    source: include_str!("reconstruct.wgsl"),
};

const ENCODE: Stage = Stage {
    name: "filtering/encode.wgsl (vsm)",
    common: &[FILTERED, MOMENTS],
    source: ENCODE_SOURCE,
};
const LOOKUP: Stage = Stage {
    name: "filtering/lookup.wgsl (vsm)",
    common: &[
        RAY_OFFSET,
        LIGHT,
        VIEWS,
        FILTERED,
        MOMENTS,
        CHEBYSHEV,
        RECONSTRUCT,
    ],
    source: LOOKUP_SOURCE,
};

impl FilteredTwin for Variance {
    fn codec(&self) -> Result<Codec> {
        codec(self)
    }
}

/// What `vsm` with `v`'s parameters gives the shared chain.
pub fn codec(v: &Variance) -> Result<Codec> {
    let mut tech = [0.0; TECH_PARAMS];
    tech[0] = v.min_variance;
    tech[1] = v.bleed_reduction;
    Ok(Codec {
        technique: "vsm",
        resolution: check_resolution("vsm", v.resolution)?,
        channels: 2,
        store: Store::F32,
        span: 1.0,
        tech,
        encode: ENCODE,
        lookup: LOOKUP,
        settings: v.filtering,
    })
}
