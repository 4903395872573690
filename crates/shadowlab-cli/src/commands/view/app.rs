//! The window and its frames: each frame takes the driver's input (a person's keys and
//! mouse, a script's steps, a benchmark's turn), runs the panel (egui), applies what was
//! done there, draws the view when it changed, measures it against the reference, and
//! shows view, error overlay and panel on the window's surface (`window`).

use super::frame::{self, Drawn};
use super::gpu_shade::{GpuShading, OnDeviceFrame};
use super::input::Drag;
use super::map_view::MapView;
use super::reference::{self, Background, Traced};
use super::screenshot::{self, ErrorFigures};
use super::session::{Session, Technique};
use super::ui::{self, Action, Fields, Widgets};
use super::window::{Drawing, Screen};
use super::{panel, Steps};
use anyhow::Result;
use shadowlab::compare::{compare, Metrics};
use shadowlab::shade;
use shadowlab_gpu::device::Gpu;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalPosition;
use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::WindowId;

/// The stage name of running the panel and showing the frame.
pub const PRESENT: &str = "panel, present";

/// The stage name of putting the view and the error overlay into the window's textures.
pub const UPLOAD: &str = "view to the window";

/// The stage name of measuring the error on the device.
pub const ERROR_STAGE: &str = "error vs gpu:raytrace";

/// The worker's message: a reference is ready.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceReady;

/// Who drives the window.
pub enum Driver {
    /// A person, through the keyboard and mouse.
    Person,
    /// A script's steps.
    Script(Steps),
    /// A benchmark: frames left to draw, and each drawn frame's stages.
    Benchmark {
        /// Frames left, the warm-up frame's included.
        left: usize,
        /// Whether the next drawn frame is the warm-up (its pipelines made, its buffers
        /// allocated, the reference's scene uploaded), which is drawn but not counted.
        warm_up: bool,
        /// Each frame's stages in milliseconds.
        frames: Vec<Vec<(String, f64)>>,
        /// Drawn offscreen even where the adapter can present (`--offscreen`).
        offscreen: bool,
    },
}

/// The application: the session, its window and what was drawn.
pub struct App<'a> {
    pub(super) session: Session<'a>,
    pub(super) background: &'a Background,
    pub(super) driver: Driver,
    pub(super) screenshot_dir: PathBuf,
    pub(super) gpu: Arc<Gpu>,
    pub(super) window: Option<Screen>,
    pub(super) drawn: Option<Drawn>,
    pub(super) traced: Option<Traced>,
    pub(super) requested: Option<reference::Key>,
    pub(super) error: Option<ErrorFigures>,
    pub(super) mouse: (Option<Drag>, Option<PhysicalPosition<f64>>),
    pub(super) shift: bool,
    pub(super) history: VecDeque<Vec<(String, f64)>>,
    pub(super) failure: Option<anyhow::Error>,
    pub(super) fields: Fields,
    pub(super) widgets: Widgets,
    pub(super) injected: Vec<egui::Event>,
    pub(super) shot: Option<PathBuf>,
    pub(super) shading: Option<GpuShading>,
    pub(super) on_device: Option<OnDeviceFrame>,
    pub(super) measure_ms: f64,
    pub(super) upload_ms: f64,
    pub(super) map_layers: u32,
    pub(super) map_view: Option<MapView>,
    pub(super) click_waits: usize,
    pub(super) scroll_to: Option<String>,
    pub(super) dump: Option<(usize, egui::TextureHandle, [f32; 2])>,
    pub(super) clipboard: Option<arboard::Clipboard>,
    pub(super) cpu_names: Vec<String>,
    pub(super) gpu_names: Vec<String>,
}

