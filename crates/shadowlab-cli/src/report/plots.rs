//! The report's plots, as SVG files in `DIR/plots/`: error and mismatch against time (one
//! point per run), error and time against each swept parameter, and along a walkthrough
//! time, error against each frame's reference and temporal error per frame.

use super::rows::{sweeps, SweepGroup};
use crate::charts::{self, Axis, Point, Scale, Series};
use crate::metrics::{FrameFigures, RunResult};
use crate::output::{create_dir, slug};
use anyhow::Result;
use std::path::Path;

/// A plot written to `DIR/plots/`: its file relative to `DIR`, and its caption.
pub struct Plot {
    /// The SVG file, relative to the report folder.
    pub file: String,
    /// What it shows.
    pub caption: String,
}

/// Draws every plot the results support into `DIR/plots/`, in the order the report shows
/// them.
pub fn draw(dir: &Path, results: &[RunResult]) -> Result<Vec<Plot>> {
    create_dir(&dir.join("plots"))?;
    let mut out = Plots {
        dir,
        plots: Vec::new(),
    };
    if results.is_empty() {
        return Ok(out.plots);
    }
    out.against_time(results)?;
    for group in sweeps(results) {
        out.against_sweep(&group)?;
    }
    out.per_frame(results)?;
    out.frame_errors(results)?;
    Ok(out.plots)
}

/// The plots written so far.
struct Plots<'d> {
    dir: &'d Path,
    plots: Vec<Plot>,
}

fn time_of(r: &RunResult) -> f64 {
    r.figures.time_ms
}

fn mismatch_of(r: &RunResult) -> f64 {
    r.mismatch_rate
}

fn error_of(r: &RunResult) -> f64 {
    r.mean_abs_error
}

impl Plots<'_> {
    /// Writes `DIR/plots/<name>.svg`.
    fn add(&mut self, name: &str, svg: &str, caption: String) -> Result<()> {
        let rel = format!("plots/{name}.svg");
        let path = self.dir.join(&rel);
        crate::output::write_file(&path, svg.as_bytes())?;
        self.plots.push(Plot { file: rel, caption });
        Ok(())
    }

    /// Error and mismatch against frame time, one labelled point per run.
    fn against_time(&mut self, results: &[RunResult]) -> Result<()> {
        let times: Vec<f64> = results.iter().map(time_of).collect();
        let time_axis = Axis::auto("frame time (ms, log scale)", &times, 20.0);
        let time_axis = if time_axis.scale == Scale::Linear {
            Axis::linear("frame time (ms)")
        } else {
            time_axis
        };
        let pts = |y: &dyn Fn(&RunResult) -> f64| -> Vec<Point> {
            results
                .iter()
                .map(|r| Point {
                    label: r.label.clone(),
                    x: time_of(r),
                    y: y(r),
                })
                .collect()
        };
        let svg = charts::scatter(
            "Error against time",
            &time_axis,
            &Axis::linear("mean absolute error (visibility, 0–1)"),
            &pts(&error_of),
        )?;
        self.add(
            "error-vs-time",
            &svg,
            "Mean absolute error of the shadow term against frame time; lower left is better."
                .into(),
        )?;
        let svg = charts::scatter(
            "Mismatch against time",
            &time_axis,
            &Axis::linear("mismatched pixels (% of covered)"),
            &pts(&|r| mismatch_of(r) * 100.0),
        )?;
        self.add("mismatch-vs-time", &svg, "Share of covered pixels whose lit/shadowed answer differs from the reference, against frame time.".into())
    }

    /// Error, and time, against one swept parameter.
    fn against_sweep(&mut self, group: &SweepGroup) -> Result<()> {
        let (t, k, runs) = (&group.technique, &group.key, &group.runs);
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
        let series = |name: &str, y: &dyn Fn(&RunResult) -> f64| Series {
            name: name.to_string(),
            points: xs.iter().zip(runs).map(|(&x, (_, r))| (x, y(r))).collect(),
        };
        let name = slug(&format!("sweep-{t}-{k}"));
        let svg = charts::lines(
            &format!("{t}: error against {k}"),
            &xaxis,
            &Axis::linear("error (fraction, 0–1)"),
            &[
                series("mismatch rate", &mismatch_of),
                series("mean abs error", &error_of),
            ],
        )?;
        self.add(
            &format!("{name}-error"),
            &svg,
            format!("{t}: mismatch rate and mean absolute error against {k}."),
        )?;
        let svg = charts::lines(
            &format!("{t}: time against {k}"),
            &xaxis,
            &Axis::linear("frame time (ms)"),
            &[series("time", &time_of)],
        )?;
        self.add(
            &format!("{name}-time"),
            &svg,
            format!("{t}: frame time against {k}."),
        )
    }

    /// Time per frame of a walkthrough, one line per run.
    fn per_frame(&mut self, results: &[RunResult]) -> Result<()> {
        let per_frame = per_frame_series(results, &|f| Some(f.time_ms));
        if per_frame.is_empty() {
            return Ok(());
        }
        let all: Vec<f64> = per_frame
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .collect();
        let yaxis = match Axis::auto("frame time (ms, log scale)", &all, 50.0) {
            a if a.scale == Scale::Log => a,
            _ => Axis::linear("frame time (ms)"),
        };
        let svg = charts::lines(
            "Time per frame",
            &Axis::linear("frame (index along the camera path)"),
            &yaxis,
            &per_frame,
        )?;
        self.add(
            "frame-times",
            &svg,
            "Each technique's frame time along the walkthrough.".into(),
        )
    }
}

