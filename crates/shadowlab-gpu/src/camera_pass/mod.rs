//! The GPU camera pass: a hardware G-buffer (triangle id, world position, face normal,
//! view depth, screen-space derivatives of the position) for benchmarks and the viewer.
//!
//! Verdicts are judged on the CPU camera pass (uploaded), so CPU and GPU techniques see
//! the same samples; this pass is the GPU's own, drawn by the hardware rasterizer with the
//! camera's `clip_from_world` (`gbuffer.wgsl`). Where it departs from the CPU pass: the
//! position is the perspective-correct interpolation of the vertices (the CPU intersects
//! the pixel's ray with the triangle's plane), the derivatives are the hardware's
//! `dpdx`/`dpdy` (differences within a 2×2 quad, where the CPU intersects the neighbouring
//! pixels' rays with the plane), and coverage follows the hardware's rounding, so the
//! triangle seen differs from the CPU's only on a few edge pixels (a test holds it to
//! 99.9% of covered pixels). The position error bound is not formed here.
//!
//! [`on_device`] is the camera pass that stays there (the viewer's, and `render
//! --camera-pass gpu`'s): the G-buffer's triangle ids, then stage `samples`
//! (`samples.wgsl`), which forms each pixel's sample from its triangle as the library's
//! pass does (the pixel ray met with the triangle's plane, the error bound, the normal)
//! straight into the layout techniques read, and reduces the covered count and the
//! receivers' bounds, the few numbers a technique's light fit needs on the CPU.

mod samples;

pub use samples::{on_device, read_view};

use crate::compute::render_pipeline_to;
use crate::device::Gpu;
use crate::shader::{Stage, ALPHA_MASK, RAY_OFFSET, TRIANGLES};
use crate::transfer::{read_texture, uniform, Timer};
use crate::upload::view_buffer;
use crate::upload::SceneBuffers;
use bytemuck::{Pod, Zeroable};
use shadowlab::camera::Camera;
use shadowlab::error::{Error, Result};
use shadowlab::math::{Aabb, Vec3};
use shadowlab::raster::NO_TRIANGLE;
use shadowlab::view::ViewSamples;

const GBUFFER: Stage = Stage {
    name: "gbuffer.wgsl",
    common: &[RAY_OFFSET, ALPHA_MASK, TRIANGLES],
    source: include_str!("gbuffer.wgsl"),
};

/// The camera pass's samples on the device ([`crate::upload::VIEW_STRIDE`] floats a
/// pixel, row-major from the top row) with the few numbers of them a technique needs on the
/// CPU: the covered pixels' count and the bounds of their positions (the receivers a light
/// view is fitted to). Made by uploading the library's camera pass ([`DeviceView::upload`])
/// or by the GPU's own ([`on_device`]), which reads back no more than
/// those numbers.
pub struct DeviceView {
    /// The samples.
    pub samples: wgpu::Buffer,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Covered pixels.
    pub covered: u64,
    /// Bounds of the covered pixels' positions ([`ViewSamples::receiver_bounds`]).
    pub receivers: Aabb,
    /// True when the samples are the library's camera pass uploaded, the one the frame's
    /// `view` holds; false when the GPU formed them and the frame's `view` holds no
    /// per-pixel data.
    pub uploaded: bool,
}

impl DeviceView {
    /// The library's camera pass `view`, uploaded.
    pub fn upload(gpu: &Gpu, view: &ViewSamples) -> Result<Self> {
        Ok(DeviceView {
            samples: view_buffer(gpu, view)?,
            width: view.width,
            height: view.height,
            covered: view.covered_count() as u64,
            receivers: view.receiver_bounds(),
            uploaded: true,
        })
    }

    /// Pixels in the image.
    pub fn pixels(&self) -> u32 {
        self.width * self.height
    }
}

/// The G-buffer's colour targets, in `gbuffer.wgsl`'s location order.
const TARGETS: [wgpu::TextureFormat; 5] = [
    wgpu::TextureFormat::R32Uint,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba32Float,
    wgpu::TextureFormat::Rgba32Float,
];

/// The triangle-id target alone, `gbuffer.wgsl`'s `fs_ids`: the pass left on the device.
const IDS: [wgpu::TextureFormat; 1] = [wgpu::TextureFormat::R32Uint];

/// `CameraU` of `gbuffer.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CameraU {
    clip_from_world: [f32; 16],
    eye: [f32; 3],
    ortho: u32,
    forward: [f32; 3],
    masks: u32,
}

/// The GPU camera pass's samples, read back, row-major from the top row.
#[derive(Clone, Debug)]
pub struct GpuView {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The triangle seen at each pixel, or `NO_TRIANGLE`.
    pub triangle: Vec<u32>,
    /// World position.
    pub position: Vec<Vec3>,
    /// Unit face normal turned towards the camera.
    pub normal: Vec<Vec3>,
    /// View depth.
    pub depth: Vec<f32>,
    /// World-position change per pixel step in x.
    pub dpdx: Vec<Vec3>,
    /// World-position change per pixel step in y.
    pub dpdy: Vec<Vec3>,
    /// The pass's GPU time from timestamp queries (ms), when the adapter has them.
    pub gpu_ms: Option<f64>,
}

