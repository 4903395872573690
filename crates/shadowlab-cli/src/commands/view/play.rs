//! The drivers' input: a script's steps played into the session and the panel (a click
//! becomes egui's pointer events at the widget's place in the last frame), and a person's
//! window events, given to the panel first and to the view when the panel does not take
//! them.

use super::app::{no_widget, App, Driver};
use super::input::{Drag, Key};
use super::script::Step;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::NamedKey;

/// The most frames a click waits for its widget to be drawn.
const CLICK_WAIT_FRAMES: usize = 10;

impl App<'_> {
    /// Plays the script's steps up to the next that needs a frame; false while it waits
    /// for the reference.
    pub(super) fn play(&mut self, event_loop: &ActiveEventLoop) -> bool {
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
                Step::Settle => {
                    steps.pop_front();
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
                    self.shot = Some(p.clone());
                    steps.pop_front();
                    return true;
                }
                Step::Click(label) => {
                    if needs_frame {
                        return true;
                    }
                    // A widget not wholly seen (scrolled out of the panel) is scrolled to
                    // first; one still cut after the frames waited is clicked where seen.
                    let whole = !self.widgets.clipped(label);
                    let found = self.widgets.centre(label);
                    let waited = self.click_waits >= CLICK_WAIT_FRAMES;
                    let Some(at) = found.filter(|_| whole || waited) else {
                        // A panel's first frame only measures itself, a list opens a
                        // frame after its click: a few frames are waited for.
                        if !waited {
                            self.click_waits += 1;
                            if self.widgets.clipped(label) {
                                self.scroll_to = Some(label.clone());
                            }
                            return true;
                        }
                        self.scroll_to = None;
                        let e = no_widget(label, &self.widgets);
                        self.fail(event_loop, e);
                        return false;
                    };
                    self.click_waits = 0;
                    self.scroll_to = None;
                    steps.pop_front();
                    steps.push_front(Step::Settle);
                    steps.push_front(Step::Release(at.x, at.y));
                    self.injected
                        .extend([egui::Event::PointerMoved(at), button(at, true)]);
                    return true;
                }
                Step::Release(x, y) => {
                    let at = egui::pos2(*x, *y);
                    steps.pop_front();
                    self.injected.push(button(at, false));
                    return true;
                }
                Step::Type(text) => {
                    let text = text.clone();
                    steps.pop_front();
                    steps.push_front(Step::Settle);
                    self.injected.extend([
                        key(egui::Key::A, egui::Modifiers::COMMAND, true),
                        key(egui::Key::A, egui::Modifiers::COMMAND, false),
                        egui::Event::Text(text),
                        key(egui::Key::Enter, egui::Modifiers::NONE, true),
                        key(egui::Key::Enter, egui::Modifiers::NONE, false),
                    ]);
                    return true;
                }
            }
        }
    }

    /// A window event: to the panel first, then (a person driving, the panel not taking
    /// it) to the view.
    pub(super) fn window_input(&mut self, event: &WindowEvent) {
        let Some(w) = &mut self.window else {
            return;
        };
        if !matches!(self.driver, Driver::Person) {
            return;
        }
        // Tab is the viewer's (the next technique), not egui's focus key, unless a field
        // is being typed into.
        let typing = w.egui.text_edit_focused();
        let tab = matches!(event, WindowEvent::KeyboardInput { event, .. }
            if event.logical_key == winit::keyboard::Key::Named(NamedKey::Tab));
        let consumed = if tab && !typing {
            false
        } else {
            let taken = w.state.on_window_event(&w.window, event);
            if taken.repaint {
                w.request_redraw();
            }
            taken.consumed
        };
        let view_width = f64::from(w.view_size.0);
        let over_view = self.mouse.1.is_some_and(|p| p.x < view_width);
        match event {
            WindowEvent::KeyboardInput { .. } if typing => return,
            WindowEvent::KeyboardInput { .. } => {}
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                ..
            } if !over_view => return,
            WindowEvent::MouseInput { .. } | WindowEvent::CursorMoved { .. } => {}
            _ if consumed => return,
            _ => {}
        }
        self.person_input(event);
    }

    /// A person's key or button in the view.
    fn person_input(&mut self, event: &WindowEvent) {
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
}

/// The primary button pressed or released at `at`.
fn button(at: egui::Pos2, pressed: bool) -> egui::Event {
    egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    }
}

/// A key pressed or released.
fn key(k: egui::Key, modifiers: egui::Modifiers, pressed: bool) -> egui::Event {
    egui::Event::Key {
        key: k,
        physical_key: None,
        pressed,
        repeat: false,
        modifiers,
    }
}
