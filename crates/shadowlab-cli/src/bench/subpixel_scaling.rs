//! `subpixel-scaling`: the sub-pixel paper's Figure 10 — time per frame of `subpixel` at
//! 1×…128× samples against brute-force supersampling, i.e. the alias-free shadow map run
//! once per sub-sample position (the camera turned by the sample's offset, less than a
//! pixel, so every pixel's primary ray passes through that sub-sample), and against `afsm`
//! at one sample.
//!
//! The paper's figure is a plot of the pterosaur scene (10 k triangles) on a GTX 280, with
//! no numbers in its text; its Table 1 gives the bunny (69 k triangles, 800×600, 512² maps,
//! 32×), which is the scene measured here, so the table prints that row beside ours. When
//! `afsm` is not available the ray-traced centre sample (`raytrace`) stands in for it, and
//! the `baseline` field says so.

use super::{median_ms, BenchReport};
use crate::config::BenchConfig;
use crate::progress;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::camera::Camera;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::{self, Frame, ShadowTechnique};
use shadowlab::view::ViewSamples;

/// The paper's Table 1, bunny row (32 samples): silhouette texels, silhouette pixels,
/// visibility evaluations, and the three stage times in ms, and frames per second.
const PAPER_BUNNY: (u32, u32, u32, [f64; 3], f64) = (3254, 18523, 609_901, [2.1, 6.3, 6.8], 61.0);
/// The paper's claim for Figure 10: supersampled alias-free shadow maps are about an order
/// of magnitude slower than the sub-pixel method at 32 samples.
const PAPER_SPEEDUP_AT_32: f64 = 10.0;

/// The same camera turned (an orthographic one moved) so that its centre ray passes
/// `(dx, dy)` pixels from the image centre: every pixel's primary ray then passes (to within a rotation of under a pixel's
/// angle) through its sub-sample at offset `(dx, dy)` from the pixel centre.
fn jittered(camera: &Camera, dx: f32, dy: f32) -> Camera {
    let mut c = *camera;
    let (cx, cy) = (camera.width as f32 * 0.5, camera.height as f32 * 0.5);
    let (o, dir) = camera.ray(cx + dx, cy + dy);
    // An orthographic camera's rays are parallel: it moves across instead.
    c.eye = camera.eye + (o - camera.ray(cx, cy).0);
    c.target = c.eye + dir * (camera.target - camera.eye).length();
    c
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let (width, height, counts): (u32, u32, &[u32]) = if a.quick {
        (512, 384, &[1, 8, 32])
    } else {
        (1024, 768, &[1, 4, 8, 16, 32, 64, 128])
    };
    let repeat = if a.quick { 1 } else { a.repeat.max(1) };
    let mut scene =
        shadowlab::scene::load("bunny", &Default::default()).context("loading the bunny scene")?;
    let mut camera = scene
        .camera
        .take()
        .context("the bunny scene has no camera")?;
    camera.width = width;
    camera.height = height;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.context("the bunny scene has no light")?;
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);

    // The one-sample baseline: afsm, or the ray-traced centre sample when afsm is missing.
    let mut baseline_name = "afsm";
    let mut baseline: Box<dyn ShadowTechnique> = techniques::create("afsm")?;
    if baseline.render(&frame).is_err() {
        baseline_name = "raytrace";
        baseline = techniques::create("raytrace")?;
    }
    let (one_ms, _) = median_ms(repeat, || baseline.render(&frame));

    let bar = progress::bar(counts.len() as u64, "subpixel-scaling");
    let mut rows = Vec::new();
    let mut technique = techniques::create("subpixel")?;
    for &n in counts {
        bar.set_message(format!("{n} samples"));
        technique.set_param("samples", &n.to_string())?;
        technique.render(&frame)?; // builds the edge adjacency and the look-up table
        let (ms, shadows) = median_ms(repeat, || technique.render(&frame));
        let shadows = shadows?;
        // Brute force: one full alias-free frame per sub-sample position.
        let mut shadow_ms = 0.0;
        let mut camera_ms = 0.0;
        for s in pattern(PatternKind::Grid, n)? {
            let cam = jittered(&camera, s.x - 0.5, s.y - 0.5);
            let v = ViewSamples::render(&scene, &cam);
            camera_ms += v.time_ms;
            let f = Frame::new(&scene, &cam, &light, &v);
            let t0 = std::time::Instant::now();
            baseline.render(&f)?;
            shadow_ms += t0.elapsed().as_secs_f64() * 1e3;
        }
        let c = &shadows.stats.counters;
        let stage = |k: &str| {
            shadows
                .stats
                .stages_ms
                .iter()
                .find(|(s, _)| s == k)
                .map_or(0.0, |(_, v)| *v)
        };
        rows.push(json!({
            "samples": n,
            "subpixel_ms": ms,
            "supersampled_afsm_ms": shadow_ms,
            "afsm_1spp_ms": one_ms,
            "baseline": baseline_name,
            "supersampled_camera_pass_ms": camera_ms,
            "speedup_vs_supersampled": shadow_ms / ms,
            "ratio_to_afsm_1spp": ms / one_ms,
            "silhouette_texels": c.get("silhouette_texels"),
            "silhouette_pixels": c.get("silhouette_pixels"),
            "visibility_evaluations": c.get("visibility_evaluations"),
            "depth_map_ms": stage("depth_map"),
            "silhouette_mask_map_ms": stage("silhouette_mask_map"),
            "pt_tt_pairs_ms": stage("pt_tt_pairs"),
            "shadow_calculation_ms": stage("shadow_calculation"),
            "width": width, "height": height, "triangles": scene.len(),
            "paper_silhouette_texels": (n == 32).then_some(PAPER_BUNNY.0),
            "paper_silhouette_pixels": (n == 32).then_some(PAPER_BUNNY.1),
            "paper_visibility_evaluations": (n == 32).then_some(PAPER_BUNNY.2),
            "paper_stages_ms": (n == 32).then_some(PAPER_BUNNY.3.to_vec()),
            "paper_total_ms": (n == 32).then_some(1000.0 / PAPER_BUNNY.4),
            "paper_speedup_vs_supersampled": (n == 32).then_some(PAPER_SPEEDUP_AT_32),
        }));
        bar.inc(1);
    }
    bar.finish_and_clear();
    print_table(&rows, baseline_name, width, height, scene.len());
    Ok(BenchReport { rows })
}

