//! What the viewer shows and how keys and drags change it: the camera, the light, the
//! technique with the parameters the user set, which overlays are on. Changes that need a
//! new frame mark it `dirty`; those that only change the overlays mark it `stale`.

use super::input::{Drag, Key, Move};
use super::reproduce::{self, ViewState};
use super::{area, fly};
use crate::args::SceneArgs;
use crate::config::parse::make_technique;
use crate::failure;
use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::scene::Scene;
use shadowlab::techniques::{self, ParamRange, ShadowTechnique};
use shadowlab_gpu::resident::OnDevice;
use std::collections::{BTreeMap, BTreeSet};

/// Which overlays are on.
pub struct Show {
    /// Any overlay at all (H turns them all off).
    pub overlays: bool,
    /// The error against the reference.
    pub error: bool,
    /// The technique's image shown, by its index among those it dumps.
    pub dump: Option<usize>,
    /// The layer of the technique's depth maps shown (drawn on the device).
    pub map: Option<u32>,
}

/// A technique, with its on-device path when it has one.
pub enum Technique {
    /// Any technique: its shadow term comes back to the CPU.
    Any(Box<dyn ShadowTechnique>),
    /// A GPU technique whose shadow term can stay on the device.
    Device(Box<dyn OnDevice>),
}

impl std::ops::Deref for Technique {
    type Target = dyn ShadowTechnique;
    fn deref(&self) -> &Self::Target {
        match self {
            Technique::Any(t) => t.as_ref(),
            Technique::Device(t) => t.as_ref(),
        }
    }
}

impl std::ops::DerefMut for Technique {
    fn deref_mut(&mut self) -> &mut Self::Target {
        match self {
            Technique::Any(t) => t.as_mut(),
            Technique::Device(t) => t.as_mut(),
        }
    }
}

/// The technique `name` with `params`: on the device where it can stay there.
fn make(name: &str, params: &[(String, String)]) -> anyhow::Result<Technique> {
    match shadowlab_gpu::techniques::create_on_device(name) {
        Some(mut t) => {
            for (k, v) in params {
                t.set_param(k, v)?;
            }
            Ok(Technique::Device(t))
        }
        None => Ok(Technique::Any(make_technique(name, params)?)),
    }
}

/// The state of the viewer.
pub struct Session<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The scene flags as given.
    pub scene_args: &'a SceneArgs,
    /// The camera (its depth range fitted when drawn).
    pub camera: Camera,
    /// The light, as `render --light` reads it back (an area light's stand-in: its
    /// centre, as hard techniques see it).
    pub light: Light,
    /// The area light, when the light has an area.
    pub area: Option<AreaLight>,
    /// Light samples per pixel under an area light (`--light-samples`).
    pub light_samples: u32,
    /// The technique's name as the command line spells it.
    pub name: String,
    /// The technique.
    pub technique: Technique,
    /// The parameters the user set, per technique.
    params: BTreeMap<String, Vec<(String, String)>>,
    /// Changes whenever the camera or light moves.
    pub view_number: u64,
    /// A new frame is needed.
    pub dirty: bool,
    /// The overlays changed.
    pub stale: bool,
    /// The flight keys held.
    pub held: BTreeSet<Move>,
    /// The overlays on.
    pub show: Show,
    /// The last message for the panel (a parameter refused, say).
    pub status: String,
    /// A screenshot is asked for.
    pub screenshot: bool,
    /// Quit is asked for.
    pub quit: bool,
}

impl<'a> Session<'a> {
    /// The session at the start: `technique` with `params`, the setup's camera and light
    /// (with its area light, when it has one).
    pub fn new(
        scene: &'a Scene,
        scene_args: &'a SceneArgs,
        camera: Camera,
        (light, area): (&Light, Option<&AreaLight>),
        technique: &str,
        params: Vec<(String, String)>,
    ) -> anyhow::Result<Self> {
        let t = make(technique, &params)?;
        let (light, area) = reproduce::as_rendered_area(light, area)?;
        Ok(Session {
            scene,
            scene_args,
            camera,
            light,
            area,
            light_samples: scene_args.light_samples,
            name: technique.to_string(),
            technique: t,
            params: BTreeMap::from([(technique.to_string(), params)]),
            view_number: 0,
            dirty: true,
            stale: true,
            held: BTreeSet::new(),
            show: Show {
                overlays: true,
                error: false,
                dump: None,
                map: None,
            },
            status: String::new(),
            screenshot: false,
            quit: false,
        })
    }

    /// The parameters the user set on the current technique.
    pub fn params(&self) -> &[(String, String)] {
        self.params.get(&self.name).map_or(&[], |p| p.as_slice())
    }

