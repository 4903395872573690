//! `gpu:raytrace`: the ray-traced reference in a compute shader.
//!
//! One thread per pixel of the camera pass forms the shadow ray exactly as the library's
//! `Reference::transmittance` does (the same `illuminates` test, the same error-bounded
//! origin, the own triangle skipped) and traces it through the library's own wide BVH,
//! flattened to eight child records a node and uploaded once per scene revision with the
//! scene. Triangles are tested with the same watertight test, alpha masks cut casters at
//! the hit's barycentrics, and semi-transparent casters multiply their transmittance in
//! triangle-index order (one traversal per caster met, each finding the next index), so the
//! result does not depend on the order threads or the traversal visit anything: no atomics.
//!
//! Invariants: the GPU's boxes hold the library's (decompressed, rescaled by the exact
//! power of two, rounded outwards; the slab test's far end stretched), so the traversal
//! culls no triangle the watertight test hits and the answer is that of testing every
//! triangle, as the CPU reference's is.
//!
//! Departures: the watertight test's double-precision fallback (an edge function exactly
//! zero in single precision) is emulated with error-free products (WGSL has no portable
//! f64): same sign, value equal but for a double rounding. A driver that contracts a
//! multiply and an add into a fused operation can move a hit by an ulp; these are the
//! floating-point ties the verdict allows. With `spp` above one, each pixel re-traces
//! primary rays through the library's grid of sub-pixel positions to their closest hit (the
//! lower triangle index on equal distance) and averages the shadow terms of those that hit,
//! as the reference does, one position a dispatch (the sum kept per pixel, in sample
//! order).
//!
//! Bounded invocations: Mesa's llvmpipe ends every loop of an invocation once its loops
//! together have turned 65535 times. Semi-transparent casters are gathered 64 to a
//! traversal and sub-pixel rays traced one a dispatch, so that a pixel of hairball (its
//! shadow rays through dozens of semi-transparent hairs) stays within that count: with 16
//! a traversal and every sub-pixel ray in one invocation, 189 of its 13670 covered pixels
//! at 160×120 came out lighter than the CPU's at one ray a pixel, and 1690 at 16. Area lights are not traced here (the CPU `raytrace` does).

use crate::compute::{bind, pipeline};
use crate::device::{shared, Gpu};
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{Stage, ALPHA_MASK, CAMERA_RAYS, LIGHT, RAY_OFFSET, TRIANGLES, WATERTIGHT};
use crate::transfer::{grid, output, uniform, Timer};
use crate::upload::{BvhBuffers, LightU, RaysU, SceneBuffers, SceneKey};
use bytemuck::{Pod, Zeroable};
use shadowlab::error::{Error, Result};
use shadowlab::math::{gamma, Vec2};
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::raytrace::RayTrace;
use shadowlab::techniques::{Frame, ShadowTechnique, Shadows, Stats};
use std::sync::Arc;

/// The technique's name.
pub const NAME: &str = "gpu:raytrace";

/// `trace.wgsl`, composed after the common files it uses.
const TRACE: Stage = Stage {
    name: "trace.wgsl",
    common: &[
        RAY_OFFSET,
        LIGHT,
        WATERTIGHT,
        ALPHA_MASK,
        TRIANGLES,
        CAMERA_RAYS,
    ],
    source: include_str!("trace.wgsl"),
};

/// Threads a workgroup.
const WORKGROUP: u32 = 64;

/// Sub-pixel positions a pixel's thread traces in one dispatch of `supersample`: one, so
/// that no invocation's loops outrun a software adapter's count (see `trace.wgsl`).
const ROUND: u32 = 1;

/// `Params` of `trace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TraceParams {
    light: LightU,
    count: u32,
    row: u32,
    transparency: u32,
    masks: u32,
}

/// The scene and BVH of one scene revision on one device, with the pipelines.
struct Resident {
    key: SceneKey,
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    bvh: BvhBuffers,
    trace: wgpu::ComputePipeline,
    /// The `supersample` entry's pipeline, made when first needed.
    supersample: Option<wgpu::ComputePipeline>,
}

/// Shadow rays in a compute shader; the CPU `raytrace`'s parameters.
#[derive(Default)]
pub struct GpuRayTrace {
    cpu: RayTrace,
    resident: Option<Resident>,
}

impl GpuRayTrace {
    /// The scene, BVH and pipelines for `frame`, uploaded when the scene changed.
    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&mut Resident> {
        let key = SceneKey::of(frame.scene);
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            self.resident = None;
            let gpu = shared()?;
            let (scene, bvh) = stats.stage("upload_scene", || -> Result<_> {
                gpu.stage(NAME, "upload_scene", || -> Result<_> {
                    Ok((
                        SceneBuffers::new(&gpu, frame.scene)?,
                        BvhBuffers::new(&gpu, frame.scene)?,
                    ))
                })?
            })?;
            let trace = gpu.stage(NAME, "pipeline", || pipeline(&gpu, &TRACE, "main"))?;
            self.resident = Some(Resident {
                key,
                gpu,
                scene,
                bvh,
                trace,
                supersample: None,
            });
        }
        self.resident
            .as_mut()
            .ok_or_else(|| Error::Internal(format!("{NAME}: the scene was not uploaded")))
    }
}

impl ShadowTechnique for GpuRayTrace {
    fn name(&self) -> &'static str {
        NAME
    }

    crate::twin::twin_params!(cpu);

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        resident::read_back(self, frame)
    }
}

