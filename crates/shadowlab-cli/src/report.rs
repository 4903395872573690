//! The HTML report of `compare`: self-contained and offline.

use anyhow::{Context, Result};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Writes `DIR/index.html` from the metrics.
pub fn write_html(dir: &Path, metrics: &Value) -> Result<()> {
    let mut h = String::new();
    let scene = metrics["scene"].as_str().unwrap_or("");
    let _ = write!(
        h,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>shadowlab — {}</title>\
         <style>body{{font-family:sans-serif;margin:2em;background:#fafafa}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:4px 8px;text-align:right}}img{{max-width:480px}}\
         .grid{{display:flex;flex-wrap:wrap;gap:12px}}figure{{margin:0}}</style></head><body>",
        esc(scene)
    );
    let _ = write!(
        h,
        "<h1>shadowlab — {}</h1><p>{} triangles, {}×{}, {} covered pixels; reference: ray traced, {} sample(s) per pixel, {:.1} ms.</p>",
        esc(scene),
        metrics["triangles"],
        metrics["width"],
        metrics["height"],
        metrics["covered_pixels"],
        metrics["reference"]["samples_per_pixel"],
        metrics["reference"]["time_ms"].as_f64().unwrap_or(0.0)
    );
    let _ = write!(h, "<table id=\"metrics\"><tr><th>technique</th><th>time ms</th><th>memory</th><th>mismatch</th><th>mean abs error</th></tr>");
    let results = metrics["results"].as_array().cloned().unwrap_or_default();
    for r in &results {
        let _ = write!(
            h,
            "<tr class=\"technique-row\"><td>{}</td><td>{:.2}</td><td>{}</td><td>{:.4}%</td><td>{:.5}</td></tr>",
            esc(r["label"].as_str().unwrap_or("")),
            r["time_ms"].as_f64().unwrap_or(0.0),
            r["memory_bytes"],
            r["mismatch_rate"].as_f64().unwrap_or(0.0) * 100.0,
            r["mean_abs_error"].as_f64().unwrap_or(0.0)
        );
    }
    let _ = write!(h, "</table><h2>Images</h2><div class=\"grid\"><figure><img src=\"reference.png\"><figcaption>reference</figcaption></figure>");
    for r in &results {
        let label = esc(r["label"].as_str().unwrap_or(""));
        let _ = write!(
            h,
            "<figure><img src=\"{}\"><figcaption>{label}</figcaption></figure><figure><img src=\"{}\"><figcaption>{label} error</figcaption></figure>",
            esc(r["image"].as_str().unwrap_or("")),
            esc(r["error_image"].as_str().unwrap_or(""))
        );
    }
    h.push_str("</div></body></html>\n");
    let p = dir.join("index.html");
    std::fs::write(&p, h).with_context(|| format!("cannot write {}", p.display()))
}