impl<'a> App<'a> {
    /// An application not yet shown, drawing on `gpu`.
    pub fn new(
        session: Session<'a>,
        background: &'a Background,
        driver: Driver,
        screenshot_dir: &Path,
        gpu: Arc<Gpu>,
    ) -> Self {
        App {
            session,
            background,
            driver,
            screenshot_dir: screenshot_dir.to_path_buf(),
            gpu,
            window: None,
            drawn: None,
            traced: None,
            requested: None,
            error: None,
            mouse: (None, None),
            shift: false,
            history: VecDeque::new(),
            failure: None,
            fields: Fields::default(),
            widgets: Widgets::default(),
            injected: Vec::new(),
            shot: None,
            shading: None,
            on_device: None,
            measure_ms: 0.0,
            upload_ms: 0.0,
            map_layers: 0,
            map_view: None,
            click_waits: 0,
            scroll_to: None,
            dump: None,
            clipboard: None,
            cpu_names: panel::cpu_names(),
            gpu_names: panel::gpu_names(),
        }
    }

    /// After the window closed: the failure that closed it, or the benchmark's summary.
    pub fn finish(self) -> Result<()> {
        if let Some(e) = self.failure {
            return Err(e);
        }
        if let Driver::Benchmark { frames, .. } = &self.driver {
            println!("{}", super::benchmark::summary(&self.session.name, frames));
            if self.window.as_ref().is_some_and(|w| w.offscreen()) {
                println!("{}", super::benchmark::OFFSCREEN);
            }
            println!("adapter: {}", self.gpu.adapter.label());
        }
        Ok(())
    }

