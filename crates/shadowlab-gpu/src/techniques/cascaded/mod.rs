//! `gpu:cascaded`: cascaded shadow maps (Engel 2006; Dimitrov 2007; Zhang et al.'s
//! parallel splits) on the GPU, twin of the library's `cascaded`: the same parameters,
//! meanings and defaults (practical splits, SDSM depth bounds, stabilized texel-snapped
//! windows, blend band, PCF).
//!
//! Stage `depth_bounds` (`depth_bounds.wgsl`, with `depth-bounds=sdsm`, the default): the
//! nearest and farthest view depth of the lit receivers are reduced on the GPU from the
//! uploaded camera-pass samples (a workgroup reduction, then integer atomics on
//! order-preserving keys: exact and order-independent) and read back: eight bytes. The
//! splits and each cascade's stabilized window are then fitted on the CPU by the library's
//! own functions (`Cascaded::views`, `sdsm_interval`): a few numbers per cascade. Stage
//! `depth` (`gpu:sm`'s `depth.wgsl`): the hardware rasterizer draws every cascade into one
//! layer of one depth array texture. Stage `lookup` (`lookup.wgsl`): a compute pass picks
//! each receiver's cascade by its view depth, reads it with PCF (hardware 2×2
//! comparisons) and blends into the next cascade across the band.
//!
//! Departures from the CPU twin: `gpu:sm`'s (the hardware rasterizer's rounding, depths
//! stored over the far plane, the adapter's bilinear weight precision under PCF); and the
//! SDSM bounds: the GPU computes each view depth `(p − eye)·forward` with the same
//! operations as the CPU, but a shader compiler may fuse its multiply-adds, so a bound
//! can differ from the CPU's in the last bit or two of the float (a relative 1e-7 of the
//! depth), which moves the split planes by as much; the min and max themselves are exact.
//! Spot and point lights take the CPU's fallback, one map (`gpu:sm`'s, or `gpu:pcf`'s with
//! a kernel), counted as `single_map_fallback`.

use super::maps::{self, depth_scale, MapScene};
use super::shadow_map::{Fallback, GpuShadowMap};
use crate::compute::{bind, pipeline};
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{float_of_key, Stage, LIGHT, MAP_COMPARE, MAP_PIXELS, ORDER_KEY, RAY_OFFSET};
use crate::transfer::{read_back, storage, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::{Light, LightView};
use shadowlab::techniques::cascaded::{sdsm_interval, Cascaded, DepthBounds};
use shadowlab::techniques::shadow_map::{check_light_map_size, check_resolution, pcf_slope_bias};
use shadowlab::techniques::{Frame, Stats};
use wgpu::util::DeviceExt;

/// `gpu:cascaded`'s name.
pub const NAME: &str = "gpu:cascaded";

const DEPTH_BOUNDS: Stage = Stage {
    name: "cascaded/depth_bounds.wgsl",
    common: &[RAY_OFFSET, LIGHT, ORDER_KEY],
    source: include_str!("depth_bounds.wgsl"),
};

const LOOKUP: Stage = Stage {
    name: "cascaded/lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT, MAP_COMPARE, MAP_PIXELS],
    source: include_str!("lookup.wgsl"),
};

/// `Params` of `depth_bounds.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct BoundsParams {
    light: LightU,
    eye: [f32; 4],
    forward: [f32; 4],
    count: u32,
    row: u32,
    pad: [u32; 2],
}

/// `CascadeU` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CascadeU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    ortho: u32,
    near: f32,
    extent: f32,
    depth_scale: f32,
    d0: f32,
    d1: f32,
    pad: [u32; 2],
}

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LookupParams {
    light: LightU,
    eye: [f32; 4],
    forward: [f32; 4],
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    blend: f32,
    cascades: u32,
}

/// The keys `depth_bounds.wgsl` starts from: +∞ for the minimum, −∞ for the maximum.
const EMPTY_KEYS: [u32; 2] = [0xff80_0000, 0x007f_ffff];

