//! The panel's last part: who draws and on which adapter, the last frame's time with a bar
//! per stage, and the frame time of the last frames as a line.

use super::ui::{PanelState, HISTORY};

/// Draws who draws, the adapter and the stage times.
pub fn timings(ui: &mut egui::Ui, s: &PanelState) {
    ui.separator();
    ui.label(&s.backend);
    ui.label(format!("adapter: {}", s.adapter));
    let Some(last) = s.history.back() else {
        return;
    };
    let total: f64 = last.iter().map(|(_, ms)| ms).sum();
    ui.label(format!(
        "frame {total:.1} ms ({:.1} fps)",
        1e3 / total.max(1e-3)
    ));
    let width = ui.available_width();
    let most = last.iter().map(|(_, ms)| *ms).fold(1e-3, f64::max);
    for (name, ms) in last {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(90.0, 12.0), egui::Sense::hover());
            let fill = egui::Rect::from_min_size(
                rect.min,
                egui::vec2((90.0 * ms / most) as f32, rect.height()),
            );
            ui.painter()
                .rect_filled(fill, 0.0, egui::Color32::from_rgb(90, 160, 220));
            ui.label(format!("{ms:7.2} ms {name}"));
        });
    }
    // The frame time of the last frames, as a line.
    let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 50.0), egui::Sense::hover());
    ui.painter()
        .rect_filled(rect, 0.0, egui::Color32::from_gray(12));
    let totals: Vec<f64> = s
        .history
        .iter()
        .map(|f| f.iter().map(|(_, ms)| ms).sum())
        .collect();
    let top = totals.iter().copied().fold(1e-3, f64::max);
    let points: Vec<egui::Pos2> = totals
        .iter()
        .enumerate()
        .map(|(i, t)| {
            egui::pos2(
                rect.left() + rect.width() * i as f32 / (HISTORY - 1) as f32,
                rect.bottom() - rect.height() * (*t / top) as f32,
            )
        })
        .collect();
    ui.painter().add(egui::Shape::line(
        points,
        egui::Stroke::new(1.0, egui::Color32::from_rgb(230, 200, 80)),
    ));
    ui.label(format!("last {} frames, top {top:.1} ms", totals.len()));
}
