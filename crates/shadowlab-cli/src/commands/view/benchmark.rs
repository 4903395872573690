//! `--benchmark-frames`: the time of each stage of the viewer's frames, each drawn from
//! scratch (camera pass, technique, shading, upload, panel and presentation), averaged
//! over the frames after a warm-up frame (which makes the pipelines and first buffers);
//! and apart from them, the GPU's own stage times (timestamp queries), which run inside
//! the technique's stages and so are not added to the frame.

/// The report's line when the frames were drawn into a texture, not the window.
pub const OFFSCREEN: &str = "drawn offscreen: each frame into a texture of the window's size, waited for, not presented (--offscreen, or an adapter that cannot present to this display)";

/// The name prefix of a GPU stage time.
pub const GPU_PREFIX: &str = "gpu ";

/// The benchmark's report: mean milliseconds of each stage and of the frame, and frames
/// per second; then the GPU's stage times.
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
    let (gpu, wall): (Vec<_>, Vec<_>) = stages
        .into_iter()
        .partition(|(s, _)| s.starts_with(GPU_PREFIX));
    let total: f64 = wall.iter().map(|(_, t)| t).sum::<f64>() / n;
    let mut out = format!(
        "{technique}: {} frames after a warm-up frame, {total:.1} ms a frame, {:.1} frames per second",
        frames.len(),
        1e3 / total.max(1e-9)
    );
    for (name, t) in &wall {
        out.push_str(&format!("\n  {name:<24} {:>8.2} ms", t / n));
    }
    if !gpu.is_empty() {
        out.push_str("\n  GPU stages (timestamp queries, within the stages above):");
        for (name, t) in &gpu {
            out.push_str(&format!("\n  {name:<24} {:>8.2} ms", t / n));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_times_are_shown_but_not_added_to_the_frame() {
        let frames = vec![
            vec![("a".to_string(), 2.0), ("gpu x".to_string(), 1.0)],
            vec![("a".to_string(), 4.0), ("gpu x".to_string(), 3.0)],
        ];
        let s = summary("t", &frames);
        assert!(
            s.starts_with("t: 2 frames after a warm-up frame, 3.0 ms a frame"),
            "{s}"
        );
        assert!(s.contains("gpu x") && s.contains("2.00 ms"), "{s}");
    }
}
