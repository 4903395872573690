//! Between the session and the panel: the lists of techniques the pickers offer, the
//! panel's view of the session, a frame of the panel, and the panel's actions applied to
//! the session.

use super::app::App;
use super::area;
use super::session::Session;
use super::ui::{self, Action, AreaShape, LightKind, PanelState, Widgets};
use super::window::Painted;
use shadowlab::area_light::AreaLight;
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::techniques::{self, EXACT_SOFT, SOFT_VARIANTS};
use std::path::Path;

/// The CPU picker's names: the library's techniques, their soft variants and the exact
/// soft technique.
pub fn cpu_names() -> Vec<String> {
    techniques::ALL
        .iter()
        .chain(SOFT_VARIANTS)
        .chain([&EXACT_SOFT])
        .map(|n| n.to_string())
        .collect()
}

/// The GPU picker's names: every registered extension's.
pub fn gpu_names() -> Vec<String> {
    techniques::extensions()
        .iter()
        .flat_map(|e| e.names.iter().map(|n| n.to_string()))
        .collect()
}

/// The light's kind, its vector (towards the light, or its position) and a spot's angle;
/// an area light's kind is `Area` and its vector its stand-in's.
pub fn light_state(l: &Light, area: Option<&AreaLight>) -> (LightKind, [f32; 3], f32) {
    let (kind, v, angle) = match *l {
        Light::Directional { to_light } => (LightKind::Directional, to_light.to_array(), 0.0),
        Light::Point { position } => (LightKind::Point, position.to_array(), 0.0),
        Light::Spot {
            position, fov_deg, ..
        } => (LightKind::Spot, position.to_array(), fov_deg),
    };
    match area {
        Some(_) => (LightKind::Area, v, angle),
        None => (kind, v, angle),
    }
}

/// The spot's opening when a light becomes a spot, degrees.
const SPOT_FOV: f32 = 60.0;

/// The light of kind `k` nearest `l`: a point light at the place a directional light comes
/// from (the scene's centre plus its diagonal along the direction), a directional light
/// from where a point light is, a spot aimed at the scene's centre.
fn of_kind(l: &Light, k: LightKind, centre: Vec3, diagonal: f32) -> Light {
    let position = match *l {
        Light::Directional { to_light } => centre + to_light.normalize() * diagonal,
        Light::Point { position } | Light::Spot { position, .. } => position,
    };
    match k {
        LightKind::Directional => Light::Directional {
            to_light: (position - centre).normalize(),
        },
        LightKind::Point | LightKind::Area => Light::Point { position },
        LightKind::Spot => Light::Spot {
            position,
            target: centre,
            fov_deg: SPOT_FOV,
        },
    }
}

/// Applies one of the panel's actions to the session; the screenshot and the command line
/// are the window's, and returned.
pub fn apply(s: &mut Session, a: Action) -> Option<Action> {
    let (centre, diagonal) = (s.scene.bounds.center(), s.scene.bounds.diagonal());
    match a {
        Action::Technique(n) => s.set_technique(&n),
        Action::Param(k, v) => s.set_param(&k, &v),
        Action::LightKind(LightKind::Area) => {
            // A disk where the light is, facing the scene's centre.
            let size = area::default_size(AreaShape::Disk, s.scene);
            let (l, a) = area::make(AreaShape::Disk, size, &s.light, s.scene);
            s.set_area(l, a);
        }
        Action::LightKind(k) => {
            let l = of_kind(&s.light, k, centre, diagonal);
            s.set_light(l);
        }
        Action::AreaShape(shape) => {
            if let Some(a) = s.area {
                let (was, size) = area::shape_of(&a);
                let size = match (was == AreaShape::Sun, shape == AreaShape::Sun) {
                    (false, false) => size,
                    _ => area::default_size(shape, s.scene),
                };
                let (l, a) = area::make(shape, size, &s.light, s.scene);
                s.set_area(l, a);
            }
        }
        Action::AreaSize(size) => {
            if let Some(a) = s.area {
                let (shape, _) = area::shape_of(&a);
                let (l, a) = area::make(shape, size, &s.light, s.scene);
                s.set_area(l, a);
            }
        }
        Action::LightVector(v) => {
            let v = Vec3::from_array(v);
            let l = match s.light {
                Light::Directional { .. } if v.length() > 0.0 => Light::Directional {
                    to_light: v.normalize(),
                },
                Light::Directional { to_light } => Light::Directional { to_light },
                Light::Point { .. } => Light::Point { position: v },
                Light::Spot {
                    target, fov_deg, ..
                } => Light::Spot {
                    position: v,
                    target,
                    fov_deg,
                },
            };
            match s.area {
                Some(a) => {
                    let (shape, size) = area::shape_of(&a);
                    let (l, a) = area::make(shape, size, &l, s.scene);
                    s.set_area(l, a);
                }
                None => s.set_light(l),
            }
        }
        Action::SpotAngle(a) => {
            if let Light::Spot {
                position, target, ..
            } = s.light
            {
                s.set_light(Light::Spot {
                    position,
                    target,
                    fov_deg: a,
                });
            }
        }
        Action::Error(on) => {
            s.show.error = on;
            s.show.overlays = true;
            s.stale = true;
        }
        Action::MapLayer(l) => {
            s.show.map = l;
            s.show.overlays = true;
            s.dirty = true;
        }
        Action::Dump(i) => {
            s.show.dump = i;
            s.show.overlays = true;
            s.dirty = true;
        }
        Action::Screenshot | Action::CopyCommand => return Some(a),
    }
    None
}

