//! `engines --backend gpu`: every GPU technique (`shadowlab_gpu::techniques::ALL`, so a
//! technique added there is measured without a change here) on the CPU suite's scenes at
//! the same equal shadow memory, against the same ray-traced reference, timed by the GPU:
//! each frame's time is the sum of its `gpu_*_ms` timestamp counters (the passes the GPU
//! runs; the upload of the view samples and the read-back are not in it), the median of
//! `--repeat` frames after an untimed one. An adapter without timestamp queries, or a
//! software one (whose timestamps need not bracket its compute passes: lavapipe's read
//! near zero for them), is timed by the wall clock instead, and the run says so. The adapter is named on the first line and
//! in every row; a software adapter's times are CPU-emulated, and the run says that too.
//!
//! Then the request's goals, each for the pairs whose techniques are in the list: the time
//! ratios at equal memory (`gpu:csm`/`gpu:pcf` at most 1.3, `gpu:psm`/`gpu:sm` 1.15,
//! `gpu:msm`/`gpu:vsm` 1.3, `gpu:cascaded`/`gpu:sm` 1.5), and every technique's frame time
//! at its defaults on chessboard at 1920×1080 against 2 ms (`--quick`: at 480×270, where
//! the figure is printed but the 1920×1080 goal is not judged).

use super::engines::{self, Backend};
use super::{verdict, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;

/// The time ratios the GPU run checks: `(a, b, target)`, `a`'s GPU time at most `target`
/// times `b`'s at equal memory.
const TIME_TARGETS: [(&str, &str, f64); 4] = [
    ("gpu:csm", "gpu:pcf", 1.3),
    ("gpu:psm", "gpu:sm", 1.15),
    ("gpu:msm", "gpu:vsm", 1.3),
    ("gpu:cascaded", "gpu:sm", 1.5),
];
/// The frame-time goal: every technique on chessboard at 1920×1080 within this many ms.
const FRAME_GOAL_MS: f64 = 2.0;
/// The frame of the frame-time goal, and the reduced frame of `--quick`.
const FRAME_GOAL_SIZE: (u32, u32) = (1920, 1080);
const QUICK_FRAME_SIZE: (u32, u32) = (480, 270);

/// Runs the suite on the GPU.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let gpu = shadowlab_gpu::device::shared()?;
    let adapter = gpu.adapter.label();
    let emulated = gpu.adapter.software;
    println!("adapter: {adapter}");
    if emulated {
        println!("a software adapter: every GPU time below is CPU-emulated, not a GPU figure");
    }
    // A software adapter's timestamps need not bracket its compute passes (lavapipe's
    // read near zero for them): its frames are timed by the wall clock.
    let backend = Backend {
        names: shadowlab_gpu::techniques::ALL,
        gpu_time: gpu.timestamps && !emulated,
        plot_prefix: "gpu-",
    };
    if backend.gpu_time {
        println!("times are GPU times: the sum of each frame's timestamped passes");
    } else if emulated {
        println!("times are wall times (a software adapter's timestamps do not bracket its compute passes), upload and read-back included");
    } else {
        println!("the adapter has no timestamp queries: times are wall times, upload and read-back included");
    }
    let rows = engines::measure(a, backend)?;
    let (scenes, budgets, _, _) = engines::plan(a);
    let present = |n: &str| backend.names.contains(&n);
    let targets: Vec<(&str, &str, f64)> = TIME_TARGETS
        .iter()
        .copied()
        .filter(|(x, y, _)| present(x) && present(y))
        .collect();
    engines::summary(&rows, budgets, &targets);
    if let Some(dir) = &a.plots {
        super::engines_rows::write_plots(dir, &rows, scenes, budgets, backend)?;
    }
    let tag = |mut v: Value| {
        v["adapter"] = json!(adapter);
        v["cpu_emulated"] = json!(emulated);
        v["gpu_time"] = json!(backend.gpu_time);
        v
    };
    let mut out: Vec<Value> = rows.iter().map(|r| tag(r.json())).collect();
    out.extend(frame_goal(a, backend)?.into_iter().map(tag));
    Ok(BenchReport { rows: out })
}

/// Every technique's time at its defaults on chessboard at the goal's frame (the quick
/// frame with `--quick`), against [`FRAME_GOAL_MS`]; one row each.
fn frame_goal(a: &BenchConfig, backend: Backend) -> Result<Vec<Value>> {
    let size = if a.quick {
        QUICK_FRAME_SIZE
    } else {
        FRAME_GOAL_SIZE
    };
    let mut scene = shadowlab::scene::load("chessboard", &Default::default())
        .context("loading the chessboard scene")?;
    let mut camera = scene.camera.take().context("chessboard has no camera")?;
    let light = scene.light.context("chessboard has no light")?;
    (camera.width, camera.height) = size;
    camera.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let judged = size == FRAME_GOAL_SIZE;
    println!(
        "\nframe time at the defaults on chessboard at {}x{} (goal: at most {FRAME_GOAL_MS} ms at {}x{}{})",
        size.0,
        size.1,
        FRAME_GOAL_SIZE.0,
        FRAME_GOAL_SIZE.1,
        if judged { "" } else { "; not judged at this size" }
    );
    let mut rows = Vec::new();
    for &name in backend.names {
        let mut t = techniques::create(name)?;
        let (ms, _) = engines::timed(t.as_mut(), &frame, a.repeat.max(1), backend.gpu_time)?;
        println!(
            "{name:>14} {ms:>9.3} ms {}",
            if judged {
                verdict(ms <= FRAME_GOAL_MS)
            } else {
                ""
            }
        );
        rows.push(json!({
            "scene": "chessboard", "technique": name, "frame_goal": true,
            "width": size.0, "height": size.1, "time_ms": ms,
            "goal_ms": FRAME_GOAL_MS, "goal_met": judged.then_some(ms <= FRAME_GOAL_MS),
        }));
    }
    Ok(rows)
}
