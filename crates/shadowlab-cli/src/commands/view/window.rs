//! The window and its framebuffer: opened at the image's size (not resizable, so a pixel
//! of the window is a pixel of the image), filled on the CPU and shown (`softbuffer`).

use crate::failure::bad_input;
use anyhow::{anyhow, Result};
use shadowlab::picture::RgbImage;
use std::num::NonZeroU32;
use std::rc::Rc;
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// An open window with its framebuffer.
pub struct Screen {
    window: Rc<Window>,
    surface: softbuffer::Surface<Rc<Window>, Rc<Window>>,
}

impl Screen {
    /// Opens a window of `width` × `height` pixels titled `title`.
    pub fn open(
        event_loop: &ActiveEventLoop,
        title: &str,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let attrs = Window::default_attributes()
            .with_title(title)
            .with_inner_size(PhysicalSize::new(width, height))
            .with_resizable(false);
        let window = Rc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| bad_input(format!("view cannot open a window: {e}")))?,
        );
        let context = softbuffer::Context::new(window.clone())
            .map_err(|e| anyhow!("cannot draw into the window: {e}"))?;
        let mut surface = softbuffer::Surface::new(&context, window.clone())
            .map_err(|e| anyhow!("cannot draw into the window: {e}"))?;
        if let (Some(w), Some(h)) = (NonZeroU32::new(width), NonZeroU32::new(height)) {
            surface
                .resize(w, h)
                .map_err(|e| anyhow!("cannot size the window's buffer: {e}"))?;
        }
        window.request_redraw();
        Ok(Screen { window, surface })
    }

    /// Asks for a frame.
    pub fn request_redraw(&self) {
        self.window.request_redraw();
    }

    /// Shows `img`.
    pub fn present(&mut self, img: &RgbImage) -> Result<()> {
        let mut buf = self
            .surface
            .buffer_mut()
            .map_err(|e| anyhow!("cannot draw into the window: {e}"))?;
        for (dst, p) in buf.iter_mut().zip(img.pixels()) {
            let [r, g, b] = p.0;
            *dst = (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b);
        }
        buf.present()
            .map_err(|e| anyhow!("cannot show the window's image: {e}"))
    }
}