    pub(super) fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.failure.get_or_insert(e);
        event_loop.exit();
    }

    pub(super) fn needs_frame(&self) -> bool {
        self.session.dirty || self.session.stale || self.drawn.is_none()
    }

    /// One frame: the driver's input, the panel and its actions, a new drawing when the
    /// view changed (or a progressive technique refines), the error, the screen. Returns
    /// whether another frame should follow at once.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<bool> {
        let mut more = match &mut self.driver {
            Driver::Person => {
                self.session.fly();
                true
            }
            Driver::Script(_) => self.play(event_loop),
            Driver::Benchmark { left, .. } => {
                // Every frame a new view, as while the camera turns: 0.2° to the right.
                self.session.drag(Drag::Look, 1.0, 0.0);
                *left -= 1;
                true
            }
        };
        let t_panel = Instant::now();
        let (actions, painted, egui_again) = self.run_panel();
        for a in actions {
            match panel::apply(&mut self.session, a) {
                Some(Action::Screenshot) => self.session.screenshot = true,
                Some(Action::CopyCommand) => self.copy_command(),
                _ => {}
            }
        }
        let panel_ms = frame::ms(t_panel);
        let refine = self.session.technique.converged() == Some(false);
        let drew = self.session.dirty || refine || self.drawn.is_none();
        if drew {
            self.draw()?;
        }
        let measured = self.error.is_some();
        self.update_error();
        // A script waiting for the reference goes on once it is measured.
        more |= !measured && self.error.is_some();
        if self.session.screenshot {
            // The screenshot key: this frame, as the keys before it left it.
            self.session.screenshot = false;
            self.key_screenshot();
        }
        let t_present = Instant::now();
        let shot = self.shot.take();
        let capture = shot.is_some();
        let show = &self.session.show;
        let error_on = show.overlays && show.error && self.error.is_some();
        let shown = match &mut self.window {
            Some(w) => w.present(painted, error_on, capture)?,
            None => None,
        };
        self.session.stale = false;
        match (shot, shown) {
            (Some(p), Some(img)) => self.screenshot(&p, &img)?,
            // Not drawn this time: the next frame takes it.
            (Some(p), None) => {
                self.shot = Some(p);
                more = true;
            }
            _ => {}
        }
        let present_ms = frame::ms(t_present);
        if drew {
            self.record(panel_ms + present_ms);
        }
        if let Driver::Benchmark { left, .. } = &self.driver {
            if *left == 0 {
                event_loop.exit();
                more = false;
            }
        }
        if self.session.quit {
            event_loop.exit();
            more = false;
        }
        if matches!(self.driver, Driver::Person) {
            more = !self.session.held.is_empty() || refine || egui_again || self.shot.is_some();
        }
        Ok(more)
    }

    /// Records a drawn frame's stages (the panel's and the present's time, the view's and
    /// error's upload, and the GPU's own stage times apart) for the plot and the benchmark.
    fn record(&mut self, present_ms: f64) {
        let Some(d) = &self.drawn else {
            return;
        };
        let mut stages = d.stages_ms.clone();
        if d.image.is_some() {
            stages.push((UPLOAD.to_string(), self.upload_ms));
        }
        stages.push((PRESENT.to_string(), present_ms));
        if self.measure_ms > 0.0 {
            stages.push((ERROR_STAGE.to_string(), self.measure_ms));
        }
        let gpu: Vec<(String, f64)> = d
            .counters
            .iter()
            .filter_map(|(k, v)| {
                let stage = k.strip_prefix("gpu_")?.strip_suffix("_ms")?;
                Some((format!("{}{stage}", super::benchmark::GPU_PREFIX), *v))
            })
            .collect();
        self.history.push_back(stages.clone());
        while self.history.len() > ui::HISTORY {
            self.history.pop_front();
        }
        if let Driver::Benchmark {
            frames, warm_up, ..
        } = &mut self.driver
        {
            match warm_up {
                true => *warm_up = false,
                false => frames.push(stages.into_iter().chain(gpu).collect()),
            }
        }
    }

    pub(super) fn render_args(&self, shot: &Path) -> Vec<String> {
        let mut state = self.session.state();
        state.gpu_camera_pass = self.drawn.as_ref().is_some_and(|d| d.gpu_camera_pass);
        super::reproduce::render_args(&state, &screenshot::render_output(shot))
    }

    /// Draws the view anew and uploads it.
    fn draw(&mut self) -> Result<()> {
        let drawn = self.draw_either();
        let s = &mut self.session;
        s.dirty = false;
        s.stale = true;
        match drawn {
            Ok((d, on_device)) => {
                let t0 = Instant::now();
                if let (Some(w), Some(img)) = (&self.window, &d.image) {
                    w.upload(&w.textures.view, img, |_| 255);
                }
                self.upload_ms = frame::ms(t0);
                self.drawn = Some(d);
                self.on_device = on_device;
                self.error = None;
                self.measure_ms = 0.0;
                self.show_dump();
                self.show_map();
                Ok(())
            }
            Err(e) if matches!(self.driver, Driver::Person) => {
                s.status = crate::failure::sentence(&e);
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    /// Whether the frame is drawn on the device: a technique that stays there, without
    /// its own images, the layers behind semi-transparent surfaces or an area light (drawn
    /// as `render` draws them, their error against the CPU's soft reference).
    pub(super) fn on_device_path(&self) -> bool {
        let s = &self.session;
        matches!(s.technique, Technique::Device(_))
            && !(s.show.overlays && s.show.dump.is_some())
            && !s.scene_args.layers
            && s.area.is_none()
    }

    /// The frame drawn on the device or, for every other technique, as `render` draws it.
    fn draw_either(&mut self) -> Result<(Drawn, Option<OnDeviceFrame>)> {
        let on_device = self.on_device_path();
        let s = &mut self.session;
        let previous = self.drawn.take();
        match (&mut s.technique, &self.window, on_device) {
            (Technique::Device(t), Some(w), true) => {
                if self.shading.is_none() {
                    self.shading = Some(GpuShading::new(self.gpu.clone(), s.scene)?);
                }
                let shading = self.shading.as_ref().expect("made above");
                let target = &w.textures.view;
                let previous = (previous, self.on_device.take());
                let (d, on) =
                    shading.draw((s.scene, &s.camera, &s.light), t.as_mut(), previous, target)?;
                Ok((d, Some(on)))
            }
            _ => {
                let dump = s.show.overlays && s.show.dump.is_some();
                let d = frame::draw(
                    s.scene,
                    &s.camera,
                    (&s.light, s.area.as_ref(), s.light_samples),
                    s.scene_args.layers,
                    &mut *s.technique,
                    dump,
                    previous,
                )?;
                Ok((d, None))
            }
        }
    }

    /// Asks the worker for the reference of the view shown, and measures the frame
    /// against it once it is there; the error image goes to the overlay's texture.
    fn update_error(&mut self) {
        if let Some(t) = self.background.take() {
            self.traced = Some(t);
        }
        if self.on_device.is_some() {
            self.measure_on_device();
            return;
        }
        let (Some(d), true) = (&self.drawn, self.session.show.error) else {
            return;
        };
        let Some(shadows) = &d.shadows else {
            return;
        };
        let key = reference::Key {
            view: self.session.view_number,
            spp: reference::spp_for(&self.session.name),
        };
        match &self.traced {
            Some(t) if t.key == key => {
                if self.error.is_some() {
                    return;
                }
                let vis = &shadows.visibility;
                let img = shade::error_image(&d.view, vis, &t.visibility);
                if let Some(w) = &self.window {
                    // Where the technique agrees with the reference (black) or nothing is
                    // covered (grey), the overlay is clear.
                    w.upload(&w.textures.error, &img, |p| match p {
                        [0, 0, 0] | [40, 40, 40] => 0,
                        _ => 255,
                    });
                }
                self.error = Some(figures(&compare(&d.view, vis, &t.visibility), key.spp));
                self.session.stale = true;
            }
            _ if self.requested != Some(key) => {
                let s = &self.session;
                let light = (&s.light, s.area.as_ref(), s.light_samples);
                self.background.request(key, &d.camera, light, &d.view);
                self.requested = Some(key);
            }
            _ => {}
        }
    }
}

impl ApplicationHandler<ReferenceReady> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            let s = &self.session;
            let title = format!("shadowlab view — {}", s.scene.name);
            let (w, h) = (s.camera.width, s.camera.height);
            let drawing = match self.driver {
                Driver::Benchmark {
                    offscreen: true, ..
                } => Drawing::Offscreen,
                Driver::Benchmark { .. } => Drawing::Benchmark,
                _ => Drawing::Window,
            };
            match Screen::open(event_loop, self.gpu.clone(), &title, (w, h), drawing) {
                Ok(w) => self.window = Some(w),
                Err(e) => self.fail(event_loop, e),
            }
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, _: ReferenceReady) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => match self.frame(event_loop) {
                Ok(true) => {
                    if let Some(w) = &self.window {
                        w.request_redraw();
                    }
                }
                Ok(false) => {}
                Err(e) => self.fail(event_loop, e),
            },
            e => self.window_input(&e),
        }
    }
}

