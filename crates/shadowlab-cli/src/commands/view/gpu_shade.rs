//! The frame on the GPU, for a technique that leaves its shadow term on the device
//! (`gpu:sm`, `gpu:pcf`, `gpu:cascaded`, `gpu:pcss`, `gpu:raytrace`, `gpu:afsm`, and
//! `gpu:psm`/`gpu:lispsm`): the GPU's own camera pass drawn into a device buffer once per
//! camera (the library's pass uploaded instead for a technique that reads the samples on
//! the CPU), the technique run over it, the view shaded into the window's texture
//! (`shade.wgsl`) and, when the error overlay is on, `gpu:raytrace` traced over the same
//! samples and compared on the device — nothing read back but the camera pass's seven
//! words (covered count, receivers' bounds), the error's four sums and the timestamp
//! queries.

use super::frame::{self, Drawn};
use super::screenshot::ErrorFigures;
use anyhow::{Context, Result};
use shadowlab::camera::Camera;
use shadowlab::frame::Frame;
use shadowlab::light::Light;
use shadowlab::scene::Scene;
use shadowlab::view::ViewSamples;
use shadowlab_gpu::camera_pass;
use shadowlab_gpu::compute::pipeline;
use shadowlab_gpu::device::Gpu;
use shadowlab_gpu::resident::DeviceView;
use shadowlab_gpu::resident::OnDevice;
use shadowlab_gpu::shader::{Stage, LIGHT, RAY_OFFSET};
use shadowlab_gpu::transfer::{read_back, storage, uniform, Timer};
use shadowlab_gpu::upload::{LightU, SceneBuffers};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

const SHADE: Stage = Stage {
    name: "view/shade.wgsl",
    common: &[RAY_OFFSET, LIGHT],
    source: include_str!("shade.wgsl"),
};

/// The reference's name.
pub const REFERENCE: &str = "gpu:raytrace";

/// `ShadeU` of `shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeU {
    light: LightU,
    width: u32,
    height: u32,
    pad: [u32; 2],
}

/// What stays on the device of a frame drawn there.
pub struct OnDeviceFrame {
    /// The camera pass's samples.
    pub view: DeviceView,
    /// The technique's shadow term.
    pub visibility: wgpu::Buffer,
}

/// A frame's camera pass as the device path takes it.
struct DevicePass {
    /// The camera, its depth range fitted.
    camera: Camera,
    /// The library's samples; none per pixel when the pass is the GPU's own.
    view: ViewSamples,
    /// The samples on the device.
    device: DeviceView,
    /// The pass's wall times.
    stages_ms: Vec<(String, f64)>,
    /// The pass's GPU times (`gpu_STAGE_ms`).
    counters: BTreeMap<String, f64>,
}

/// The shading and the error on the device, for one scene.
pub struct GpuShading {
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    albedo: wgpu::Buffer,
    reference: Box<dyn OnDevice>,
}

impl GpuShading {
    /// The shading of `scene` on `gpu`: each triangle's albedo uploaded.
    pub fn new(gpu: Arc<Gpu>, scene: &Scene) -> Result<Self> {
        let albedo: Vec<f32> = (0..scene.len())
            .flat_map(|i| scene.material_of(i).color.to_array())
            .collect();
        let albedo = storage(&gpu, "the triangles' albedo", bytemuck::cast_slice(&albedo))?;
        let reference = shadowlab_gpu::techniques::create_on_device(REFERENCE)
            .context("the GPU reference is not registered")?;
        Ok(GpuShading {
            scene: SceneBuffers::new(&gpu, scene)?,
            gpu,
            albedo,
            reference,
        })
    }

    fn uniform(&self, light: &Light, (width, height): (u32, u32)) -> wgpu::Buffer {
        let u = ShadeU {
            light: LightU::of(light),
            width,
            height,
            pad: [0; 2],
        };
        uniform(&self.gpu, "the view's shading", &u)
    }

