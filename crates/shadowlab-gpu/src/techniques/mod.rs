//! The `gpu:` techniques: one folder per technique, mirroring the library's technique
//! folders, and the registry that creates them by name.

pub mod alias_free;
pub mod pcss;
pub mod raytrace;
pub mod shadow_map;
pub mod subpixel;

use shadowlab::error::{Error, Result};
use shadowlab::techniques::ShadowTechnique;

/// Every GPU technique's name, in the order reports list them.
pub const ALL: &[&str] = &[
    shadow_map::SM,
    shadow_map::PCF,
    raytrace::NAME,
    alias_free::NAME,
    pcss::NAME,
    subpixel::NAME,
];

/// A GPU technique by name (`gpu:raytrace`, …), with the defaults of its CPU twin.
pub fn create(name: &str) -> Result<Box<dyn ShadowTechnique>> {
    Ok(match name {
        shadow_map::SM => Box::new(shadow_map::GpuShadowMap::standard()),
        shadow_map::PCF => Box::new(shadow_map::GpuShadowMap::pcf()),
        raytrace::NAME => Box::new(raytrace::GpuRayTrace::default()),
        alias_free::NAME => Box::new(alias_free::GpuAliasFree::default()),
        pcss::NAME => Box::new(pcss::GpuPcss::default()),
        subpixel::NAME => Box::new(subpixel::GpuSubpixel::default()),
        _ => {
            return Err(Error::param(format!(
                "unknown GPU technique {name:?}: the GPU techniques are {}",
                ALL.join(", ")
            )))
        }
    })
}