impl App<'_> {
    /// The error of a frame drawn on the device, against gpu:raytrace traced there; once
    /// for each frame drawn.
    fn measure_on_device(&mut self) {
        let s = &self.session;
        let (Some(d), Some(on), Some(shading), Some(w), true, None) = (
            &mut self.drawn,
            &self.on_device,
            &mut self.shading,
            &self.window,
            s.show.error,
            &self.error,
        ) else {
            return;
        };
        let t0 = Instant::now();
        let spp = reference::spp_for(&s.name);
        match shading.measure(s.scene, &s.light, d, on, spp, &w.textures.error) {
            Ok((f, times)) => {
                self.error = Some(f);
                d.counters.extend(times);
            }
            Err(e) => {
                self.session.status = crate::failure::sentence(&e);
                self.session.show.error = false;
            }
        }
        self.measure_ms = frame::ms(t0);
        self.session.stale = true;
    }
}

/// The figures of a comparison against a reference of `spp` samples per pixel.
fn figures(m: &Metrics, spp: u32) -> ErrorFigures {
    ErrorFigures {
        mismatch_rate: m.mismatch_rate,
        mean_abs_error: m.mean_abs_error,
        reference_spp: spp,
    }
}

/// The error of a missing widget, for scripts.
pub fn no_widget(label: &str, w: &Widgets) -> anyhow::Error {
    crate::failure::bad_input(format!(
        "no widget labelled {label:?} in the panel; it shows {}",
        w.labels().join(", ")
    ))
}
