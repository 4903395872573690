//! The report's metrics table: the reference's row, then one row per run with its
//! parameters, time and stages (a bar of their shares), memory, mismatch, mean error and
//! counters; the best value of each measure in green. The page's script sorts it.

use super::format::{bytes, esc, folded};
use super::rows::reference_samples;
use crate::charts;
use crate::metrics::{Metrics, RunResult};
use shadowlab::techniques::param_text;
use std::fmt::Write as _;

/// The measures a run is ranked by, each with its best (smallest) value over the runs.
struct Best {
    time: f64,
    mismatch: f64,
    error: f64,
}

impl Best {
    fn of(results: &[RunResult]) -> Self {
        let best =
            |key: &dyn Fn(&RunResult) -> f64| results.iter().map(key).fold(f64::INFINITY, f64::min);
        Best {
            time: best(&|r| r.figures.time_ms),
            mismatch: best(&|r| r.mismatch_rate),
            error: best(&|r| r.mean_abs_error),
        }
    }
}

/// Appends the metrics section.
pub fn section(o: &mut String, metrics: &Metrics) {
    let reference = &metrics.reference;
    o.push_str(
        "<section id=\"metrics-section\"><h2>Metrics</h2><p class=\"note\">Times are each technique's own frame time \
         (the camera pass is shared and reported once). Mismatch: share of covered pixels whose luminance differs from the \
         reference by at least 0.5. Mean error: mean absolute luminance difference over covered pixels. Click a header to sort; \
         best values in green.</p>\
         <table id=\"metrics\"><thead><tr><th class=\"text\">technique</th><th class=\"text\">parameters</th><th>time (ms)</th>\
         <th class=\"text\">stages (ms)</th><th>memory</th><th>mismatch</th><th>mean abs error</th><th class=\"text\">counters</th></tr></thead>",
    );
    let _ = write!(
        o,
        "<tbody><tr class=\"reference-row\"><td class=\"text\">reference (ray traced)</td><td class=\"text small\">{}, {} pattern</td>\
         <td data-v=\"{:.6}\">{:.2}</td><td class=\"small stages\"><span class=\"kv\">BVH build {:.2}</span> <span class=\"kv\">trace {:.2}</span></td><td></td><td>0</td><td>0</td><td></td></tr></tbody><tbody class=\"runs\">",
        esc(&reference_samples(metrics)),
        esc(&reference.pattern),
        reference.time_ms,
        reference.time_ms,
        reference.bvh_build_ms,
        reference.trace_ms
    );
    let best = Best::of(&metrics.results);
    for r in &metrics.results {
        run_row(o, r, &best);
    }
    o.push_str("</tbody></table></section>\n");
}

/// One run's row.
fn run_row(o: &mut String, r: &RunResult, best: &Best) {
    let params: Vec<String> = r
        .params
        .iter()
        .map(|(k, v)| {
            format!(
                "<span class=\"kv\">{}={}</span>",
                esc(k),
                esc(&param_text(v))
            )
        })
        .collect();
    let time = r.figures.time_ms;
    let (stages, stage_text) = stages(r);
    // A GPU run names its adapter first (a software adapter's says CPU-emulated).
    let device = r
        .figures
        .device
        .iter()
        .map(|d| format!("<span class=\"kv\">on {}</span>", esc(d)));
    let counters: Vec<String> =
        device
            .chain(r.figures.counters.iter().map(|(k, v)| {
                format!("<span class=\"kv\">{} {}</span>", esc(k), charts::short(*v))
            }))
            .collect();
    let memory = r.figures.memory_bytes as f64;
    let (mismatch, error) = (r.mismatch_rate, r.mean_abs_error);
    let cls = |v: f64, b: f64| if v <= b { " class=\"best\"" } else { "" };
    let _ = write!(
        o,
        "<tr class=\"technique-row\" data-label=\"{}\"><td class=\"text\">{}{}</td><td class=\"text small params\">{}</td>\
         <td data-v=\"{:.6}\"{}>{:.2}</td><td class=\"small stages\" data-v=\"{:.6}\">{}{}</td><td data-v=\"{}\">{}</td>\
         <td data-v=\"{:.8}\"{}>{:.4}%</td><td data-v=\"{:.8}\"{}>{:.5}</td><td class=\"text small counters\">{}</td></tr>",
        esc(&r.label),
        esc(&r.label),
        verdict_note(r),
        folded(&params),
        time,
        cls(time, best.time),
        time,
        time,
        stages,
        stage_text,
        memory,
        bytes(memory),
        mismatch,
        cls(mismatch, best.mismatch),
        mismatch * 100.0,
        error,
        cls(error, best.error),
        error,
        folded(&counters)
    );
}

/// A run's stages: the bar of their shares of its time, and their times as text.
fn stages(r: &RunResult) -> (String, String) {
    let time = r.figures.time_ms;
    let mut bar = String::from("<div class=\"stagebar\">");
    let mut text = Vec::new();
    for (i, (k, v)) in r.figures.stages_ms.0.iter().enumerate() {
        let c = charts::color(i);
        let _ = write!(
            bar,
            "<span title=\"{} {:.2} ms\" style=\"width:{:.2}%;background:rgb({},{},{})\"></span>",
            esc(k),
            v,
            if time > 0.0 { v / time * 100.0 } else { 0.0 },
            c.0,
            c.1,
            c.2
        );
        text.push(format!(
            "<span class=\"kv\"><span style=\"color:rgb({},{},{})\">■</span> {} {}</span>",
            c.0,
            c.1,
            c.2,
            esc(k),
            charts::short(*v)
        ));
    }
    bar.push_str("</div>");
    (bar, text.join(" "))
}

/// Under a technique's name: the reference its verdict used (under an area light, with
/// its mean standard error) and, for a progressive technique, how many frames it had.
fn verdict_note(r: &RunResult) -> String {
    let mut parts = vec![match r.reference_std_error {
        Some(se) => format!("vs {} spp (σ {se:.5})", r.reference_spp),
        None => format!("vs {} spp", r.reference_spp),
    }];
    if let Some(c) = r.converged {
        let n = r.frames_run;
        parts.push(if c {
            format!("converged in {n} frames")
        } else {
            format!("{n} frames, not converged")
        });
    }
    format!(
        "<br><span class=\"small verdict\">{}</span>",
        esc(&parts.join(" · "))
    )
}
