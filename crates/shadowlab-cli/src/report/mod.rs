//! The report of `compare`: `DIR/index.html`, self-contained and offline (no network
//! resource; every image is a file beside it), drawn from the typed [`Metrics`] that
//! `compare` also writes as `metrics.json`: the shaded images side by side, each
//! technique's error image, a before/after slider between any two images, zoomed crops of
//! each technique's worst error region, the metrics table, SVG plots (error against time,
//! error and time against a swept parameter, time, error and temporal error per frame),
//! the walkthrough animations (reference and technique side by side, the temporal error
//! plotted under them) and a gallery of whatever intermediate images the techniques
//! dumped into `DIR/dump`.
//!
//! Opened as `index.html?selftest=1`, the page checks itself once loaded — every technique
//! has a table row, every image decoded, the slider moves — and writes the verdict as JSON
//! into `<pre id="selftest">`, which a headless browser can dump.
//!
//! The sections, top of the flow first: [`plots`] (the SVG files), [`html`] (the page,
//! section by section, with [`tables`] for the metrics table and [`dump`] for the
//! gallery), over [`rows`] (what the page reads off the metrics), [`format`](mod@format) (escaping,
//! URLs, cells) and [`assets`] (style sheet and script). [`crops`] finds the worst error
//! regions and writes their images while `compare` measures.

pub mod assets;
pub mod crops;
pub mod dump;
pub mod format;
pub mod html;
pub mod plots;
pub mod rows;
pub mod tables;

use crate::metrics::Metrics;
use anyhow::Result;
use std::path::Path;

/// Writes `DIR/index.html` and its plots in `DIR/plots/` from the metrics of `compare`.
pub fn write(dir: &Path, metrics: &Metrics) -> Result<()> {
    let plots = plots::draw(dir, &metrics.results)?;
    let dumped = dump::Dumped::find(dir, metrics.dump.as_deref());
    let page = html::page(metrics, &plots, &dumped);
    crate::output::write_file(&dir.join("index.html"), page.as_bytes())
}
