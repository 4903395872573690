//! `gpu:sm` and `gpu:pcf`: the standard shadow map (Williams 1978) and percentage-closer
//! filtering (Reeves et al. 1987) on the GPU, twins of the library's `sm` and `pcf`.
//!
//! Stage `depth` (`depth.wgsl`): the hardware rasterizer draws the scene into a depth map
//! per light view (one for directional and spot lights, six cube faces for a point light:
//! the layers of one array texture), over the CPU's own light views (the library's
//! `light_views`, fitted to the same receivers). Each fragment writes the library's linear
//! depth over the view's far plane, so the hardware depth test keeps the nearest caster
//! and the look-up compares linear depths; alpha-masked casters are discarded where cut.
//! Stage `lookup` (`lookup.wgsl`): a compute pass over the camera pass's samples applies
//! the CPU's bias (constant plus slope-scaled, in texels at the receiver; PCF's slope term
//! scaled by its reach) and compares: `gpu:sm` with the nearest texel, `gpu:pcf` with
//! `kernel × kernel` hardware bilinear 2×2 comparisons through a comparison sampler.
//!
//! Departures from the CPU twin: the hardware rasterizer's coverage and depth
//! interpolation differ from the library's rasterizer by rounding (its fill rule is the
//! same top-left rule), depths are stored divided by the far plane (a monotonic rounding),
//! and the hardware's bilinear weights have the adapter's sub-texel precision (8 bits on
//! many GPUs) where the CPU's are exact: so the two differ on a few edge pixels, which
//! the verdict tests bound. The map is drawn by the hardware rasterizer on every adapter
//! (`counters.hardware_raster = 1`); a compute rasterizer is not offered yet.

use crate::compute::{bind_entries, pipeline, render_pipeline, to_rgb};
use crate::device::{shared, Gpu};
use crate::resident::{DeviceShadows, OnDevice};
use crate::shader::{Stage, ALPHA_MASK, LIGHT, RAY_OFFSET, TRIANGLES};
use crate::transfer::{grid, output, read_back, storage, uniform, Timer};
use crate::upload::{view_buffer, LightU, SceneBuffers, SceneKey};
use bytemuck::{Pod, Zeroable};
use shadowlab::error::{Error, Result};
use shadowlab::light::{light_views, LightView};
use shadowlab::techniques::shadow_map::{check_resolution, ShadowMap, DIRECTIONAL_PAD};
use shadowlab::techniques::{Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use std::collections::BTreeMap;
use std::sync::Arc;

/// `gpu:sm`'s name.
pub const SM: &str = "gpu:sm";
/// `gpu:pcf`'s name.
pub const PCF: &str = "gpu:pcf";

const DEPTH: Stage = Stage {
    name: "depth.wgsl",
    common: &[ALPHA_MASK, TRIANGLES],
    source: include_str!("depth.wgsl"),
};

const LOOKUP: Stage = Stage {
    name: "lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT],
    source: include_str!("lookup.wgsl"),
};

const WORKGROUP: u32 = 64;

/// `FaceU` of `depth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct FaceU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    depth_scale: f32,
    masks: u32,
    pad: [u32; 2],
}

/// `ViewU` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ViewU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    ortho: u32,
    near: f32,
    extent: f32,
    depth_scale: f32,
}

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LookupParams {
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    pad: [u32; 2],
}

/// The depth a view's linear depths are divided by before they are stored: its far plane.
fn depth_scale(v: &LightView) -> f32 {
    if v.far.is_finite() && v.far > 0.0 {
        v.far
    } else {
        1.0
    }
}

/// The scene on one device, with the pipelines.
struct Resident {
    key: SceneKey,
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    depth: wgpu::RenderPipeline,
    lookup: wgpu::ComputePipeline,
    sampler: wgpu::Sampler,
}

/// A shadow map drawn by the hardware rasterizer; the CPU `sm`'s or `pcf`'s parameters.
pub struct GpuShadowMap {
    name: &'static str,
    cpu: ShadowMap,
    resident: Option<Resident>,
    /// The last frame's maps, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

impl GpuShadowMap {
    /// `gpu:sm`.
    pub fn standard() -> Self {
        GpuShadowMap {
            name: SM,
            cpu: ShadowMap::standard(),
            resident: None,
            last_maps: None,
        }
    }

