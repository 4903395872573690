//! The panel, drawn with egui in the column right of the view: the technique (CPU and
//! GPU pickers), every parameter of its table (slider or choice, and a field; the range,
//! default and meaning as the tooltip), the light (punctual, or an area light's shape and
//! size), the stage timings of the last frames,
//! the adapter and who draws, the error against the reference, the technique's own
//! images, screenshot and the command line.
//!
//! The panel does not change the session itself: it returns [`Action`]s, applied before
//! the next frame is drawn. Every widget a person can use is recorded with its label and
//! rectangle ([`Widgets`]), so that a script clicks a widget by its label in the last
//! frame's layout, as a pointer would. The panel scrolls when it is taller than the
//! window; a script's click on a widget scrolled out of view scrolls to it first.

use super::window::PANEL_WIDTH;
use shadowlab::techniques::ParamSpec;
use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// Frames of stage timings the plot shows.
pub const HISTORY: usize = 120;

/// What a person did in the panel.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Switch to this technique.
    Technique(String),
    /// Set a parameter of the current technique (key, value as text).
    Param(String, String),
    /// The light: its kind.
    LightKind(LightKind),
    /// The light: its direction (directional) or position (point, spot).
    LightVector([f32; 3]),
    /// The spot's opening angle in degrees.
    SpotAngle(f32),
    /// The area light's shape.
    AreaShape(AreaShape),
    /// The area light's size: a radius or half a side in world units, a sun's angular
    /// diameter in degrees.
    AreaSize(f32),
    /// The error overlay on or off.
    Error(bool),
    /// The technique's image shown, by index; `None` for none.
    Dump(Option<usize>),
    /// The layer of the technique's depth maps shown (on the device); `None` for none.
    MapLayer(Option<u32>),
    /// A screenshot.
    Screenshot,
    /// The `render` command line to the clipboard.
    CopyCommand,
}

/// A light's kind, as the panel offers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// Parallel rays.
    Directional,
    /// From a point, all around.
    Point,
    /// From a point, within a cone.
    Spot,
    /// From an area (its shape below).
    Area,
}

/// An area light's shape, as the panel offers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AreaShape {
    /// A disk facing the scene's centre.
    Disk,
    /// A square facing the scene's centre.
    Rect,
    /// A sphere.
    Sphere,
    /// A light at infinity of some angular diameter.
    Sun,
}

impl AreaShape {
    /// The shapes, with their labels.
    pub const ALL: [(AreaShape, &'static str); 4] = [
        (AreaShape::Disk, "disk"),
        (AreaShape::Rect, "rect"),
        (AreaShape::Sphere, "sphere"),
        (AreaShape::Sun, "sun"),
    ];
}

/// The widgets drawn in a frame, by label.
#[derive(Clone, Debug, Default)]
pub struct Widgets {
    /// Label and rectangle (pixels), in drawing order: the part that can be seen.
    pub rects: Vec<(String, egui::Rect)>,
    /// The labels of widgets drawn but cut at the top or bottom (scrolled out of the
    /// panel, or out of an open list): a click scrolls to them first.
    clipped: BTreeSet<String>,
    /// The widget the panel scrolls to this frame.
    scroll_to: Option<String>,
}

impl Widgets {
    /// The centre of the widget labelled `label`.
    pub fn centre(&self, label: &str) -> Option<egui::Pos2> {
        self.rects
            .iter()
            .rev()
            .find(|(l, _)| l == label)
            .map(|(_, r)| r.center())
    }

    /// Whether the widget labelled `label` was drawn cut at the top or bottom.
    pub fn clipped(&self, label: &str) -> bool {
        self.clipped.contains(label)
    }

    /// The labels, for an error message: those seen, then those scrolled out of view.
    pub fn labels(&self) -> Vec<String> {
        let seen = self.rects.iter().map(|(l, _)| l.clone());
        let hidden = self
            .clipped
            .iter()
            .filter(|l| !self.rects.iter().any(|(s, _)| s == *l))
            .cloned();
        seen.chain(hidden).collect()
    }

