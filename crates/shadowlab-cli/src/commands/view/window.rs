//! The window on the GPU: a `wgpu` surface on the device every `gpu:` technique shares,
//! the view pass (`blit.wgsl`: the shaded view copied pixel for pixel, the error overlay
//! laid over it) and the panel drawn by egui on top. The window is the view's size plus
//! the panel's column on the right (not resizable, so a pixel of the view is a pixel of
//! `render`'s image); a screenshot draws the same frame into a texture and reads it back.
//!
//! A benchmark drawn offscreen (`--offscreen`, or an adapter that cannot present to the
//! window) draws each frame into a texture of the window's size instead and waits for it:
//! the same work but the swap, and the report says so.

use crate::failure::bad_input;
use anyhow::{anyhow, Result};
use shadowlab::picture::RgbImage;
use shadowlab_gpu::device::Gpu;
use std::sync::Arc;
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// Width of the panel's column in pixels.
pub const PANEL_WIDTH: u32 = 340;

/// The least window height, so that the panel has room beside a small view (it scrolls
/// when it is taller than the window).
pub const MIN_HEIGHT: u32 = 360;

/// The view pass's uniform (`Blit` of `blit.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlitU {
    width: u32,
    height: u32,
    error_on: u32,
    pad: u32,
}

/// The view's textures on the device: the shaded view and the error overlay (RGBA8, the
/// overlay's alpha 0 where there is no error).
pub struct ViewTextures {
    /// The shaded view.
    pub view: wgpu::Texture,
    /// The error overlay.
    pub error: wgpu::Texture,
}

/// How frames reach the screen.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Drawing {
    /// Into the window, at the display's refresh.
    Window,
    /// A benchmark: into the window as fast as it goes, or offscreen when the adapter
    /// cannot present to it.
    Benchmark,
    /// A benchmark drawn offscreen (`--offscreen`).
    Offscreen,
}

/// What a frame is drawn into: the window's surface, or (a benchmark on an adapter that
/// cannot present to this display) a texture of its size.
enum Target {
    Surface {
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
    },
    Offscreen(wgpu::Texture),
}

/// An open window with its surface, egui and the view pass.
pub struct Screen {
    /// The window.
    pub window: Arc<Window>,
    /// The shared device.
    pub gpu: Arc<Gpu>,
    target: Target,
    size: (u32, u32),
    target_format: wgpu::TextureFormat,
    /// egui's context.
    pub egui: egui::Context,
    /// egui's window state (its input).
    pub state: egui_winit::State,
    renderer: egui_wgpu::Renderer,
    blit: wgpu::RenderPipeline,
    /// The view's textures.
    pub textures: ViewTextures,
    /// The view's size.
    pub view_size: (u32, u32),
}

/// What one frame of egui drew.
pub struct Painted {
    /// Its primitives.
    pub jobs: Vec<egui::ClippedPrimitive>,
    /// Its texture changes.
    pub textures: egui::TexturesDelta,
    /// Pixels per point.
    pub ppp: f32,
}

fn rgba_texture(gpu: &Gpu, label: &str, (w, h): (u32, u32)) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    })
}

