// The one-tailed Chebyshev bound of variance shadow maps (the library's
// `variance::chebyshev`): the lit fraction of a receiver at depth `d` behind filtered
// moments `(mean, second)`, the variance floored at `min_variance`, with the light-bleeding
// reduction `reduction`. Shared by gpu:vsm and gpu:evsm.

fn chebyshev(d: f32, mean: f32, second: f32, min_variance: f32, reduction: f32) -> f32 {
    if d <= mean {
        return 1.0;
    }
    if !(abs(mean) < 3.0e38 && abs(second) < 3.0e38 && abs(d) < 3.0e38) {
        // Moments that are not finite carry no occlusion information.
        return 1.0;
    }
    let variance = max(second - mean * mean, min_variance);
    let t = d - mean;
    let p = variance / (variance + t * t);
    if reduction > 0.0 {
        return clamp((p - reduction) / (1.0 - reduction), 0.0, 1.0);
    }
    return p;
}
