//! `engines`: every technique — the papers' and the ones engines ship (`cascaded`,
//! `lispsm`, `evsm`, `msm`) — on the same scenes at equal shadow memory, measured against
//! the ray-traced reference on the same camera pass.
//!
//! For each scene and memory budget (4, 16 and 64 MiB) every technique with a map gets the
//! largest resolution whose memory, as the technique reports it on that frame, fits the
//! budget: a first guess from its fixed bytes and bytes per texel, read from two probe
//! renders at [`PROBE_RESOLUTIONS`] (so mip chains, channel counts, a point light's six
//! faces and per-sample buffers are counted as the technique counts them), is kept when its
//! measured memory fits, and otherwise the side is searched on measured memory
//! ([`fitting_side`]: `subpixel`'s per-pixel buffers grow as its map coarsens, so its
//! memory is not linear in the texels). `asm` gets the budget as its `budget-mb`. A
//! technique whose memory is over the budget even at a 16² map (or, for `asm`, at its
//! budget) is left out of that budget, with a line that says so. `afsm`, `raytrace` and the reference have no map to size: they run once per
//! scene and their own memory is reported. Times are the technique's own frame time (the
//! shared camera pass excluded), the median of `--repeat` runs after one untimed run; the
//! reference is one ray per pixel centre, so filtered techniques' mean error includes
//! their softening of hard edges. `--quick` runs `street` at 4 MiB, 512×384, one timed run.
//!
//! The targets checked at the end, on one run's ratios at equal memory: `cascaded` (4
//! cascades) at most [`CASCADED_TIME_TARGET`]× `sm`'s time, `msm` at most
//! [`MSM_TIME_TARGET`]× `vsm`'s, `lispsm` at most [`LISPSM_TIME_TARGET`]× `sm`'s; on `street`
//! at 16 MiB (one 2048² map) `cascaded` at most a quarter of `sm`'s mismatch. Each time
//! ratio is printed as the median and the worst over the run's scene × budget pairs (under
//! spot and point lights `cascaded` and `lispsm` fall back to `sm`'s one map).

pub use super::engines_rows::{Backend, Row};
use super::{median_ms, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use shadowlab::compare::compare;
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::techniques::{self, Frame, ShadowTechnique, Visibility};
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

/// The time ratios the CPU run checks: `(a, b, target)` for `a`'s time at most `target`
/// times `b`'s.
const CPU_TIME_TARGETS: [(&str, &str, f64); 3] = [
    ("cascaded", "sm", CASCADED_TIME_TARGET),
    ("msm", "vsm", MSM_TIME_TARGET),
    ("lispsm", "sm", LISPSM_TIME_TARGET),
];

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

/// Stop the search for the largest fitting side once it is known within this share.
const SEARCH_TOLERANCE: u32 = 64;

/// The largest map side whose memory, as `measure(side)` reports it, is at or under `budget`
/// bytes; `Err(bytes)` with the memory of a [`MIN_RESOLUTION`]² map when not even that
/// fits. The linear model of [`fitting_resolution`] gives the first guess, and it is kept
/// when its measured memory fits; otherwise (memory that is not fixed bytes plus bytes per
/// texel, such as per-pixel buffers that grow as the map coarsens) the side is bisected
/// between [`MIN_RESOLUTION`] and the guess on measured memory, to within
/// 1/[`SEARCH_TOLERANCE`] of the largest fitting side. Every side returned was measured.
fn fitting_side(
    probe: [u64; 2],
    budget: u64,
    mut measure: impl FnMut(u32) -> Result<u64>,
) -> Result<std::result::Result<u32, u64>> {
    let guess = fitting_resolution(probe, budget).unwrap_or(MIN_RESOLUTION);
    let at_guess = measure(guess)?;
    if at_guess <= budget {
        return Ok(Ok(guess));
    }
    if guess == MIN_RESOLUTION {
        return Ok(Err(at_guess));
    }
    let at_min = measure(MIN_RESOLUTION)?;
    if at_min > budget {
        return Ok(Err(at_min));
    }
    let (mut lo, mut hi) = (MIN_RESOLUTION, guess);
    while hi - lo > 1 && (hi - lo) * SEARCH_TOLERANCE > lo {
        let mid = lo + (hi - lo) / 2;
        if measure(mid)? <= budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Ok(lo))
}

/// A frame's GPU time: the sum of its stats' `gpu_*_ms` timestamp counters.
pub fn gpu_ms(stats: &techniques::Stats) -> f64 {
    stats
        .counters
        .iter()
        .filter(|(k, _)| k.starts_with("gpu_") && k.ends_with("_ms"))
        .map(|(_, v)| v)
        .sum()
}

/// Renders `t` on `frame`: median time of `repeat` runs after an untimed one (wall time,
/// or with `gpu_time` the frames' GPU time), the result.
pub fn timed(
    t: &mut dyn ShadowTechnique,
    frame: &Frame,
    repeat: usize,
    gpu_time: bool,
) -> Result<(f64, techniques::Shadows)> {
    t.render(frame)?;
    if !gpu_time {
        let (ms, r) = median_ms(repeat, || t.render(frame));
        return Ok((ms, r?));
    }
    let mut times = Vec::new();
    let mut last = t.render(frame)?;
    times.push(gpu_ms(&last.stats));
    for _ in 1..repeat.max(1) {
        last = t.render(frame)?;
        times.push(gpu_ms(&last.stats));
    }
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], last))
}