    /// `gpu:pcf`.
    pub fn pcf() -> Self {
        GpuShadowMap {
            name: PCF,
            cpu: ShadowMap::pcf(),
            resident: None,
            last_maps: None,
        }
    }

    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&mut Resident> {
        let key = SceneKey::of(frame.scene);
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            self.resident = None;
            let gpu = shared()?;
            let name = self.name;
            let scene = stats.stage("upload_scene", || {
                gpu.stage(name, "upload_scene", || {
                    SceneBuffers::new(&gpu, frame.scene)
                })
            })??;
            let (depth, lookup, sampler) = gpu.stage(name, "pipeline", || {
                (
                    render_pipeline(&gpu, "depth", depth_pipeline),
                    pipeline(&gpu, &LOOKUP, "main"),
                    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                        label: Some("shadow comparison"),
                        mag_filter: wgpu::FilterMode::Linear,
                        min_filter: wgpu::FilterMode::Linear,
                        compare: Some(wgpu::CompareFunction::LessEqual),
                        ..Default::default()
                    }),
                )
            })?;
            self.resident = Some(Resident {
                key,
                gpu,
                scene,
                depth,
                lookup,
                sampler,
            });
        }
        self.resident
            .as_mut()
            .ok_or_else(|| Error::Internal(format!("{}: the scene was not uploaded", self.name)))
    }
}

/// The depth stage's render pipeline: no colour target, a 32-bit float depth written by
/// the fragment, the nearest kept (`Less`), both faces drawn.
fn depth_pipeline(device: &wgpu::Device) -> wgpu::RenderPipeline {
    DEPTH.depth_tested_pipeline(device, &[])
}

impl ShadowTechnique for GpuShadowMap {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        self.cpu.params()
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        self.cpu.param_specs()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        crate::twin::set_twin_param(self.name, &mut self.cpu, key, value)
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let gpu = shared()?;
        let n = frame.view.triangle.len() as u64;
        let mut stats = Stats::default();
        let view = stats.stage("upload_view", || view_buffer(&gpu, frame.view))?;
        let out = self.shadow_term(frame, &view, &mut stats)?;
        let raw = stats.stage("readback", || {
            gpu.stage(self.name, "readback", || read_back(&gpu, &out, n * 12))
        })??;
        Ok(Shadows::of_frame(frame, to_rgb(&raw), stats))
    }
}

impl OnDevice for GpuShadowMap {
    fn render_on_device(&mut self, frame: &Frame, view: &wgpu::Buffer) -> Result<DeviceShadows> {
        let mut stats = Stats::default();
        let visibility = self.shadow_term(frame, view, &mut stats)?;
        Ok(DeviceShadows { visibility, stats })
    }

    fn depth_maps(&self) -> Option<&wgpu::Texture> {
        self.last_maps.as_ref()
    }
}

impl GpuShadowMap {
    /// The maps and the look-up over the uploaded `view`: the shadow terms on the device.
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &wgpu::Buffer,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let name = self.name;
        let res_side = check_resolution(name, self.cpu.resolution)?;
        let cpu = self.cpu.clone();
        let res = self.resident(frame, stats)?;
        let gpu = res.gpu.clone();
        gpu.check_texture_side(&format!("{name}.resolution"), res_side)?;
        let views = light_views(
            frame.light,
            &frame.view.receiver_bounds(),
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        let layers = views.len() as u32;
        if layers > gpu.limits.max_texture_array_layers {
            return Err(Error::Limit(format!(
                "{name}: {layers} light views need more array layers than the adapter's {}",
                gpu.limits.max_texture_array_layers
            )));
        }
        let n = frame.view.triangle.len() as u32;
        let out = output(&gpu, "the shadow terms", u64::from(n) * 12)?;
        let mut timer = Timer::new(&gpu, 8);
        let map = stats.stage("shadow_map", || {
            gpu.stage(name, "shadow_map", || {
                draw_maps(res, frame, &views, res_side, &mut timer)
            })
        })??;
        stats.stage("lookup", || {
            gpu.stage(name, "lookup", || {
                lookup(res, frame, &cpu, &views, &map, view, &out, &mut timer)
            })
        })??;
        for (stage, ms) in timer.read(&gpu)? {
            stats.count(&format!("gpu_{stage}_ms"), ms);
        }
        self.last_maps = Some(map);
        stats.memory_bytes = u64::from(res_side).pow(2) * u64::from(layers) * 4;
        stats.count(
            "map_texels",
            f64::from(res_side).powi(2) * f64::from(layers),
        );
        stats.count("hardware_raster", 1.0);
        stats.device = Some(gpu.adapter.label());
        Ok(out)
    }
}