impl ShadowTerm for GpuRayTrace {
    /// The rays traced for the uploaded `view`: the shadow terms on the device.
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        if frame.area.is_some() {
            return Err(Error::param(format!(
                "{NAME} traces punctual lights only: use raytrace for the area light's soft reference"
            )));
        }
        let spp = self.cpu.spp;
        let res = self.resident(frame, stats)?;
        let gpu = res.gpu.clone();
        let n = view.pixels();
        let out = output(&gpu, "the shadow terms", u64::from(n) * 12)?;
        let mut timer = Timer::new(&gpu, spp.max(1) + 1);
        if spp <= 1 {
            stats.stage("trace", || {
                gpu.stage(NAME, "trace", || trace(res, frame, view, &out, &mut timer))
            })??;
        } else {
            let samples = pattern(PatternKind::Grid, spp)?;
            if res.supersample.is_none() {
                let p = gpu.stage(NAME, "pipeline", || pipeline(&gpu, &TRACE, "supersample"))?;
                res.supersample = Some(p);
            }
            stats.stage("trace", || {
                gpu.stage(NAME, "trace", || {
                    supersample(res, frame, view, &samples, &out, &mut timer)
                })
            })??;
        }
        for (stage, ms) in timer.read(&gpu)? {
            stats.count(&format!("gpu_{stage}_ms"), ms);
        }
        stats.count("rays", view.covered as f64 * f64::from(spp.max(1)));
        stats.memory_bytes = res.scene.bytes + res.bvh.bytes;
        stats.device = Some(gpu.adapter.label());
        Ok(out)
    }
}

/// `CameraU` of `trace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CameraU {
    rays: RaysU,
    spp: u32,
    gamma7: f32,
    gamma16: f32,
    first: u32,
    round: u32,
    pad: [u32; 3],
}

/// The trace's parameters for `frame`.
fn trace_params(
    gpu: &Gpu,
    res: &Resident,
    frame: &Frame,
    view: &DeviceView,
) -> (TraceParams, (u32, u32)) {
    let n = view.pixels();
    let (gx, gy, row) = grid(gpu, n, WORKGROUP);
    let params = TraceParams {
        light: LightU::of(frame.light),
        count: n,
        row,
        transparency: u32::from(res.scene.transparency),
        masks: u32::from(res.scene.masks),
    };
    (params, (gx, gy))
}

/// Records and submits one dispatch of `pipeline` over every pixel with `buffers` bound.
fn dispatch(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    buffers: &[&wgpu::Buffer],
    groups: (u32, u32),
    timer: &mut Timer,
) {
    let group = bind(&gpu.device, pipeline, buffers);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("trace"),
            timestamp_writes: timer.pass("trace"),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }
    gpu.queue.submit([encoder.finish()]);
}

/// Records and submits the trace with `samples` sub-pixel positions a pixel, in rounds of
/// [`ROUND`] positions.
fn supersample(
    res: &Resident,
    frame: &Frame,
    view: &DeviceView,
    samples: &[Vec2],
    out: &wgpu::Buffer,
    timer: &mut Timer,
) -> Result<()> {
    let gpu = &res.gpu;
    let (params, groups) = trace_params(gpu, res, frame, view);
    let params = uniform(gpu, "trace parameters", &params);
    let rays = RaysU::of(frame.camera);
    let cam = |first: u32| CameraU {
        rays,
        spp: samples.len() as u32,
        gamma7: gamma(7),
        gamma16: gamma(16),
        first,
        round: ROUND,
        pad: [0; 3],
    };
    let subpixel: Vec<f32> = samples.iter().flat_map(|s| [s.x, s.y]).collect();
    let subpixel = crate::transfer::storage(
        gpu,
        "the sub-pixel positions",
        bytemuck::cast_slice(&subpixel),
    )?;
    let accum = output(gpu, "the sub-pixel sums", u64::from(view.pixels()) * 16)?;
    let pipeline = res
        .supersample
        .as_ref()
        .ok_or_else(|| Error::Internal(format!("{NAME}: no supersample pipeline")))?;
    for first in (0..samples.len() as u32).step_by(ROUND as usize) {
        let cam = uniform(gpu, "camera", &cam(first));
        let mut buffers = trace_bindings(res, &params, &view.samples, out);
        buffers.extend([&subpixel, &cam, &accum]);
        dispatch(gpu, pipeline, &buffers, groups, timer);
    }
    Ok(())
}

/// The bindings `trace.wgsl` declares in both of its entry points, in binding order: the
/// parameters, the scene and its BVH, the camera pass's samples and the output.
fn trace_bindings<'a>(
    res: &'a Resident,
    params: &'a wgpu::Buffer,
    view: &'a wgpu::Buffer,
    out: &'a wgpu::Buffer,
) -> Vec<&'a wgpu::Buffer> {
    let s = &res.scene;
    vec![
        params,
        &s.triangles,
        &res.bvh.children,
        &res.bvh.primitives,
        &s.material_of,
        &s.materials,
        &s.uvs,
        &s.texels,
        view,
        out,
    ]
}

/// Records and submits the one-sample trace.
fn trace(
    res: &Resident,
    frame: &Frame,
    view: &DeviceView,
    out: &wgpu::Buffer,
    timer: &mut Timer,
) -> Result<()> {
    let gpu = &res.gpu;
    let (params, groups) = trace_params(gpu, res, frame, view);
    let params = uniform(gpu, "trace parameters", &params);
    let buffers = trace_bindings(res, &params, &view.samples, out);
    dispatch(gpu, &res.trace, &buffers, groups, timer);
    Ok(())
}
