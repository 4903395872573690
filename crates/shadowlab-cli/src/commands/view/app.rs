//! The window and its events: what a person's keys and mouse do, what a script's steps do,
//! when a frame is drawn, and how it reaches the screen (a CPU framebuffer, `softbuffer`).

use super::frame::{self, Drawn};
use super::input::{Drag, Key};
use super::overlay::{self, Inset, Overlays, Rect};
use super::reference::{self, Background, Traced};
use super::screenshot::{self, ErrorFigures};
use super::script::Step;
use super::session::Session;
use super::window::Screen;
use super::Steps;
use anyhow::{anyhow, Result};
use shadowlab::compare::{compare, Metrics};
use shadowlab::picture::RgbImage;
use shadowlab::shade;
use std::path::{Path, PathBuf};
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalPosition;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::window::WindowId;

/// The stage name of laying the overlays and showing the image.
pub const PRESENT: &str = "overlays, present";

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
        /// Frames left.
        left: usize,
        /// Each frame's stages in milliseconds.
        frames: Vec<Vec<(String, f64)>>,
    },
}

/// The error against the reference of the frame shown.
struct ErrorView {
    image: RgbImage,
    figures: ErrorFigures,
}

/// The application: the session, its window and what was drawn.
pub struct App<'a> {
    session: Session<'a>,
    background: &'a Background,
    driver: Driver,
    screenshot_dir: PathBuf,
    window: Option<Screen>,
    drawn: Option<Drawn>,
    composed: Option<(RgbImage, Vec<Rect>)>,
    traced: Option<Traced>,
    requested: Option<reference::Key>,
    error: Option<ErrorView>,
    mouse: (Option<Drag>, Option<PhysicalPosition<f64>>),
    shift: bool,
    frame_ms: f64,
    present_ms: f64,
    frames: u64,
    failure: Option<anyhow::Error>,
}

impl<'a> App<'a> {
    /// An application not yet shown.
    pub fn new(
        session: Session<'a>,
        background: &'a Background,
        driver: Driver,
        screenshot_dir: &Path,
    ) -> Self {
        App {
            session,
            background,
            driver,
            screenshot_dir: screenshot_dir.to_path_buf(),
            window: None,
            drawn: None,
            composed: None,
            traced: None,
            requested: None,
            error: None,
            mouse: (None, None),
            shift: false,
            frame_ms: 0.0,
            present_ms: 0.0,
            frames: 0,
            failure: None,
        }
    }

    /// After the window closed: the failure that closed it, or the benchmark's summary.
    pub fn finish(self) -> Result<()> {
        if let Some(e) = self.failure {
            return Err(e);
        }
        if let Driver::Benchmark { frames, .. } = &self.driver {
            println!("{}", super::benchmark::summary(&self.session.name, frames));
        }
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.failure.get_or_insert(e);
        event_loop.exit();
    }

