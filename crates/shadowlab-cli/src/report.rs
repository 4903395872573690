//! The report of `compare`: `DIR/index.html`, self-contained and offline (no network
//! resource; every image is a file beside it), with the shaded images side by side, each
//! technique's error image, a before/after slider between any two images, zoomed crops of
//! each technique's worst error region, the metrics table, SVG plots (error against time,
//! error and time against a swept parameter, time per frame), the walkthrough animations
//! and a gallery of whatever intermediate images the techniques dumped into `DIR/dump`.
//!
//! Opened as `index.html?selftest=1`, the page checks itself once loaded — every technique
//! has a table row, every image decoded, the slider moves — and writes the verdict as JSON
//! into `<pre id="selftest">`, which a headless browser can dump.
//!
//! Also here: the animated GIF writer of `--frames` and the search for the worst error
//! region.

use crate::plots::{self, Axis, Point, Scale, Series};
use anyhow::{Context, Result};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{imageops, Delay, RgbImage};
use serde_json::{json, Value};
use shadowlab::compare::luminance;
use shadowlab::techniques::Visibility;
use shadowlab::view::ViewSamples;
use std::fmt::Write as _;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Display time of one animation frame in milliseconds (10 frames per second).
pub const ANIMATION_FRAME_MS: u32 = 100;
/// Animations are scaled down to at most this width: GIF size grows with the pixel count
/// and its 256-colour palette hides fine detail anyway; the numbered PNGs keep full size.
pub const ANIMATION_MAX_WIDTH: u32 = 640;
/// GIF palette quantization speed (1 = best colours, 30 = fastest): 10 keeps shadow
/// gradients without banding at a few tens of milliseconds per frame.
const ANIMATION_QUANTIZE_SPEED: i32 = 10;

/// Side of the worst-error window as a fraction of the image's shorter side: small enough
/// to show single texels, large enough to show the shape of the artifact.
pub const CROP_FRACTION: f64 = 1.0 / 8.0;
/// Smallest and largest side of the worst-error window in pixels.
pub const CROP_SIDE_RANGE: (u32, u32) = (16, 128);
/// Each panel of a crop is enlarged (nearest neighbour, so pixels stay visible) to about
/// this many pixels across.
pub const CROP_PANEL_PIXELS: u32 = 256;
/// White gap between the panels of a crop, in pixels.
const CROP_GAP: u32 = 6;

/// At most this many dumped images are shown in the gallery; the rest are listed by count.
pub const DUMP_GALLERY_MAX: usize = 240;

/// Writes an animated GIF frame by frame, so a walkthrough never sits in memory.
pub struct Animation {
    encoder: GifEncoder<BufWriter<File>>,
    path: PathBuf,
}

impl Animation {
    /// Starts an endlessly looping animation at `path`.
    pub fn create(path: &Path) -> Result<Self> {
        let file =
            File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        let mut encoder =
            GifEncoder::new_with_speed(BufWriter::new(file), ANIMATION_QUANTIZE_SPEED);
        encoder
            .set_repeat(Repeat::Infinite)
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(Animation {
            encoder,
            path: path.to_path_buf(),
        })
    }

    /// Appends one frame, scaled down to [`ANIMATION_MAX_WIDTH`] if wider.
    pub fn push(&mut self, img: &RgbImage) -> Result<()> {
        let rgba = if img.width() > ANIMATION_MAX_WIDTH {
            let h = ((img.height() as u64 * ANIMATION_MAX_WIDTH as u64) / img.width() as u64).max(1)
                as u32;
            image::DynamicImage::ImageRgb8(imageops::resize(
                img,
                ANIMATION_MAX_WIDTH,
                h,
                imageops::FilterType::Triangle,
            ))
            .into_rgba8()
        } else {
            image::DynamicImage::ImageRgb8(img.clone()).into_rgba8()
        };
        let frame = image::Frame::from_parts(
            rgba,
            0,
            0,
            Delay::from_numer_denom_ms(ANIMATION_FRAME_MS, 1),
        );
        self.encoder
            .encode_frame(frame)
            .with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// Finishes the file.
    pub fn finish(self) -> Result<()> {
        let path = self.path;
        // The GIF trailer is written when the encoder drops; the buffer flushes with it.
        drop(self.encoder);
        if !path.is_file() {
            anyhow::bail!("cannot write {}", path.display());
        }
        Ok(())
    }
}

/// The square window where a technique's shadow term is furthest from the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Side in pixels.
    pub side: u32,
    /// Mean absolute luminance error over the window's pixels (uncovered ones count 0).
    pub mean_abs_error: f64,
}

impl Region {
    /// The region as report JSON, with the crop image's file name.
    pub fn to_json(self, crop: &str) -> Value {
        json!({"x": self.x, "y": self.y, "width": self.side, "height": self.side,
               "mean_abs_error": self.mean_abs_error, "crop": crop})
    }
}

/// The side of the worst-error window for a `width × height` image.
pub fn crop_side(width: u32, height: u32) -> u32 {
    let s = (width.min(height) as f64 * CROP_FRACTION).round() as u32;
    s.clamp(CROP_SIDE_RANGE.0, CROP_SIDE_RANGE.1)
        .min(width.min(height))
        .max(1)
}

/// Finds the window of [`crop_side`] pixels with the largest summed absolute luminance
/// error of `vis` against `reference` over covered pixels; the first in row order wins a
/// tie. `None` when the two agree everywhere.
pub fn worst_region(
    view: &ViewSamples,
    vis: &Visibility,
    reference: &Visibility,
) -> Option<Region> {
    let n = view.width as usize * view.height as usize;
    if vis.value.len() != n || reference.value.len() != n {
        return None;
    }
    let error: Vec<f64> = (0..n)
        .map(|k| {
            if view.covered(k) {
                (luminance(vis.value[k]) - luminance(reference.value[k])).abs() as f64
            } else {
                0.0
            }
        })
        .collect();
    worst_window(
        &error,
        view.width,
        view.height,
        crop_side(view.width, view.height),
    )
}