impl Screen {
    /// Opens a window for a view of `width` × `height` pixels titled `title`, on `gpu`,
    /// drawn as `drawing` says.
    pub fn open(
        event_loop: &ActiveEventLoop,
        gpu: Arc<Gpu>,
        title: &str,
        (width, height): (u32, u32),
        drawing: Drawing,
    ) -> Result<Self> {
        let size = PhysicalSize::new(width + PANEL_WIDTH, height.max(MIN_HEIGHT));
        let attrs = Window::default_attributes()
            .with_title(title)
            .with_inner_size(size)
            .with_resizable(false);
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| bad_input(format!("view cannot open a window: {e}")))?,
        );
        // Offscreen, no surface is made: the adapter may have been opened without the display.
        let surface = match drawing {
            Drawing::Offscreen => None,
            _ => match gpu.instance.create_surface(window.clone()) {
                Ok(s) => Some(s),
                Err(_) if drawing == Drawing::Benchmark => None,
                Err(e) => return Err(anyhow!("cannot draw into the window with the GPU: {e}")),
            },
        };
        let on_surface =
            surface.and_then(|s| surface_target(&gpu, s, size, drawing == Drawing::Window));
        let (target, target_format) = match on_surface {
            Some(t) => t,
            None if drawing != Drawing::Window => {
                let format = wgpu::TextureFormat::Rgba8Unorm;
                let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("the offscreen window"),
                    size: wgpu::Extent3d {
                        width: size.width,
                        height: size.height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                });
                (Target::Offscreen(t), format)
            }
            None => {
                return Err(bad_input(format!(
                    "the GPU adapter {} cannot draw into this window",
                    gpu.adapter.name
                )))
            }
        };
        let egui = egui::Context::default();
        let state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(1.0),
            None,
            Some(gpu.limits.max_texture_dimension_2d as usize),
        );
        let renderer = egui_wgpu::Renderer::new(
            &gpu.device,
            target_format,
            egui_wgpu::RendererOptions::PREDICTABLE,
        );
        let blit = blit_pipeline(&gpu.device, target_format);
        let textures = ViewTextures {
            view: rgba_texture(&gpu, "the view", (width, height)),
            error: rgba_texture(&gpu, "the error overlay", (width, height)),
        };
        window.request_redraw();
        Ok(Screen {
            window,
            gpu,
            target,
            size: (size.width, size.height),
            target_format,
            egui,
            state,
            renderer,
            blit,
            textures,
            view_size: (width, height),
        })
    }

    /// Whether frames go to a texture instead of the window (see the module's note).
    pub fn offscreen(&self) -> bool {
        matches!(self.target, Target::Offscreen(_))
    }

    /// Asks for a frame.
    pub fn request_redraw(&self) {
        self.window.request_redraw();
    }

    /// Writes an RGB image (the view's size) into `texture`, alpha `alpha`.
    pub fn upload(&self, texture: &wgpu::Texture, img: &RgbImage, alpha: impl Fn(&[u8; 3]) -> u8) {
        let rgba: Vec<u8> = img
            .pixels()
            .flat_map(|p| [p.0[0], p.0[1], p.0[2], alpha(&p.0)])
            .collect();
        self.gpu.queue.write_texture(
            texture.as_image_copy(),
            &rgba,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(img.width() * 4),
                rows_per_image: Some(img.height()),
            },
            texture.size(),
        );
    }

    /// egui's texture for `texture` (a technique's map in the panel).
    pub fn native_texture(&mut self, texture: &wgpu::TextureView) -> egui::TextureId {
        self.renderer
            .register_native_texture(&self.gpu.device, texture, wgpu::FilterMode::Nearest)
    }

    /// Forgets egui's texture `id`.
    pub fn free_texture(&mut self, id: egui::TextureId) {
        self.renderer.free_texture(&id);
    }

    /// Draws the view (with the error overlay when `error_on`) and egui's `painted` into
    /// the window; with `capture`, draws the same into a texture and returns it read back
    /// (`None` when the window could not be drawn this time: the caller asks again).
    pub fn present(
        &mut self,
        painted: Painted,
        error_on: bool,
        capture: bool,
    ) -> Result<Option<RgbImage>> {
        for (id, deltas) in &painted.textures.set {
            for delta in deltas {
                self.renderer
                    .update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.size.0, self.size.1],
            pixels_per_point: painted.ppp,
        };
        let gpu = self.gpu.clone();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let extra = self.renderer.update_buffers(
            &gpu.device,
            &gpu.queue,
            &mut encoder,
            &painted.jobs,
            &screen,
        );
        let blit_u = BlitU {
            width: self.view_size.0,
            height: self.view_size.1,
            error_on: u32::from(error_on),
            pad: 0,
        };
        let blit_u = shadowlab_gpu::transfer::uniform(&gpu, "the view pass", &blit_u);
        let view = self.textures.view.create_view(&Default::default());
        let error = self.textures.error.create_view(&Default::default());
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("the view pass"),
            layout: &self.blit.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: blit_u.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&error),
                },
            ],
        });
        let (frame, texture) = match &self.target {
            Target::Surface { surface, config } => match surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(f)
                | wgpu::CurrentSurfaceTexture::Suboptimal(f) => {
                    let t = f.texture.clone();
                    (Some(f), t)
                }
                wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                    return Ok(None)
                }
                _ => {
                    // Outdated or lost: configured again, drawn on the next frame.
                    surface.configure(&gpu.device, config);
                    return Ok(None);
                }
            },
            Target::Offscreen(t) => (None, t.clone()),
        };
        let target = texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.target_format),
            ..Default::default()
        });
        self.draw(&mut encoder, &target, &group, &painted.jobs, &screen);
        let captured = if capture {
            let t = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: texture.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: self.target_format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let v = t.create_view(&Default::default());
            self.draw(&mut encoder, &v, &group, &painted.jobs, &screen);
            Some(t)
        } else {
            None
        };
        gpu.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        match frame {
            Some(f) => gpu.queue.present(f),
            // Offscreen, the frame counts until the GPU has drawn it.
            None => gpu
                .device
                .poll(wgpu::PollType::wait_indefinitely())
                .map(|_| ())
                .map_err(|e| anyhow!("waiting for the GPU to draw the frame failed: {e}"))?,
        }
        for id in &painted.textures.free {
            self.renderer.free_texture(id);
        }
        match captured {
            Some(t) => Ok(Some(super::capture::read_rgb(&gpu, &t)?)),
            None => Ok(None),
        }
    }

    fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        group: &wgpu::BindGroup,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("view and panel"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let mut pass = pass.forget_lifetime();
        pass.set_pipeline(&self.blit);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
        self.renderer.render(&mut pass, jobs, screen);
    }
}

/// The window's surface configured for drawing, and the format frames are drawn in; `None`
/// when the adapter cannot present to it.
fn surface_target(
    gpu: &Gpu,
    surface: wgpu::Surface<'static>,
    size: PhysicalSize<u32>,
    vsync: bool,
) -> Option<(Target, wgpu::TextureFormat)> {
    let caps = surface.get_capabilities(&gpu.handle);
    let &format = caps
        .formats
        .iter()
        .find(|f| !f.is_srgb())
        .or(caps.formats.first())?;
    // The view's bytes go to the window unchanged: through a non-sRGB view.
    let target_format = format.remove_srgb_suffix();
    let config = wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: size.width,
        height: size.height,
        // A benchmark times the frames, not the display's refresh.
        present_mode: if vsync {
            wgpu::PresentMode::AutoVsync
        } else {
            wgpu::PresentMode::AutoNoVsync
        },
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        color_space: wgpu::SurfaceColorSpace::Auto,
        view_formats: if target_format == format {
            vec![]
        } else {
            vec![target_format]
        },
    };
    surface.configure(&gpu.device, &config);
    Some((Target::Surface { surface, config }, target_format))
}

fn blit_pipeline(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("blit.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("blit.wgsl").into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("the view pass"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}
