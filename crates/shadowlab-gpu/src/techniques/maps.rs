//! What the warped and split shadow maps (`gpu:psm`, `gpu:lispsm`, `gpu:cascaded`) share:
//! the scene kept on the device, depth array textures whose layers the hardware
//! rasterizer fills (through `gpu:sm`'s `depth.wgsl` for light views, or a technique's own
//! depth stage), the comparison sampler of PCF, and the look-up's dispatch over the camera
//! pass's samples with its shadow terms read back and its times counted.

use crate::compute::{pipeline, render_pipeline};
use crate::device::{shared, Gpu};
use crate::resident::DeviceView;
use crate::shader::{Stage, ALPHA_MASK, LIGHT_DEPTH, TRIANGLES};
use crate::transfer::{grid, output, storage, uniform, Timer};
use crate::upload::{SceneBuffers, SceneKey};
use bytemuck::{Pod, Zeroable};
use shadowlab::error::{Error, Result};
use shadowlab::light::LightView;
use shadowlab::math::Vec3;
use shadowlab::techniques::{Frame, Stats};
use std::sync::Arc;

/// `gpu:sm`'s depth stage (`shadow_map/depth.wgsl`), which the warped and split maps draw
/// their light views through too.
pub(crate) const DEPTH: Stage = Stage {
    name: "shadow_map/depth.wgsl",
    common: &[ALPHA_MASK, TRIANGLES, LIGHT_DEPTH],
    source: include_str!("shadow_map/depth.wgsl"),
};

/// `FaceU` of `shadow_map/depth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct FaceU {
    pub(crate) clip_from_world: [f32; 16],
    pub(crate) light_from_world: [f32; 16],
    pub(crate) depth_scale: f32,
    pub(crate) masks: u32,
    pub(crate) pad: [u32; 2],
}

/// The depth a view's linear depths are divided by before they are stored: its far plane.
pub(crate) fn depth_scale(v: &LightView) -> f32 {
    if v.far.is_finite() && v.far > 0.0 {
        v.far
    } else {
        1.0
    }
}

/// `ViewU` of the look-ups (`shadow_map/lookup.wgsl`, `pcss/receiver.wgsl`): a light view
/// as the look-up projects a receiver into it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct ViewU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    ortho: u32,
    near: f32,
    extent: f32,
    depth_scale: f32,
}

/// The light views as `ViewU`s in a storage buffer.
pub(crate) fn view_table(gpu: &Gpu, views: &[LightView]) -> Result<wgpu::Buffer> {
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
    storage(gpu, "the light views", bytemuck::cast_slice(&table))
}

/// Threads per workgroup of the look-ups.
pub(crate) const WORKGROUP: u32 = 64;

/// The scene uploaded to the shared device, kept while the scene does not change.
pub(crate) struct MapScene {
    key: SceneKey,
    /// The device.
    pub(crate) gpu: Arc<Gpu>,
    /// The scene's buffers.
    pub(crate) scene: SceneBuffers,
}

impl MapScene {
    /// The scene of `frame` uploaded to the shared device.
    pub(crate) fn upload(name: &str, frame: &Frame, stats: &mut Stats) -> Result<MapScene> {
        let key = SceneKey::of(frame.scene);
        let gpu = shared()?;
        let scene = stats.stage("upload_scene", || {
            gpu.stage(name, "upload_scene", || {
                SceneBuffers::new(&gpu, frame.scene)
            })
        })??;
        Ok(MapScene { key, gpu, scene })
    }

    /// Whether this is the scene of `frame`.
    pub(crate) fn holds(&self, frame: &Frame) -> bool {
        self.key == SceneKey::of(frame.scene)
    }

    /// The scene of `frame` on the device, uploaded into `slot` unless it is there.
    pub(crate) fn keep<'a>(
        slot: &'a mut Option<MapScene>,
        name: &str,
        frame: &Frame,
        stats: &mut Stats,
    ) -> Result<&'a MapScene> {
        if slot.as_ref().is_none_or(|r| !r.holds(frame)) {
            *slot = None;
            *slot = Some(MapScene::upload(name, frame, stats)?);
        }
        slot.as_ref()
            .ok_or_else(|| Error::Internal(format!("{name}: the scene was not uploaded")))
    }
}

/// A new depth array texture of `layers` layers of `side²` texels, checked against the
/// adapter's limits (`param` names the parameter that sets the side).
pub(crate) fn depth_array(
    gpu: &Gpu,
    name: &str,
    param: &str,
    side: u32,
    layers: u32,
) -> Result<wgpu::Texture> {
    gpu.check_texture_side(param, side)?;
    if layers > gpu.limits.max_texture_array_layers {
        return Err(Error::Limit(format!(
            "{name}: {layers} maps need more array layers than the adapter's {}",
            gpu.limits.max_texture_array_layers
        )));
    }
    Ok(gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadow maps"),
        size: wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: layers.max(1),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    }))
}

