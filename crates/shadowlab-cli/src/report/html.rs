//! The report page, section by section as it reads from the top: the header (scene,
//! image, reference, threads), the navigation, the metrics table, the before/after
//! slider, the plots, the images side by side with their error images, the worst error
//! regions, the walkthrough animations, the gallery of intermediate images, and the
//! provenance (camera, light, scene), followed by the data the page's self-test checks.

use super::assets::{CSS, SCRIPT};
use super::dump::Dumped;
use super::format::{esc, url};
use super::plots::{Plot, TEMPORAL_ERROR_PLOT};
use super::rows::reference_samples;
use super::tables;
use crate::metrics::Metrics;
use serde_json::json;
use std::fmt::Write as _;

/// The whole page.
pub fn page(metrics: &Metrics, plots: &[Plot], dumped: &Dumped) -> String {
    let mut o = String::with_capacity(64 * 1024);
    header(&mut o, metrics);
    nav(&mut o, metrics, dumped);
    tables::section(&mut o, metrics);
    slider(&mut o, metrics);
    plots_section(&mut o, plots);
    images(&mut o, metrics);
    crops(&mut o, metrics);
    animations(&mut o, metrics, plots);
    dumped.section(&mut o);
    provenance(&mut o, metrics);
    self_test_data(&mut o, metrics);
    o
}

/// The document head and the header line: what was measured, and on what.
fn header(o: &mut String, m: &Metrics) {
    let scene = &m.scene.scene;
    let reference = &m.reference;
    let (w, h) = (m.width, m.height);
    let _ = write!(
        o,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">\
         <title>shadowlab — {}</title><style>{CSS}</style></head><body>\n",
        esc(scene)
    );
    let _ = writeln!(
        o,
        "<header><h1>shadowlab — {}</h1><p>{} triangles · {}×{} pixels · {} covered · camera pass {:.1} ms · \
         reference: ray traced, {} per pixel, {:.1} ms (BVH {:.1} + trace {:.1}) · {} thread(s){} · shadowlab {}</p></header>",
        esc(scene),
        m.scene.triangles,
        w,
        h,
        m.covered_pixels,
        m.camera_pass_ms,
        esc(&reference_samples(m)),
        reference.time_ms,
        reference.bvh_build_ms,
        reference.trace_ms,
        m.threads,
        if m.frames > 1 { format!(" · {} frames (figures are of the last)", m.frames) } else { String::new() },
        esc(&m.shadowlab_version)
    );
}

/// True when some run has a walkthrough animation.
fn has_animation(m: &Metrics) -> bool {
    m.results.iter().any(|r| r.animation.is_some())
}

/// The navigation bar: one link per section shown.
fn nav(o: &mut String, m: &Metrics, dumped: &Dumped) {
    o.push_str("<nav><a href=\"#metrics-section\">metrics</a><a href=\"#compare\">slider</a><a href=\"#plots\">plots</a><a href=\"#images\">images</a><a href=\"#crops\">worst regions</a>");
    if has_animation(m) {
        o.push_str("<a href=\"#animation\">animation</a>");
    }
    if !dumped.is_empty() {
        o.push_str("<a href=\"#dump\">intermediate images</a>");
    }
    o.push_str("<a href=\"#provenance\">provenance</a><a href=\"metrics.json\">metrics.json</a></nav>\n<main>\n");
}

/// The before/after slider between any two images, the reference on the left and the
/// first run that is not itself a ray tracer on the right.
fn slider(o: &mut String, m: &Metrics) {
    let ref_image = &m.reference.image;
    let (w, h) = (m.width, m.height);
    let mut options = format!(
        "<option value=\"{}\">reference</option>",
        esc(&url(ref_image))
    );
    for r in &m.results {
        let _ = write!(
            options,
            "<option value=\"{}\">{}</option>",
            esc(&url(&r.image)),
            esc(&r.label)
        );
        let _ = write!(
            options,
            "<option value=\"{}\">{} error</option>",
            esc(&url(&r.error_image)),
            esc(&r.label)
        );
    }
    let first = m
        .results
        .iter()
        .find(|r| r.technique != "raytrace")
        .or(m.results.first())
        .map(|r| (url(&r.image), r.label.as_str()))
        .unwrap_or((url(ref_image), "reference"));
    let sel_b = options.replacen(
        &format!(
            "<option value=\"{}\">{}</option>",
            esc(&first.0),
            esc(first.1)
        ),
        &format!(
            "<option value=\"{}\" selected>{}</option>",
            esc(&first.0),
            esc(first.1)
        ),
        1,
    );
    let _ = writeln!(
        o,
        "<section id=\"compare\"><h2>Before / after</h2><p class=\"note\">Drag across the image or move the slider: \
         the left part shows the first choice, the right part the second.</p>\
         <div class=\"slider-controls\"><label>left <select id=\"slider-left\">{options}</select></label>\
         <label>right <select id=\"slider-right\">{sel_b}</select></label></div>\
         <div class=\"slider\" id=\"slider\"><img id=\"slider-b\" src=\"{}\" alt=\"right image\" width=\"{w}\" height=\"{h}\">\
         <img id=\"slider-a\" src=\"{}\" alt=\"left image\" style=\"clip-path:inset(0 50% 0 0)\">\
         <div id=\"slider-handle\" style=\"left:50%\"></div>\
         <span class=\"tag\" id=\"tag-a\" style=\"left:8px\">reference</span><span class=\"tag\" id=\"tag-b\" style=\"right:8px\">{}</span></div>\
         <input type=\"range\" id=\"slider-range\" min=\"0\" max=\"100\" step=\"0.1\" value=\"50\" aria-label=\"split position\"></section>",
        esc(&first.0),
        esc(&url(ref_image)),
        esc(first.1)
    );
}