/// The `side × side` window of largest summed `error` (row-major, `width × height`); the
/// first in row order wins a tie. `None` when the largest sum is rounding noise.
pub fn worst_window(error: &[f64], width: u32, height: u32, side: u32) -> Option<Region> {
    let (w, h, side) = (width as usize, height as usize, side as usize);
    if w == 0 || h == 0 || side == 0 || side > w.min(h) || error.len() != w * h {
        return None;
    }
    // Summed-area table, built in a fixed order so the answer depends on the images alone.
    let mut sat = vec![0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0f64;
        for x in 0..w {
            row += error[y * w + x];
            sat[(y + 1) * (w + 1) + x + 1] = sat[y * (w + 1) + x + 1] + row;
        }
    }
    let window = |x: usize, y: usize| {
        let (x1, y1) = (x + side, y + side);
        sat[y1 * (w + 1) + x1] - sat[y * (w + 1) + x1] - sat[y1 * (w + 1) + x]
            + sat[y * (w + 1) + x]
    };
    let mut best = (0.0, 0, 0);
    for y in 0..=h - side {
        for x in 0..=w - side {
            let s = window(x, y);
            if s > best.0 + WINDOW_TIE {
                best = (s, x, y);
            }
        }
    }
    (best.0 > WINDOW_NOISE).then(|| Region {
        x: best.1 as u32,
        y: best.2 as u32,
        side: side as u32,
        mean_abs_error: best.0 / (side * side) as f64,
    })
}

/// Window sums closer than this count as equal, so the summed-area table's rounding
/// cannot move the chosen window between equally bad places.
const WINDOW_TIE: f64 = 1e-9;
/// A window whose summed error is below this shows rounding noise, not an error worth a
/// crop.
const WINDOW_NOISE: f64 = 1e-6;

/// Writes `DIR/crops/<stem>.png`: the region of each image side by side (reference,
/// technique, error), enlarged with nearest-neighbour sampling. Returns the path relative
/// to `dir`.
pub fn write_crop(dir: &Path, stem: &str, region: &Region, panels: &[&RgbImage]) -> Result<String> {
    let zoom = (CROP_PANEL_PIXELS / region.side).max(1);
    let p = region.side * zoom;
    let n = panels.len() as u32;
    let mut out = RgbImage::from_pixel(
        n * p + n.saturating_sub(1) * CROP_GAP,
        p,
        image::Rgb([255, 255, 255]),
    );
    for (i, img) in panels.iter().enumerate() {
        let x0 = i as u32 * (p + CROP_GAP);
        for y in 0..p {
            for x in 0..p {
                let (sx, sy) = (region.x + x / zoom, region.y + y / zoom);
                if sx < img.width() && sy < img.height() {
                    out.put_pixel(x0 + x, y, *img.get_pixel(sx, sy));
                }
            }
        }
    }
    let rel = format!("crops/{stem}.png");
    let path = dir.join(&rel);
    std::fs::create_dir_all(dir.join("crops"))
        .with_context(|| format!("cannot create {}", dir.join("crops").display()))?;
    shadowlab::shade::save_png(&out, &path)?;
    Ok(rel)
}

/// The reference sample counts of a report: "16 samples or 1 sample (…)" when the
/// verdicts used more than one reference.
fn reference_samples(metrics: &Value) -> String {
    let counts: Vec<u64> = match metrics["references"].as_array() {
        Some(list) if !list.is_empty() => list
            .iter()
            .filter_map(|r| r["samples_per_pixel"].as_u64())
            .collect(),
        _ => metrics["reference"]["samples_per_pixel"]
            .as_u64()
            .into_iter()
            .collect(),
    };
    let each: Vec<String> = counts
        .iter()
        .map(|&n| format!("{n} sample{}", if n == 1 { "" } else { "s" }))
        .collect();
    if each.len() > 1 {
        format!(
            "{} (each technique's row says which its verdict used)",
            each.join(" or ")
        )
    } else {
        each.join("")
    }
}

/// Under a technique's name: the reference its verdict used and, for a progressive
/// technique, how many frames it had.
fn verdict_note(r: &Value) -> String {
    let mut parts = Vec::new();
    if let Some(n) = r["reference_spp"].as_u64() {
        parts.push(format!("vs {n} spp"));
    }
    if let (Some(n), Some(c)) = (r["frames_run"].as_u64(), r["converged"].as_bool()) {
        parts.push(if c {
            format!("converged in {n} frames")
        } else {
            format!("{n} frames, not converged")
        });
    }
    if parts.is_empty() {
        return String::new();
    }
    format!(
        "<br><span class=\"small verdict\">{}</span>",
        esc(&parts.join(" · "))
    )
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// A relative path as a URL: each component percent-encoded where needed.
fn url(rel: &str) -> String {
    let mut s = String::new();
    for b in rel.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            s.push(b as char);
        } else {
            let _ = write!(s, "%{b:02X}");
        }
    }
    s
}

fn bytes(n: f64) -> String {
    if n >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", n / (1024.0 * 1024.0))
    } else if n >= 1024.0 {
        format!("{:.1} KiB", n / 1024.0)
    } else {
        format!("{n:.0} B")
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

fn s(v: &Value) -> &str {
    v.as_str().unwrap_or("")
}

/// Table cells show at most this many parameters or counters; the rest unfold on a click,
/// so every row stays a line or two tall.
const CELL_ITEMS: usize = 4;

/// `items` joined, those past [`CELL_ITEMS`] folded into a `<details>`.
fn folded(items: &[String]) -> String {
    if items.len() <= CELL_ITEMS + 1 {
        return items.join(" ");
    }
    format!(
        "<details><summary>{} <span class=\"more\">+{} more</span></summary>{}</details>",
        items[..CELL_ITEMS].join(" "),
        items.len() - CELL_ITEMS,
        items[CELL_ITEMS..].join(" ")
    )
}

/// One technique run as the report sees it.
struct Row<'a> {
    label: &'a str,
    technique: &'a str,
    v: &'a Value,
}

