//! Techniques run over the frames of a view, as `render` and `compare` both run them: the
//! camera pass of each frame (shared by every technique, with the layers behind
//! semi-transparent surfaces when asked for), a still view run again until a progressive
//! technique converges, a sequence frame by frame, and the shaded image of a result.

use crate::config::{RunPlan, Setup};
use crate::metrics::FrameFigures;
use anyhow::{Context, Result};
use shadowlab::camera::Camera;
use shadowlab::frame::{DumpSink, Frame, Visibility};
use shadowlab::math::Vec3;
use shadowlab::picture::RgbImage;
use shadowlab::shade;
use shadowlab::techniques::{ShadowTechnique, Shadows};
use shadowlab::view::{ViewLayers, ViewSamples};
use std::time::Instant;

/// The most frames a still view gives a progressive technique to converge in.
pub const MAX_STILL_FRAMES: usize = 64;

/// One frame's camera pass: the camera, its samples and, when asked for, the layers.
pub struct Pass {
    /// The camera of the frame, its depth range fitted.
    pub camera: Camera,
    /// The camera pass.
    pub view: ViewSamples,
    /// The surfaces behind semi-transparent ones (`--layers`).
    pub layers: Option<ViewLayers>,
}

/// The scene on the GPU, for its camera pass (`render --camera-pass gpu`): uploaded once
/// for every frame of a sequence.
pub struct GpuScene {
    gpu: std::sync::Arc<shadowlab_gpu::device::Gpu>,
    buffers: shadowlab_gpu::upload::SceneBuffers,
}

impl GpuScene {
    /// `setup`'s scene uploaded to the shared device; no adapter is the user's error.
    pub fn new(setup: &Setup) -> Result<Self> {
        let gpu = shadowlab_gpu::device::shared().map_err(|e| match e {
            shadowlab::error::Error::Internal(m) => anyhow::anyhow!("the GPU camera pass: {m}"),
            e => crate::failure::bad_input(format!("--camera-pass gpu needs a GPU and {e}")),
        })?;
        let buffers = shadowlab_gpu::upload::SceneBuffers::new(&gpu, &setup.scene)?;
        Ok(GpuScene { gpu, buffers })
    }
}

/// The camera of frame `i` of `setup`, checked.
fn frame_camera(setup: &Setup, i: usize) -> Result<Camera> {
    let camera = setup.camera_at(i);
    camera
        .validate()
        .with_context(|| format!("frame {i} of the camera path of {}", setup.scene.name))?;
    Ok(camera)
}

impl Pass {
    /// Renders frame `i` of `setup`, into the buffers of the `previous` frame's camera
    /// pass when one is handed back (a sequence keeps one pass's memory across frames).
    pub fn render(setup: &Setup, i: usize, previous: Option<Pass>) -> Result<Pass> {
        let camera = frame_camera(setup, i)?;
        let view = match previous {
            Some(mut p) => {
                p.view.render_into(&setup.scene, &camera)?;
                p.view
            }
            None => ViewSamples::try_render(&setup.scene, &camera)?,
        };
        Self::with_layers(setup, camera, view)
    }

    /// Renders frame `i` of `setup` with the GPU's camera pass
    /// ([`shadowlab_gpu::camera_pass::on_device`]) over the scene uploaded once (`gpu`),
    /// its samples read back.
    pub fn render_on_gpu(setup: &Setup, i: usize, gpu: &GpuScene) -> Result<Pass> {
        let camera = frame_camera(setup, i)?;
        let t0 = std::time::Instant::now();
        let (g, buffers) = (&gpu.gpu, &gpu.buffers);
        let (on_device, _) =
            shadowlab_gpu::camera_pass::on_device(g, buffers, setup.scene.len(), &camera)?;
        let mut view = shadowlab_gpu::camera_pass::read_view(g, &on_device, &camera)?;
        view.time_ms = t0.elapsed().as_secs_f64() * 1e3;
        Self::with_layers(setup, camera, view)
    }

    /// The pass of `camera` and its samples `view`, with the layers behind
    /// semi-transparent surfaces when `setup` asks for them.
    fn with_layers(setup: &Setup, camera: Camera, view: ViewSamples) -> Result<Pass> {
        let layers = if setup.layers {
            Some(ViewLayers::render(&setup.scene, &camera, &view)?)
        } else {
            None
        };
        Ok(Pass {
            camera,
            view,
            layers,
        })
    }

    /// Frame `index` of the pass, its intermediate images handed to `dump`.
    pub fn frame<'a>(
        &'a self,
        setup: &'a Setup,
        index: usize,
        dump: Option<&'a dyn DumpSink>,
    ) -> Frame<'a> {
        let mut frame = Frame::new(&setup.scene, &self.camera, &setup.light, &self.view)
            .with_area(setup.area.as_ref(), setup.light_samples);
        if let Some(l) = &self.layers {
            frame = frame.with_layers(l);
        }
        frame.index = index;
        frame.dump = dump;
        frame
    }

    /// The shaded image of a technique's result (see [`Pass::shade_result`]).
    pub fn shade(&self, setup: &Setup, s: &Shadows) -> RgbImage {
        self.shade_result(setup, &s.visibility, s.layers.as_deref())
    }

    /// The shaded image of a result: the layers composited when the frame has them and the
    /// technique shaded them, else the nearest surfaces.
    pub fn shade_result(
        &self,
        setup: &Setup,
        vis: &Visibility,
        layer_vis: Option<&[Vec3]>,
    ) -> RgbImage {
        match (&self.layers, layer_vis) {
            (Some(l), Some(lv)) => {
                shade::shade_layers(&setup.scene, &self.view, l, &setup.light, vis, lv)
            }
            _ => shade::shade(&setup.scene, &self.view, &setup.light, vis),
        }
    }
}

/// One technique run over every frame of a sequence: the last frame's result and the
/// per-frame figures.
pub struct Run {
    /// The technique.
    pub technique: Box<dyn ShadowTechnique>,
    /// Its label.
    pub label: String,
    /// The last frame's result and its time in milliseconds.
    pub last: Option<(Shadows, f64)>,
    /// Every frame's figures.
    pub frames: Vec<FrameFigures>,
}

impl Run {
    /// A run that has rendered nothing yet.
    pub fn new(plan: RunPlan) -> Self {
        Run {
            technique: plan.technique,
            label: plan.label,
            last: None,
            frames: Vec::new(),
        }
    }

    /// Renders one frame of a sequence, or a still frame: then a progressive technique
    /// (see [`ShadowTechnique::converged`]) is run on it again until it converges or has
    /// had [`MAX_STILL_FRAMES`] frames.
    pub fn render(&mut self, frame: &Frame, still: bool) -> Result<()> {
        self.render_once(frame)?;
        while still
            && self.technique.converged() == Some(false)
            && self.frames.len() < MAX_STILL_FRAMES
        {
            self.render_once(frame)?;
        }
        Ok(())
    }

    fn render_once(&mut self, frame: &Frame) -> Result<()> {
        let t0 = Instant::now();
        let s = self
            .technique
            .render(frame)
            .with_context(|| format!("technique {}", self.label))?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        self.frames.push(FrameFigures {
            frame: frame.index,
            time_ms: ms,
            memory_bytes: s.stats.memory_bytes,
            verdict: None,
        });
        self.last = Some((s, ms));
        Ok(())
    }

    /// The last frame's result and its time.
    pub fn result(&self) -> &(Shadows, f64) {
        self.last
            .as_ref()
            .expect("every run renders at least one frame")
    }
}
