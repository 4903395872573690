//! `gpu:csm` and `gpu:csm-soft`: convolution shadow maps (Annen et al. 2007) on the GPU,
//! twins of the library's `csm` and `csm-soft`, on the shared chain of
//! [`super::filtering`] (whose module doc gives the stages and where the GPU departs).
//!
//! Encoder (`basis.wgsl`): the Fourier basis images `sin(c_k z)`, `cos(c_k z)`, two terms
//! to a layer of `Rgba8Unorm` texels (the paper's 8-bit storage) or 32-bit floats, with a
//! real mip chain read by the hardware's tri-linear filtering, anisotropic look-ups as
//! probes along the footprint (see [`super::filtering`]). Test (`reconstruction.wgsl`): Eq. 13 over every layer, offset and scaled about the
//! pivot as the library's `csm` does. Departures: the basis is evaluated directly per term
//! (the library rotates the angle term by term, and rounds large 8-bit maps' depths to 2¹⁶
//! levels first), so a code may differ by one.

use super::filtering::{
    Codec, FilteredTwin, Store, ENCODE_SOURCE, FILTERED, LOOKUP_SOURCE, TECH_PARAMS, VIEWS,
};
use crate::shader::{Common, Stage, LIGHT, RAY_OFFSET};
use shadowlab::error::Result;
use shadowlab::techniques::convolution::{Convolution, Expansion, Precision};
use shadowlab::techniques::shadow_map::check_resolution;

/// `gpu:csm`'s name.
pub const CSM: &str = "gpu:csm";
/// `gpu:csm-soft`'s name.
pub const CSM_SOFT: &str = "gpu:csm-soft";

const BASIS: Common = Common {
    name: "convolution/basis.wgsl",
    source: include_str!("basis.wgsl"),
};
const RECONSTRUCTION: Common = Common {
    name: "convolution/reconstruction.wgsl",
    source: include_str!("reconstruction.wgsl"),
};

const ENCODE: Stage = Stage {
    name: "filtering/encode.wgsl (csm)",
    common: &[FILTERED, BASIS],
    source: ENCODE_SOURCE,
};
const LOOKUP: Stage = Stage {
    name: "filtering/lookup.wgsl (csm)",
    common: &[RAY_OFFSET, LIGHT, VIEWS, FILTERED, BASIS, RECONSTRUCTION],
    source: LOOKUP_SOURCE,
};

impl FilteredTwin for Convolution {
    fn codec(&self) -> Result<Codec> {
        codec(self)
    }
}

/// What `csm` with `c`'s parameters gives the shared chain.
pub fn codec(c: &Convolution) -> Result<Codec> {
    let exp = c.expansion();
    let offset = c.resolved_offset();
    let u8 = c.precision == Precision::U8;
    let mut tech = [0.0; TECH_PARAMS];
    tech[..5].copy_from_slice(&[
        exp.m as f32,
        if u8 { 1.0 } else { 0.0 },
        offset,
        c.scale,
        c.pivot,
    ]);
    for k in 1..=exp.m {
        tech[7 + k as usize] = 2.0 * exp.attenuation(k) / Expansion::c(k);
    }
    Ok(Codec {
        technique: "csm",
        resolution: check_resolution("csm", c.resolution)?,
        channels: exp.channels() as u32,
        store: if u8 { Store::U8 } else { Store::F32 },
        span: 1.0 - 2.0 * offset,
        tech,
        encode: ENCODE,
        lookup: LOOKUP,
        settings: c.filtering,
    })
}
