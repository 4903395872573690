//! Stage `samples` of the GPU camera pass (`samples.wgsl`): the G-buffer's triangle ids
//! made into the view samples techniques read, on the device, with the covered count and
//! the receivers' bounds reduced beside them — the pass whose samples never leave the
//! device ([`on_device`]), and the same samples read back into the library's
//! [`ViewSamples`] for a technique on the CPU ([`read_view`]).

use super::{draw, DeviceView, IDS};
use crate::compute::pipeline;
use crate::device::Gpu;
use crate::shader::{float_of_key, Stage, CAMERA_RAYS, ORDER_KEY, RAY_OFFSET};
use crate::transfer::{grid, output, read_back, uniform, Timer};
use crate::upload::{RaysU, SceneBuffers, VIEW_STRIDE};
use bytemuck::{Pod, Zeroable};
use shadowlab::camera::Camera;
use shadowlab::error::{Error, Result};
use shadowlab::math::{gamma, Aabb, Vec3};
use shadowlab::view::ViewSamples;
use wgpu::util::DeviceExt;

const SAMPLES: Stage = Stage {
    name: "samples.wgsl",
    common: &[RAY_OFFSET, CAMERA_RAYS, ORDER_KEY],
    source: include_str!("samples.wgsl"),
};

/// Invocations a workgroup of `samples.wgsl`.
const WORKGROUP: u32 = 64;
/// Pixels an invocation of `samples.wgsl` forms (its `PER_THREAD`).
const PER_THREAD: u32 = 16;

/// `SamplesU` of `samples.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SamplesU {
    rays: RaysU,
    height: u32,
    gamma7: f32,
    gamma16: f32,
    row: u32,
}

/// The camera pass of `scene` (uploaded as `buffers`, `triangles` of them) from
/// `camera`, left on the device: the G-buffer drawn, the samples formed, and only the
/// seven words of the covered count and the receivers' bounds read back. Also the GPU
/// times of its two stages (`gpu_gbuffer_ms`, `gpu_samples_ms`; none without timestamps).
pub fn on_device(
    gpu: &Gpu,
    buffers: &SceneBuffers,
    triangles: usize,
    camera: &Camera,
) -> Result<(DeviceView, Vec<(String, f64)>)> {
    let pixels = u64::from(camera.width) * u64::from(camera.height);
    let bytes = pixels * VIEW_STRIDE as u64 * 4;
    let samples = output(gpu, "the camera pass's samples", bytes)?;
    let mut timer = Timer::new(gpu, 2);
    let targets = draw(
        gpu,
        buffers,
        triangles,
        camera,
        (&IDS, "fs_ids"),
        &mut timer,
    )?;
    let (gx, gy, row) = grid(gpu, (pixels as u32).div_ceil(PER_THREAD), WORKGROUP);
    let u = SamplesU {
        rays: RaysU::of(camera),
        height: camera.height,
        gamma7: gamma(7),
        gamma16: gamma(16),
        row,
    };
    let u = uniform(gpu, "the camera pass's rays", &u);
    // The count from zero, the minima from the largest key, the maxima from the smallest.
    let start: [u32; 7] = [0, u32::MAX, u32::MAX, u32::MAX, 0, 0, 0];
    let summary = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("the camera pass's summary"),
            contents: bytemuck::cast_slice(&start),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let pipe = gpu.stage("camera pass", "pipeline", || {
        pipeline(gpu, &SAMPLES, "main")
    })?;
    let ids = targets[0].create_view(&Default::default());
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("samples"),
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: u.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&ids),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: buffers.triangles.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: samples.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: summary.as_entire_binding(),
            },
        ],
    });
    gpu.stage("camera pass", "samples", || {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("samples"),
                timestamp_writes: timer.pass("samples"),
            });
            pass.set_pipeline(&pipe);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        gpu.queue.submit([encoder.finish()]);
    })?;
    let raw = read_back(gpu, &summary, 28)?;
    let w: Vec<u32> = bytemuck::pod_collect_to_vec(&raw);
    let receivers = if w[0] == 0 {
        Aabb::EMPTY
    } else {
        Aabb {
            min: Vec3::new(float_of_key(w[1]), float_of_key(w[2]), float_of_key(w[3])),
            max: Vec3::new(float_of_key(w[4]), float_of_key(w[5]), float_of_key(w[6])),
        }
    };
    let times = timer
        .read(gpu)?
        .into_iter()
        .map(|(stage, ms)| (format!("gpu_{stage}_ms"), ms))
        .collect();
    let view = DeviceView {
        samples,
        width: camera.width,
        height: camera.height,
        covered: u64::from(w[0]),
        receivers,
        uploaded: false,
    };
    Ok((view, times))
}

/// The GPU camera pass's samples `view` of `camera`, read back into the library's
/// [`ViewSamples`] (view depth and derivatives formed on the CPU from them), for a
/// technique that runs there.
pub fn read_view(gpu: &Gpu, view: &DeviceView, camera: &Camera) -> Result<ViewSamples> {
    let n = view.pixels() as usize;
    let raw = read_back(gpu, &view.samples, (n * VIEW_STRIDE * 4) as u64)?;
    let f: Vec<f32> = bytemuck::pod_collect_to_vec(&raw);
    let at = |k: usize, i: usize| Vec3::new(f[k + i], f[k + i + 1], f[k + i + 2]);
    let mut triangle = Vec::with_capacity(n);
    let (mut position, mut error, mut normal) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    for k in (0..n).map(|k| k * VIEW_STRIDE) {
        position.push(at(k, 0));
        error.push(at(k, 3));
        normal.push(at(k, 6));
        triangle.push(f[k + 9].to_bits());
    }
    ViewSamples::from_samples(camera, triangle, position, error, normal).ok_or_else(|| {
        Error::Internal("the GPU camera pass's samples do not match its image size".into())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uniform_has_the_wgsl_size() {
        assert_eq!(std::mem::size_of::<SamplesU>(), 80);
    }
}
