//! `shadowlab bench SUITE`: benchmark suites that reproduce the papers' tables. Each suite
//! prints a table with the paper's figures beside ours and, with `--json`, writes
//! `{"suite", "machine", "rows"}`. Times are medians of several runs in milliseconds.

mod afsm_scaling;
mod asm_walkthrough;
mod csm_table;
mod engines;
mod psm_lights;
mod subpixel_scaling;

use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::path::PathBuf;

/// `shadowlab bench`.
#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// The suite: afsm-scaling, subpixel-scaling, csm-table, asm-walkthrough, psm-lights,
    /// engines.
    pub suite: String,
    /// Also write the rows as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// A reduced run that finishes in under a minute on two cores.
    #[arg(long)]
    pub quick: bool,
    /// Write the suite's plots (SVG) into this folder (`engines`: error against memory, and
    /// error against time with the Pareto front marked, per scene).
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Runs per measurement (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
}

/// What a suite produced.
pub struct BenchReport {
    /// Rows, each an object with at least the fields CLI.md names for the suite.
    pub rows: Vec<Value>,
}

/// Every suite name.
pub const SUITES: &[&str] = &[
    "afsm-scaling",
    "subpixel-scaling",
    "csm-table",
    "asm-walkthrough",
    "psm-lights",
    "engines",
];

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

/// Runs a suite.
pub fn run(a: &BenchArgs) -> Result<()> {
    let report: BenchReport = match a.suite.as_str() {
        "afsm-scaling" => afsm_scaling::run(a)?,
        "subpixel-scaling" => subpixel_scaling::run(a)?,
        "csm-table" => csm_table::run(a)?,
        "asm-walkthrough" => asm_walkthrough::run(a)?,
        "psm-lights" => psm_lights::run(a)?,
        "engines" => engines::run(a)?,
        _ => bail!(
            "unknown bench suite {:?}: known suites are {}",
            a.suite,
            SUITES.join(", ")
        ),
    };
    if let Some(p) = &a.json {
        crate::commands::write_json(
            p,
            &json!({"suite": a.suite, "machine": machine(), "rows": report.rows}),
        )?;
    }
    Ok(())
}