impl Row<'_> {
    fn time(&self) -> f64 {
        f(&self.v["time_ms"])
    }
    fn mismatch(&self) -> f64 {
        f(&self.v["mismatch_rate"])
    }
    fn error(&self) -> f64 {
        f(&self.v["mean_abs_error"])
    }
    /// The swept parameter and its value, when this run is one value of a `--sweep`.
    fn sweep(&self) -> Option<(String, String)> {
        if let (Some(k), Some(v)) = (
            self.v["sweep"]["key"].as_str(),
            self.v["sweep"]["value"].as_str(),
        ) {
            return Some((k.to_string(), v.to_string()));
        }
        let rest = self.label.strip_prefix(self.technique)?.strip_prefix('.')?;
        let (k, v) = rest.split_once('=')?;
        Some((k.to_string(), v.to_string()))
    }
}

/// The unit of a technique parameter as CLI.md names them, for plot axes.
fn param_unit(key: &str) -> Option<&'static str> {
    Some(match key {
        "resolution" => "texels per side",
        "budget-mb" => "MiB",
        "kernel" | "blur" => "texels",
        "samples" => "samples per pixel",
        "m" => "basis terms",
        "leaf-size" => "samples per leaf",
        "alpha" => "scale factor",
        _ => return None,
    })
}

/// True when there are at least three positive values, each the same ratio (other than
/// 1) times the one before.
fn geometric(xs: &[f64]) -> bool {
    if xs.len() < 3 || xs.iter().any(|&x| x <= 0.0) {
        return false;
    }
    let r = xs[1] / xs[0];
    // Ratios within this relative tolerance count as equal (values are typed by hand).
    const RATIO_TOLERANCE: f64 = 0.02;
    (r - 1.0).abs() > RATIO_TOLERANCE
        && xs
            .windows(2)
            .all(|w| ((w[1] / w[0]) / r - 1.0).abs() < RATIO_TOLERANCE)
}

/// A plot written to `DIR/plots/`.
struct Plot {
    file: String,
    caption: String,
}

fn write_plot(
    dir: &Path,
    name: &str,
    svg: &str,
    caption: String,
    out: &mut Vec<Plot>,
) -> Result<()> {
    let rel = format!("plots/{name}.svg");
    let path = dir.join(&rel);
    std::fs::write(&path, svg).with_context(|| format!("cannot write {}", path.display()))?;
    out.push(Plot { file: rel, caption });
    Ok(())
}

