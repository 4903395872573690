//! The shadow term kept on the device: for a window that shades and measures on the GPU
//! (the viewer), a technique may leave its result in a device buffer instead of reading it
//! back. Techniques opt in by implementing [`OnDevice`];
//! `techniques::create_on_device` makes those that do by name, and every other
//! technique works as before through [`ShadowTechnique::render`] (its result uploaded by
//! the caller).

pub use crate::camera_pass::DeviceView;
use crate::compute::to_rgb;
use crate::device::{shared, Gpu};
use crate::transfer::read_back as read_back_bytes;
use shadowlab::error::Result;
use shadowlab::math::Vec3;
use shadowlab::techniques::{Frame, ShadowTechnique, Shadows, Stats};
use wgpu::util::DeviceExt;

/// A frame's shadow term on the device.
pub struct DeviceShadows {
    /// Three `f32` a pixel (RGB transmittance towards the light), row-major from the top
    /// row: the layout [`ShadowTechnique::render`] reads back.
    pub visibility: wgpu::Buffer,
    /// The frame's stages, counters and device, as `render` reports them.
    pub stats: Stats,
}

/// A technique whose shadow term can stay on the device.
pub trait OnDevice: ShadowTechnique {
    /// Renders `frame`'s shadow term into a device buffer without reading it back;
    /// `view` holds the frame's camera-pass samples on the device. Unless
    /// [`OnDevice::needs_cpu_samples`], the technique reads nothing per pixel of
    /// `frame.view` (which then holds no per-pixel data when `view` is the GPU's own
    /// pass). Small control words (timestamps, a technique's overflow flags) may still be
    /// read.
    fn render_on_device(&mut self, frame: &Frame, view: &DeviceView) -> Result<DeviceShadows>;

    /// True when the technique, as its parameters stand, reads the camera pass's samples
    /// on the CPU too (a light fit over every visible point, samples traced from the
    /// pixels): its frame's `view` must hold them, so it cannot run on a camera pass that
    /// stayed on the device.
    fn needs_cpu_samples(&self) -> bool {
        false
    }

    /// The last frame's depth maps, for a viewer to show: a `Depth32Float` array texture,
    /// one layer a light view, holding linear depth over the view's far plane. `None` for
    /// a technique without maps.
    fn depth_maps(&self) -> Option<&wgpu::Texture> {
        None
    }
}

/// A technique whose whole frame is passes over the uploaded view samples that end in a
/// shadow-term buffer: it is [`OnDevice`], and its [`ShadowTechnique::render`] is
/// [`read_back`].
pub(crate) trait ShadowTerm: ShadowTechnique {
    /// The frame's passes over the uploaded `view`, counting into `stats`: the shadow
    /// terms on the device (three `f32` a pixel).
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer>;

    /// See [`OnDevice::needs_cpu_samples`].
    fn cpu_samples(&self) -> bool {
        false
    }

    /// The last frame's depth maps ([`OnDevice::depth_maps`]).
    fn last_maps(&self) -> Option<&wgpu::Texture> {
        None
    }
}

impl<T: ShadowTerm> OnDevice for T {
    fn render_on_device(&mut self, frame: &Frame, view: &DeviceView) -> Result<DeviceShadows> {
        let mut stats = Stats::default();
        let visibility = self.shadow_term(frame, view, &mut stats)?;
        Ok(DeviceShadows { visibility, stats })
    }

    fn needs_cpu_samples(&self) -> bool {
        self.cpu_samples()
    }

    fn depth_maps(&self) -> Option<&wgpu::Texture> {
        self.last_maps()
    }
}

/// `impl ShadowTechnique` for a [`ShadowTerm`] twin whose CPU technique is its field `cpu`:
/// the name `$name`, the twin's parameters, and `render` as [`read_back`].
macro_rules! device_twin {
    ($t:ty, $name:expr) => {
        impl shadowlab::techniques::ShadowTechnique for $t {
            fn name(&self) -> &'static str {
                $name
            }

            crate::twin::twin_params!(cpu);

            fn render(
                &mut self,
                frame: &shadowlab::techniques::Frame,
            ) -> shadowlab::error::Result<shadowlab::techniques::Shadows> {
                crate::resident::read_back(self, frame)
            }
        }
    };
}
pub(crate) use device_twin;

/// [`ShadowTechnique::render`] through [`OnDevice::render_on_device`]: the view samples
/// uploaded (stage `upload_view`, first), the shadow terms read back (`readback`, last).
pub(crate) fn read_back(t: &mut dyn OnDevice, frame: &Frame) -> Result<Shadows> {
    let gpu = shared()?;
    let name = t.name();
    let mut up = Stats::default();
    let view = up.stage("upload_view", || DeviceView::upload(&gpu, frame.view))?;
    let DeviceShadows {
        visibility,
        mut stats,
    } = t.render_on_device(frame, &view)?;
    stats.stages_ms.splice(0..0, up.stages_ms);
    let bytes = frame.view.triangle.len() as u64 * 12;
    let raw = stats.stage("readback", || {
        gpu.stage(name, "readback", || {
            read_back_bytes(&gpu, &visibility, bytes)
        })
    })??;
    Ok(Shadows::of_frame(frame, to_rgb(&raw), stats))
}

/// Shadow terms computed on the CPU (a frame no map reaches) as a device buffer of the
/// layout [`DeviceShadows::visibility`] has.
pub(crate) fn upload_terms(gpu: &Gpu, terms: &[Vec3]) -> wgpu::Buffer {
    let flat: Vec<f32> = terms.iter().flat_map(|v| v.to_array()).collect();
    let bytes: &[u8] = bytemuck::cast_slice(&flat);
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("the shadow terms"),
            contents: if bytes.is_empty() { &[0; 12] } else { bytes },
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        })
}