/// Cascaded shadow maps on the GPU; the CPU `cascaded`'s parameters.
#[derive(Default)]
pub struct GpuCascaded {
    cpu: Cascaded,
    scene: Option<MapScene>,
    /// The last frame's cascades, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

/// The camera's eye and forward axis as the shaders read them.
fn eye_forward(frame: &Frame) -> ([f32; 4], [f32; 4]) {
    let cam = frame.camera;
    (
        cam.eye.extend(0.0).to_array(),
        cam.forward().extend(0.0).to_array(),
    )
}

/// The view depth interval of the cascades: the camera's, or SDSM's from the lit
/// receivers' depth bounds reduced on the GPU.
fn depth_interval(
    ms: &MapScene,
    cpu: &Cascaded,
    frame: &Frame,
    view: &DeviceView,
    timer: &mut Timer,
    stats: &mut Stats,
) -> Result<(f32, f32)> {
    let cam = frame.camera;
    if cpu.depth_bounds == DepthBounds::Camera {
        return Ok((cam.near, cam.far));
    }
    let gpu = &ms.gpu;
    let (count, row, (gx, gy)) = maps::lookup_grid(gpu, view);
    let (eye, forward) = eye_forward(frame);
    let params = BoundsParams {
        light: LightU::of(frame.light),
        eye,
        forward,
        count,
        row,
        pad: [0; 2],
    };
    let params = uniform(gpu, "depth-bounds parameters", &params);
    let bounds = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("the depth bounds"),
            contents: bytemuck::cast_slice(&EMPTY_KEYS),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let reduce = gpu.stage(NAME, "pipeline", || pipeline(gpu, &DEPTH_BOUNDS, "main"))?;
    let group = bind(&gpu.device, &reduce, &[&params, &view.samples, &bounds]);
    let raw = stats.stage("depth_bounds", || {
        gpu.stage(NAME, "depth_bounds", || {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("depth_bounds"),
                    timestamp_writes: timer.pass("depth_bounds"),
                });
                pass.set_pipeline(&reduce);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([encoder.finish()]);
            read_back(gpu, &bounds, 8)
        })
    })??;
    let key = |i: usize| u32::from_le_bytes([raw[i], raw[i + 1], raw[i + 2], raw[i + 3]]);
    let (lo, hi) = (float_of_key(key(0)), float_of_key(key(4)));
    stats.count("sdsm_near", f64::from(lo));
    stats.count("sdsm_far", f64::from(hi));
    Ok(sdsm_interval(frame, (lo, hi)))
}

resident::device_twin!(GpuCascaded, NAME);

impl ShadowTerm for GpuCascaded {
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let cpu = self.cpu.clone();
        check_resolution(NAME, cpu.resolution)?;
        let Light::Directional { to_light } = *frame.light else {
            return GpuShadowMap::fallback(
                frame,
                view,
                stats,
                (&mut self.scene, &mut self.last_maps),
                &Fallback {
                    kernel: cpu.kernel,
                    resolution: cpu.resolution,
                    bias: cpu.bias,
                    slope_bias: cpu.slope_bias,
                    counter: "single_map_fallback",
                },
            );
        };
        let res = check_resolution(NAME, cpu.resolved_cascade_resolution())?;
        check_light_map_size(NAME, cpu.cascades, res)?;
        let ms = MapScene::keep(&mut self.scene, NAME, frame, stats)?;
        let gpu = ms.gpu.clone();
        let layers = cpu.cascades as u32;
        let texture = maps::depth_array(&gpu, NAME, &format!("{NAME}.resolution"), res, layers)?;
        let mut timer = Timer::new(&gpu, layers + 2);
        let interval = depth_interval(ms, &cpu, frame, view, &mut timer, stats)?;
        let views = cpu.views(frame, to_light, interval, stats);
        let lights: Vec<LightView> = views.iter().map(|v| v.2).collect();
        stats.stage("shadow_map", || {
            gpu.stage(NAME, "shadow_map", || {
                maps::draw_views(ms, &texture, &lights, frame, &mut timer)
            })
        })?;
        let table: Vec<CascadeU> = views
            .iter()
            .map(|(d0, d1, v)| CascadeU {
                clip_from_world: v.clip_from_world.to_cols_array(),
                light_from_world: v.light_from_world.to_cols_array(),
                ortho: u32::from(v.orthographic),
                near: v.near,
                extent: v.extent,
                depth_scale: depth_scale(v),
                d0: *d0,
                d1: *d1,
                pad: [0; 2],
            })
            .collect();
        let table = storage(&gpu, "the cascades", bytemuck::cast_slice(&table))?;
        let (count, row, _) = maps::lookup_grid(&gpu, view);
        let (eye, forward) = eye_forward(frame);
        let slope = pcf_slope_bias(cpu.slope_bias, cpu.kernel);
        let params = LookupParams {
            light: LightU::of(frame.light),
            eye,
            forward,
            count,
            row,
            res,
            kernel: cpu.kernel,
            bias: cpu.bias,
            slope_bias: slope,
            blend: cpu.blend,
            cascades: layers,
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
                table.as_entire_binding(),
                wgpu::BindingResource::TextureView(&array),
                wgpu::BindingResource::Sampler(&sampler),
            ],
            view,
            &mut timer,
            stats,
        )?;
        maps::count_maps(stats, &texture);
        stats.count("cascades", f64::from(layers));
        stats.count("cascade_resolution", f64::from(res));
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
        assert_eq!(std::mem::size_of::<BoundsParams>(), 96);
        assert_eq!(std::mem::size_of::<CascadeU>(), 160);
        assert_eq!(std::mem::size_of::<LookupParams>(), 112);
    }

    #[test]
    fn the_empty_keys_are_the_infinities() {
        assert_eq!(float_of_key(EMPTY_KEYS[0]), f32::INFINITY);
        assert_eq!(float_of_key(EMPTY_KEYS[1]), f32::NEG_INFINITY);
    }
}