    pub(super) fn add(&mut self, label: impl Into<String>, ui: &egui::Ui, r: &egui::Response) {
        let label = label.into();
        if self.scroll_to.as_deref() == Some(label.as_str()) {
            r.scroll_to_me(Some(egui::Align::Center));
        }
        // Only what can be clicked: the part inside the visible clip area. One cut at
        // the top or bottom is scrolled out of view (not while egui measures the panel).
        let clip = ui.clip_rect();
        let vis = r.rect.intersect(clip);
        if !ui.is_sizing_pass() && (r.rect.top() < clip.top() || r.rect.bottom() > clip.bottom()) {
            self.clipped.insert(label.clone());
        }
        if vis.is_positive() {
            self.rects.push((label, vis));
        }
    }
}

/// What the panel shows (read from the session and the last frame).
pub struct PanelState<'a> {
    /// The technique's name.
    pub technique: &'a str,
    /// Names in the CPU picker.
    pub cpu_names: &'a [String],
    /// Names in the GPU picker.
    pub gpu_names: &'a [String],
    /// The parameter table and the current values.
    pub specs: Vec<ParamSpec>,
    /// Current values.
    pub values: BTreeMap<String, serde_json::Value>,
    /// Default values (a fresh technique's).
    pub defaults: BTreeMap<String, serde_json::Value>,
    /// The light's kind, vector and spot angle.
    pub light: (LightKind, [f32; 3], f32),
    /// The area light's shape and size, when the light has an area.
    pub area: Option<(AreaShape, f32)>,
    /// The largest size of an area light in world units (the scene's size).
    pub area_max: f32,
    /// Light samples per pixel under an area light.
    pub light_samples: u32,
    /// Who draws, whether the path reads back.
    pub backend: String,
    /// The adapter's line.
    pub adapter: String,
    /// The last frames' stages, oldest first.
    pub history: &'a VecDeque<Vec<(String, f64)>>,
    /// The error line (figures or "tracing").
    pub error: Option<String>,
    /// The error overlay on.
    pub error_on: bool,
    /// The technique's images: names; the one shown and its texture.
    pub dumps: Vec<String>,
    /// The image shown.
    pub dump: Option<(usize, egui::TextureId, [f32; 2])>,
    /// The layers of the technique's depth maps on the device (0 for none).
    pub maps: u32,
    /// The layer shown and its picture.
    pub map: Option<(u32, egui::TextureId)>,
    /// The last message.
    pub status: &'a str,
    /// The command line of the view.
    pub command: String,
}

/// The panel's own memory across frames: the text being typed into each field.
#[derive(Default)]
pub struct Fields {
    pub(super) text: BTreeMap<String, String>,
    technique: String,
}

/// Draws the panel, scrolled to the widget labelled `scroll_to` when one is given;
/// returns the actions and the widgets by label.
pub fn panel(
    ctx: &egui::Context,
    view_width: u32,
    s: &PanelState,
    fields: &mut Fields,
    scroll_to: Option<&str>,
) -> (Vec<Action>, Widgets) {
    if fields.technique != s.technique {
        fields.text.clear();
        fields.technique = s.technique.to_string();
    }
    let mut out = Vec::new();
    let mut w = Widgets {
        scroll_to: scroll_to.map(str::to_string),
        ..Widgets::default()
    };
    let area = egui::Rect::from_min_size(
        egui::pos2(view_width as f32, 0.0),
        egui::vec2(PANEL_WIDTH as f32, ctx.content_rect().height()),
    );
    egui::Area::new(egui::Id::unique("panel"))
        .fixed_pos(area.min)
        .show(ctx, |ui| {
            ui.set_clip_rect(area);
            egui::Frame::new()
                .fill(egui::Color32::from_gray(24))
                .inner_margin(6.0)
                .show(ui, |ui| {
                    ui.set_width(area.width() - 12.0);
                    ui.set_min_height(area.height() - 12.0);
                    // The panel scrolls when it is taller than the window; a script's
                    // click scrolls to its widget at once.
                    egui::ScrollArea::vertical()
                        .max_height(area.height() - 12.0)
                        .auto_shrink(false)
                        .animated(false)
                        .show(ui, |ui| {
                            technique(ui, s, &mut out, &mut w);
                            super::param_widgets::params(ui, s, fields, &mut out, &mut w);
                            error(ui, s, &mut out, &mut w);
                            light(ui, s, &mut out, &mut w);
                            actions(ui, s, &mut out, &mut w);
                            views(ui, s, &mut out, &mut w);
                            super::timings::timings(ui, s);
                        });
                });
        });
    (out, w)
}