fn print_table(rows: &[Value], baseline: &str, width: u32, height: u32, triangles: usize) {
    let f = |r: &Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    println!(
        "subpixel-scaling: bunny ({triangles} triangles), {width}x{height}, {} threads; brute force = {baseline} once per sub-sample",
        rayon::current_num_threads()
    );
    println!(
        "{:>7} {:>12} {:>10} {:>16} {:>9} {:>10} {:>10} {:>12}   paper (bunny, GTX 280)",
        "samples",
        "subpixel ms",
        "x 1spp",
        "supersampled ms",
        "speed-up",
        "sil texels",
        "sil pixels",
        "evaluations"
    );
    for r in rows {
        let paper = if r["samples"] == 32 {
            format!(
                "{:.1} ms; {} / {} / {}; ~{}x faster",
                1000.0 / PAPER_BUNNY.4,
                PAPER_BUNNY.0,
                PAPER_BUNNY.1,
                PAPER_BUNNY.2,
                PAPER_SPEEDUP_AT_32
            )
        } else {
            String::new()
        };
        println!(
            "{:>7} {:>12.1} {:>10.2} {:>16.1} {:>9.1} {:>10} {:>10} {:>12}   {paper}",
            r["samples"],
            f(r, "subpixel_ms"),
            f(r, "ratio_to_afsm_1spp"),
            f(r, "supersampled_afsm_ms"),
            f(r, "speedup_vs_supersampled"),
            f(r, "silhouette_texels"),
            f(r, "silhouette_pixels"),
            f(r, "visibility_evaluations"),
        );
    }
    if let Some(r) = rows.first() {
        println!("{baseline} at one sample: {:.1} ms", f(r, "afsm_1spp_ms"));
    }
}
