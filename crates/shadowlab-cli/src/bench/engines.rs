//! `engines`: every technique — the papers' and the ones engines ship (`cascaded`,
//! `lispsm`, `evsm`, `msm`) — on the same scenes at equal shadow memory, measured against
//! the ray-traced reference on the same camera pass.
//!
//! For each scene and memory budget (4, 16 and 64 MiB) every technique with a map gets the
//! largest resolution whose memory fits the budget: its fixed bytes and bytes per texel are
//! read from two probe renders at [`PROBE_RESOLUTIONS`] (so mip chains, channel counts, a
//! point light's six faces and per-sample buffers are counted as the technique counts
//! them), and `asm` gets the budget as its
//! `budget-mb`. `afsm`, `raytrace` and the reference have no map to size: they run once per
//! scene and their own memory is reported. Times are the technique's own frame time (the
//! shared camera pass excluded), the median of `--repeat` runs after one untimed run; the
//! reference is one ray per pixel centre, so filtered techniques' mean error includes
//! their softening of hard edges. `--quick` runs `street` at 4 MiB, 512×384, one timed run.
//!
//! The targets checked at the end, on one run's ratios at equal memory: `cascaded` (4
//! cascades) at most [`CASCADED_TIME_TARGET`]× `sm`'s time, `msm` at most
//! [`MSM_TIME_TARGET`]× `vsm`'s, `lispsm` at most [`LISPSM_TIME_TARGET`]× `sm`'s; on `street`
//! at 16 MiB (one 2048² map) `cascaded` at most a quarter of `sm`'s mismatch.

use super::{median_ms, BenchReport};
use crate::charts::{self, Axis, Point, Series};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::compare::compare;
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::techniques::{self, Frame, ShadowTechnique};
use shadowlab::view::ViewSamples;

/// Memory budgets of the full run, MiB.
const BUDGETS_MIB: [u64; 3] = [4, 16, 64];
/// Scenes of the full run (the bunny is the real scanned mesh).
const SCENES: [&str; 6] = [
    "street",
    "room",
    "chessboard",
    "fence",
    "fence-leak",
    "bunny",
];
/// The scene of `--quick`: a directional light, so `cascaded` and `lispsm` run their own
/// maps (under a spot or point light they fall back to one map, which times nothing new).
const QUICK_SCENES: [&str; 1] = ["street"];
/// Map sides of the two probe renders that measure a technique's fixed bytes and bytes per
/// texel.
const PROBE_RESOLUTIONS: [u32; 2] = [128, 256];
/// Time targets (ratios at equal memory).
const CASCADED_TIME_TARGET: f64 = 1.5;
const MSM_TIME_TARGET: f64 = 1.3;
const LISPSM_TIME_TARGET: f64 = 1.15;
/// `cascaded`'s mismatch on `street` at 16 MiB, at most this share of `sm`'s.
const CASCADED_MISMATCH_TARGET: f64 = 0.25;

/// One measured technique at one budget.
struct Row {
    scene: String,
    technique: String,
    budget_mib: Option<u64>,
    resolution: Option<u32>,
    memory_bytes: u64,
    time_ms: f64,
    mismatch: f64,
    mean_error: f64,
}

impl Row {
    fn json(&self) -> Value {
        json!({
            "scene": self.scene, "technique": self.technique, "budget_mib": self.budget_mib,
            "resolution": self.resolution, "memory_bytes": self.memory_bytes,
            "time_ms": self.time_ms, "mismatch": self.mismatch, "mean_abs_error": self.mean_error,
        })
    }
}

/// The parameter that sizes a technique's memory, if it has one.
fn sizing_key(t: &dyn ShadowTechnique) -> Option<&'static str> {
    let p = t.params();
    if p.contains_key("budget-mb") {
        Some("budget-mb")
    } else if p.contains_key("resolution") {
        Some("resolution")
    } else {
        None
    }
}

/// The smallest map side the suite sizes a technique to: below it a map holds no shadow
/// worth measuring.
const MIN_RESOLUTION: u32 = 16;

/// The resolution whose memory fits `budget` bytes for a technique that took `probe[i]`
/// bytes at [`PROBE_RESOLUTIONS`]`[i]`: memory is taken as fixed bytes plus bytes per texel.
/// `None` when not even a [`MIN_RESOLUTION`]² map fits (the technique's fixed buffers, such
/// as per-pixel ones, take the budget).
fn fitting_resolution(probe: [u64; 2], budget: u64) -> Option<u32> {
    let [r0, r1] = PROBE_RESOLUTIONS.map(|r| (r as f64).powi(2));
    let per_texel = ((probe[1] as f64 - probe[0] as f64) / (r1 - r0)).max(1e-9);
    let fixed = (probe[0] as f64 - per_texel * r0).max(0.0);
    let side = ((budget as f64 - fixed).max(0.0) / per_texel)
        .sqrt()
        .floor();
    (side >= MIN_RESOLUTION as f64).then(|| side.min(16384.0) as u32)
}