fn technique(ui: &mut egui::Ui, s: &PanelState, out: &mut Vec<Action>, w: &mut Widgets) {
    ui.heading(s.technique);
    for (label, names) in [
        ("cpu technique", s.cpu_names),
        ("gpu technique", s.gpu_names),
    ] {
        let current = if names.iter().any(|n| n == s.technique) {
            s.technique
        } else {
            "-"
        };
        ui.horizontal(|ui| {
            let r = egui::ComboBox::from_id_salt(label)
                .selected_text(current)
                .height(560.0)
                .show_ui(ui, |ui| {
                    for n in names {
                        let r = ui.selectable_label(n == s.technique, n.as_str());
                        w.add(n.clone(), ui, &r);
                        if r.clicked() && n != s.technique {
                            out.push(Action::Technique(n.clone()));
                        }
                    }
                });
            w.add(label, ui, &r.response);
            ui.label(label);
        });
    }
}

fn light(ui: &mut egui::Ui, s: &PanelState, out: &mut Vec<Action>, w: &mut Widgets) {
    ui.separator();
    ui.label("light (right drag in the view turns it)");
    let (kind, v, angle) = s.light;
    ui.horizontal(|ui| {
        for (k, name) in [
            (LightKind::Directional, "directional"),
            (LightKind::Point, "point"),
            (LightKind::Spot, "spot"),
            (LightKind::Area, "area"),
        ] {
            let r = ui.radio(kind == k, name);
            w.add(name, ui, &r);
            if r.clicked() && kind != k {
                out.push(Action::LightKind(k));
            }
        }
    });
    if let Some((shape, size)) = s.area {
        area(ui, s, shape, size, out, w);
    }
    let what = match (kind, s.area) {
        (_, Some((AreaShape::Sun, _))) | (LightKind::Directional, _) => "towards",
        _ => "at",
    };
    ui.horizontal(|ui| {
        ui.label(what);
        let mut nv = v;
        let mut changed = false;
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            let r = ui.add(egui::DragValue::new(&mut nv[i]).speed(0.01).prefix(*axis));
            w.add(format!("light {axis}"), ui, &r);
            changed |= r.changed();
        }
        if changed {
            out.push(Action::LightVector(nv));
        }
    });
    if kind == LightKind::Spot {
        let mut a = angle;
        let r = ui.add(egui::Slider::new(&mut a, 1.0..=170.0).text("opening (degrees)"));
        w.add("spot opening", ui, &r);
        if r.changed() {
            out.push(Action::SpotAngle(a));
        }
    }
}

/// The area light's shape and size.
fn area(
    ui: &mut egui::Ui,
    s: &PanelState,
    shape: AreaShape,
    size: f32,
    out: &mut Vec<Action>,
    w: &mut Widgets,
) {
    ui.horizontal(|ui| {
        for (k, name) in AreaShape::ALL {
            let r = ui.radio(shape == k, name);
            w.add(name, ui, &r);
            if r.clicked() && shape != k {
                out.push(Action::AreaShape(k));
            }
        }
    });
    let (range, text) = match shape {
        AreaShape::Sun => (0.05..=30.0, "angular diameter (degrees)"),
        AreaShape::Rect => (s.area_max * 1e-3..=s.area_max, "half side"),
        AreaShape::Disk | AreaShape::Sphere => (s.area_max * 1e-3..=s.area_max, "radius"),
    };
    let mut v = size;
    let r = ui.add(
        egui::Slider::new(&mut v, range)
            .logarithmic(true)
            .text(text),
    );
    w.add("area size", ui, &r);
    if r.drag_stopped() || (r.changed() && !r.dragged()) {
        out.push(Action::AreaSize(v));
    }
    ui.label(format!(
        "{} light samples a pixel (--light-samples); hard techniques see its centre",
        s.light_samples
    ));
}