    /// Draws the frame of `camera` and `light` with `technique` on the device, shading it
    /// into `target`. The camera pass is the GPU's own, its samples never read back
    /// (kept from `previous` when the camera is the same), unless the technique reads the
    /// samples on the CPU: then the library's pass is uploaded.
    pub fn draw(
        &self,
        (scene, camera, light): (&Scene, &Camera, &Light),
        technique: &mut dyn OnDevice,
        previous: (Option<Drawn>, Option<OnDeviceFrame>),
        target: &wgpu::Texture,
    ) -> Result<(Drawn, OnDeviceFrame)> {
        let DevicePass {
            camera,
            view,
            device: device_view,
            mut stages_ms,
            mut counters,
        } = if technique.needs_cpu_samples() {
            self.uploaded_pass(scene, camera, previous.0)?
        } else {
            self.camera_pass(scene, camera, previous)?
        };
        let gpu_camera_pass = !device_view.uploaded;
        let f = Frame::new(scene, &camera, light, &view);
        let t1 = Instant::now();
        let shadows = technique
            .render_on_device(&f, &device_view)
            .with_context(|| format!("technique {}", technique.name()))?;
        let technique_ms = frame::ms(t1);
        if shadows.stats.stages_ms.is_empty() {
            stages_ms.push((technique.name().to_string(), technique_ms));
        } else {
            stages_ms.extend(shadows.stats.stages_ms.iter().cloned());
        }
        let t2 = Instant::now();
        counters.extend(shadows.stats.counters.clone());
        let size = (camera.width, camera.height);
        let u = self.uniform(light, size);
        let group = self.group(
            "shade",
            &[
                (0, &u),
                (1, &device_view.samples),
                (2, &shadows.visibility),
                (3, &self.albedo),
            ],
            target,
        );
        let ms = self.dispatch("shade", &group, size)?;
        counters.insert("gpu_shade_ms".to_string(), ms);
        stages_ms.push(("shade (GPU)".to_string(), frame::ms(t2)));
        let drawn = Drawn {
            camera,
            view,
            layers: None,
            shadows: None,
            image: None,
            stages_ms,
            dumps: Vec::new(),
            counters,
            gpu_camera_pass,
        };
        let on_device = OnDeviceFrame {
            view: device_view,
            visibility: shadows.visibility,
        };
        Ok((drawn, on_device))
    }

    /// The library's camera pass of `camera` (kept from `previous` as [`frame::camera_pass`]
    /// keeps it), uploaded: for a technique that reads the samples on the CPU too.
    fn uploaded_pass(
        &self,
        scene: &Scene,
        camera: &Camera,
        previous: Option<Drawn>,
    ) -> Result<DevicePass> {
        let (camera, view, _, mut stages_ms) = frame::camera_pass(scene, camera, false, previous)?;
        let t0 = Instant::now();
        let device = DeviceView::upload(&self.gpu, &view)?;
        stages_ms.push(("upload view".to_string(), frame::ms(t0)));
        Ok(DevicePass {
            camera,
            view,
            device,
            stages_ms,
            counters: BTreeMap::new(),
        })
    }

    /// The GPU's camera pass of `camera`, its depth range fitted: kept from the previous
    /// frame when that frame's was the GPU's of the same camera, else drawn. The frame's
    /// `view` holds no per-pixel data (the samples stay on the device); the counters hold
    /// the pass's GPU times.
    fn camera_pass(
        &self,
        scene: &Scene,
        camera: &Camera,
        (previous, previous_on): (Option<Drawn>, Option<OnDeviceFrame>),
    ) -> Result<DevicePass> {
        let mut camera = *camera;
        camera.fit_depth_range(&scene.bounds);
        camera.validate()?;
        if let (Some(p), Some(on)) = (previous, previous_on) {
            if p.gpu_camera_pass && p.camera == camera {
                return Ok(DevicePass {
                    camera,
                    view: p.view,
                    device: on.view,
                    stages_ms: vec![("camera pass (GPU, kept)".to_string(), 0.0)],
                    counters: BTreeMap::new(),
                });
            }
        }
        let t0 = Instant::now();
        let (device, times) = camera_pass::on_device(&self.gpu, &self.scene, scene.len(), &camera)?;
        Ok(DevicePass {
            camera,
            view: ViewSamples::unsampled(&camera),
            device,
            stages_ms: vec![("camera pass (GPU)".to_string(), frame::ms(t0))],
            counters: times.into_iter().collect(),
        })
    }