/// The bytes a technique that took `probe` bytes at [`PROBE_RESOLUTIONS`] needs at the
/// smallest map, for the line that says it does not fit.
fn smallest_bytes(probe: [u64; 2]) -> f64 {
    let [r0, r1] = PROBE_RESOLUTIONS.map(|r| (r as f64).powi(2));
    let per_texel = ((probe[1] as f64 - probe[0] as f64) / (r1 - r0)).max(0.0);
    (probe[0] as f64 - per_texel * r0).max(0.0) + per_texel * (MIN_RESOLUTION as f64).powi(2)
}

/// Renders `t` on `frame`: median time of `repeat` runs after an untimed one, the result.
fn timed(
    t: &mut dyn ShadowTechnique,
    frame: &Frame,
    repeat: usize,
) -> Result<(f64, techniques::Shadows)> {
    t.render(frame)?;
    let (ms, r) = median_ms(repeat, || t.render(frame));
    Ok((ms, r?))
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let (scenes, budgets, size, repeat): (&[&str], &[u64], (u32, u32), usize) = if a.quick {
        (&QUICK_SCENES, &[4], (512, 384), 1)
    } else {
        (&SCENES, &BUDGETS_MIB, (1024, 768), a.repeat)
    };
    println!(
        "engines: every technique at equal shadow memory ({} MiB); {}x{}, {} threads; times are medians of {repeat} runs; reference 1 ray per pixel",
        budgets.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(", "),
        size.0,
        size.1,
        rayon::current_num_threads()
    );
    let mut rows: Vec<Row> = Vec::new();
    for &name in scenes {
        let scene = shadowlab::scene::load(name, &Default::default())
            .with_context(|| format!("loading the {name} scene"))?;
        let mut camera = scene
            .camera
            .with_context(|| format!("{name} has no camera"))?;
        let light = scene
            .light
            .with_context(|| format!("{name} has no light"))?;
        (camera.width, camera.height) = size;
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        let reference = Reference::build(&scene).visibility(&frame, &[vec2(0.5, 0.5)]);
        println!(
            "\n{name}: {} triangles, {} light, {} covered pixels",
            scene.len(),
            light.kind(),
            view.covered_count()
        );
        println!(
            "{:>10} {:>7} {:>6} {:>10} {:>10} {:>9} {:>9}",
            "technique", "budget", "res", "memory", "time ms", "mismatch", "mean err"
        );
        let pb = crate::progress::bar(techniques::ALL.len() as u64, name.to_string());
        for &tname in techniques::ALL {
            let mut t = techniques::create(tname)?;
            let key = sizing_key(t.as_ref());
            let probe = match key {
                Some("resolution") => {
                    let mut bytes = [0u64; 2];
                    for (b, r) in bytes.iter_mut().zip(PROBE_RESOLUTIONS) {
                        t.set_param("resolution", &r.to_string())?;
                        *b = t.render(&frame)?.stats.memory_bytes;
                    }
                    Some(bytes)
                }
                _ => None,
            };
            let budget_list: Vec<Option<u64>> = match key {
                Some(_) => budgets.iter().map(|&b| Some(b)).collect(),
                None => vec![None],
            };
            for b in budget_list {
                let mut res = None;
                if let Some(b) = b {
                    match (key, probe) {
                        (Some("resolution"), Some(p)) => {
                            let Some(r) = fitting_resolution(p, b << 20) else {
                                pb.suspend(|| {
                                    println!(
                                        "{tname:>10} {:>7}   does not fit: {:.1}Mi at a {MIN_RESOLUTION}² map",
                                        format!("{b} MiB"),
                                        smallest_bytes(p) / (1u64 << 20) as f64
                                    )
                                });
                                continue;
                            };
                            t.set_param("resolution", &r.to_string())?;
                            res = Some(r);
                        }
                        _ => t.set_param("budget-mb", &b.to_string())?,
                    }
                }
                let (ms, out) = timed(t.as_mut(), &frame, repeat)?;
                let m = compare(&view, &out.visibility, &reference);
                let row = Row {
                    scene: name.to_string(),
                    technique: tname.to_string(),
                    budget_mib: b,
                    resolution: res,
                    memory_bytes: out.stats.memory_bytes,
                    time_ms: ms,
                    mismatch: m.mismatch_rate,
                    mean_error: m.mean_abs_error,
                };
                pb.suspend(|| {
                    println!(
                        "{:>10} {:>7} {:>6} {:>8.1}Mi {:>10.1} {:>8.3}% {:>9.4}",
                        row.technique,
                        b.map_or("-".into(), |b| format!("{b} MiB")),
                        res.map_or("-".into(), |r| r.to_string()),
                        row.memory_bytes as f64 / (1u64 << 20) as f64,
                        row.time_ms,
                        row.mismatch * 100.0,
                        row.mean_error
                    )
                });
                rows.push(row);
            }
            pb.inc(1);
        }
        pb.finish_and_clear();
    }
    summary(&rows, budgets);
    if let Some(dir) = &a.plots {
        write_plots(dir, &rows, scenes, budgets)?;
    }
    Ok(BenchReport {
        rows: rows.iter().map(Row::json).collect(),
    })
}