/// The plots, each linked to its SVG file.
fn plots_section(o: &mut String, plots: &[Plot]) {
    o.push_str("<section id=\"plots\"><h2>Plots</h2><div class=\"grid plots\">");
    for p in plots {
        let _ = write!(
            o,
            "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>",
            esc(&url(&p.file)),
            esc(&p.caption)
        );
    }
    o.push_str("</div></section>\n");
}

/// The reference and each run's shaded and error images side by side, the worst region
/// outlined.
fn images(o: &mut String, m: &Metrics) {
    let (w, h) = (m.width as f64, m.height as f64);
    let _ = write!(
        o,
        "<section id=\"images\"><h2>Images</h2><p class=\"note\">Each technique's shaded frame and its error against the reference: \
         red where the technique is lighter, blue where it is darker, black where they agree (brightness ∝ √|error|). \
         The yellow box marks the worst region, enlarged below.</p><div class=\"grid\">\
         <figure class=\"ref\"><a href=\"{0}\"><img src=\"{0}\" alt=\"reference\"></a><figcaption>reference (ray traced)</figcaption></figure>",
        esc(&url(&m.reference.image))
    );
    for r in m.references.iter().filter(|r| r.std_error_image.is_some()) {
        let _ = write!(
            o,
            "<figure class=\"ref\"><a href=\"{0}\"><img src=\"{0}\" alt=\"reference standard error\"></a>\
             <figcaption>reference standard error, {1} spp: mean {2:.5} (yellow, brightness ∝ √σ)</figcaption></figure>",
            esc(&url(r.std_error_image.as_deref().unwrap_or_default())),
            r.samples_per_pixel,
            r.mean_std_error.unwrap_or(0.0)
        );
    }
    for r in &m.results {
        let bx = match &r.worst_region {
            Some(g) if w > 0.0 && h > 0.0 => format!(
                "<div class=\"box\" style=\"left:{:.3}%;top:{:.3}%;width:{:.3}%;height:{:.3}%\"></div>",
                g.x as f64 / w * 100.0,
                g.y as f64 / h * 100.0,
                g.width as f64 / w * 100.0,
                g.height as f64 / h * 100.0
            ),
            _ => String::new(),
        };
        let _ = write!(
            o,
            "<figure><div class=\"pair\"><a class=\"frame\" href=\"{0}\"><img src=\"{0}\" alt=\"{2}\">{3}</a>\
             <a class=\"frame\" href=\"{1}\"><img src=\"{1}\" alt=\"{2} error\">{3}</a></div>\
             <figcaption>{2} — {4:.2} ms, mismatch {5:.3}%, mean error {6:.4}{7}</figcaption></figure>",
            esc(&url(&r.image)),
            esc(&url(&r.error_image)),
            esc(&r.label),
            bx,
            r.figures.time_ms,
            r.mismatch_rate * 100.0,
            r.mean_abs_error,
            r.reference_std_error
                .map_or(String::new(), |s| format!(" (reference σ {s:.5})"))
        );
    }
    o.push_str("</div></section>\n");
}

