//! Stage `lookup`: the hardware sampler over the pre-filtered maps, per pixel of the camera
//! pass, and the technique's test.

use super::fit::{filter_code, Fitted};
use super::Codec;
use crate::device::Gpu;
use crate::transfer::{grid, output, read_back, storage, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::techniques::filtering::{Filter, MAX_ANISOTROPY};
use shadowlab::techniques::{Frame, Stats};

const WORKGROUP: u32 = 64;

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    light: LightU,
    count: u32,
    row: u32,
    groups: u32,
    filtering: u32,
    soft: u32,
    max_aniso: u32,
    top: f32,
    side: f32,
}

/// The sampler of a look-up: clamp-to-edge, bilinear within a level, linear between levels
/// (tri-linear) for mip-mapped look-ups.
fn sampler(gpu: &Gpu, codec: &Codec) -> wgpu::Sampler {
    let mipmap = match codec.settings.filter {
        Filter::Bilinear => wgpu::MipmapFilterMode::Nearest,
        _ => wgpu::MipmapFilterMode::Linear,
    };
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("filtered map"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: mipmap,
        ..Default::default()
    })
}

/// Looks every pixel up and reads the shadow terms back (three floats a pixel); records the
/// stages `lookup` and `readback`.
#[allow(clippy::too_many_arguments)]
pub(super) fn run(
    gpu: &Gpu,
    name: &str,
    frame: &Frame,
    codec: &Codec,
    table: &wgpu::Buffer,
    fitted: &Fitted,
    texture: &wgpu::Texture,
    levels: u32,
    view: &wgpu::Buffer,
    derivs: &wgpu::Buffer,
    timer: &mut Timer,
    stats: &mut Stats,
) -> Result<Vec<u8>> {
    let n = frame.view.triangle.len() as u32;
    let out = output(gpu, "the shadow terms", u64::from(n) * 12)?;
    stats.stage("lookup", || {
        gpu.stage(name, "lookup", || -> Result<()> {
            let (gx, gy, row) = grid(gpu, n, WORKGROUP);
            let params = Params {
                light: LightU::of(frame.light),
                count: n,
                row,
                groups: codec.groups(),
                filtering: filter_code(codec.settings.filter),
                soft: u32::from(fitted.widths.is_some()),
                max_aniso: codec.settings.max_aniso.clamp(1, MAX_ANISOTROPY),
                top: levels.saturating_sub(1) as f32,
                side: codec.resolution as f32,
            };
            let params = uniform(gpu, "look-up parameters", &params);
            let tech = uniform(gpu, "technique parameters", &codec.tech);
            let dummy;
            let soft = match &fitted.widths {
                Some(w) => w,
                None => {
                    dummy = storage(gpu, "no penumbra footprints", &[0; 4])?;
                    &dummy
                }
            };
            let maps = texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let sampler = sampler(gpu, codec);
            let p = crate::compute::pipeline(gpu, &codec.lookup, "main");
            let buffers = [&params, &tech, table, view, derivs, soft];
            let mut entries = crate::compute::bind_entries(&buffers);
            entries.push(wgpu::BindGroupEntry {
                binding: 6,
                resource: wgpu::BindingResource::TextureView(&maps),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 7,
                resource: wgpu::BindingResource::Sampler(&sampler),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 8,
                resource: out.as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 9,
                resource: fitted.ranges.as_entire_binding(),
            });
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &p.get_bind_group_layout(0),
                entries: &entries,
            });
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("lookup"),
                    timestamp_writes: timer.pass("lookup"),
                });
                pass.set_pipeline(&p);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([encoder.finish()]);
            Ok(())
        })
    })??;
    stats.stage("readback", || {
        gpu.stage(name, "readback", || read_back(gpu, &out, u64::from(n) * 12))
    })?
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<Params>(), 80);
    }
}
