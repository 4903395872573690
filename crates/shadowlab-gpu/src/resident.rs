//! The shadow term kept on the device: for a window that shades and measures on the GPU
//! (the viewer), a technique may leave its result in a device buffer instead of reading it
//! back. Techniques opt in by implementing [`OnDevice`];
//! `techniques::create_on_device` makes those that do by name, and every other
//! technique works as before through [`ShadowTechnique::render`] (its result uploaded by
//! the caller).

use shadowlab::error::Result;
use shadowlab::techniques::{Frame, ShadowTechnique, Stats};

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
    /// `view` holds the frame's camera-pass samples already uploaded
    /// ([`crate::upload::view_buffer`]). Small control words (timestamps, a technique's
    /// overflow flags) may still be read.
    fn render_on_device(&mut self, frame: &Frame, view: &wgpu::Buffer) -> Result<DeviceShadows>;

    /// The last frame's depth maps, for a viewer to show: a `Depth32Float` array texture,
    /// one layer a light view, holding linear depth over the view's far plane. `None` for
    /// a technique without maps.
    fn depth_maps(&self) -> Option<&wgpu::Texture> {
        None
    }
}
