//! The benchmark suites that reproduce the papers' tables, one module each, and what they
//! share: the median of timed runs, the machine's description, the rows they return.
//! Each suite prints a table with the paper's figures beside ours; times are medians of
//! several runs in milliseconds. `commands::bench` runs them.

pub mod afsm_scaling;
pub mod asm_walkthrough;
pub mod csm_table;
pub mod engines;
pub mod psm_lights;
pub mod soft_exact;
pub mod subpixel_scaling;

use serde_json::{json, Value};

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
