//! `gpu:lispsm`: light-space perspective shadow maps (Wimmer, Scherzer & Purgathofer 2004)
//! on the GPU, twin of the library's `lispsm`: the same parameters, meanings and defaults.
//!
//! The warp is fitted on the CPU by the library's own fit (`LightSpacePerspective::fit`:
//! the lit receivers' light-space extent, the paper's `n_opt` or the given `n`, the
//! window); it is a handful of numbers a frame. Stage `depth` (`gpu:sm`'s `depth.wgsl`):
//! the hardware rasterizer draws the scene through the warped light view, storing the
//! linear light depth over the view's far plane. Stage `lookup` (`lookup.wgsl`): a compute
//! pass over the camera pass's samples projects each through the warp, subtracts `sm`'s
//! bias in texels of the warped map at the receiver, and compares (nearest texel, or PCF
//! with hardware 2×2 comparisons). Spot and point lights take the CPU's fallback, `sm`'s
//! map (here `gpu:sm`'s, or `gpu:pcf`'s with a kernel), counted as `single_map_fallback`.
//!
//! Departures from the CPU twin: `gpu:sm`'s (the hardware rasterizer's rounding, depths
//! stored over the far plane, the adapter's bilinear weight precision under PCF), and the
//! texel size at the receiver evaluated in f32 where the CPU uses f64.

use super::maps::{self, depth_scale, MapScene};
use super::shadow_map::{Fallback, GpuShadowMap};
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{Stage, LIGHT, MAP_COMPARE, MAP_PIXELS, RAY_OFFSET};
use crate::transfer::{uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::Light;
use shadowlab::techniques::lispsm::LightSpacePerspective;
use shadowlab::techniques::shadow_map::{check_light_map_size, check_resolution, pcf_slope_bias};
use shadowlab::techniques::{Frame, Stats};

/// `gpu:lispsm`'s name.
pub const NAME: &str = "gpu:lispsm";

const LOOKUP: Stage = Stage {
    name: "lispsm/lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT, MAP_COMPARE, MAP_PIXELS],
    source: include_str!("lookup.wgsl"),
};

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    depth_scale: f32,
    eye_y: f32,
    texel_x: f32,
    texel_y: f32,
    pad: [u32; 2],
}

/// Light-space perspective shadow maps on the GPU; the CPU `lispsm`'s parameters.
#[derive(Default)]
pub struct GpuLispsm {
    cpu: LightSpacePerspective,
    scene: Option<MapScene>,
    /// The last frame's map, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

resident::device_twin!(GpuLispsm, NAME);

impl ShadowTerm for GpuLispsm {
    /// The light's fit reads every visible point on the CPU.
    fn cpu_samples(&self) -> bool {
        true
    }

    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let res = check_resolution(NAME, self.cpu.resolution)?;
        let Light::Directional { to_light } = *frame.light else {
            let c = &self.cpu;
            return GpuShadowMap::fallback(
                frame,
                view,
                stats,
                (&mut self.scene, &mut self.last_maps),
                &Fallback {
                    kernel: c.kernel,
                    resolution: c.resolution,
                    bias: c.bias,
                    slope_bias: c.slope_bias,
                    counter: "single_map_fallback",
                },
            );
        };
        check_light_map_size(NAME, 1, res)?;
        let Some((basis, warp, light_view)) = stats.stage("fit", || self.cpu.fit(frame, to_light))
        else {
            return maps::unreached(frame);
        };
        let cpu = self.cpu.clone();
        let ms = MapScene::keep(&mut self.scene, NAME, frame, stats)?;
        let gpu = ms.gpu.clone();
        let texture = maps::depth_array(&gpu, NAME, &format!("{NAME}.resolution"), res, 1)?;
        let mut timer = Timer::new(&gpu, 2);
        stats.stage("shadow_map", || {
            gpu.stage(NAME, "shadow_map", || {
                maps::draw_views(
                    ms,
                    &texture,
                    std::slice::from_ref(&light_view),
                    frame,
                    &mut timer,
                )
            })
        })?;
        let (count, row, _) = maps::lookup_grid(&gpu, view);
        let d = (warp.y.1 - warp.y.0).max(1e-12);
        let k = 2.0 * (warp.n + d) / d;
        let slope = pcf_slope_bias(cpu.slope_bias, cpu.kernel);
        let params = Params {
            clip_from_world: light_view.clip_from_world.to_cols_array(),
            light_from_world: basis.to_cols_array(),
            light: LightU::of(frame.light),
            count,
            row,
            res,
            kernel: cpu.kernel,
            bias: cpu.bias,
            slope_bias: slope,
            depth_scale: depth_scale(&light_view),
            eye_y: warp.ey as f32,
            texel_x: ((warp.x_window.1 - warp.x_window.0) / f64::from(res)) as f32,
            texel_y: (2.0 / (k * warp.n * f64::from(res))) as f32,
            pad: [0; 2],
        };
        let params = uniform(&gpu, "look-up parameters", &params);
        let sampler = maps::comparison_sampler(&gpu);
        let array = maps::array_view(&texture);
        let value = maps::look_up(
            ms,
            NAME,
            &LOOKUP,
            &[
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&array),
                wgpu::BindingResource::Sampler(&sampler),
            ],
            view,
            &mut timer,
            stats,
        )?;
        maps::count_maps(stats, &texture);
        stats.count("n", warp.n);
        self.last_maps = Some(texture);
        Ok(value)
    }

    fn last_maps(&self) -> Option<&wgpu::Texture> {
        self.last_maps.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<Params>(), 224);
    }
}
