//! Stages `encode`, `blur` and `mipmap`: each view's groups of channels encoded, blurred
//! and mip-mapped by compute passes into the levels of one sampled array texture.

use super::maps::{padded_row, Format};
use super::{Codec, FILTERED};
use crate::compute::{bind, pipeline};
use crate::device::Gpu;
use crate::shader::Stage;
use crate::transfer::{storage, uniform, Timer};
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::techniques::filtering::binomial_weights;

const BLUR: Stage = Stage {
    name: "filtering/blur.wgsl",
    common: &[FILTERED],
    source: include_str!("blur.wgsl"),
};

const MIP: Stage = Stage {
    name: "filtering/mip.wgsl",
    common: &[FILTERED],
    source: include_str!("mip.wgsl"),
};

/// `PlaneU` of `encode.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct PlaneU {
    res: u32,
    layer: u32,
    group: u32,
    format: u32,
}

/// `BlurU` of `blur.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct BlurU {
    res: u32,
    taps: u32,
    horizontal: u32,
    format: u32,
}

/// `MipU` of `mip.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
pub(super) struct MipU {
    sw: u32,
    sh: u32,
    src: u32,
    dw: u32,
    dh: u32,
    dst: u32,
    format: u32,
    texel_words: u32,
    row_words: u32,
    packed_at: u32,
    channels: u32,
    as_float: u32,
}

/// Work buffers of the pre-filtering: every level as `vec4<f32>`s, the blur's second
/// pass, and the packed bytes of every level.
struct Work {
    levels: wgpu::Buffer,
    blurred: wgpu::Buffer,
    packed: wgpu::Buffer,
    /// First texel of each level in `levels`, first byte of each in `packed`.
    level_at: Vec<u32>,
    packed_at: Vec<u64>,
    weights: wgpu::Buffer,
}

impl Work {
    fn new(gpu: &Gpu, f: &Format, blur: u32) -> Result<Self> {
        let (mut texels, mut bytes) = (0u64, 0u64);
        let (mut level_at, mut packed_at) = (Vec::new(), Vec::new());
        for l in 0..f.levels {
            let s = f.level_side(l);
            level_at.push(texels as u32);
            packed_at.push(bytes);
            texels += u64::from(s) * u64::from(s);
            bytes += u64::from(padded_row(s, f.texel_bytes)) * u64::from(s);
        }
        let side = u64::from(f.side);
        gpu.check_binding("the filtered map's mip levels", texels * 16)?;
        let buffer = |what: &str, size: u64, usage: wgpu::BufferUsages| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(what),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let st = wgpu::BufferUsages::STORAGE;
        Ok(Work {
            levels: buffer("filtered levels", texels * 16, st),
            blurred: buffer(
                "blurred rows",
                if blur > 1 { side * side * 16 } else { 16 },
                st,
            ),
            packed: buffer("packed levels", bytes, st | wgpu::BufferUsages::COPY_SRC),
            level_at,
            packed_at,
            weights: storage(
                gpu,
                "the blur's weights",
                bytemuck::cast_slice(&binomial_weights(blur.max(1))),
            )?,
        })
    }
}

/// Encodes, blurs and mip-maps every view's groups of channels into the levels of one
/// sampled array texture (layer `view · groups + group`).
pub(super) fn prefilter(
    gpu: &Gpu,
    codec: &Codec,
    f: &Format,
    texels: &wgpu::Texture,
    views: u32,
    ranges: &wgpu::Buffer,
    timer: &mut Timer,
) -> Result<wgpu::Texture> {
    let groups = codec.groups();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("filtered map"),
        size: wgpu::Extent3d {
            width: f.side,
            height: f.side,
            depth_or_array_layers: views * groups,
        },
        mip_level_count: f.levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: f.texture,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let blur = codec.settings.blur;
    let work = Work::new(gpu, f, blur)?;
    let tech = uniform(gpu, "technique parameters", &codec.tech);
    let depth_view = texels.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    for i in 0..views {
        for g in 0..groups {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let plane = PlaneU {
                res: f.side,
                layer: i,
                group: g,
                format: codec.store.code(),
            };
            encode_pass(
                gpu,
                codec,
                &mut encoder,
                &plane,
                &tech,
                &depth_view,
                ranges,
                &work,
                timer,
            );
            if blur > 1 {
                blur_passes(gpu, codec, &mut encoder, f, &work, timer);
            }
            mip_passes(gpu, codec, &mut encoder, f, &work, timer);
            for l in 0..f.levels {
                let s = f.level_side(l);
                encoder.copy_buffer_to_texture(
                    wgpu::TexelCopyBufferInfo {
                        buffer: &work.packed,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: work.packed_at[l as usize],
                            bytes_per_row: Some(padded_row(s, f.texel_bytes)),
                            rows_per_image: Some(s),
                        },
                    },
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: l,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: i * groups + g,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d {
                        width: s,
                        height: s,
                        depth_or_array_layers: 1,
                    },
                );
            }
            gpu.queue.submit([encoder.finish()]);
        }
    }
    Ok(texture)
}

