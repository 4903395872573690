//! `raytrace`: the ray-traced reference as a technique, so its cost sits in the same
//! tables as the others. See [`crate::reference`] for how rays are traced. The layers
//! behind semi-transparent surfaces ([`Frame::layers`]) get one shadow ray each. Under an
//! area light ([`Frame::area`]) it is the soft-shadow reference of
//! [`crate::soft_reference`], with the frame's light samples per pixel.

use super::{find_param, Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use crate::error::Result;
use crate::reference::Reference;
use crate::sampling::{pattern, PatternKind};
use std::collections::BTreeMap;

/// Shadow rays from every visible sample (or from `spp` re-traced primary rays per pixel).
#[derive(Clone, Debug)]
pub struct RayTrace {
    /// Primary rays per pixel; 1 traces from the camera pass's samples.
    pub spp: u32,
}

impl Default for RayTrace {
    fn default() -> Self {
        RayTrace { spp: 1 }
    }
}

/// Shadow rays a pixel costs: `spp`, or under an area light the larger of `spp` and the
/// light samples (see [`crate::soft_reference`]).
fn rays_per_pixel(frame: &Frame, spp: u32) -> f64 {
    match frame.area {
        Some(_) => spp.max(frame.light_samples) as f64,
        None => spp as f64,
    }
}

impl ShadowTechnique for RayTrace {
    fn name(&self) -> &'static str {
        "raytrace"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([("spp".to_string(), self.spp.into())])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::int(
            "spp",
            1,
            1024,
            "primary rays per pixel on a regular grid; 1 traces from the camera pass's samples",
        )]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let spec = find_param("raytrace", &self.param_specs(), key)?;
        if key == "spp" {
            self.spp = spec.u32("raytrace", value)?;
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let mut stats = Stats::default();
        let reference = stats.stage("bvh_build", || Reference::build(frame.scene));
        let samples = pattern(PatternKind::Grid, self.spp)?;
        let visibility = stats.stage("trace", || match frame.area {
            Some(area) => {
                crate::soft_reference::soft_visibility(
                    &reference,
                    frame,
                    area,
                    frame.light_samples,
                    &samples,
                )
                .visibility
            }
            None => reference.visibility(frame, &samples),
        });
        stats.memory_bytes = reference.memory_bytes() as u64;
        let layers = frame
            .layers
            .map(|l| stats.stage("layers", || reference.layer_visibility(frame, l)));
        let layer_rays = frame.layers.map_or(0, |l| l.len());
        stats.count(
            "rays",
            frame.view.covered_count() as f64 * rays_per_pixel(frame, self.spp) + layer_rays as f64,
        );
        Ok(Shadows {
            layers,
            ..Shadows::new(visibility, stats)
        })
    }
}