    /// What the view is made of, for its command line.
    pub fn state(&self) -> ViewState<'_> {
        ViewState {
            scene: self.scene_args,
            camera: &self.camera,
            light: &self.light,
            area: self.area.as_ref(),
            light_samples: self.light_samples,
            technique: &self.name,
            params: self.params(),
            gpu_camera_pass: false,
        }
    }

    /// A key pressed (flight keys: pressed down).
    pub fn press(&mut self, k: Key) {
        self.stale = true;
        match k {
            Key::Move(m) => {
                self.held.insert(m);
            }
            Key::NextTechnique => self.switch(1),
            Key::PreviousTechnique => self.switch(techniques::ALL.len() - 1),
            Key::ParamUp => self.step_param(true),
            Key::ParamDown => self.step_param(false),
            Key::Error => self.show.error = !self.show.error,
            Key::Dumps => {
                self.show.dump = match self.show.dump {
                    None => Some(0),
                    Some(i) => Some(i + 1),
                };
                self.dirty = true;
            }
            Key::HideOverlays => self.show.overlays = !self.show.overlays,
            Key::Screenshot => self.screenshot = true,
            Key::Quit => self.quit = true,
        }
    }

    /// A flight key released.
    pub fn release(&mut self, m: Move) {
        self.held.remove(&m);
    }

    /// One frame's flight: a step for each held key.
    pub fn fly(&mut self) {
        if !self.held.is_empty() {
            fly::fly(&mut self.camera, &self.held, self.scene);
            self.moved();
        }
    }

    /// A mouse drag by (dx, dy) pixels.
    pub fn drag(&mut self, d: Drag, dx: f32, dy: f32) {
        match d {
            Drag::Look => fly::look(&mut self.camera, dx, dy),
            Drag::Light => {
                let turned = fly::drag_light(&self.light, &self.camera, self.scene, dx, dy);
                match self.area {
                    Some(a) => {
                        let (shape, size) = area::shape_of(&a);
                        let (l, a) = area::make(shape, size, &turned, self.scene);
                        self.set_area(l, a);
                    }
                    None => self.set_light(turned),
                }
                return;
            }
        }
        self.moved();
    }

    fn moved(&mut self) {
        self.view_number += 1;
        self.dirty = true;
        self.stale = true;
    }

    /// Switches to the technique `by` places further in the list.
    fn switch(&mut self, by: usize) {
        let all = techniques::ALL;
        let at = all.iter().position(|n| *n == self.name).unwrap_or(0);
        self.set_technique(all[(at + by) % all.len()]);
    }

    /// Switches to the technique `name`, with the parameters the user set on it before.
    pub fn set_technique(&mut self, name: &str) {
        let params = self.params.get(name).cloned().unwrap_or_default();
        match make(name, &params) {
            Ok(t) => {
                self.technique = t;
                self.name = name.to_string();
                self.show.dump = None;
                self.show.map = None;
                self.dirty = true;
                self.stale = true;
                self.status.clear();
            }
            Err(e) => self.status = failure::sentence(&e),
        }
    }

    /// Sets the current technique's parameter `key` to `text` (a refusal goes to the
    /// panel's message).
    pub fn set_param(&mut self, key: &str, text: &str) {
        self.stale = true;
        match self.technique.set_param(key, text) {
            Ok(()) => {
                let p = self.params.entry(self.name.clone()).or_default();
                p.retain(|(k, _)| k != key);
                p.push((key.to_string(), text.to_string()));
                self.status.clear();
                self.dirty = true;
            }
            Err(e) => self.status = failure::sentence(&e.into()),
        }
    }

    /// Replaces the light by the punctual light `l` as `render --light` reads it back.
    pub fn set_light(&mut self, l: Light) {
        match reproduce::as_rendered(&l) {
            Ok(l) => {
                self.light = l;
                self.area = None;
                self.moved();
            }
            Err(e) => self.status = failure::sentence(&e),
        }
    }

    /// Replaces the light by the area light `a` with its stand-in `l`, as `render
    /// --light` (and `--light-size`) read them back.
    pub fn set_area(&mut self, l: Light, a: AreaLight) {
        match reproduce::as_rendered_area(&l, Some(&a)) {
            Ok((l, a)) => {
                self.light = l;
                self.area = a;
                self.moved();
            }
            Err(e) => self.status = failure::sentence(&e),
        }
    }

    /// The technique's main parameter: `resolution` where it has one, else its first
    /// number; with its current value.
    pub fn main_param(&self) -> Option<(&'static str, ParamRange, serde_json::Value)> {
        let specs = self.technique.param_specs();
        let spec = specs
            .iter()
            .find(|s| s.key == techniques::RESOLUTION.key)
            .or_else(|| {
                specs
                    .iter()
                    .find(|s| matches!(s.range, ParamRange::Int(..) | ParamRange::Real(..)))
            })?;
        let value = self.technique.params().get(spec.key)?.clone();
        Some((spec.key, spec.range, value))
    }

    /// Doubles (`up`) or halves the main parameter within its range.
    fn step_param(&mut self, up: bool) {
        let Some((key, range, value)) = self.main_param() else {
            self.status = format!("{} has no numeric parameter", self.name);
            return;
        };
        let text = match (range, value.as_f64()) {
            (ParamRange::Int(lo, hi), Some(v)) => {
                let v = v as i64;
                let n = if up { v.saturating_mul(2) } else { v / 2 };
                n.clamp(lo, hi).to_string()
            }
            (ParamRange::Real(lo, hi), Some(v)) => {
                let n = if up { v * 2.0 } else { v / 2.0 };
                techniques::param_text(&n.clamp(lo, hi).into())
            }
            _ => return,
        };
        self.set_param(key, &text);
    }
}
