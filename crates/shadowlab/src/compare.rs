//! Quality metrics of a shadow term against the reference, over covered pixels.

pub use crate::frame::luminance;
use crate::frame::Visibility;
use crate::math::Vec3;
use crate::view::ViewSamples;

/// A visibility difference at or above this counts as a mismatch: the pixel's lit/shadowed
/// answer flipped.
pub const MISMATCH_THRESHOLD: f32 = 0.5;

/// How far a shadow term is from the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Number of covered pixels compared.
    pub covered_pixels: usize,
    /// Share of covered pixels whose luminance differs by at least [`MISMATCH_THRESHOLD`].
    pub mismatch_rate: f64,
    /// Mean absolute luminance difference over covered pixels.
    pub mean_abs_error: f64,
    /// Mean absolute difference of each RGB channel, averaged over channels.
    pub mean_abs_error_rgb: f64,
}

/// Compares `vis` with `reference` over the pixels `view` covers.
pub fn compare(view: &ViewSamples, vis: &Visibility, reference: &Visibility) -> Metrics {
    let pairs = (0..vis.value.len())
        .filter(|&k| view.covered(k))
        .map(|k| (vis.value[k], reference.value[k]));
    metrics(pairs)
}

/// Compares two lists of per-sample shadow terms (e.g. the layer samples behind
/// semi-transparent surfaces) entry by entry; `covered_pixels` counts the samples.
pub fn compare_samples(vis: &[Vec3], reference: &[Vec3]) -> Metrics {
    assert_eq!(
        vis.len(),
        reference.len(),
        "sample lists of different lengths"
    );
    metrics(vis.iter().copied().zip(reference.iter().copied()))
}

fn metrics(pairs: impl Iterator<Item = (Vec3, Vec3)>) -> Metrics {
    let mut m = Metrics::default();
    let (mut mismatches, mut sum, mut sum_rgb) = (0usize, 0f64, 0f64);
    for (v, r) in pairs {
        m.covered_pixels += 1;
        let d = (luminance(v) - luminance(r)).abs();
        if d >= MISMATCH_THRESHOLD {
            mismatches += 1;
        }
        sum += d as f64;
        let e = (v - r).abs();
        sum_rgb += (e.x + e.y + e.z) as f64 / 3.0;
    }
    if m.covered_pixels > 0 {
        let n = m.covered_pixels as f64;
        m.mismatch_rate = mismatches as f64 / n;
        m.mean_abs_error = sum / n;
        m.mean_abs_error_rgb = sum_rgb / n;
    }
    m
}