/// The scenes, budgets, frame size and runs per measurement of a run.
pub fn plan(a: &BenchConfig) -> (&'static [&'static str], &'static [u64], (u32, u32), usize) {
    if a.quick {
        (&QUICK_SCENES, &[4], (512, 384), 1)
    } else {
        (&SCENES, &BUDGETS_MIB, (1024, 768), a.repeat)
    }
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let rows = measure(a, Backend::CPU)?;
    let (scenes, budgets, _, _) = plan(a);
    summary(&rows, budgets, &CPU_TIME_TARGETS);
    if let Some(dir) = &a.plots {
        super::engines_rows::write_plots(dir, &rows, scenes, budgets, Backend::CPU)?;
    }
    Ok(BenchReport {
        rows: rows.iter().map(Row::json).collect(),
    })
}

/// Measures every technique of `backend` on the run's scenes at its budgets, printing a
/// table per scene; the rows.
pub fn measure(a: &BenchConfig, backend: Backend) -> Result<Vec<Row>> {
    let (scenes, budgets, size, repeat) = plan(a);
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
        let pb = crate::progress::bar(backend.names.len() as u64, name.to_string());
        let on = OnScene {
            name,
            frame: &frame,
            reference: &reference,
            gpu_time: backend.gpu_time,
        };
        for &tname in backend.names {
            measure_technique(&on, tname, budgets, repeat, &pb, &mut rows)?;
            pb.inc(1);
        }
        pb.finish_and_clear();
    }
    Ok(rows)
}

/// What a scene's measurements share: the frame and its reference.
struct OnScene<'a> {
    name: &'a str,
    frame: &'a Frame<'a>,
    reference: &'a Visibility,
    /// Time by the GPU's timestamps.
    gpu_time: bool,
}

/// Prints that `tname` is left out at `budget` MiB because its memory does not fit.
fn not_fitting(pb: &indicatif::ProgressBar, tname: &str, budget: u64, why: String) {
    pb.suspend(|| {
        println!(
            "{tname:>10} {:>7}   does not fit: {why}; left out",
            format!("{budget} MiB")
        )
    });
}

/// Measures technique `tname` on `on` at every budget (once when it has no memory to size),
/// appending its rows: techniques with a map side get the largest one whose measured memory
/// fits ([`fitting_side`]), `asm` the budget as its `budget-mb`; a technique whose memory
/// is over the budget even so is left out of that budget, and says so.
fn measure_technique(
    on: &OnScene,
    tname: &str,
    budgets: &[u64],
    repeat: usize,
    pb: &indicatif::ProgressBar,
    rows: &mut Vec<Row>,
) -> Result<()> {
    let frame = on.frame;
    let mut t = techniques::create(tname)?;
    let key = sizing_key(t.as_ref());
    let memory_at = |t: &mut Box<dyn ShadowTechnique>, r: u32| -> Result<u64> {
        t.set_param("resolution", &r.to_string())?;
        Ok(t.render(frame)?.stats.memory_bytes)
    };
    let probe = match key {
        Some("resolution") => Some([
            memory_at(&mut t, PROBE_RESOLUTIONS[0])?,
            memory_at(&mut t, PROBE_RESOLUTIONS[1])?,
        ]),
        _ => None,
    };
    let budget_list: Vec<Option<u64>> = match key {
        Some(_) => budgets.iter().map(|&b| Some(b)).collect(),
        None => vec![None],
    };
    for b in budget_list {
        let mut res = None;
        if let Some(b) = b {
            if let Some(p) = probe {
                match fitting_side(p, b << 20, |r| memory_at(&mut t, r))? {
                    Ok(r) => {
                        t.set_param("resolution", &r.to_string())?;
                        res = Some(r);
                    }
                    Err(bytes) => {
                        let why = format!("{} at a {MIN_RESOLUTION}² map", mib(bytes));
                        not_fitting(pb, tname, b, why);
                        continue;
                    }
                }
            } else {
                t.set_param("budget-mb", &b.to_string())?;
            }
        }
        let (ms, out) = timed(t.as_mut(), frame, repeat, on.gpu_time)?;
        if let Some(b) = b.filter(|&b| out.stats.memory_bytes > b << 20) {
            not_fitting(
                pb,
                tname,
                b,
                format!("{} at its budget", mib(out.stats.memory_bytes)),
            );
            continue;
        }
        let m = compare(frame.view, &out.visibility, on.reference);
        let row = Row {
            scene: on.name.to_string(),
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
                "{:>10} {:>7} {:>6} {:>10} {:>10.1} {:>8.3}% {:>9.4}",
                row.technique,
                b.map_or("-".into(), |b| format!("{b} MiB")),
                res.map_or("-".into(), |r| r.to_string()),
                mib(row.memory_bytes),
                row.time_ms,
                row.mismatch * 100.0,
                row.mean_error
            )
        });
        rows.push(row);
    }
    Ok(())
}