/// Workgroups of 8×8 covering a `side²` level.
fn groups_of(side: u32) -> u32 {
    side.div_ceil(8)
}

#[allow(clippy::too_many_arguments)]
fn encode_pass(
    gpu: &Gpu,
    codec: &Codec,
    encoder: &mut wgpu::CommandEncoder,
    plane: &PlaneU,
    tech: &wgpu::Buffer,
    depth_view: &wgpu::TextureView,
    ranges: &wgpu::Buffer,
    work: &Work,
    timer: &mut Timer,
) {
    let p = pipeline(gpu, &codec.encode, "main");
    let plane_u = uniform(gpu, "plane", plane);
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &p.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: plane_u.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: tech.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(depth_view),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: work.levels.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: ranges.as_entire_binding(),
            },
        ],
    });
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("encode"),
        timestamp_writes: timer.pass("encode"),
    });
    pass.set_pipeline(&p);
    pass.set_bind_group(0, &group, &[]);
    pass.dispatch_workgroups(groups_of(plane.res), groups_of(plane.res), 1);
}

fn blur_passes(
    gpu: &Gpu,
    codec: &Codec,
    encoder: &mut wgpu::CommandEncoder,
    f: &Format,
    work: &Work,
    timer: &mut Timer,
) {
    let p = pipeline(gpu, &BLUR, "main");
    let groups: Vec<wgpu::BindGroup> = [
        (1u32, &work.levels, &work.blurred),
        (0, &work.blurred, &work.levels),
    ]
    .iter()
    .map(|&(horizontal, src, dst)| {
        let u = uniform(
            gpu,
            "blur pass",
            &BlurU {
                res: f.side,
                taps: codec.settings.blur,
                horizontal,
                format: codec.store.code(),
            },
        );
        bind(&gpu.device, &p, &[&u, &work.weights, src, dst])
    })
    .collect();
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("blur"),
        timestamp_writes: timer.pass("blur"),
    });
    pass.set_pipeline(&p);
    for g in &groups {
        pass.set_bind_group(0, g, &[]);
        pass.dispatch_workgroups(groups_of(f.side), groups_of(f.side), 1);
    }
}

fn mip_passes(
    gpu: &Gpu,
    codec: &Codec,
    encoder: &mut wgpu::CommandEncoder,
    f: &Format,
    work: &Work,
    timer: &mut Timer,
) {
    let reduce = pipeline(gpu, &MIP, "reduce");
    let pack = pipeline(gpu, &MIP, "pack");
    let base = MipU {
        format: codec.store.code(),
        texel_words: f.texel_bytes / 4,
        channels: f.channels,
        as_float: u32::from(f.as_float),
        ..Default::default()
    };
    let mut steps: Vec<(bool, u32, wgpu::BindGroup)> = Vec::new();
    for l in 1..f.levels {
        let (s, d) = (f.level_side(l - 1), f.level_side(l));
        let u = MipU {
            sw: s,
            sh: s,
            src: work.level_at[l as usize - 1],
            dw: d,
            dh: d,
            dst: work.level_at[l as usize],
            ..base
        };
        let u = uniform(gpu, "mip level", &u);
        steps.push((false, d, bind(&gpu.device, &reduce, &[&u, &work.levels])));
    }
    for l in 0..f.levels {
        let s = f.level_side(l);
        let u = MipU {
            sw: s,
            sh: s,
            src: work.level_at[l as usize],
            row_words: padded_row(s, f.texel_bytes) / 4,
            packed_at: (work.packed_at[l as usize] / 4) as u32,
            ..base
        };
        let u = uniform(gpu, "packed level", &u);
        steps.push((
            true,
            s,
            bind(&gpu.device, &pack, &[&u, &work.levels, &work.packed]),
        ));
    }
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("mipmap"),
        timestamp_writes: timer.pass("mipmap"),
    });
    for (packing, side, group) in &steps {
        pass.set_pipeline(if *packing { &pack } else { &reduce });
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(groups_of(*side), groups_of(*side), 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<PlaneU>(), 16);
        assert_eq!(std::mem::size_of::<BlurU>(), 16);
        assert_eq!(std::mem::size_of::<MipU>(), 48);
    }
}
