//! `gpu`: every `gpu:` technique on bunny, chessboard, bumpy and hairball at 1920×1080
//! (`--quick`: 480×270), its wall time (upload of the view samples, GPU work and read-back
//! included) and each stage's, the GPU time of each stage from timestamp queries, shadow
//! rays per second for `gpu:raytrace` (over the trace stage's wall time, and over its GPU
//! time), and the CPU twin's time beside it, with the adapter in every row. The
//! scene's upload (and BVH build) happens in an untimed first frame, as a scene stays
//! resident across frames. A software adapter's figures are CPU-emulated, and every line
//! and row says so.

use super::{median_ms, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;

/// The scenes, as the issue of GPU figures names them.
const SCENES: &[&str] = &["bunny", "chessboard", "bumpy", "hairball"];

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let (width, height) = if a.quick { (480, 270) } else { (1920, 1080) };
    let repeat = a.repeat.max(1);
    let gpu = shadowlab_gpu::device::shared()?;
    let adapter = gpu.adapter.label();
    let emulated = gpu.adapter.software;
    println!("adapter: {adapter}");
    if emulated {
        println!("a software adapter: every GPU time below is CPU-emulated, not a GPU figure");
    }
    println!(
        "{:<12} {:<14} {:>10} {:>26} {:>12} {:>10}",
        "scene", "technique", "wall ms", "GPU stages ms", "Mrays/s", "CPU ms"
    );
    let mut rows = Vec::new();
    for &name in SCENES {
        let mut scene = shadowlab::scene::load(name, &Default::default())
            .with_context(|| format!("loading {name}"))?;
        let mut camera = scene.camera.take().context("the scene has no camera")?;
        (camera.width, camera.height) = (width, height);
        camera.fit_depth_range(&scene.bounds);
        let light = scene.light.context("the scene has no light")?;
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        for &tname in shadowlab_gpu::techniques::ALL {
            let mut t = techniques::create(tname)?;
            t.render(&frame)?; // uploads the scene and builds the pipelines
            let (wall_ms, shadows) = median_ms(repeat, || t.render(&frame));
            let stats = shadows?.stats;
            let stages: Vec<(String, f64)> = stats
                .counters
                .iter()
                .filter_map(|(k, v)| {
                    let stage = k.strip_prefix("gpu_")?.strip_suffix("_ms")?;
                    Some((stage.to_string(), *v))
                })
                .collect();
            // Rays per second over the trace stage's wall time (submission to completion)
            // and over its GPU time (timestamps; a software adapter may not bracket its
            // compute work with them, so the wall figure is the one printed).
            let rays = stats.counters.get("rays").copied();
            let per_s = |ms: Option<f64>| match (rays, ms) {
                (Some(r), Some(ms)) if ms > 0.0 => Some(r / (ms / 1e3)),
                _ => None,
            };
            let trace_wall = stats.stages_ms.iter().find(|s| s.0 == "trace").map(|s| s.1);
            let rays_per_s = per_s(trace_wall);
            let rays_per_s_gpu = per_s(stages.iter().find(|s| s.0 == "trace").map(|s| s.1));
            let twin = tname.trim_start_matches("gpu:");
            let mut cpu = techniques::create(twin)?;
            let (cpu_ms, r) = median_ms(1, || cpu.render(&frame));
            r?;
            let stage_text: Vec<String> = stages
                .iter()
                .map(|(s, ms)| format!("{s} {ms:.2}"))
                .collect();
            println!(
                "{:<12} {:<14} {:>10.2} {:>26} {:>12} {:>10.1}",
                name,
                tname,
                wall_ms,
                stage_text.join(", "),
                rays_per_s.map_or("—".into(), |r| format!("{:.1}", r / 1e6)),
                cpu_ms
            );
            let stage_map: serde_json::Map<String, Value> = stages
                .iter()
                .map(|(s, ms)| (s.clone(), json!(ms)))
                .collect();
            let wall_map: serde_json::Map<String, Value> = stats
                .stages_ms
                .iter()
                .map(|(s, ms)| (s.clone(), json!(ms)))
                .collect();
            rows.push(json!({
                "scene": name,
                "width": width,
                "height": height,
                "technique": tname,
                "wall_ms": wall_ms,
                "stages_ms": wall_map,
                "gpu_stages_ms": stage_map,
                "shadow_rays_per_s": rays_per_s,
                "shadow_rays_per_s_gpu_time": rays_per_s_gpu,
                "cpu_technique": twin,
                "cpu_ms": cpu_ms,
                "adapter": adapter,
                "cpu_emulated": emulated,
            }));
        }
    }
    rows.push(subpixel_goal((width, height), repeat, &adapter, emulated)?);
    Ok(BenchReport { rows })
}

/// The sub-pixel paper's claim on a GPU: `gpu:subpixel` at 32 samples at least
/// [`SUBPIXEL_GOAL`] times faster than `gpu:raytrace` at 32 rays a pixel on the same frame
/// (chessboard). Times are the frames' GPU times on a hardware adapter with timestamps,
/// else wall times (and a software adapter's are CPU-emulated).
fn subpixel_goal(size: (u32, u32), repeat: usize, adapter: &str, emulated: bool) -> Result<Value> {
    let gpu = shadowlab_gpu::device::shared()?;
    let gpu_time = gpu.timestamps && !emulated;
    let mut scene = shadowlab::scene::load("chessboard", &Default::default())?;
    let mut camera = scene.camera.take().context("chessboard has no camera")?;
    (camera.width, camera.height) = size;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.context("chessboard has no light")?;
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let time = |name: &str, key: &str| -> Result<f64> {
        let mut t = techniques::create(name)?;
        t.set_param(key, "32")?;
        Ok(super::engines::timed(t.as_mut(), &frame, repeat, gpu_time)?.0)
    };
    let subpixel_ms = time("gpu:subpixel", "samples")?;
    let raytrace_ms = time("gpu:raytrace", "spp")?;
    let ratio = raytrace_ms / subpixel_ms.max(1e-9);
    println!(
        "\ngoal on chessboard at {}x{}: gpu:raytrace (spp=32) {raytrace_ms:.2} ms / gpu:subpixel \
         (samples=32) {subpixel_ms:.2} ms = {ratio:.2} (target at least {SUBPIXEL_GOAL}; {} times{})",
        size.0,
        size.1,
        if gpu_time { "GPU" } else { "wall" },
        if emulated { ", CPU-emulated" } else { "" }
    );
    Ok(json!({
        "scene": "chessboard", "width": size.0, "height": size.1,
        "technique": "gpu:subpixel", "subpixel_goal": true,
        "subpixel_ms": subpixel_ms, "raytrace_ms": raytrace_ms, "speedup": ratio,
        "target": SUBPIXEL_GOAL, "goal_met": ratio >= SUBPIXEL_GOAL,
        "gpu_time": gpu_time, "adapter": adapter, "cpu_emulated": emulated,
    }))
}

/// The sub-pixel paper's speed-up over ray tracing at 32 samples a pixel.
const SUBPIXEL_GOAL: f64 = 10.0;