fn error(ui: &mut egui::Ui, s: &PanelState, out: &mut Vec<Action>, w: &mut Widgets) {
    ui.separator();
    let mut on = s.error_on;
    let r = ui.checkbox(&mut on, "error overlay");
    w.add("error overlay", ui, &r);
    if r.changed() {
        out.push(Action::Error(on));
    }
    if let Some(line) = &s.error {
        ui.label(line);
    }
}

fn views(ui: &mut egui::Ui, s: &PanelState, out: &mut Vec<Action>, w: &mut Widgets) {
    ui.separator();
    let shown = s.dump.map(|d| d.0);
    let text = shown
        .and_then(|i| s.dumps.get(i).cloned())
        .or_else(|| s.map.map(|m| format!("shadow map {}", m.0)))
        .unwrap_or_else(|| "none".to_string());
    let r = egui::ComboBox::from_id_salt("technique view")
        .selected_text(text)
        .show_ui(ui, |ui| {
            let r = ui.selectable_label(shown.is_none() && s.map.is_none(), "none");
            w.add("view none", ui, &r);
            if r.clicked() {
                out.push(Action::Dump(None));
                out.push(Action::MapLayer(None));
            }
            for i in 0..s.maps {
                let name = format!("shadow map {i}");
                let r = ui.selectable_label(s.map.is_some_and(|m| m.0 == i), &name);
                w.add(format!("view {name}"), ui, &r);
                if r.clicked() {
                    out.push(Action::MapLayer(Some(i)));
                }
            }
            for (i, name) in s.dumps.iter().enumerate() {
                let r = ui.selectable_label(shown == Some(i), name);
                w.add(format!("view {name}"), ui, &r);
                if r.clicked() {
                    out.push(Action::Dump(Some(i)));
                }
            }
            if s.dumps.is_empty() && s.maps == 0 {
                // Asking once draws the frame with the technique's images kept.
                let r = ui.selectable_label(false, "(look for images)");
                w.add("view look", ui, &r);
                if r.clicked() {
                    out.push(Action::Dump(Some(0)));
                }
            }
        });
    w.add("technique view", ui, &r.response);
    ui.label("technique view");
    if let Some((_, id)) = s.map {
        let side = ui.available_width().min(256.0);
        let r = ui.image((id, egui::vec2(side, side)));
        w.add("shadow map picture", ui, &r);
    }
    if let Some((_, id, [iw, ih])) = s.dump {
        let scale = (ui.available_width() / iw).min(1.0);
        ui.image((id, egui::vec2(iw * scale, ih * scale)));
    }
}

fn actions(ui: &mut egui::Ui, s: &PanelState, out: &mut Vec<Action>, w: &mut Widgets) {
    ui.separator();
    ui.horizontal(|ui| {
        let r = ui.button("screenshot");
        w.add("screenshot", ui, &r);
        if r.clicked() {
            out.push(Action::Screenshot);
        }
        let r = ui.button("copy command line").on_hover_text(&s.command);
        w.add("copy command line", ui, &r);
        if r.clicked() {
            out.push(Action::CopyCommand);
        }
    });
    if !s.status.is_empty() {
        ui.colored_label(egui::Color32::from_rgb(240, 170, 80), s.status);
    }
    ui.label("keys: WASD EQ fly, Tab technique, [ ] parameter, R error, M images, H hide, P shot");
}
