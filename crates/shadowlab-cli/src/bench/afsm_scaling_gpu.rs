//! `afsm-scaling`'s GPU rows: `gpu:afsm` and `gpu:raytrace` (its BVH prebuilt: uploaded by
//! an untimed first frame, as the scene is for `gpu:afsm`) on the same scene, camera and
//! light as the CPU rows at 1920×1080 (the GPU goals' size; `--quick`: 480×270), each the median of
//! `--repeat` runs: the wall time (view upload, GPU work, read-back) and the GPU time (the
//! sum of the stages' timestamp-query times), with the share of covered pixels where the
//! two differ (both are exact: floating-point ties only). Without an adapter the rows are
//! left out with a line saying why; a software adapter's times are labelled CPU-emulated.

use super::verdict;
use shadowlab::camera::Camera;
use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::scene::Scene;
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;
use std::time::Instant;

/// The GPU rows' frame size, and with `--quick`.
pub fn size(quick: bool) -> (u32, u32) {
    if quick {
        (480, 270)
    } else {
        (1920, 1080)
    }
}

/// One GPU technique's times on one frame.
pub struct GpuRun {
    /// Median wall time of the frame, ms.
    pub wall_ms: f64,
    /// Median GPU time of its passes (timestamp queries), ms.
    pub gpu_ms: f64,
    /// The last run's shadow terms.
    last: Shadows,
}

/// Both GPU techniques' times on one frame, and the adapter.
pub struct GpuTimes {
    /// Share of covered pixels where the two differ by ≥ 0.5.
    pub mismatch_rate: f64,
    /// The adapter's line (ends `CPU-emulated` for a software one).
    pub adapter: String,
    /// `gpu:afsm`.
    pub afsm: GpuRun,
    /// `gpu:raytrace`.
    pub raytrace: GpuRun,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn gpu_ms(s: &Shadows) -> f64 {
    s.stats
        .counters
        .iter()
        .filter(|(k, _)| k.starts_with("gpu_") && k.ends_with("_ms"))
        .map(|(_, v)| v)
        .sum()
}

/// `name` on `frame`: one untimed run, then the median of `repeat`.
fn run_one(name: &str, frame: &Frame, repeat: usize) -> anyhow::Result<(GpuRun, String)> {
    let mut t = techniques::create(name)?;
    t.render(frame)?;
    let mut walls = Vec::new();
    let mut gpus = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        let s = t.render(frame)?;
        walls.push(t0.elapsed().as_secs_f64() * 1e3);
        gpus.push(gpu_ms(&s));
        last = Some(s);
    }
    let last = last.ok_or_else(|| anyhow::anyhow!("{name}: no run"))?;
    let adapter = last.stats.device.clone().unwrap_or_default();
    Ok((
        GpuRun {
            wall_ms: median(walls),
            gpu_ms: median(gpus),
            last,
        },
        adapter,
    ))
}

/// Both GPU techniques on `scene` seen by `camera` at [`size`] under `light`, or `None`
/// (with the reason printed) when there is no adapter.
pub fn measure(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    repeat: usize,
    quick: bool,
) -> Option<GpuTimes> {
    let mut camera = *camera;
    (camera.width, camera.height) = size(quick);
    camera.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(scene, &camera);
    let frame = Frame::new(scene, &camera, light, &view);
    let afsm = run_one("gpu:afsm", &frame, repeat);
    let raytrace = run_one("gpu:raytrace", &frame, repeat);
    match (afsm, raytrace) {
        (Ok((afsm, adapter)), Ok((raytrace, _))) => Some(GpuTimes {
            mismatch_rate: compare(&view, &afsm.last.visibility, &raytrace.last.visibility)
                .mismatch_rate,
            adapter,
            afsm,
            raytrace,
        }),
        (Err(e), _) | (_, Err(e)) => {
            if !crate::progress::quiet() {
                eprintln!("afsm-scaling: GPU rows left out: {e}");
            }
            None
        }
    }
}

/// The GPU target of one column: `gpu:afsm`'s GPU time at most `gpu:raytrace`'s.
pub fn target(g: &GpuTimes) -> String {
    format!(
        "gpu:afsm {:.2} ms vs gpu:raytrace {:.2} ms GPU time (target at most 1.00x, {:.2}x): {}",
        g.afsm.gpu_ms,
        g.raytrace.gpu_ms,
        g.afsm.gpu_ms / g.raytrace.gpu_ms,
        verdict(g.afsm.gpu_ms <= g.raytrace.gpu_ms)
    )
}