impl App<'_> {
    /// Runs the panel for this frame: its actions, what it painted, whether egui asks for
    /// another frame soon.
    pub(super) fn run_panel(&mut self) -> (Vec<Action>, Painted, bool) {
        let mut fields = std::mem::take(&mut self.fields);
        let injected = std::mem::take(&mut self.injected);
        let Some(mut w) = self.window.take() else {
            let none = Painted {
                jobs: Vec::new(),
                textures: Default::default(),
                ppp: 1.0,
            };
            return (Vec::new(), none, false);
        };
        let mut raw = w.state.take_egui_input(&w.window);
        raw.events.extend(injected);
        // A point is a pixel whatever the display's scale: the panel lies beside a view
        // whose pixels are render's.
        if let Some(v) = raw.viewports.get_mut(&egui::ViewportId::ROOT) {
            v.native_pixels_per_point = Some(1.0);
        }
        let ctx = w.egui.clone();
        let mut actions = Vec::new();
        let mut widgets = Widgets::default();
        let view_width = w.view_size.0;
        let scroll_to = self.scroll_to.as_deref();
        let out = {
            let state = self.session.show.overlays.then(|| self.panel_state());
            ctx.run_pass(raw, |ctx| {
                if let Some(state) = &state {
                    (actions, widgets) = ui::panel(ctx, view_width, state, &mut fields, scroll_to);
                }
            })
        };
        w.state
            .handle_platform_output(&w.window, out.platform_output.clone());
        let again = out
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .is_some_and(|v| v.repaint_delay.as_millis() < 100);
        let jobs = ctx.tessellate(out.shapes, out.pixels_per_point);
        self.window = Some(w);
        self.fields = fields;
        self.widgets = widgets;
        let painted = Painted {
            jobs,
            textures: out.textures_delta,
            ppp: out.pixels_per_point,
        };
        (actions, painted, again)
    }

    pub(super) fn panel_state(&self) -> PanelState<'_> {
        let s = &self.session;
        let defaults = shadowlab::techniques::create(&s.name)
            .map(|t| t.params())
            .unwrap_or_default();
        let on_device = self.on_device.is_some();
        let gpu_pass = self.drawn.as_ref().is_some_and(|d| d.gpu_camera_pass);
        let backend = match (on_device, s.name.starts_with("gpu:")) {
            (true, _) if gpu_pass => {
                "drawn on the GPU: camera pass, technique, shading, error (nothing read back)"
            }
            (true, _) => {
                "CPU camera pass uploaded (the technique reads it there); technique, shading, error on the GPU"
            }
            (false, true) => "GPU technique (its shadow term read back), CPU shading, uploaded",
            (false, false) => "CPU technique, CPU shading, image uploaded",
        };
        let against = match on_device {
            true => format!(
                "{} on the GPU, every frame drawn",
                super::gpu_shade::REFERENCE
            ),
            false => match s.area {
                Some(_) => format!(
                    "the CPU soft reference ({} light samples a pixel), each new view",
                    s.light_samples
                ),
                None => "the CPU reference, each new view".to_string(),
            },
        };
        let error = s.show.error.then(|| match &self.error {
            Some(e) => format!(
                "mismatch {:.3}%  mean abs error {:.4}\nagainst {against} ({} spp)",
                e.mismatch_rate * 100.0,
                e.mean_abs_error,
                e.reference_spp
            ),
            None => "tracing the reference...".to_string(),
        });
        let dumps = self
            .drawn
            .as_ref()
            .map(|d| d.dumps.iter().map(|(n, _)| n.clone()).collect())
            .unwrap_or_default();
        PanelState {
            technique: &s.name,
            cpu_names: &self.cpu_names,
            gpu_names: &self.gpu_names,
            specs: s.technique.param_specs(),
            values: s.technique.params(),
            defaults,
            light: light_state(&s.light, s.area.as_ref()),
            area: s.area.as_ref().map(area::shape_of),
            area_max: s.scene.bounds.diagonal() / 4.0,
            light_samples: s.light_samples,
            backend: backend.to_string(),
            adapter: self.gpu.adapter.label(),
            history: &self.history,
            error,
            error_on: s.show.error,
            dumps,
            dump: self.dump.as_ref().map(|(i, t, size)| (*i, t.id(), *size)),
            maps: self.map_layers,
            map: self.map_view.as_ref().map(|m| (m.layer, m.id)),
            status: &s.status,
            command: super::reproduce::command_line(&self.render_args(Path::new("view.png"))),
        }
    }
}
