//! What every technique's passes share: a compute pipeline from a stage's entry point,
//! bind groups of buffers by binding number, and shadow terms read back as RGB.

use crate::device::Gpu;
use crate::shader::{PipelineKey, Stage};
use shadowlab::math::Vec3;

/// The compute pipeline of `stage`'s entry point `entry`, with the layout its bindings
/// imply: made once per device and kept.
pub fn pipeline(gpu: &Gpu, stage: &Stage, entry: &str) -> wgpu::ComputePipeline {
    let mut made = gpu.compute.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = made.iter().find(|(k, _)| k.is(stage, entry)) {
        return p.clone();
    }
    let module = stage.module(&gpu.device);
    let p = gpu
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(stage.name),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
    made.push((PipelineKey::new(stage, entry), p.clone()));
    p
}

/// `stage`'s depth-tested render pipeline ([`Stage::depth_tested_pipeline`]) with the
/// colour `targets` and fragment entry point `fs`, made once per device and kept.
pub fn render_pipeline(
    gpu: &Gpu,
    stage: &Stage,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    render_pipeline_to(gpu, stage, "fs", targets)
}

/// [`render_pipeline`] with the fragment entry point `fragment`.
pub fn render_pipeline_to(
    gpu: &Gpu,
    stage: &Stage,
    fragment: &str,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    let mut made = gpu.render.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = made.iter().find(|(k, _)| k.is(stage, fragment)) {
        return p.clone();
    }
    let p = stage.depth_tested_pipeline(&gpu.device, fragment, targets);
    made.push((PipelineKey::new(stage, fragment), p.clone()));
    p
}

/// Bind-group entries with `buffers` at bindings 0, 1, ….
pub fn bind_entries<'a>(buffers: &[&'a wgpu::Buffer]) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// A bind group of `pipeline`'s group 0 with `buffers` at bindings 0, 1, ….
pub fn bind(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &bind_entries(buffers),
    })
}

/// Shadow terms read back (three little-endian floats a pixel) as RGB values.
pub fn to_rgb(raw: &[u8]) -> Vec<Vec3> {
    raw.chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            Vec3::new(f(0), f(4), f(8))
        })
        .collect()
}