/// `bytes` in MiB, one decimal, as the table prints memory.
fn mib(bytes: u64) -> String {
    format!("{:.1}Mi", bytes as f64 / (1u64 << 20) as f64)
}

/// The row of `technique` on `scene` at `budget`.
pub fn find<'r>(rows: &'r [Row], scene: &str, technique: &str, budget: u64) -> Option<&'r Row> {
    rows.iter()
        .find(|r| r.scene == scene && r.technique == technique && r.budget_mib == Some(budget))
}

/// Prints the targets' ratios, each with its target and whether it is met: for the time
/// ratios the median and the worst over the scene × budget pairs of the run (on a loaded
/// machine one slow repetition can make the worst, so both are shown).
pub fn summary(rows: &[Row], budgets: &[u64], targets: &[(&str, &str, f64)]) {
    println!();
    let scenes: Vec<&str> = {
        let mut s: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
        s.dedup();
        s
    };
    for &(a, b, target) in targets {
        let mut ratios: Vec<f64> = Vec::new();
        for s in &scenes {
            for &bud in budgets {
                if let (Some(x), Some(y)) = (find(rows, s, a, bud), find(rows, s, b, bud)) {
                    ratios.push(x.time_ms / y.time_ms);
                }
            }
        }
        if ratios.is_empty() {
            continue;
        }
        ratios.sort_by(f64::total_cmp);
        let n = ratios.len();
        let median = (ratios[(n - 1) / 2] + ratios[n / 2]) / 2.0;
        let worst = ratios[n - 1];
        println!(
            "time {a}/{b} at equal memory over {} scene×budget pairs (target at most {target}): median {median:.2} {}, worst {worst:.2} {}",
            ratios.len(),
            verdict(median <= target),
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

#[cfg(test)]
mod tests {
    use super::*;

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
        // 16 bytes a texel plus a third for mips (as a whole number of bytes per texel, 21).
        let r = fitting_resolution(bytes(0, 21), 64 << 20).unwrap() as u64;
        assert!(r * r * 21 <= 64 << 20 && (r + 1) * (r + 1) * 21 > 64 << 20);
    }

    /// Checks [`fitting_side`] against a search of every side: what it returns was measured
    /// at or under the budget and is within the tolerance of the largest side that is (for
    /// memory that grows with the side beyond the sizes that fit), or nothing fits.
    fn check_fit(memory: impl Fn(u32) -> u64, budget: u64) -> Option<u32> {
        let probe = PROBE_RESOLUTIONS.map(&memory);
        let mut measured = Vec::new();
        let fit = fitting_side(probe, budget, |r| {
            measured.push(r);
            Ok(memory(r))
        })
        .unwrap();
        let largest = (MIN_RESOLUTION..=16384)
            .rev()
            .find(|&r| memory(r) <= budget);
        match fit {
            Ok(r) => {
                assert!(measured.contains(&r) && memory(r) <= budget, "{r}");
                let best = largest.unwrap();
                assert!(
                    r <= best && (best - r) * SEARCH_TOLERANCE <= r,
                    "{r} of {best}"
                );
                Some(r)
            }
            Err(bytes) => {
                assert_eq!(bytes, memory(MIN_RESOLUTION));
                assert!(memory(MIN_RESOLUTION) > budget);
                None
            }
        }
    }

    #[test]
    fn fitted_sides_are_measured_under_the_budget() {
        // Linear memory: the model's guess is exact.
        assert_eq!(check_fit(|r| 4 * (r as u64).pow(2), 16 << 20), Some(2048));
        // Per-pixel buffers that shrink as the map grows (silhouettes of a coarser map
        // cover more pixels): the probes see negative bytes per texel.
        let shrinking = |r: u32| (36u64 << 20) - 4096 * r as u64 + 4 * (r as u64).pow(2);
        assert_eq!(check_fit(shrinking, 4 << 20), None);
        assert!(check_fit(shrinking, 64 << 20).is_some());
        // Memory growing faster than the texels: the linear guess overshoots and is cut back.
        let steep = |r: u32| 4 * (r as u64).pow(2) + (r as u64).pow(3) / 64;
        assert!(check_fit(steep, 16 << 20).unwrap() < 2048);
    }
}
