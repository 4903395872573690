//! `csm-table`: the convolution shadow map paper's Table 1 — frame times of `csm` for
//! M ∈ {4, 8, 16}, map sizes 256²–2048² and blur none / 3×3 / 7×7, beside 3×3 PCF, at
//! 1024×768 on the minified `fence-far` scene (the paper used a 365k-face scene seen from
//! far, Figure 10, with 16× anisotropic tri-linear filtering, which is `csm`'s default).
//!
//! Each cell gives the technique's own time (`render`: light map, basis images, blur, mip
//! chain, look-ups) and its ratio to 3×3 PCF's, then the ratio of whole frames: the camera
//! pass (rasterizing the scene from the eye at 1024×768, shared by every technique, timed
//! alone) plus the technique, against the same for PCF. The paper reports frames per second
//! of whole GPU frames, which include drawing the scene from the eye, so the whole-frame
//! ratio is the one comparable to the paper's ratio, printed beside ours; the technique-only
//! ratio is the stricter one.

use super::{camera_pass_line, median_ms, verdict, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::json;
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;

/// Map sides of the paper's columns.
const SIZES: [u32; 4] = [256, 512, 1024, 2048];
/// Truncation orders of the paper's rows.
const ORDERS: [u32; 3] = [4, 8, 16];
/// Blur kernel sides of the paper's three blocks (0 = none).
const BLURS: [u32; 3] = [0, 3, 7];
/// The target: `csm` at M = 4 without blur at most this multiple of 3×3 PCF's time.
const M4_TARGET: f64 = 1.3;
/// The paper's PCF frame rates per map size (fps).
const PAPER_PCF_FPS: [f64; 4] = [76.0, 74.0, 71.0, 69.0];

/// The paper's `csm` frame rate (fps) for a blur, order and size column.
fn paper_fps(blur: u32, m: u32, col: usize) -> f64 {
    let table: [[f64; 4]; 3] = match blur {
        0 => [
            [64.0, 62.0, 60.0, 50.0],
            [55.0, 53.0, 49.0, 38.0],
            [47.0, 45.0, 39.0, 26.0],
        ],
        3 => [
            [63.0, 61.0, 57.0, 43.0],
            [53.0, 50.0, 44.0, 30.0],
            [42.0, 39.0, 32.0, 19.0],
        ],
        _ => [
            [62.0, 60.0, 53.0, 36.0],
            [52.0, 49.0, 41.0, 24.0],
            [41.0, 38.0, 28.0, 14.0],
        ],
    };
    let row = ORDERS.iter().position(|&o| o == m).unwrap_or(0);
    table[row][col]
}

fn blur_name(b: u32) -> String {
    if b == 0 {
        "none".into()
    } else {
        format!("{b}x{b}")
    }
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let scene = shadowlab::scene::load("fence-far", &Default::default())
        .context("loading the fence-far scene")?;
    let mut camera = scene.camera.context("fence-far has no camera")?;
    camera.width = 1024;
    camera.height = 768;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.context("fence-far has no light")?;
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);

    let (sizes, orders, blurs, repeat): (&[u32], &[u32], &[u32], usize) = if a.quick {
        (&[256, 1024], &[4, 16], &[0, 7], 1)
    } else {
        (&SIZES, &ORDERS, &BLURS, a.repeat)
    };
    let time = |name: &str, params: &[(&str, String)]| -> Result<f64> {
        let mut t = techniques::create(name)?;
        for (k, v) in params {
            t.set_param(k, v)?;
        }
        // One untimed frame first, so page faults of fresh buffers are not timed.
        t.render(&frame)?;
        let (ms, r) = median_ms(repeat, || t.render(&frame));
        r?;
        Ok(ms)
    };

    let mut pcf = Vec::new();
    for &s in sizes {
        pcf.push(time(
            "pcf",
            &[("resolution", s.to_string()), ("kernel", "3".into())],
        )?);
    }
    println!(
        "csm-table: fence-far, 1024x768, {} covered pixels, {} threads",
        view.covered_count(),
        rayon::current_num_threads(),
    );
    // The camera pass, as every technique's frame includes it.
    let (camera_ms, _) = camera_pass_line(&scene, &camera, repeat);
    println!("each cell: technique ms (ratio to 3x3 PCF) | whole-frame ratio | paper fps (ratio)");
    let header: String = sizes
        .iter()
        .map(|s| format!(" | {:>37}", format!("S: {s}²")))
        .collect();
    let mut rows = Vec::new();
    // The target's cells: M = 4 without blur, technique-only ratio to PCF per map size.
    let mut m4 = Vec::new();
    for &b in blurs {
        println!("\nC = {}{header}", blur_name(b));
        if b == 0 {
            let cells: String = sizes
                .iter()
                .zip(&pcf)
                .map(|(&s, &p)| {
                    let col = SIZES.iter().position(|&x| x == s).unwrap_or(0);
                    format!(
                        " | {:>7.1} ms (1.00) | 1.00 | {:>3.0} fps (1.00)",
                        p, PAPER_PCF_FPS[col]
                    )
                })
                .collect();
            println!("PCF   {cells}");
        }
        for &m in orders {
            let mut cells = String::new();
            for (&s, &p) in sizes.iter().zip(&pcf) {
                let params = [
                    ("resolution", s.to_string()),
                    ("m", m.to_string()),
                    (
                        "blur",
                        if b == 0 {
                            "none".to_string()
                        } else {
                            b.to_string()
                        },
                    ),
                ];
                let ms = time("csm", &params)?;
                let col = SIZES.iter().position(|&x| x == s).unwrap_or(0);
                let fps = paper_fps(b, m, col);
                let paper_ratio = PAPER_PCF_FPS[col] / fps;
                let frame_ratio = (camera_ms + ms) / (camera_ms + p);
                if m == 4 && b == 0 {
                    m4.push((s, ms / p));
                }
                cells.push_str(&format!(
                    " | {:>7.1} ms ({:.2}) | {:.2} | {:>3.0} fps ({:.2})",
                    ms,
                    ms / p,
                    frame_ratio,
                    fps,
                    paper_ratio
                ));
                rows.push(json!({
                    "m": m,
                    "map_size": s,
                    "blur": blur_name(b),
                    "csm_ms": ms,
                    "pcf_ms": p,
                    "camera_pass_ms": camera_ms,
                    "ratio_to_pcf": ms / p,
                    "frame_ratio_to_pcf": frame_ratio,
                    "paper_csm_fps": fps,
                    "paper_pcf_fps": PAPER_PCF_FPS[col],
                    "paper_ratio_to_pcf": paper_ratio,
                }));
            }
            println!("M = {m:<2}{cells}");
        }
    }
    println!("\ntargets: M = 4 without blur at most {M4_TARGET}x a 3x3 PCF frame, technique alone (the paper's whole frames: 1.19 at 256²-1024², 1.38 at 2048²):");
    for (s, r) in m4 {
        println!("  S = {s}²: {r:.2}x: {}", verdict(r <= M4_TARGET));
    }
    Ok(BenchReport { rows })
}