/// One line per run of a per-frame figure, over the frames that have it; runs with fewer
/// than two such frames are left out.
fn per_frame_series(
    results: &[RunResult],
    y: &dyn Fn(&FrameFigures) -> Option<f64>,
) -> Vec<Series> {
    results
        .iter()
        .filter_map(|r| {
            let fr = r.frames.as_ref()?;
            Some(Series {
                name: r.label.clone(),
                points: fr
                    .iter()
                    .filter_map(|f| Some((f.frame as f64, y(f)?)))
                    .collect(),
            })
        })
        .filter(|s| s.points.len() > 1)
        .collect()
}

/// The name of the temporal error plot, `plots/temporal-error.svg` (the walkthrough
/// section shows it under the animations).
pub const TEMPORAL_ERROR_PLOT: &str = "temporal-error";

impl Plots<'_> {
    /// Mean error against each frame's own reference, and temporal error, per frame.
    fn frame_errors(&mut self, results: &[RunResult]) -> Result<()> {
        let frame_axis = Axis::linear("frame (index along the camera path)");
        let errors = per_frame_series(results, &|f| Some(f.verdict?.mean_abs_error));
        if !errors.is_empty() {
            let svg = charts::lines(
                "Error per frame",
                &frame_axis,
                &Axis::linear("mean absolute error (fraction, 0–1)"),
                &errors,
            )?;
            self.add(
                "frame-errors",
                &svg,
                "Each technique's mean absolute error against the reference traced for the same frame, along the walkthrough.".into(),
            )?;
        }
        let temporal = per_frame_series(results, &|f| f.verdict?.temporal_error);
        if !temporal.is_empty() {
            let svg = charts::lines(
                "Temporal error per frame",
                &frame_axis,
                &Axis::linear("temporal error (fraction, 0–1)"),
                &temporal,
            )?;
            self.add(
                TEMPORAL_ERROR_PLOT,
                &svg,
                "Temporal error: from each frame to the next, mean |Δ technique − Δ reference| of the shadow term over the pixels visible in both; 0 when the shadows move as the true ones do, high where they shimmer.".into(),
            )?;
        }
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometric_sweeps() {
        assert!(geometric(&[512.0, 1024.0, 2048.0, 4096.0]));
        assert!(geometric(&[4.0, 8.0, 16.0]));
        assert!(!geometric(&[4.0, 8.0]));
        assert!(!geometric(&[1.0, 2.0, 3.0]));
        assert!(!geometric(&[2.0, 2.0, 2.0]));
    }
}