/// Draws every plot the metrics support into `DIR/plots/`.
fn make_plots(dir: &Path, rows: &[Row]) -> Result<Vec<Plot>> {
    let pdir = dir.join("plots");
    std::fs::create_dir_all(&pdir).with_context(|| format!("cannot create {}", pdir.display()))?;
    let mut out = Vec::new();
    if rows.is_empty() {
        return Ok(out);
    }
    let times: Vec<f64> = rows.iter().map(Row::time).collect();
    let time_axis = Axis::auto("frame time (ms, log scale)", &times, 20.0);
    let time_axis = if time_axis.scale == Scale::Linear {
        Axis::linear("frame time (ms)")
    } else {
        time_axis
    };
    let pts = |y: &dyn Fn(&Row) -> f64| -> Vec<Point> {
        rows.iter()
            .map(|r| Point {
                label: r.label.to_string(),
                x: r.time(),
                y: y(r),
            })
            .collect()
    };
    let svg = plots::scatter(
        "Error against time",
        &time_axis,
        &Axis::linear("mean absolute error (visibility, 0–1)"),
        &pts(&|r| r.error()),
    )?;
    write_plot(
        dir,
        "error-vs-time",
        &svg,
        "Mean absolute error of the shadow term against frame time; lower left is better.".into(),
        &mut out,
    )?;
    let svg = plots::scatter(
        "Mismatch against time",
        &time_axis,
        &Axis::linear("mismatched pixels (% of covered)"),
        &pts(&|r| r.mismatch() * 100.0),
    )?;
    write_plot(dir, "mismatch-vs-time", &svg, "Share of covered pixels whose lit/shadowed answer differs from the reference, against frame time.".into(), &mut out)?;

    // One pair of plots per swept (technique, parameter), values in the order given.
    type Sweep<'r> = (String, String, Vec<(String, &'r Row<'r>)>);
    let mut sweeps: Vec<Sweep> = Vec::new();
    for r in rows {
        if let Some((k, v)) = r.sweep() {
            match sweeps.iter_mut().find(|s| s.0 == r.technique && s.1 == k) {
                Some(s) => s.2.push((v, r)),
                None => sweeps.push((r.technique.to_string(), k, vec![(v, r)])),
            }
        }
    }
    for (t, k, runs) in &sweeps {
        let nums: Option<Vec<f64>> = runs
            .iter()
            .map(|(v, _)| v.parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect();
        let desc = match param_unit(k) {
            Some(u) => format!("{t}.{k} ({u})"),
            None => format!("{t}.{k}"),
        };
        let names: Vec<String> = runs.iter().map(|(v, _)| v.clone()).collect();
        let index: Vec<f64> = (0..runs.len()).map(|i| i as f64).collect();
        let categories = |desc: String| Axis {
            desc,
            scale: Scale::Categories(names.clone()),
        };
        // Geometric values (512, 1024, 2048, …) sit evenly on a log axis: draw them as
        // categories so each value carries its own tick; other numbers get a true axis.
        let (xaxis, xs) = match nums {
            Some(xs) if geometric(&xs) => (categories(format!("{desc}, log scale")), index),
            Some(xs) => (Axis::auto(desc.clone(), &xs, 16.0), xs),
            None => (categories(desc.clone()), index),
        };
        let series = |name: &str, y: &dyn Fn(&Row) -> f64| Series {
            name: name.to_string(),
            points: xs.iter().zip(runs).map(|(&x, (_, r))| (x, y(r))).collect(),
        };
        let name = crate::commands::slug(&format!("sweep-{t}-{k}"));
        let svg = plots::lines(
            &format!("{t}: error against {k}"),
            &xaxis,
            &Axis::linear("error (fraction, 0–1)"),
            &[
                series("mismatch rate", &|r| r.mismatch()),
                series("mean abs error", &|r| r.error()),
            ],
        )?;
        write_plot(
            dir,
            &format!("{name}-error"),
            &svg,
            format!("{t}: mismatch rate and mean absolute error against {k}."),
            &mut out,
        )?;
        let svg = plots::lines(
            &format!("{t}: time against {k}"),
            &xaxis,
            &Axis::linear("frame time (ms)"),
            &[series("time", &|r| r.time())],
        )?;
        write_plot(
            dir,
            &format!("{name}-time"),
            &svg,
            format!("{t}: frame time against {k}."),
            &mut out,
        )?;
    }

    // Time per frame of a walkthrough.
    let per_frame: Vec<Series> = rows
        .iter()
        .filter_map(|r| {
            let fr = r.v["frames"].as_array()?;
            Some(Series {
                name: r.label.to_string(),
                points: fr
                    .iter()
                    .map(|x| (f(&x["frame"]), f(&x["time_ms"])))
                    .collect(),
            })
        })
        .filter(|s| s.points.len() > 1)
        .collect();
    if !per_frame.is_empty() {
        let all: Vec<f64> = per_frame
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .collect();
        let yaxis = match Axis::auto("frame time (ms, log scale)", &all, 50.0) {
            a if a.scale == Scale::Log => a,
            _ => Axis::linear("frame time (ms)"),
        };
        let svg = plots::lines(
            "Time per frame",
            &Axis::linear("frame (index along the camera path)"),
            &yaxis,
            &per_frame,
        )?;
        write_plot(
            dir,
            "frame-times",
            &svg,
            "Each technique's frame time along the walkthrough.".into(),
            &mut out,
        )?;
    }
    Ok(out)
}

/// Files under `DIR/<sub>`, relative to `dir` and sorted: images (PNG, JPEG, GIF, SVG)
/// and everything else.
fn dumped_files(dir: &Path, sub: &str) -> (Vec<String>, Vec<String>) {
    fn walk(root: &Path, d: &Path, out: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(d) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if let Ok(rel) = p.strip_prefix(root) {
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut all = Vec::new();
    walk(dir, &dir.join(sub), &mut all);
    all.sort();
    all.into_iter().partition(|rel| {
        let ext = rel.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
        matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg" | "gif" | "svg"))
    })
}

/// The gallery group of a dumped image: its folder under `dump/`, else its file name up
/// to the first `-` or `_`.
fn dump_group(rel: &str) -> String {
    let inner = rel.strip_prefix("dump/").unwrap_or(rel);
    match inner.split_once('/') {
        Some((d, _)) => d.to_string(),
        None => inner
            .split(['-', '_', '.'])
            .next()
            .unwrap_or(inner)
            .to_string(),
    }
}

const CSS: &str = r#"
:root{--fg:#1d2330;--muted:#667085;--line:#d9dee7;--bg:#f6f7f9;--card:#fff;--accent:#2563eb}
*{box-sizing:border-box}
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;color:var(--fg);background:var(--bg);margin:0}
header{background:#141a26;color:#eef2f8;padding:18px 28px}
header h1{margin:0 0 4px;font-size:22px;font-weight:600}
header p{margin:0;color:#b8c2d3}
nav{position:sticky;top:0;z-index:5;background:#fff;border-bottom:1px solid var(--line);padding:6px 28px}
nav a{margin-right:16px;color:var(--accent);text-decoration:none}
main{padding:10px 28px 40px}
section{background:var(--card);border:1px solid var(--line);border-radius:8px;padding:14px 18px;margin:16px 0}
h2{font-size:17px;margin:0 0 10px}
.note{color:var(--muted);margin:4px 0 10px}
table{border-collapse:collapse;width:100%}
th,td{border-bottom:1px solid var(--line);padding:5px 8px;text-align:right;vertical-align:top}
th{background:#f0f2f6;cursor:pointer;user-select:none;white-space:nowrap}
th.text,td.text{text-align:left}
tr.reference-row td{background:#fbfbf2}
td.best{font-weight:700;color:#0a7a3b}
.stagebar{display:flex;height:9px;width:100%;border-radius:2px;overflow:hidden;background:#eee;margin:4px 0 3px}
.kv{display:inline-block;white-space:nowrap;margin-right:9px}
details summary{cursor:pointer;list-style:none}
details summary::-webkit-details-marker{display:none}
.more{color:var(--accent);white-space:nowrap}
td.params{max-width:230px}
td.stages{width:300px;text-align:left}
td.stages .kv{margin-right:6px}
tr td:first-child{white-space:nowrap}
td.counters{max-width:330px}
.stagebar span{display:block;height:100%}
.small{font-size:12px;color:var(--muted)}
.grid{display:flex;flex-wrap:wrap;gap:14px}
figure{margin:0}
figcaption{font-size:12px;color:var(--muted);margin-top:2px}
.pair{display:flex;gap:6px}
.pair img,.ref img{width:320px;display:block;border:1px solid var(--line)}
.frame{position:relative;display:inline-block}
.box{position:absolute;border:2px solid #ffd400;box-shadow:0 0 0 1px #000;pointer-events:none}
.slider-controls{display:flex;gap:14px;align-items:center;flex-wrap:wrap;margin-bottom:8px}
.slider{position:relative;display:inline-block;max-width:min(100%,1024px);cursor:ew-resize;touch-action:none;user-select:none;line-height:0}
.slider img{display:block;max-width:100%;height:auto}
#slider-a{position:absolute;left:0;top:0;width:100%;height:100%}
#slider-handle{position:absolute;top:0;bottom:0;width:2px;margin-left:-1px;background:#fff;box-shadow:0 0 3px #000;pointer-events:none}
.tag{position:absolute;top:8px;background:rgba(0,0,0,.6);color:#fff;padding:2px 6px;border-radius:3px;font-size:12px;line-height:1.3}
#slider-range{width:min(100%,1024px);display:block;margin-top:8px}
.crop img{display:block;border:1px solid var(--line)}
.cropcap{display:flex;font-size:12px;color:var(--muted)}
.cropcap span{flex:1;text-align:center}
.plots img{width:640px;max-width:100%;border:1px solid var(--line);background:#fff}
.groups{display:flex;flex-wrap:wrap;gap:10px 28px}
.group h3{font-size:14px;margin:6px 0}
.gallery img{max-width:200px;max-height:200px;display:block;border:1px solid var(--line);image-rendering:pixelated;background:#222}
pre{background:#f0f2f6;padding:8px;overflow:auto;font-size:12px}
#selftest{display:none}
"#;

const SCRIPT: &str = r#"
(function(){
const data=JSON.parse(document.getElementById('report-data').textContent);
const selA=document.getElementById('slider-left'),selB=document.getElementById('slider-right');
const imgA=document.getElementById('slider-a'),imgB=document.getElementById('slider-b');
const range=document.getElementById('slider-range'),handle=document.getElementById('slider-handle');
const box=document.getElementById('slider'),tagA=document.getElementById('tag-a'),tagB=document.getElementById('tag-b');
function setSplit(p){
  p=Math.max(0,Math.min(100,p));
  imgA.style.clipPath='inset(0 '+(100-p)+'% 0 0)';
  handle.style.left=p+'%';
  if(String(range.value)!==String(p))range.value=p;
}
function pick(sel,img,tag){const o=sel.options[sel.selectedIndex];img.src=o.value;tag.textContent=o.textContent;}
if(range){
  range.addEventListener('input',()=>setSplit(parseFloat(range.value)));
  selA.addEventListener('change',()=>pick(selA,imgA,tagA));
  selB.addEventListener('change',()=>pick(selB,imgB,tagB));
  let drag=false;
  const at=e=>{const r=box.getBoundingClientRect();setSplit((e.clientX-r.left)/r.width*100);};
  box.addEventListener('pointerdown',e=>{drag=true;if(box.setPointerCapture&&e.pointerId!==undefined){try{box.setPointerCapture(e.pointerId)}catch(_){}}at(e);});
  box.addEventListener('pointermove',e=>{if(drag)at(e);});
  window.addEventListener('pointerup',()=>{drag=false;});
  setSplit(parseFloat(range.value));
}
// Sortable metrics table: click a header; numbers sort by their data-v.
document.querySelectorAll('#metrics th').forEach((th,i)=>{
  th.addEventListener('click',()=>{
    const tb=document.querySelector('#metrics tbody.runs');
    const rows=[...tb.rows];const asc=th.dataset.dir!=='asc';th.dataset.dir=asc?'asc':'desc';
    rows.sort((a,b)=>{const x=a.cells[i].dataset.v,y=b.cells[i].dataset.v;
      const c=(x!==undefined&&y!==undefined)?parseFloat(x)-parseFloat(y):a.cells[i].textContent.localeCompare(b.cells[i].textContent);
      return asc?c:-c;});
    rows.forEach(r=>tb.appendChild(r));
  });
});
if(!/[?&]selftest=1\b/.test(location.search))return;
function run(){
  const out={};
  const rows=[...document.querySelectorAll('tr.technique-row')].map(r=>r.dataset.label);
  out.expected_rows=data.labels;
  out.missing_rows=data.labels.filter(l=>!rows.includes(l));
  const imgs=[...document.images];
  out.images=imgs.length;
  out.broken_images=imgs.filter(i=>!(i.complete&&i.naturalWidth>0)).map(i=>i.getAttribute('src'));
  out.plots=imgs.filter(i=>/\.svg$/.test(i.getAttribute('src')||'')).length;
  let moved=false,dragged=false,picked=false;
  if(range){
    range.value=20;range.dispatchEvent(new Event('input'));
    const c1=getComputedStyle(imgA).clipPath,h1=handle.getBoundingClientRect().left;
    range.value=80;range.dispatchEvent(new Event('input'));
    const c2=getComputedStyle(imgA).clipPath,h2=handle.getBoundingClientRect().left;
    moved=c1!==c2&&h2>h1;
    const r=box.getBoundingClientRect();
    const ev=(t,x)=>box.dispatchEvent(new PointerEvent(t,{bubbles:true,clientX:x,clientY:r.top+r.height/2,pointerId:1}));
    ev('pointerdown',r.left+r.width*0.3);ev('pointermove',r.left+r.width*0.6);window.dispatchEvent(new PointerEvent('pointerup',{}));
    dragged=Math.abs(parseFloat(range.value)-60)<1;
    if(selB.options.length>2){const before=imgB.getAttribute('src');selB.selectedIndex=2;selB.dispatchEvent(new Event('change'));picked=imgB.getAttribute('src')!==before;}else picked=true;
  }
  out.slider_moved=moved;out.slider_dragged=dragged;out.slider_picks=picked;
  out.ok=out.missing_rows.length===0&&out.broken_images.length===0&&moved&&dragged&&picked;
  const pre=document.getElementById('selftest');pre.textContent=JSON.stringify(out);pre.dataset.done='1';
}
if(document.readyState==='complete')run();else window.addEventListener('load',run);
})();
"#;

/// Writes `DIR/index.html` (and its plots in `DIR/plots/`) from the metrics of `compare`.
pub fn write_html(dir: &Path, metrics: &Value) -> Result<()> {
    let results = metrics["results"].as_array().cloned().unwrap_or_default();
    let rows: Vec<Row> = results
        .iter()
        .map(|v| Row {
            label: v["label"]
                .as_str()
                .or(v["technique"].as_str())
                .unwrap_or("?"),
            technique: s(&v["technique"]),
            v,
        })
        .collect();
    let plots = make_plots(dir, &rows)?;
    let scene = s(&metrics["scene"]);
    let reference = &metrics["reference"];
    let ref_image = reference["image"].as_str().unwrap_or("reference.png");
    let (w, h) = (f(&metrics["width"]), f(&metrics["height"]));
    let frames = metrics["frames"].as_u64().unwrap_or(1);

    let mut o = String::with_capacity(64 * 1024);
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
        metrics["triangles"],
        w,
        h,
        metrics["covered_pixels"],
        f(&metrics["camera_pass_ms"]),
        esc(&reference_samples(metrics)),
        f(&reference["time_ms"]),
        f(&reference["bvh_build_ms"]),
        f(&reference["trace_ms"]),
        metrics["threads"],
        if frames > 1 { format!(" · {frames} frames (figures are of the last)") } else { String::new() },
        esc(s(&metrics["shadowlab_version"]))
    );
    // Only a run with --dump shows its dump folder, so a stale one is never passed off as
    // this run's.
    let (dumps, dump_other) = match metrics["dump"].as_str() {
        Some(sub) => dumped_files(dir, sub),
        None => (Vec::new(), Vec::new()),
    };
    let has_anim = rows.iter().any(|r| r.v["animation"].is_string());
    o.push_str("<nav><a href=\"#metrics-section\">metrics</a><a href=\"#compare\">slider</a><a href=\"#plots\">plots</a><a href=\"#images\">images</a><a href=\"#crops\">worst regions</a>");
    if has_anim {
        o.push_str("<a href=\"#animation\">animation</a>");
    }
    if !dumps.is_empty() || !dump_other.is_empty() {
        o.push_str("<a href=\"#dump\">intermediate images</a>");
    }
    o.push_str("<a href=\"#provenance\">provenance</a><a href=\"metrics.json\">metrics.json</a></nav>\n<main>\n");

    // Before/after slider.
    let mut options = format!(
        "<option value=\"{}\">reference</option>",
        esc(&url(ref_image))
    );
    for r in &rows {
        let _ = write!(
            options,
            "<option value=\"{}\">{}</option>",
            esc(&url(s(&r.v["image"]))),
            esc(r.label)
        );
        if let Some(e) = r.v["error_image"].as_str() {
            let _ = write!(
                options,
                "<option value=\"{}\">{} error</option>",
                esc(&url(e)),
                esc(r.label)
            );
        }
    }
    // The first run that is not itself a ray tracer is the interesting default.
    let first = rows
        .iter()
        .find(|r| r.technique != "raytrace")
        .or(rows.first())
        .map(|r| (url(s(&r.v["image"])), r.label))
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
    let mut slider = String::new();
    let _ = writeln!(
        slider,
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

    // Metrics table.
    let best = |key: &dyn Fn(&Row) -> f64| rows.iter().map(key).fold(f64::INFINITY, f64::min);
    let (best_t, best_m, best_e) = (
        best(&|r| r.time()),
        best(&|r| r.mismatch()),
        best(&|r| r.error()),
    );
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
        esc(reference["pattern"].as_str().unwrap_or("grid")),
        f(&reference["time_ms"]),
        f(&reference["time_ms"]),
        f(&reference["bvh_build_ms"]),
        f(&reference["trace_ms"])
    );
    for r in &rows {
        let params = r.v["params"]
            .as_object()
            .map(|m| {
                m.iter()
                    .map(|(k, v)| {
                        format!(
                            "<span class=\"kv\">{}={}</span>",
                            esc(k),
                            esc(v.to_string().trim_matches('"'))
                        )
                    })
                    .collect::<Vec<_>>()
            })
            .map(|items| folded(&items))
            .unwrap_or_default();
        let time = r.time();
        let mut stages = String::from("<div class=\"stagebar\">");
        let mut stage_text = Vec::new();
        if let Some(st) = r.v["stages_ms"].as_object() {
            for (i, (k, v)) in st.iter().enumerate() {
                let c = plots::color(i);
                let _ = write!(
                    stages,
                    "<span title=\"{} {:.2} ms\" style=\"width:{:.2}%;background:rgb({},{},{})\"></span>",
                    esc(k),
                    f(v),
                    if time > 0.0 { f(v) / time * 100.0 } else { 0.0 },
                    c.0,
                    c.1,
                    c.2
                );
                stage_text.push(format!(
                    "<span class=\"kv\"><span style=\"color:rgb({},{},{})\">■</span> {} {}</span>",
                    c.0,
                    c.1,
                    c.2,
                    esc(k),
                    plots::short(f(v))
                ));
            }
        }
        stages.push_str("</div>");
        let counters = r.v["counters"]
            .as_object()
            .map(|m| {
                m.iter()
                    .map(|(k, v)| {
                        format!(
                            "<span class=\"kv\">{} {}</span>",
                            esc(k),
                            plots::short(f(v))
                        )
                    })
                    .collect::<Vec<_>>()
            })
            .map(|items| folded(&items))
            .unwrap_or_default();
        let cls = |v: f64, b: f64| if v <= b { " class=\"best\"" } else { "" };
        let _ = write!(
            o,
            "<tr class=\"technique-row\" data-label=\"{}\"><td class=\"text\">{}{}</td><td class=\"text small params\">{}</td>\
             <td data-v=\"{:.6}\"{}>{:.2}</td><td class=\"small stages\" data-v=\"{:.6}\">{}{}</td><td data-v=\"{}\">{}</td>\
             <td data-v=\"{:.8}\"{}>{:.4}%</td><td data-v=\"{:.8}\"{}>{:.5}</td><td class=\"text small counters\">{}</td></tr>",
            esc(r.label),
            esc(r.label),
            verdict_note(r.v),
            params,
            time,
            cls(time, best_t),
            time,
            time,
            stages,
            stage_text.join(" "),
            f(&r.v["memory_bytes"]),
            bytes(f(&r.v["memory_bytes"])),
            r.mismatch(),
            cls(r.mismatch(), best_m),
            r.mismatch() * 100.0,
            r.error(),
            cls(r.error(), best_e),
            r.error(),
            counters
        );
    }
    o.push_str("</tbody></table></section>\n");
    o.push_str(&slider);

    // Plots.
    o.push_str("<section id=\"plots\"><h2>Plots</h2><div class=\"grid plots\">");
    for p in &plots {
        let _ = write!(
            o,
            "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>",
            esc(&url(&p.file)),
            esc(&p.caption)
        );
    }
    o.push_str("</div></section>\n");

    // Images side by side, the worst region outlined.
    let _ = write!(
        o,
        "<section id=\"images\"><h2>Images</h2><p class=\"note\">Each technique's shaded frame and its error against the reference: \
         red where the technique is lighter, blue where it is darker, black where they agree (brightness ∝ √|error|). \
         The yellow box marks the worst region, enlarged below.</p><div class=\"grid\">\
         <figure class=\"ref\"><a href=\"{0}\"><img src=\"{0}\" alt=\"reference\"></a><figcaption>reference (ray traced)</figcaption></figure>",
        esc(&url(ref_image))
    );
    for r in &rows {
        let bx = match r.v["worst_region"].as_object() {
            Some(g) if w > 0.0 && h > 0.0 => format!(
                "<div class=\"box\" style=\"left:{:.3}%;top:{:.3}%;width:{:.3}%;height:{:.3}%\"></div>",
                f(&g["x"]) / w * 100.0,
                f(&g["y"]) / h * 100.0,
                f(&g["width"]) / w * 100.0,
                f(&g["height"]) / h * 100.0
            ),
            _ => String::new(),
        };
        let _ = write!(
            o,
            "<figure><div class=\"pair\"><a class=\"frame\" href=\"{0}\"><img src=\"{0}\" alt=\"{2}\">{3}</a>\
             <a class=\"frame\" href=\"{1}\"><img src=\"{1}\" alt=\"{2} error\">{3}</a></div>\
             <figcaption>{2} — {4:.2} ms, mismatch {5:.3}%, mean error {6:.4}</figcaption></figure>",
            esc(&url(s(&r.v["image"]))),
            esc(&url(s(&r.v["error_image"]))),
            esc(r.label),
            bx,
            r.time(),
            r.mismatch() * 100.0,
            r.error()
        );
    }
    o.push_str("</div></section>\n");

    // Worst regions.
    o.push_str("<section id=\"crops\"><h2>Worst error regions</h2><p class=\"note\">For each technique, the window with the largest \
                summed error, enlarged: reference, technique, error.</p><div class=\"grid\">");
    let mut any_crop = false;
    for r in &rows {
        let g = &r.v["worst_region"];
        if let Some(c) = g["crop"].as_str() {
            any_crop = true;
            let _ = write!(
                o,
                "<figure class=\"crop\"><img src=\"{}\" alt=\"{} worst region\"><div class=\"cropcap\"><span>reference</span><span>{}</span><span>error</span></div>\
                 <figcaption>{} — pixels ({}, {}) to ({}, {}); mean error there {:.4} (whole frame {:.4})</figcaption></figure>",
                esc(&url(c)),
                esc(r.label),
                esc(r.label),
                esc(r.label),
                g["x"],
                g["y"],
                f(&g["x"]) + f(&g["width"]),
                f(&g["y"]) + f(&g["height"]),
                f(&g["mean_abs_error"]),
                r.error()
            );
        }
    }
    if !any_crop {
        o.push_str("<p>Every technique matches the reference exactly.</p>");
    }
    let exact: Vec<&str> = rows
        .iter()
        .filter(|r| r.v["worst_region"].is_null())
        .map(|r| r.label)
        .collect();
    if any_crop && !exact.is_empty() {
        let _ = write!(
            o,
            "<p class=\"note\">No error anywhere: {}.</p>",
            esc(&exact.join(", "))
        );
    }
    o.push_str("</div></section>\n");

    if has_anim {
        let _ = write!(o, "<section id=\"animation\"><h2>Walkthrough</h2><p class=\"note\">{frames} frames along the camera path; numbered full-size frames are in <a href=\"frames/\">frames/</a>.</p><div class=\"grid\">");
        for r in &rows {
            if let Some(a) = r.v["animation"].as_str() {
                let _ = write!(o, "<figure><img src=\"{}\" alt=\"{} walkthrough\" style=\"max-width:320px\"><figcaption>{}</figcaption></figure>", esc(&url(a)), esc(r.label), esc(r.label));
            }
        }
        o.push_str("</div></section>\n");
    }

    if !dumps.is_empty() || !dump_other.is_empty() {
        let _ = write!(o, "<section id=\"dump\"><h2>Intermediate images</h2><p class=\"note\">What the techniques wrote into <a href=\"dump/\">dump/</a>: shadow maps, warped maps, sample points, tile trees, masks.</p>");
        let mut group = None;
        o.push_str("<div class=\"groups\">");
        for rel in dumps.iter().take(DUMP_GALLERY_MAX) {
            let g = dump_group(rel);
            if group.as_ref() != Some(&g) {
                if group.is_some() {
                    o.push_str("</div></div>");
                }
                let _ = write!(
                    o,
                    "<div class=\"group\"><h3>{}</h3><div class=\"grid gallery\">",
                    esc(&g)
                );
                group = Some(g);
            }
            let name = rel.strip_prefix("dump/").unwrap_or(rel);
            let _ = write!(o, "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>", esc(&url(rel)), esc(name));
        }
        if group.is_some() {
            o.push_str("</div></div>");
        }
        o.push_str("</div>");
        if dumps.len() > DUMP_GALLERY_MAX {
            let _ = write!(
                o,
                "<p class=\"note\">{} more images in dump/.</p>",
                dumps.len() - DUMP_GALLERY_MAX
            );
        }
        if !dump_other.is_empty() {
            o.push_str("<p class=\"note\">Other files: ");
            for (i, rel) in dump_other.iter().enumerate() {
                let name = rel.strip_prefix("dump/").unwrap_or(rel);
                let sep = if i > 0 { ", " } else { "" };
                let _ = write!(o, "{sep}<a href=\"{}\">{}</a>", esc(&url(rel)), esc(name));
            }
            o.push_str("</p>");
        }
        o.push_str("</section>\n");
    }

    let prov = json!({
        "scene_source": metrics["scene_source"], "scene_params": metrics["scene_params"],
        "camera": metrics["camera"], "light": metrics["light"], "warnings": metrics["warnings"],
    });
    let _ = write!(
        o,
        "<section id=\"provenance\"><h2>Provenance</h2><p class=\"note\">The resolved camera and light in world units; the full figures are in <a href=\"metrics.json\">metrics.json</a>.</p><pre>{}</pre></section>\n</main>\n",
        esc(&serde_json::to_string_pretty(&prov).expect("JSON values serialize"))
    );

    let data = json!({
        "labels": rows.iter().map(|r| r.label).collect::<Vec<_>>(),
        "reference": ref_image,
    });
    // `<` escaped so no string can close the script element.
    let data = data.to_string().replace('<', "\\u003c");
    let _ = write!(
        o,
        "<pre id=\"selftest\"></pre>\n<script type=\"application/json\" id=\"report-data\">{data}</script>\n<script>{SCRIPT}</script>\n</body></html>\n"
    );
    let p = dir.join("index.html");
    std::fs::write(&p, o).with_context(|| format!("cannot write {}", p.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_side_follows_image_size() {
        assert_eq!(crop_side(1024, 768), 96);
        assert_eq!(crop_side(64, 48), 16);
        assert_eq!(crop_side(8, 8), 8);
        assert_eq!(crop_side(8000, 8000), 128);
    }

    #[test]
    fn worst_window_matches_brute_force() {
        let (w, h, side) = (37u32, 23u32, 5u32);
        // A deterministic pseudo-random error field with one hot spot.
        let mut e: Vec<f64> = (0..w * h)
            .map(|i| ((i.wrapping_mul(2654435761) >> 7) % 97) as f64 / 970.0)
            .collect();
        for y in 14..18 {
            for x in 25..29 {
                e[(y * w + x) as usize] += 1.0;
            }
        }
        let got = worst_window(&e, w, h, side).unwrap();
        let mut best = (f64::NEG_INFINITY, 0, 0);
        for y in 0..=h - side {
            for x in 0..=w - side {
                let mut s = 0.0;
                for yy in y..y + side {
                    for xx in x..x + side {
                        s += e[(yy * w + xx) as usize];
                    }
                }
                if s > best.0 + 1e-9 {
                    best = (s, x, y);
                }
            }
        }
        assert_eq!((got.x, got.y), (best.1, best.2));
        assert!((got.mean_abs_error - best.0 / 25.0).abs() < 1e-9);
        assert!(
            got.x <= 25 && got.x + side >= 29 && got.y <= 14 && got.y + side >= 18,
            "{got:?}"
        );
    }

    #[test]
    fn worst_window_of_no_error_is_none() {
        assert_eq!(worst_window(&[0.0; 100], 10, 10, 4), None);
        assert_eq!(worst_window(&[1.0; 100], 10, 10, 11), None);
    }

    #[test]
    fn urls_are_escaped() {
        assert_eq!(url("plots/a b#.svg"), "plots/a%20b%23.svg");
        assert_eq!(esc("<a href=\"x\">"), "&lt;a href=&quot;x&quot;&gt;");
    }

    #[test]
    fn geometric_sweeps() {
        assert!(geometric(&[512.0, 1024.0, 2048.0, 4096.0]));
        assert!(geometric(&[4.0, 8.0, 16.0]));
        assert!(!geometric(&[4.0, 8.0]));
        assert!(!geometric(&[1.0, 2.0, 3.0]));
        assert!(!geometric(&[2.0, 2.0, 2.0]));
    }

    #[test]
    fn dump_groups() {
        assert_eq!(dump_group("dump/afsm/bsp.png"), "afsm");
        assert_eq!(dump_group("dump/sm-depth-0000.png"), "sm");
        assert_eq!(dump_group("dump/psm_post.png"), "psm");
    }
}