/// Each run's worst error region, enlarged: reference, technique, error.
fn crops(o: &mut String, m: &Metrics) {
    o.push_str("<section id=\"crops\"><h2>Worst error regions</h2><p class=\"note\">For each technique, the window with the largest \
                summed error, enlarged: reference, technique, error.</p><div class=\"grid\">");
    let mut any_crop = false;
    for r in &m.results {
        if let Some(g) = &r.worst_region {
            any_crop = true;
            let _ = write!(
                o,
                "<figure class=\"crop\"><img src=\"{}\" alt=\"{} worst region\"><div class=\"cropcap\"><span>reference</span><span>{}</span><span>error</span></div>\
                 <figcaption>{} — pixels ({}, {}) to ({}, {}); mean error there {:.4} (whole frame {:.4})</figcaption></figure>",
                esc(&url(&g.crop)),
                esc(&r.label),
                esc(&r.label),
                esc(&r.label),
                g.x,
                g.y,
                g.x as f64 + g.width as f64,
                g.y as f64 + g.height as f64,
                g.mean_abs_error,
                r.mean_abs_error
            );
        }
    }
    if !any_crop {
        o.push_str("<p>Every technique matches the reference exactly.</p>");
    }
    let exact: Vec<&str> = m
        .results
        .iter()
        .filter(|r| r.worst_region.is_none())
        .map(|r| r.label.as_str())
        .collect();
    if any_crop && !exact.is_empty() {
        let _ = write!(
            o,
            "<p class=\"note\">No error anywhere: {}.</p>",
            esc(&exact.join(", "))
        );
    }
    o.push_str("</div></section>\n");
}

/// The walkthrough of a sequence: each run's animation beside the reference's, its
/// temporal error in the caption, and the temporal error per frame under them.
fn animations(o: &mut String, m: &Metrics, plots: &[Plot]) {
    if !has_animation(m) {
        return;
    }
    let frames = m.frames;
    let _ = write!(
        o,
        "<section id=\"animation\"><h2>Walkthrough</h2><p class=\"note\">{frames} frames along the camera path, the reference \
         (left) and each technique (right), every frame judged against its own reference; numbered full-size frames are in \
         <a href=\"frames/\">frames/</a>. Temporal error: from each frame to the next, the mean |Δ technique − Δ reference| \
         of the shadow term over the pixels visible in both (reprojected into the frame before), averaged over the frames — \
         0 when a technique's shadows move as the true ones do, high where they shimmer or swim.</p><div class=\"grid\">"
    );
    for r in &m.results {
        let Some(a) = r.walkthrough.as_ref().or(r.animation.as_ref()) else {
            continue;
        };
        let temporal = match r.temporal_error {
            Some(t) => format!(" — temporal error {t:.5}"),
            None => String::new(),
        };
        let single = match &r.animation {
            Some(s) => format!(" (<a href=\"{}\">alone</a>)", esc(&url(s))),
            None => String::new(),
        };
        let _ = write!(
            o,
            "<figure><img src=\"{}\" alt=\"{} walkthrough\" style=\"max-width:640px\"><figcaption>reference | {}{}{}</figcaption></figure>",
            esc(&url(a)),
            esc(&r.label),
            esc(&r.label),
            esc(&temporal),
            single
        );
    }
    o.push_str("</div>");
    let temporal_file = format!("plots/{TEMPORAL_ERROR_PLOT}.svg");
    if let Some(p) = plots.iter().find(|p| p.file == temporal_file) {
        let _ = write!(
            o,
            "<figure class=\"temporal\"><img src=\"{0}\" alt=\"{1}\"><figcaption>{1}</figcaption></figure>",
            esc(&url(&p.file)),
            esc(&p.caption)
        );
    }
    o.push_str("</section>\n");
}

/// The resolved camera and light and the scene they belong to.
fn provenance(o: &mut String, m: &Metrics) {
    let prov = json!({
        "scene_source": m.scene.scene_source, "scene_params": m.scene.scene_params,
        "up": m.scene.up, "camera": m.camera, "light": m.light, "warnings": m.scene.warnings,
    });
    let _ = write!(
        o,
        "<section id=\"provenance\"><h2>Provenance</h2><p class=\"note\">The resolved camera and light in world units; the full figures are in <a href=\"metrics.json\">metrics.json</a>.</p><pre>{}</pre></section>\n</main>\n",
        esc(&serde_json::to_string_pretty(&prov).expect("JSON values serialize"))
    );
}

/// What the page's self-test expects (every run's label, the reference image), and the
/// script.
fn self_test_data(o: &mut String, m: &Metrics) {
    let data = json!({
        "labels": m.results.iter().map(|r| r.label.as_str()).collect::<Vec<_>>(),
        "reference": m.reference.image,
    });
    // `<` escaped so no string can close the script element.
    let data = data.to_string().replace('<', "\\u003c");
    let _ = write!(
        o,
        "<pre id=\"selftest\"></pre>\n<script type=\"application/json\" id=\"report-data\">{data}</script>\n<script>{SCRIPT}</script>\n</body></html>\n"
    );
}
