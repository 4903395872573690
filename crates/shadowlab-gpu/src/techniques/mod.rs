//! The `gpu:` techniques: one folder per technique, mirroring the library's technique
//! folders, and the registry that creates them by name.

pub mod adaptive;
pub mod alias_free;
pub mod cascaded;
pub mod convolution;
pub mod filtering;
pub mod lispsm;
mod maps;
pub mod moments;
pub mod pcss;
pub mod perspective;
pub mod raytrace;
pub mod shadow_map;
pub mod subpixel;
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
    perspective::NAME,
    lispsm::NAME,
    cascaded::NAME,
    variance::VSM,
    moments::EVSM,
    moments::MSM,
    convolution::CSM,
    variance::VSM_SOFT,
    moments::EVSM_SOFT,
    moments::MSM_SOFT,
    convolution::CSM_SOFT,
    adaptive::NAME,
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
        perspective::NAME => Box::new(perspective::GpuPsm::default()),
        lispsm::NAME => Box::new(lispsm::GpuLispsm::default()),
        cascaded::NAME => Box::new(cascaded::GpuCascaded::default()),
        variance::VSM => filtered(variance::VSM, Box::new(Variance::default()), false),
        variance::VSM_SOFT => filtered(variance::VSM_SOFT, Box::new(Variance::default()), true),
        moments::EVSM => filtered(
            moments::EVSM,
            Box::new(ExponentialVariance::default()),
            false,
        ),
        moments::EVSM_SOFT => filtered(
            moments::EVSM_SOFT,
            Box::new(ExponentialVariance::default()),
            true,
        ),
        moments::MSM => filtered(moments::MSM, Box::new(MomentShadowMap::default()), false),
        moments::MSM_SOFT => filtered(
            moments::MSM_SOFT,
            Box::new(MomentShadowMap::default()),
            true,
        ),
        convolution::CSM => filtered(convolution::CSM, Box::new(Convolution::default()), false),
        convolution::CSM_SOFT => filtered(
            convolution::CSM_SOFT,
            Box::new(Convolution::default()),
            true,
        ),
        adaptive::NAME => Box::new(adaptive::GpuAdaptive::default()),
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

/// A filtered map (`gpu:vsm`, `gpu:msm-soft`, …) on the shared filtering chain, with its CPU
/// twin at its defaults (`soft`: the twin's blocker-search penumbrae).
fn filtered(
    name: &'static str,
    twin: Box<dyn filtering::FilteredTwin>,
    soft: bool,
) -> Box<dyn ShadowTechnique> {
    Box::new(GpuFiltered::new(name, twin, soft))
}

/// The GPU technique `name` with its on-device path ([`crate::resident::OnDevice`]: the
/// shadow term left in a device buffer), when it has one.
pub fn create_on_device(name: &str) -> Option<Box<dyn crate::resident::OnDevice>> {
    Some(match name {
        shadow_map::SM => Box::new(shadow_map::GpuShadowMap::standard()),
        shadow_map::PCF => Box::new(shadow_map::GpuShadowMap::pcf()),
        raytrace::NAME => Box::new(raytrace::GpuRayTrace::default()),
        alias_free::NAME => Box::new(alias_free::GpuAliasFree::default()),
        perspective::NAME => Box::new(perspective::GpuPsm::default()),
        lispsm::NAME => Box::new(lispsm::GpuLispsm::default()),
        cascaded::NAME => Box::new(cascaded::GpuCascaded::default()),
        pcss::NAME => Box::new(pcss::GpuPcss::default()),
        _ => return None,
    })
}
