//! The benchmark suites that reproduce the papers' tables, one module each, and what they
//! share: the median of timed runs, the machine's description, the rows they return.
//! Each suite prints a table with the paper's figures beside ours; times are medians of
//! several runs in milliseconds. `commands::bench` runs them.

pub mod afsm_scaling;
pub mod afsm_scaling_gpu;
pub mod asm_walkthrough;
pub mod csm_table;
pub mod engines;
pub mod engines_gpu;
pub mod engines_rows;
pub mod gpu;
pub mod psm_lights;
pub mod soft_exact;
pub mod subpixel_scaling;

use serde_json::{json, Value};
use shadowlab::camera::Camera;
use shadowlab::scene::Scene;
use shadowlab::view::ViewSamples;

/// What a suite produced.
pub struct BenchReport {
    /// Rows, each an object with at least the fields CLI.md names for the suite.
    pub rows: Vec<Value>,
}

/// The median of `n` timed runs of `f`, in milliseconds, and the last result.
pub fn median_ms<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..n.max(1) {
        let t0 = std::time::Instant::now();
        last = Some(f());
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], last.expect("ran at least once"))
}

/// The camera pass timed as a sequence runs it (its buffers kept from the frame before),
/// beside the memory-bandwidth bound of writing its per-pixel arrays once: the same bytes
/// written by a parallel fill over the same threads, measured in the same run. Prints one
/// line and returns the camera pass's median time (ms) and its JSON figures.
pub fn camera_pass_line(scene: &Scene, camera: &Camera, repeat: usize) -> (f64, Value) {
    use rayon::prelude::*;
    let mut view = ViewSamples::render(scene, camera);
    let (camera_ms, _) = median_ms(repeat.max(3), || {
        view.render_into(scene, camera)
            .expect("the buffers of the first pass are kept")
    });
    let pixels = camera.width as usize * camera.height as usize;
    let bytes = pixels * ViewSamples::bytes_per_pixel();
    let mut stream = vec![0u8; bytes];
    let mut value = 0u8;
    let (bound_ms, _) = median_ms(repeat.max(3), || {
        value = value.wrapping_add(1);
        stream
            .par_chunks_mut(1 << 16)
            .for_each(|c| c.fill(std::hint::black_box(value)));
    });
    let mpix = pixels as f64 / 1e6;
    println!(
        "camera pass {:.1} ms, {:.1} ms/MPixel vs measured bandwidth bound {:.2} ms/MPixel (writing its {} bytes a pixel once, {:.1} GB/s): {:.1}x the bound",
        camera_ms,
        camera_ms / mpix,
        bound_ms / mpix,
        ViewSamples::bytes_per_pixel(),
        bytes as f64 / bound_ms / 1e6,
        camera_ms / bound_ms
    );
    let figures = json!({
        "camera_pass_ms": camera_ms,
        "camera_pass_ms_per_mpixel": camera_ms / mpix,
        "bandwidth_bound_ms_per_mpixel": bound_ms / mpix,
        "bytes_per_pixel": ViewSamples::bytes_per_pixel(),
    });
    (camera_ms, figures)
}

/// "met" or "missed", for the target lines every suite prints.
pub fn verdict(met: bool) -> &'static str {
    if met {
        "met"
    } else {
        "missed"
    }
}

/// Facts about the machine a benchmark ran on.
pub fn machine() -> Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_default();
    json!({
        "cpu": cpu,
        "threads": rayon::current_num_threads(),
        "os": std::env::consts::OS,
        "arch": std::env::consts::ARCH,
        "shadowlab_version": env!("CARGO_PKG_VERSION"),
    })
}