    /// A person's key or button, unless a script or benchmark drives the window.
    fn person_input(&mut self, event: &WindowEvent) {
        if !matches!(self.driver, Driver::Person) {
            return;
        }
        match event {
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            // Keys released while the window had no keyboard never say so.
            WindowEvent::Focused(false) => {
                self.session.held.clear();
                self.mouse.0 = None;
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let Some(k) = Key::from_winit(&event.logical_key, self.shift) else {
                    return;
                };
                match (event.state, k) {
                    (ElementState::Released, Key::Move(m)) => self.session.release(m),
                    (ElementState::Pressed, k) if !event.repeat => self.session.press(k),
                    _ => {}
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.mouse.0 = match state {
                    ElementState::Pressed => Drag::from_winit(*button),
                    ElementState::Released => None,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (Some(d), Some(last)) = (self.mouse.0, self.mouse.1) {
                    let (dx, dy) = (position.x - last.x, position.y - last.y);
                    self.session.drag(d, dx as f32, dy as f32);
                }
                self.mouse.1 = Some(*position);
            }
            _ => return,
        }
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    /// Plays the script's steps up to the next that needs a frame; false while it waits
    /// for the reference.
    fn play(&mut self, event_loop: &ActiveEventLoop) -> bool {
        loop {
            let (needs_frame, measured) = (self.needs_frame(), self.error.is_some());
            let Driver::Script(steps) = &mut self.driver else {
                return true;
            };
            let Some(step) = steps.front_mut() else {
                event_loop.exit();
                return false;
            };
            match step {
                Step::Key(k) => {
                    let k = *k;
                    steps.pop_front();
                    self.session.press(k);
                    if let Key::Move(m) = k {
                        // A press and release: one frame's step.
                        self.session.fly();
                        self.session.release(m);
                    }
                }
                Step::Drag(d, dx, dy) => {
                    let (d, dx, dy) = (*d, *dx, *dy);
                    steps.pop_front();
                    self.session.drag(d, dx, dy);
                }
                Step::Hold(m, n) => {
                    let m = *m;
                    *n -= 1;
                    if *n == 0 {
                        steps.pop_front();
                    }
                    self.session.press(Key::Move(m));
                    self.session.fly();
                    self.session.release(m);
                    return true;
                }
                Step::Frames(n) => {
                    *n -= 1;
                    if *n == 0 {
                        steps.pop_front();
                    }
                    return true;
                }
                Step::WaitReference => {
                    self.session.show.error = true;
                    self.session.show.overlays = true;
                    if needs_frame || !measured {
                        // Drawn first; then woken when the reference is there.
                        return needs_frame;
                    }
                    steps.pop_front();
                    self.session.stale = true;
                    return true;
                }
                Step::Screenshot(p) => {
                    if needs_frame {
                        return true;
                    }
                    let p = p.clone();
                    steps.pop_front();
                    if let Err(e) = self.screenshot(&p) {
                        self.fail(event_loop, e);
                        return false;
                    }
                }
            }
        }
    }

    fn needs_frame(&self) -> bool {
        self.session.dirty || self.session.stale || self.composed.is_none()
    }

    /// One frame: the driver's input, a new drawing when the view changed (or a
    /// progressive technique refines), the overlays, the screen. Returns whether another
    /// frame should follow at once.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<bool> {
        let t0 = Instant::now();
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
        let refine = self.session.technique.converged() == Some(false);
        let drew = self.session.dirty || refine || self.drawn.is_none();
        if drew {
            self.draw()?;
        }
        let measured = self.error.is_some();
        self.update_error();
        // A script waiting for the reference goes on once it is measured.
        more |= !measured && self.error.is_some();
        let t1 = Instant::now();
        if self.session.stale || self.composed.is_none() || self.session.show.overlays {
            self.compose();
        }
        self.present()?;
        self.present_ms = frame::ms(t1);
        if drew {
            self.frame_ms = frame::ms(t0);
        }
        self.frames += 1;
        if self.session.screenshot {
            self.session.screenshot = false;
            self.key_screenshot();
        }
        if let Driver::Benchmark { left, frames } = &mut self.driver {
            if let Some(d) = &self.drawn {
                let mut stages = d.stages_ms.clone();
                stages.push((PRESENT.to_string(), self.present_ms));
                frames.push(stages);
            }
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
            more = !self.session.held.is_empty() || refine;
        }
        Ok(more)
    }

    /// Draws the view anew.
    fn draw(&mut self) -> Result<()> {
        let s = &mut self.session;
        let dump = s.show.overlays && s.show.dump.is_some();
        let drawn = frame::draw(
            s.scene,
            &s.camera,
            &s.light,
            s.scene_args.layers,
            s.technique.as_mut(),
            dump,
            self.drawn.take(),
        );
        s.dirty = false;
        s.stale = true;
        match drawn {
            Ok(d) => {
                self.drawn = Some(d);
                self.error = None;
                Ok(())
            }
            Err(e) if matches!(self.driver, Driver::Person) => {
                s.status = crate::failure::sentence(&e);
                Ok(())
            }
            Err(e) => Err(e),
        }
    }

    /// Asks the worker for the reference of the view shown, and measures the frame
    /// against it once it is there.
    fn update_error(&mut self) {
        if let Some(t) = self.background.take() {
            self.traced = Some(t);
        }
        let (Some(d), true) = (&self.drawn, self.session.show.error) else {
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
                let vis = &d.shadows.visibility;
                self.error = Some(ErrorView {
                    image: shade::error_image(&d.view, vis, &t.visibility),
                    figures: figures(&compare(&d.view, vis, &t.visibility), key.spp),
                });
                self.session.stale = true;
            }
            _ if self.requested != Some(key) => {
                self.background
                    .request(key, &d.camera, &self.session.light, &d.view);
                self.requested = Some(key);
            }
            _ => {}
        }
    }

    /// Lays the overlays over the drawn view.
    fn compose(&mut self) {
        let Some(d) = &self.drawn else {
            return;
        };
        if let Some(i) = self.session.show.dump {
            if i >= d.dumps.len() {
                // Past the last image: the overlay goes off.
                self.session.show.dump = None;
                if d.dumps.is_empty() {
                    self.session.status = format!("{} shows no images", self.session.name);
                }
            }
        }
        let s = &self.session;
        let mut o = Overlays::default();
        if s.show.overlays {
            o.panel =
                super::panel::lines(s, d, (self.frame_ms, self.present_ms), self.error_line());
            if s.show.error {
                o.error = self.error.as_ref().map(|e| Inset {
                    image: &e.image,
                    caption: format!("error vs {} spp reference", e.figures.reference_spp),
                });
            }
            if let Some(i) = s.show.dump {
                o.dump = d.dumps.get(i).map(|(name, img)| Inset {
                    image: img,
                    caption: name.clone(),
                });
            }
        }
        self.composed = Some(overlay::compose(&d.image, &o));
        self.session.stale = false;
    }

    fn error_line(&self) -> Option<String> {
        if !self.session.show.error {
            return None;
        }
        Some(match &self.error {
            Some(e) => format!(
                "mismatch {:.3}%  mean abs error {:.4}",
                e.figures.mismatch_rate * 100.0,
                e.figures.mean_abs_error
            ),
            None => "error: tracing the reference...".to_string(),
        })
    }

    /// Shows the composed image.
    fn present(&mut self) -> Result<()> {
        match (&mut self.window, &self.composed) {
            (Some(w), Some((img, _))) => w.present(img),
            _ => Ok(()),
        }
    }

    /// Writes the window as it is now to `path`, with its command line.
    fn screenshot(&self, path: &Path) -> Result<()> {
        let Some((img, rects)) = &self.composed else {
            return Ok(());
        };
        let args =
            super::reproduce::render_args(&self.session.state(), &screenshot::render_output(path));
        let shown = self.session.show.overlays && self.session.show.error;
        let error = self.error.as_ref().filter(|_| shown).map(|e| &e.figures);
        let line = screenshot::write(path, img, rects, error, &args)?;
        println!("{}: {line}", path.display());
        Ok(())
    }

    /// The screenshot key: the next free numbered file; a failure goes to the panel.
    fn key_screenshot(&mut self) {
        let result = match screenshot::next_free(&self.screenshot_dir) {
            Some(p) => self.screenshot(&p),
            None => Err(anyhow!(
                "{} holds {} screenshots already",
                self.screenshot_dir.display(),
                screenshot::MAX_NUMBERED
            )),
        };
        if let Err(e) = result {
            self.session.status = crate::failure::sentence(&e);
            self.session.stale = true;
        }
    }
}

impl ApplicationHandler<ReferenceReady> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            let s = &self.session;
            let title = format!("shadowlab view — {}", s.scene.name);
            match Screen::open(event_loop, &title, s.camera.width, s.camera.height) {
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
            e => self.person_input(&e),
        }
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
