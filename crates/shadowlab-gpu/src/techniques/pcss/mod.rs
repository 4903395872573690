//! `gpu:pcss`: percentage-closer soft shadows (Fernando 2005) on the GPU, twin of the
//! library's `pcss`, with its parameters, meanings and defaults, under every light the
//! library supports: punctual lights, and area lights through their stand-in's views
//! with the light's width taken from the area light (`light-size` 0) as the CPU takes it.
//!
//! Stage `shadow_map`: `gpu:sm`'s depth stage (`shadow_map/depth.wgsl`, the hardware
//! rasterizer over the library's light views), drawn by the same function. Stage
//! `min_pyramid` (`min_pyramid.wgsl`): the library's min-depth pyramid of each map,
//! reduced a level a pass. Stage `blocker_search` (`blocker_search.wgsl`): the paper's
//! blocker search and penumbra estimation, the library's `BlockerSearch` (the search
//! region bounded twice through the pyramid, a regular grid of taps, similar triangles);
//! a receiver with no blocker is lit there. Stage `filter` (`filter.wgsl`): variable-
//! kernel PCF over the estimated penumbra with the slope bias grown with the kernel.
//! Both read `receiver.wgsl`, the receiver as the CPU's `pcss` sees it.
//!
//! Departures from the CPU twin: the map is `gpu:sm`'s (hardware rasterization, depths
//! stored over the far plane, an empty texel holding the far plane where the CPU holds
//! infinity, which no receiver's depth exceeds), the blocker depths are averaged in
//! `f32` where the CPU sums in `f64`, and each filter tap's 2×2 comparison is weighted by
//! the hardware's bilinear filtering (a comparison sampler, as the paper's sample and
//! `gpu:pcf` use) with the adapter's sub-texel precision where the CPU's weights are
//! exact. So a few pixels differ slightly; the verdict tests bound the difference.

mod min_pyramid;

use super::maps::{self, MapScene};
use crate::compute::pipeline;
use crate::device::Gpu;
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{Common, Stage, LIGHT, RAY_OFFSET};
use crate::transfer::{output, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::light_views;
use shadowlab::techniques::filtering::blocker_search::grid_side;
use shadowlab::techniques::pcss::{light_width, Pcss};
use shadowlab::techniques::shadow_map::{check_resolution, DIRECTIONAL_PAD};
use shadowlab::techniques::{Frame, Stats};

/// `gpu:pcss`'s name.
pub const NAME: &str = "gpu:pcss";

/// `pcss/receiver.wgsl`: the parameters, views and map both look-up stages read, and a
/// receiver as the library's `pcss` sees it.
const RECEIVER: Common = Common {
    name: "pcss/receiver.wgsl",
    source: include_str!("receiver.wgsl"),
};

const BLOCKER_SEARCH: Stage = Stage {
    name: "pcss/blocker_search.wgsl",
    common: &[RAY_OFFSET, LIGHT, RECEIVER],
    source: include_str!("blocker_search.wgsl"),
};

const FILTER: Stage = Stage {
    name: "pcss/filter.wgsl",
    common: &[RAY_OFFSET, LIGHT, RECEIVER],
    source: include_str!("filter.wgsl"),
};

/// `Params` of `receiver.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    search_side: u32,
    filter_side: u32,
    bias: f32,
    slope_bias: f32,
    width: f32,
    levels: u32,
    layer_stride: u32,
    pad: [u32; 2],
}

