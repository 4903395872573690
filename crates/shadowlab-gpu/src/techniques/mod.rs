//! The `gpu:` techniques: one folder per technique, mirroring the library's technique
//! folders, and the registry that creates them by name.

pub mod alias_free;
pub mod convolution;
pub mod filtering;
pub mod moments;
pub mod raytrace;
pub mod shadow_map;
pub mod variance;

use filtering::GpuFiltered;
use shadowlab::error::{Error, Result};
use shadowlab::techniques::convolution::Convolution;
use shadowlab::techniques::moments::evsm::ExponentialVariance;
use shadowlab::techniques::moments::msm::MomentShadowMap;
use shadowlab::techniques::variance::Variance;
use shadowlab::techniques::ShadowTechnique;

/// Every GPU technique's name, in the order reports list them.
pub const ALL: &[&str] = &[
    shadow_map::SM,
    shadow_map::PCF,
    raytrace::NAME,
    alias_free::NAME,
    variance::VSM,
    moments::EVSM,
    moments::MSM,
    convolution::CSM,
    variance::VSM_SOFT,
    moments::EVSM_SOFT,
    moments::MSM_SOFT,
    convolution::CSM_SOFT,
];

/// A GPU technique by name (`gpu:raytrace`, …), with the defaults of its CPU twin.
pub fn create(name: &str) -> Result<Box<dyn ShadowTechnique>> {
    Ok(match name {
        shadow_map::SM => Box::new(shadow_map::GpuShadowMap::standard()),
        shadow_map::PCF => Box::new(shadow_map::GpuShadowMap::pcf()),
        raytrace::NAME => Box::new(raytrace::GpuRayTrace::default()),
        alias_free::NAME => Box::new(alias_free::GpuAliasFree::default()),
        variance::VSM | variance::VSM_SOFT => Box::new(GpuFiltered::new(
            if name == variance::VSM {
                variance::VSM
            } else {
                variance::VSM_SOFT
            },
            Box::new(Variance::default()),
            name == variance::VSM_SOFT,
        )),
        moments::EVSM | moments::EVSM_SOFT => Box::new(GpuFiltered::new(
            if name == moments::EVSM {
                moments::EVSM
            } else {
                moments::EVSM_SOFT
            },
            Box::new(ExponentialVariance::default()),
            name == moments::EVSM_SOFT,
        )),
        moments::MSM | moments::MSM_SOFT => Box::new(GpuFiltered::new(
            if name == moments::MSM {
                moments::MSM
            } else {
                moments::MSM_SOFT
            },
            Box::new(MomentShadowMap::default()),
            name == moments::MSM_SOFT,
        )),
        convolution::CSM | convolution::CSM_SOFT => Box::new(GpuFiltered::new(
            if name == convolution::CSM {
                convolution::CSM
            } else {
                convolution::CSM_SOFT
            },
            Box::new(Convolution::default()),
            name == convolution::CSM_SOFT,
        )),
        _ => {
            return Err(Error::param(format!(
                "unknown GPU technique {name:?}: the GPU techniques are {}",
                ALL.join(", ")
            )))
        }
    })
}