    /// Traces the reference with `spp` samples a pixel over the drawn frame `d`, compares
    /// it with the technique's shadow term into `overlay`, and returns the figures and the
    /// GPU times of the trace and the comparison (`gpu_STAGE_ms`).
    pub fn measure(
        &mut self,
        scene: &Scene,
        light: &Light,
        d: &Drawn,
        on: &OnDeviceFrame,
        spp: u32,
        overlay: &wgpu::Texture,
    ) -> Result<(ErrorFigures, Vec<(String, f64)>)> {
        self.reference.set_param("spp", &spp.to_string())?;
        let f = Frame::new(scene, &d.camera, light, &d.view);
        let reference = self.reference.render_on_device(&f, &on.view)?;
        let size = (d.camera.width, d.camera.height);
        let u = self.uniform(light, size);
        // New buffers start zeroed.
        let sums = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("the error's sums, read"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = self.group(
            "measure",
            &[
                (0, &u),
                (1, &on.view.samples),
                (2, &on.visibility),
                (5, &reference.visibility),
                (6, &sums),
            ],
            overlay,
        );
        let measure_ms = self.dispatch("measure", &group, size)?;
        let mut times: Vec<(String, f64)> = reference
            .stats
            .counters
            .iter()
            .filter(|(k, _)| k.starts_with("gpu_") && k.ends_with("_ms"))
            .map(|(k, v)| (format!("gpu_error_{}", &k[4..]), *v))
            .collect();
        times.push(("gpu_error_compare_ms".to_string(), measure_ms));
        let raw = read_back(&self.gpu, &sums, 16)?;
        let w: Vec<u32> = bytemuck::pod_collect_to_vec(&raw);
        let covered = f64::from(w[0]).max(1.0);
        let sum = (f64::from(w[3]) * 4294967296.0 + f64::from(w[2])) / 65536.0;
        let figures = ErrorFigures {
            mismatch_rate: f64::from(w[1]) / covered,
            mean_abs_error: sum / covered,
            reference_spp: spp,
        };
        Ok((figures, times))
    }

    fn group(
        &self,
        entry: &str,
        buffers: &[(u32, &wgpu::Buffer)],
        image: &wgpu::Texture,
    ) -> (wgpu::ComputePipeline, wgpu::BindGroup) {
        let pipe = pipeline(&self.gpu, &SHADE, entry);
        let image = image.create_view(&Default::default());
        let mut entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .map(|(b, buf)| wgpu::BindGroupEntry {
                binding: *b,
                resource: buf.as_entire_binding(),
            })
            .collect();
        entries.push(wgpu::BindGroupEntry {
            binding: 4,
            resource: wgpu::BindingResource::TextureView(&image),
        });
        let group = self
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(entry),
                layout: &pipe.get_bind_group_layout(0),
                entries: &entries,
            });
        (pipe, group)
    }

    /// Runs `entry` over the image; returns its GPU time (ms; 0 without timestamps).
    fn dispatch(
        &self,
        entry: &str,
        (pipe, group): &(wgpu::ComputePipeline, wgpu::BindGroup),
        (w, h): (u32, u32),
    ) -> Result<f64> {
        let gpu = &self.gpu;
        let mut timer = Timer::new(gpu, 1);
        gpu.stage("view", entry, || {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(entry),
                    timestamp_writes: timer.pass(entry),
                });
                pass.set_pipeline(pipe);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
            }
            gpu.queue.submit([encoder.finish()]);
        })?;
        Ok(timer.read(gpu)?.first().map_or(0.0, |s| s.1))
    }
}
