//! The `gpu:` techniques: one folder per technique, mirroring the library's technique
//! folders, and the registry that creates them by name.

pub mod alias_free;
pub mod raytrace;
pub mod shadow_map;

use shadowlab::error::{Error, Result};
use shadowlab::techniques::ShadowTechnique;

/// Every GPU technique's name, in the order reports list them.
pub const ALL: &[&str] = &[
    shadow_map::SM,
    shadow_map::PCF,
    raytrace::NAME,
    alias_free::NAME,
];

/// A GPU technique by name (`gpu:raytrace`, …), with the defaults of its CPU twin.
pub fn create(name: &str) -> Result<Box<dyn ShadowTechnique>> {
    Ok(match name {
        shadow_map::SM => Box::new(shadow_map::GpuShadowMap::standard()),
        shadow_map::PCF => Box::new(shadow_map::GpuShadowMap::pcf()),
        raytrace::NAME => Box::new(raytrace::GpuRayTrace::default()),
        alias_free::NAME => Box::new(alias_free::GpuAliasFree::default()),
        _ => {
            return Err(Error::param(format!(
                "unknown GPU technique {name:?}: the GPU techniques are {}",
                ALL.join(", ")
            )))
        }
    })
}

/// The GPU technique `name` with its on-device path ([`crate::resident::OnDevice`]: the
/// shadow term left in a device buffer), when it has one.
pub fn create_on_device(name: &str) -> Option<Box<dyn crate::resident::OnDevice>> {
    Some(match name {
        shadow_map::SM => Box::new(shadow_map::GpuShadowMap::standard()),
        shadow_map::PCF => Box::new(shadow_map::GpuShadowMap::pcf()),
        raytrace::NAME => Box::new(raytrace::GpuRayTrace::default()),
        alias_free::NAME => Box::new(alias_free::GpuAliasFree::default()),
        _ => return None,
    })
}