/// Counts the maps of `texture` (a [`depth_array`]) into `stats`: its bytes as the frame's
/// memory (4 a texel) and its texels as `map_texels`.
pub(crate) fn count_maps(stats: &mut Stats, texture: &wgpu::Texture) {
    let texels = u64::from(texture.width())
        * u64::from(texture.height())
        * u64::from(texture.depth_or_array_layers());
    stats.memory_bytes = texels * 4;
    stats.count("map_texels", texels as f64);
}

/// Draws the scene once per layer of `texture` with `depth` (a stage whose bindings are
/// a uniform, then the scene's triangles, materials, UVs and texels), layer `i` with the
/// uniform `faces[i]`; the passes are timed as `shadow_map`.
pub(crate) fn draw_layers(
    ms: &MapScene,
    depth: &wgpu::RenderPipeline,
    texture: &wgpu::Texture,
    faces: &[wgpu::Buffer],
    frame: &Frame,
    timer: &mut Timer,
) {
    let (gpu, s) = (&ms.gpu, &ms.scene);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (i, face) in faces.iter().enumerate() {
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &depth.get_bind_group_layout(0),
            entries: &crate::compute::bind_entries(&[
                face,
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
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow_map"),
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
        pass.set_pipeline(depth);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..frame.scene.len() as u32 * 3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
}

/// Draws each light view into one layer of `texture` with `gpu:sm`'s depth stage: linear
/// depths divided by the view's far plane.
pub(crate) fn draw_views(
    ms: &MapScene,
    texture: &wgpu::Texture,
    views: &[LightView],
    frame: &Frame,
    timer: &mut Timer,
) {
    let gpu = &ms.gpu;
    let depth = render_pipeline(gpu, &DEPTH, &[]);
    let faces: Vec<wgpu::Buffer> = views
        .iter()
        .map(|v| {
            let face = FaceU {
                clip_from_world: v.clip_from_world.to_cols_array(),
                light_from_world: v.light_from_world.to_cols_array(),
                depth_scale: depth_scale(v),
                masks: u32::from(ms.scene.masks),
                pad: [0; 2],
            };
            uniform(gpu, "light view", &face)
        })
        .collect();
    draw_layers(ms, &depth, texture, &faces, frame, timer);
}

/// The sampler of PCF's hardware 2×2 comparisons (bilinear, `LessEqual`: lit where the
/// receiver is not behind the stored depth).
pub(crate) fn comparison_sampler(gpu: &Gpu) -> wgpu::Sampler {
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadow comparison"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    })
}

/// The whole array of `texture` as the look-up samples it.
pub(crate) fn array_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// The look-up grid over the frame's pixels: `(pixels, threads per row)` for the
/// parameters, and the workgroups.
pub(crate) fn lookup_grid(gpu: &Gpu, view: &DeviceView) -> (u32, u32, (u32, u32)) {
    let n = view.pixels();
    let (gx, gy, row) = grid(gpu, n, WORKGROUP);
    (n, row, (gx, gy))
}

/// Runs `stage`'s `main` over the frame's pixels with `resources` at bindings 0, 1, …
/// (the uploaded view samples `view` and the output buffer appended last but one and
/// last), and counts the timed stages and the device: the shadow terms stay on the device.
#[allow(clippy::too_many_arguments)]
pub(crate) fn look_up(
    ms: &MapScene,
    name: &str,
    stage: &Stage,
    resources: &[wgpu::BindingResource],
    view: &DeviceView,
    timer: &mut Timer,
    stats: &mut Stats,
) -> Result<wgpu::Buffer> {
    let gpu = &ms.gpu;
    let n = view.pixels();
    let out = output(gpu, "the shadow terms", u64::from(n) * 12)?;
    let (_, _, (gx, gy)) = lookup_grid(gpu, view);
    let lookup = gpu.stage(name, "pipeline", || pipeline(gpu, stage, "main"))?;
    let mut entries: Vec<wgpu::BindGroupEntry> = resources
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect();
    let k = entries.len() as u32;
    entries.push(wgpu::BindGroupEntry {
        binding: k,
        resource: view.samples.as_entire_binding(),
    });
    entries.push(wgpu::BindGroupEntry {
        binding: k + 1,
        resource: out.as_entire_binding(),
    });
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &lookup.get_bind_group_layout(0),
        entries: &entries,
    });
    stats.stage("lookup", || {
        gpu.stage(name, "lookup", || {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("lookup"),
                    timestamp_writes: timer.pass("lookup"),
                });
                pass.set_pipeline(&lookup);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([encoder.finish()]);
        })
    })?;
    for (stage, ms) in timer.read(gpu)? {
        stats.count(&format!("gpu_{stage}_ms"), ms);
    }
    stats.count("hardware_raster", 1.0);
    stats.device = Some(gpu.adapter.label());
    Ok(out)
}

/// The shadow terms of a frame whose light reaches no receiver, on the device: dark where
/// a surface is shown, lit where none is.
pub(crate) fn unreached(frame: &Frame) -> Result<wgpu::Buffer> {
    let view = frame.view;
    let terms: Vec<Vec3> = (0..view.triangle.len())
        .map(|k| {
            if view.covered(k) {
                Vec3::ZERO
            } else {
                Vec3::ONE
            }
        })
        .collect();
    Ok(crate::resident::upload_terms(&*shared()?, &terms))
}
