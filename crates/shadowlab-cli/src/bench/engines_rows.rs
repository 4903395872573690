//! The `engines` suite's rows, what it measures (the library's techniques or the GPU's),
//! and its plots per scene: mean error against memory (a line per technique) and, at the
//! middle budget, error against time with the Pareto front marked.

use crate::charts::{self, Axis, Point, Series};
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::techniques;

/// What the suite measures: the library's techniques timed by the wall clock, or the GPU
/// techniques timed by the GPU (`engines --backend gpu`).
#[derive(Clone, Copy)]
pub struct Backend {
    /// The techniques, in report order.
    pub names: &'static [&'static str],
    /// Times are the frame's GPU time (the sum of the stats' `gpu_*_ms` timestamp
    /// counters) instead of its wall time.
    pub gpu_time: bool,
    /// What the plots' file names start with after `engines-`: empty, or `gpu-`.
    pub plot_prefix: &'static str,
}

impl Backend {
    /// The library's techniques, by wall time.
    pub const CPU: Backend = Backend {
        names: techniques::ALL,
        gpu_time: false,
        plot_prefix: "",
    };
}

/// One measured technique at one budget.
pub struct Row {
    /// The scene.
    pub scene: String,
    /// The technique.
    pub technique: String,
    /// The memory budget, MiB (`None` for a technique without a map to size).
    pub budget_mib: Option<u64>,
    /// The map side that fits the budget.
    pub resolution: Option<u32>,
    /// The memory the technique reported.
    pub memory_bytes: u64,
    /// Its time, ms.
    pub time_ms: f64,
    /// Its mismatch against the reference (share of pixels).
    pub mismatch: f64,
    /// Its mean absolute error against the reference.
    pub mean_error: f64,
}

impl Row {
    /// The row as the JSON report holds it.
    pub fn json(&self) -> Value {
        json!({
            "scene": self.scene, "technique": self.technique, "budget_mib": self.budget_mib,
            "resolution": self.resolution, "memory_bytes": self.memory_bytes,
            "time_ms": self.time_ms, "mismatch": self.mismatch, "mean_abs_error": self.mean_error,
        })
    }
}

/// Indices of the rows on the Pareto front of (time, error): no other row is at least as
/// fast and at least as accurate, and better in one.
fn pareto(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| {
            !points
                .iter()
                .any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

/// Per scene: mean error against memory (a line per technique) and, at the middle budget,
/// error against time with the Pareto front marked.
pub fn write_plots(
    dir: &std::path::Path,
    rows: &[Row],
    scenes: &[&str],
    budgets: &[u64],
    backend: Backend,
) -> Result<()> {
    let prefix = backend.plot_prefix;
    let time_axis = if backend.gpu_time {
        "GPU time of the technique (ms)"
    } else {
        "frame time of the technique (ms)"
    };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create --plots folder {}", dir.display()))?;
    for &s in scenes {
        let series: Vec<Series> = backend
            .names
            .iter()
            .map(|&t| Series {
                name: t.to_string(),
                points: rows
                    .iter()
                    .filter(|r| r.scene == s && r.technique == t)
                    .map(|r| {
                        (
                            r.memory_bytes.max(1) as f64 / (1u64 << 20) as f64,
                            r.mean_error,
                        )
                    })
                    .collect(),
            })
            .filter(|se| !se.points.is_empty())
            .collect();
        let mem: Vec<f64> = series
            .iter()
            .flat_map(|se| se.points.iter().map(|p| p.0))
            .collect();
        let svg = charts::lines(
            &format!("{s}: error against memory"),
            &Axis::auto("shadow memory (MiB)", &mem, 8.0),
            &Axis::linear("mean absolute error (visibility, 0–1)"),
            &series,
        )?;
        let file = dir.join(format!("engines-{prefix}{s}-error-vs-memory.svg"));
        crate::output::write_file(&file, svg.as_bytes())?;
        let mid = budgets[budgets.len() / 2];
        let at: Vec<&Row> = rows
            .iter()
            .filter(|r| r.scene == s && (r.budget_mib == Some(mid) || r.budget_mib.is_none()))
            .collect();
        let front = pareto(
            &at.iter()
                .map(|r| (r.time_ms, r.mean_error))
                .collect::<Vec<_>>(),
        );
        let points: Vec<Point> = at
            .iter()
            .zip(&front)
            .map(|(r, &f)| Point {
                label: if f {
                    format!("{} ◆ Pareto", r.technique)
                } else {
                    r.technique.clone()
                },
                x: r.time_ms,
                y: r.mean_error,
            })
            .collect();
        let times: Vec<f64> = points.iter().map(|p| p.x).collect();
        let svg = charts::scatter(
            &format!("{s}: error against time at {mid} MiB (◆ marks the Pareto front)"),
            &Axis::auto(time_axis, &times, 10.0),
            &Axis::linear("mean absolute error (visibility, 0–1)"),
            &points,
        )?;
        let file = dir.join(format!("engines-{prefix}{s}-error-vs-time.svg"));
        crate::output::write_file(&file, svg.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let p = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (0.5, 0.9), (2.0, 0.2)];
        assert_eq!(pareto(&p), vec![true, true, false, true, true]);
    }
}