/// The row of `technique` on `scene` at `budget`.
fn find<'r>(rows: &'r [Row], scene: &str, technique: &str, budget: u64) -> Option<&'r Row> {
    rows.iter()
        .find(|r| r.scene == scene && r.technique == technique && r.budget_mib == Some(budget))
}

/// Prints the targets' ratios.
fn summary(rows: &[Row], budgets: &[u64]) {
    println!();
    let scenes: Vec<&str> = {
        let mut s: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
        s.dedup();
        s
    };
    for (a, b, target) in [
        ("cascaded", "sm", CASCADED_TIME_TARGET),
        ("msm", "vsm", MSM_TIME_TARGET),
        ("lispsm", "sm", LISPSM_TIME_TARGET),
    ] {
        let mut worst = 0.0f64;
        for s in &scenes {
            for &bud in budgets {
                if let (Some(x), Some(y)) = (find(rows, s, a, bud), find(rows, s, b, bud)) {
                    worst = worst.max(x.time_ms / y.time_ms);
                }
            }
        }
        println!(
            "time {a}/{b} at equal memory: worst {worst:.2} (target at most {target}) {}",
            verdict(worst <= target)
        );
    }
    if let (Some(c), Some(s)) = (
        find(rows, "street", "cascaded", 16),
        find(rows, "street", "sm", 16),
    ) {
        let r = c.mismatch / s.mismatch.max(1e-12);
        println!(
            "street at 16 MiB: cascaded mismatch {:.3}% vs sm {:.3}%: ratio {r:.2} (target at most {CASCADED_MISMATCH_TARGET}) {}",
            c.mismatch * 100.0,
            s.mismatch * 100.0,
            verdict(r <= CASCADED_MISMATCH_TARGET)
        );
    }
}

fn verdict(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "NOT met"
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
fn write_plots(
    dir: &std::path::Path,
    rows: &[Row],
    scenes: &[&str],
    budgets: &[u64],
) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create --plots folder {}", dir.display()))?;
    for &s in scenes {
        let series: Vec<Series> = techniques::ALL
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
        std::fs::write(dir.join(format!("engines-{s}-error-vs-memory.svg")), svg)?;
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
            &Axis::auto("frame time of the technique (ms)", &times, 10.0),
            &Axis::linear("mean absolute error (visibility, 0–1)"),
            &points,
        )?;
        std::fs::write(dir.join(format!("engines-{s}-error-vs-time.svg")), svg)?;
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

    #[test]
    fn resolutions_fit_the_budget() {
        let bytes =
            |fixed: u64, per: u64| PROBE_RESOLUTIONS.map(|r| fixed + per * (r as u64).pow(2));
        // 4 bytes a texel: a 16 MiB budget is one 2048² map.
        assert_eq!(fitting_resolution(bytes(0, 4), 16 << 20), Some(2048));
        // Fixed buffers come off the budget first.
        assert_eq!(fitting_resolution(bytes(12 << 20, 4), 16 << 20), Some(1024));
        // Fixed buffers over the budget leave no map that fits.
        assert_eq!(fitting_resolution(bytes(20 << 20, 4), 16 << 20), None);
        let need = smallest_bytes(bytes(20 << 20, 4));
        assert_eq!(need, (20u64 << 20) as f64 + 4.0 * 256.0);
        // 16 bytes a texel plus a third for mips (as a whole number of bytes per texel, 21).
        let r = fitting_resolution(bytes(0, 21), 64 << 20).unwrap() as u64;
        assert!(r * r * 21 <= 64 << 20 && (r + 1) * (r + 1) * 21 > 64 << 20);
    }
}
