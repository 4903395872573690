//! Stage `depth`: the light's maps drawn, and the format of the sampled texture they are
//! pre-filtered into.

use super::{Codec, Store};
use crate::compute::{bind_entries, render_pipeline};
use crate::device::Gpu;
use crate::shader::{Stage, ALPHA_MASK, LIGHT_DEPTH, TRIANGLES};
use crate::techniques::maps::{depth_scale, FaceU};
use crate::transfer::{uniform, Timer};
use crate::upload::SceneBuffers;
use shadowlab::error::{Error, Result};
use shadowlab::light::LightView;
use shadowlab::techniques::filtering::Filter;
use shadowlab::techniques::Frame;

const DEPTH: Stage = Stage {
    name: "filtering/depth.wgsl",
    common: &[ALPHA_MASK, TRIANGLES, LIGHT_DEPTH],
    source: include_str!("depth.wgsl"),
};

/// The format of the depth stage's colour target: a texel's depth bits and triangle.
const TEXEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;

/// The depth stage's render pipeline (one per device).
pub(super) fn depth_pipeline(gpu: &Gpu) -> wgpu::RenderPipeline {
    render_pipeline(
        gpu,
        &DEPTH,
        &[Some(wgpu::ColorTargetState {
            format: TEXEL_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })],
    )
}

/// Draws every light view's map (depth bits and triangle) into a layer of a new array
/// texture.
pub(super) fn draw(
    gpu: &Gpu,
    depth: &wgpu::RenderPipeline,
    s: &SceneBuffers,
    frame: &Frame,
    views: &[LightView],
    side: u32,
    timer: &mut Timer,
) -> wgpu::Texture {
    let size = wgpu::Extent3d {
        width: side,
        height: side,
        depth_or_array_layers: views.len() as u32,
    };
    let texels = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("filtered map texels"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TEXEL_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let tested = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("filtered map depth test"),
        size: wgpu::Extent3d {
            depth_or_array_layers: 1,
            ..size
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let tested_view = tested.create_view(&Default::default());
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
            layout: &depth.get_bind_group_layout(0),
            entries: &bind_entries(&[
                &face,
                &s.triangles,
                &s.material_of,
                &s.materials,
                &s.uvs,
                &s.texels,
            ]),
        });
        let layer = texels.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: i as u32,
            array_layer_count: Some(1),
            ..Default::default()
        });
        let empty = wgpu::Color {
            r: f64::from(f32::INFINITY.to_bits()),
            g: f64::from(u32::MAX),
            b: 0.0,
            a: 0.0,
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &layer,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(empty),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &tested_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
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
    texels
}

/// Bytes of a row of `width` texels of `bytes` each, padded for a texture copy.
pub(super) fn padded_row(width: u32, bytes: u32) -> u32 {
    (width * bytes).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// The sampled texture's format and shape for a technique's codec on this adapter.
#[derive(Clone, Copy, Debug)]
pub(super) struct Format {
    /// The texture format.
    pub texture: wgpu::TextureFormat,
    /// Channels a texel of it has (2 or 4).
    pub channels: u32,
    /// Its bytes a texel.
    pub texel_bytes: u32,
    /// True when 16-bit codes are kept in floats (no 16-bit normalized formats).
    pub as_float: bool,
    /// Mip levels (1 for bilinear look-ups).
    pub levels: u32,
    /// Map side.
    pub side: u32,
}

impl Format {
    /// The format `codec` is stored in here; refuses 32-bit floats on an adapter that
    /// cannot filter them.
    pub fn of(gpu: &Gpu, name: &str, codec: &Codec) -> Result<Self> {
        use wgpu::TextureFormat as F;
        let four = codec.channels > 2 || codec.store == Store::U8;
        let features = gpu.device.features();
        let norm16 = features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM);
        let f32_ok = features.contains(wgpu::Features::FLOAT32_FILTERABLE);
        let (texture, as_float) = match (codec.store, four) {
            (Store::U8, _) => (F::Rgba8Unorm, false),
            (Store::F16, true) => (F::Rgba16Float, false),
            (Store::F16, false) => (F::Rg16Float, false),
            (Store::Unorm16, true) if norm16 => (F::Rgba16Unorm, false),
            (Store::Unorm16, false) if norm16 => (F::Rg16Unorm, false),
            (Store::Unorm16, true) => (F::Rgba32Float, true),
            (Store::Unorm16, false) => (F::Rg32Float, true),
            (Store::F32, true) => (F::Rgba32Float, false),
            (Store::F32, false) => (F::Rg32Float, false),
        };
        let float32 = matches!(texture, F::Rgba32Float | F::Rg32Float);
        if float32 && !f32_ok {
            return Err(Error::Limit(format!(
                "{name}: the adapter {} cannot filter 32-bit float textures; use bits=16 (or precision=u8)",
                gpu.adapter.name
            )));
        }
        let texel_bytes = texture.block_copy_size(None).unwrap_or(4);
        let side = codec.resolution;
        let levels = if codec.settings.filter == Filter::Bilinear {
            1
        } else {
            32 - side.leading_zeros()
        };
        Ok(Format {
            texture,
            channels: if four { 4 } else { 2 },
            texel_bytes,
            as_float,
            levels,
            side,
        })
    }

    /// The side of level `l`.
    pub fn level_side(&self, l: u32) -> u32 {
        (self.side >> l).max(1)
    }

    /// Bytes of `layers` layers of every level.
    pub fn bytes(&self, layers: u32) -> u64 {
        (0..self.levels)
            .map(|l| u64::from(self.level_side(l)).pow(2) * u64::from(self.texel_bytes))
            .sum::<u64>()
            * u64::from(layers)
    }
}