/// Draws every light view's depth map into one layer of a new array texture.
fn draw_maps(
    res: &Resident,
    frame: &Frame,
    views: &[LightView],
    side: u32,
    timer: &mut Timer,
) -> Result<wgpu::Texture> {
    let gpu = &res.gpu;
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadow map"),
        size: wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: views.len() as u32,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let s = &res.scene;
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (i, v) in views.iter().enumerate() {
        let face = FaceU {
            clip_from_world: v.clip_from_world.to_cols_array(),
            light_from_world: v.light_from_world.to_cols_array(),
            depth_scale: depth_scale(v),
            masks: u32::from(s.masks),
            pad: [0; 2],
        };
        let face = uniform(gpu, "light view", &face);
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &res.depth.get_bind_group_layout(0),
            entries: &bind_entries(&[
                &face,
                &s.triangles,
                &s.material_of,
                &s.materials,
                &s.uvs,
                &s.texels,
            ]),
        });
        let layer = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: i as u32,
            array_layer_count: Some(1),
            ..Default::default()
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &layer,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render_pass("shadow_map"),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&res.depth);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..frame.scene.len() as u32 * 3, 0..1);
        }
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(texture)
}

/// Records and submits the look-up over every pixel.
#[allow(clippy::too_many_arguments)]
fn lookup(
    res: &Resident,
    frame: &Frame,
    cpu: &ShadowMap,
    views: &[LightView],
    map: &wgpu::Texture,
    view: &wgpu::Buffer,
    out: &wgpu::Buffer,
    timer: &mut Timer,
) -> Result<()> {
    let gpu = &res.gpu;
    let n = frame.view.triangle.len() as u32;
    let (gx, gy, row) = grid(gpu, n, WORKGROUP);
    // PCF compares at texels up to kernel/2 + 1 away: the CPU scales its slope term so.
    let slope = if cpu.kernel > 0 {
        cpu.slope_bias * (cpu.kernel / 2 + 1) as f32
    } else {
        cpu.slope_bias
    };
    let params = LookupParams {
        light: LightU::of(frame.light),
        count: n,
        row,
        res: cpu.resolution,
        kernel: cpu.kernel,
        bias: cpu.bias,
        slope_bias: slope,
        pad: [0; 2],
    };
    let params = uniform(gpu, "look-up parameters", &params);
    let table: Vec<ViewU> = views
        .iter()
        .map(|v| ViewU {
            clip_from_world: v.clip_from_world.to_cols_array(),
            light_from_world: v.light_from_world.to_cols_array(),
            ortho: u32::from(v.orthographic),
            near: v.near,
            extent: v.extent,
            depth_scale: depth_scale(v),
        })
        .collect();
    let table = storage(gpu, "the light views", bytemuck::cast_slice(&table))?;
    let map_view = map.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.lookup.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: table.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: view.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(&map_view),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(&res.sampler),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("lookup"),
            timestamp_writes: timer.pass("lookup"),
        });
        pass.set_pipeline(&res.lookup);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<FaceU>(), 144);
        assert_eq!(std::mem::size_of::<ViewU>(), 144);
        assert_eq!(std::mem::size_of::<LookupParams>(), 80);
    }
}
