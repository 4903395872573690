//! `--benchmark-frames`: the time of each stage of the viewer's frames, each drawn from
//! scratch (camera pass, technique, shading, overlays and presentation), averaged.

/// The benchmark's report: mean milliseconds of each stage and of the frame, and frames
/// per second.
pub fn summary(technique: &str, frames: &[Vec<(String, f64)>]) -> String {
    let n = frames.len().max(1) as f64;
    let mut stages: Vec<(String, f64)> = Vec::new();
    for f in frames {
        for (name, ms) in f {
            match stages.iter_mut().find(|(s, _)| s == name) {
                Some((_, t)) => *t += ms,
                None => stages.push((name.clone(), *ms)),
            }
        }
    }
    let total: f64 = stages.iter().map(|(_, t)| t).sum::<f64>() / n;
    let mut out = format!(
        "{technique}: {} frames, {total:.1} ms a frame, {:.1} frames per second",
        frames.len(),
        1e3 / total.max(1e-9)
    );
    for (name, t) in &stages {
        out.push_str(&format!("\n  {name:<24} {:>8.2} ms", t / n));
    }
    out
}