/// Percentage-closer soft shadows on the GPU; the CPU `pcss`'s parameters.
#[derive(Default)]
pub struct GpuPcss {
    cpu: Pcss,
    scene: Option<MapScene>,
    /// The last frame's maps, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

resident::device_twin!(GpuPcss, NAME);

impl ShadowTerm for GpuPcss {
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let side = check_resolution(NAME, self.cpu.resolution)?;
        let cpu = self.cpu.clone();
        let ms = MapScene::keep(&mut self.scene, NAME, frame, stats)?;
        let gpu = ms.gpu.clone();
        let views = light_views(
            frame.light,
            &view.receivers,
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        let layers = views.len() as u32;
        let map = maps::depth_array(&gpu, NAME, &format!("{NAME}.resolution"), side, layers)?;
        let (search_pipe, filter_pipe) = gpu.stage(NAME, "pipeline", || {
            (
                pipeline(&gpu, &BLOCKER_SEARCH, "main"),
                pipeline(&gpu, &FILTER, "main"),
            )
        })?;
        let sampler = maps::comparison_sampler(&gpu);
        let (n, row, (gx, gy)) = maps::lookup_grid(&gpu, view);
        let out = output(&gpu, "the shadow terms", u64::from(n) * 12)?;
        let radii = output(&gpu, "the penumbra radii", u64::from(n) * 4)?;
        let mut timer = Timer::new(&gpu, 32);
        stats.stage("shadow_map", || {
            gpu.stage(NAME, "shadow_map", || {
                maps::draw_views(ms, &map, &views, frame, &mut timer)
            })
        })?;
        let pyramid = stats.stage("min_pyramid", || {
            gpu.stage(NAME, "min_pyramid", || {
                min_pyramid::build(&gpu, &map, side, layers, &mut timer)
            })
        })??;
        let params = Params {
            light: LightU::of(frame.light),
            count: n,
            row,
            res: side,
            search_side: grid_side(cpu.blocker_samples),
            filter_side: grid_side(cpu.filter_samples),
            bias: cpu.bias,
            slope_bias: cpu.slope_bias,
            width: light_width(cpu.light_size, frame),
            levels: pyramid.count,
            layer_stride: pyramid.layer_stride,
            pad: [0; 2],
        };
        let params = uniform(&gpu, "pcss parameters", &params);
        let table = maps::view_table(&gpu, &views)?;
        let map_view = maps::array_view(&map);
        let shared = [
            params.as_entire_binding(),
            table.as_entire_binding(),
            view.samples.as_entire_binding(),
            wgpu::BindingResource::TextureView(&map_view),
        ];
        let search = [
            pyramid.table.as_entire_binding(),
            pyramid.buffer.as_entire_binding(),
            radii.as_entire_binding(),
            out.as_entire_binding(),
        ];
        let filter = [
            wgpu::BindingResource::Sampler(&sampler),
            radii.as_entire_binding(),
            out.as_entire_binding(),
        ];
        for (stage, pipe, own) in [
            ("blocker_search", &search_pipe, &search[..]),
            ("filter", &filter_pipe, &filter[..]),
        ] {
            stats.stage(stage, || {
                gpu.stage(NAME, stage, || {
                    dispatch(&gpu, pipe, &shared, own, (gx, gy), stage, &mut timer)
                })
            })?;
        }
        for (stage, ms) in timer.read(&gpu)? {
            stats.count(&format!("gpu_{stage}_ms"), ms);
        }
        maps::count_maps(stats, &map);
        stats.memory_bytes += pyramid.bytes(layers);
        stats.count("hardware_raster", 1.0);
        stats.device = Some(gpu.adapter.label());
        self.last_maps = Some(map);
        Ok(out)
    }

    fn last_maps(&self) -> Option<&wgpu::Texture> {
        self.last_maps.as_ref()
    }
}

/// Records and submits one look-up stage over every pixel: the `shared` bindings at 0, 1,
/// …, then the stage's `own` after them.
fn dispatch(
    gpu: &Gpu,
    pipe: &wgpu::ComputePipeline,
    shared: &[wgpu::BindingResource],
    own: &[wgpu::BindingResource],
    (gx, gy): (u32, u32),
    stage: &str,
    timer: &mut Timer,
) {
    let entries: Vec<wgpu::BindGroupEntry> = shared
        .iter()
        .chain(own)
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect();
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipe.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(stage),
            timestamp_writes: timer.pass(stage),
        });
        pass.set_pipeline(pipe);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<Params>(), 96);
    }
}
