//! The panel's parameter widgets: every parameter of the current technique's table as a
//! checkbox, a choice, or a slider with a text field (applied on Enter), the meaning,
//! range and default as the tooltip.

use super::ui::{Action, Fields, PanelState, Widgets};
use shadowlab::techniques::{param_text, ParamRange, ParamSpec};

/// The tooltip of a parameter: its meaning, range and default.
fn tooltip(spec: &ParamSpec, default: Option<&serde_json::Value>) -> String {
    let d = default.map(param_text).unwrap_or_default();
    format!("{}\nrange {}, default {d}", spec.meaning, spec.range)
}

/// The parameters of the current technique, one row each.
pub fn params(
    ui: &mut egui::Ui,
    s: &PanelState,
    fields: &mut Fields,
    out: &mut Vec<Action>,
    w: &mut Widgets,
) {
    ui.separator();
    ui.label("parameters");
    if s.specs.is_empty() {
        ui.label("(none)");
    }
    egui::Grid::new("params").num_columns(2).show(ui, |ui| {
        for spec in &s.specs {
            let value = s.values.get(spec.key).cloned().unwrap_or_default();
            let tip = tooltip(spec, s.defaults.get(spec.key));
            ui.label(spec.key).on_hover_text(&tip);
            ui.horizontal(|ui| {
                param(ui, spec, &value, &tip, fields, out, w);
            });
            ui.end_row();
        }
    });
}

fn param(
    ui: &mut egui::Ui,
    spec: &ParamSpec,
    value: &serde_json::Value,
    tip: &str,
    fields: &mut Fields,
    out: &mut Vec<Action>,
    w: &mut Widgets,
) {
    let key = spec.key.to_string();
    match spec.range {
        ParamRange::Flag => {
            let mut on = value.as_bool().unwrap_or(false);
            let r = ui.checkbox(&mut on, "").on_hover_text(tip);
            w.add(&key, ui, &r);
            if r.changed() {
                out.push(Action::Param(key, on.to_string()));
            }
        }
        ParamRange::Choice(words) => {
            let now = value.as_str().unwrap_or("").to_string();
            let r = egui::ComboBox::from_id_salt(&key)
                .selected_text(&now)
                .show_ui(ui, |ui| {
                    for word in words {
                        let r = ui.selectable_label(*word == now, *word);
                        w.add(format!("{key}={word}"), ui, &r);
                        if r.clicked() && *word != now {
                            out.push(Action::Param(key.clone(), word.to_string()));
                        }
                    }
                });
            w.add(&key, ui, &r.response.on_hover_text(tip));
        }
        ParamRange::Int(lo, hi) => {
            let mut v = value.as_i64().unwrap_or(lo);
            let r = ui.add(
                egui::Slider::new(&mut v, lo..=hi)
                    .logarithmic(lo >= 0 && hi > 1000)
                    .show_value(false),
            );
            w.add(format!("{key} slider"), ui, &r);
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                out.push(Action::Param(key.clone(), v.to_string()));
            }
            field(ui, &key, value, tip, fields, out, w);
        }
        ParamRange::Real(lo, hi) => {
            let mut v = value.as_f64().unwrap_or(lo);
            let r = ui.add(egui::Slider::new(&mut v, lo..=hi).show_value(false));
            w.add(format!("{key} slider"), ui, &r);
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                out.push(Action::Param(key.clone(), param_text(&v.into())));
            }
            field(ui, &key, value, tip, fields, out, w);
        }
    }
}

/// A text field for a number: applied on Enter.
fn field(
    ui: &mut egui::Ui,
    key: &str,
    value: &serde_json::Value,
    tip: &str,
    fields: &mut Fields,
    out: &mut Vec<Action>,
    w: &mut Widgets,
) {
    let text = fields
        .text
        .entry(key.to_string())
        .or_insert_with(|| param_text(value));
    let r = ui
        .add(egui::TextEdit::singleline(text).desired_width(70.0))
        .on_hover_text(tip);
    w.add(key, ui, &r);
    if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
        out.push(Action::Param(key.to_string(), text.trim().to_string()));
    } else if !r.has_focus() {
        // Shows the value in force (a refused one is replaced by it).
        *text = param_text(value);
    }
}