fn target(gpu: &Gpu, camera: &Camera, format: wgpu::TextureFormat) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("gbuffer"),
        size: wgpu::Extent3d {
            width: camera.width,
            height: camera.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// Draws the G-buffer of `scene` (uploaded as `buffers`, `triangles` of them) from
/// `camera` and reads it back.
pub fn render(
    gpu: &Gpu,
    buffers: &SceneBuffers,
    triangles: usize,
    camera: &Camera,
) -> Result<GpuView> {
    let mut timer = Timer::new(gpu, 1);
    let textures = draw(
        gpu,
        buffers,
        triangles,
        camera,
        (&TARGETS, "fs"),
        &mut timer,
    )?;
    let planes: Vec<Vec<u8>> = textures
        .iter()
        .map(|t| read_texture(gpu, t))
        .collect::<Result<_>>()?;
    let gpu_ms = timer.read(gpu)?.first().map(|s| s.1);
    Ok(unpack(camera, &planes, gpu_ms))
}

/// Records and submits the G-buffer pass of `scene` (uploaded as `buffers`, `triangles`
/// of them) from `camera` into the targets `formats` written by fragment entry point
/// `fragment` ([`TARGETS`] and `fs`, or [`IDS`] and `fs_ids`), timed by `timer` as
/// `gbuffer`; returns the targets in that order.
fn draw(
    gpu: &Gpu,
    buffers: &SceneBuffers,
    triangles: usize,
    camera: &Camera,
    (formats, fragment): (&[wgpu::TextureFormat], &str),
    timer: &mut Timer,
) -> Result<Vec<wgpu::Texture>> {
    gpu.check_texture_side("the image width", camera.width)?;
    gpu.check_texture_side("the image height", camera.height)?;
    let bytes: u32 = formats
        .iter()
        .map(|f| f.block_copy_size(None).unwrap_or(16))
        .sum();
    if bytes > gpu.limits.max_color_attachment_bytes_per_sample {
        return Err(Error::Limit(format!(
            "the GPU camera pass writes {bytes} bytes a pixel, over the adapter's limit of {} ({})",
            gpu.limits.max_color_attachment_bytes_per_sample, gpu.adapter.name
        )));
    }
    let targets: Vec<Option<wgpu::ColorTargetState>> =
        formats.iter().map(|&f| Some(f.into())).collect();
    let pipe = render_pipeline_to(gpu, &GBUFFER, fragment, &targets);
    let f = camera.forward();
    let cam = CameraU {
        clip_from_world: camera.clip_from_world().to_cols_array(),
        eye: camera.eye.to_array(),
        ortho: u32::from(camera.is_orthographic()),
        forward: f.to_array(),
        masks: u32::from(buffers.masks),
    };
    let cam = uniform(gpu, "camera", &cam);
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipe.get_bind_group_layout(0),
        entries: &crate::compute::bind_entries(&[
            &cam,
            &buffers.triangles,
            &buffers.material_of,
            &buffers.materials,
            &buffers.uvs,
            &buffers.texels,
        ]),
    });
    let textures: Vec<wgpu::Texture> = formats.iter().map(|&f| target(gpu, camera, f)).collect();
    let views: Vec<wgpu::TextureView> = textures
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let depth = target(gpu, camera, wgpu::TextureFormat::Depth32Float);
    let depth_view = depth.create_view(&Default::default());
    let no_triangle = f64::from(NO_TRIANGLE);
    let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let clear = if i == 0 {
                wgpu::Color {
                    r: no_triangle,
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                }
            } else {
                wgpu::Color::TRANSPARENT
            };
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass("gbuffer"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipe);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..triangles as u32 * 3, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(textures)
}

fn unpack(camera: &Camera, planes: &[Vec<u8>], gpu_ms: Option<f64>) -> GpuView {
    let f32s = |p: &[u8]| -> Vec<f32> {
        p.chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
    let vec3s = |p: &[u8]| -> Vec<Vec3> {
        f32s(p)
            .chunks_exact(4)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let triangle: Vec<u32> = planes[0]
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let pos = f32s(&planes[1]);
    GpuView {
        width: camera.width,
        height: camera.height,
        triangle,
        position: pos
            .chunks_exact(4)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect(),
        depth: pos.chunks_exact(4).map(|c| c[3]).collect(),
        normal: vec3s(&planes[2]),
        dpdx: vec3s(&planes[3]),
        dpdy: vec3s(&planes[4]),
        gpu_ms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_camera_struct_has_the_wgsl_size() {
        assert_eq!(std::mem::size_of::<CameraU>(), 96);
    }
}
