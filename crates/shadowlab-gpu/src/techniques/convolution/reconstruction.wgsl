// gpu:csm, the test of stage `lookup` (Annen et al. 2007, Eq. 13, Section 3.2.2): the
// weighted sum of the filtered basis images of every group, 1/2 + Σ_k (2σ_k/c_k)
// [cos(c_k d') B_{2k−1} − sin(c_k d') B_{2k}] at d' = d − offset, scaled about the pivot
// and clamped (the library's `csm` test). 8-bit texels sample as code/255, decoded to
// [-1, 1] as 2s − 1. Composed after convolution/basis.wgsl.

fn shade(d: f32, view_index: u32) -> f32 {
    let m = u32(tp(0u));
    let dd = d - tp(2u);
    var sum = 0.0;
    for (var g = 0u; g < (m + 1u) / 2u; g++) {
        var s = fetch(g);
        if tp(1u) > 0.5 {
            s = 2.0 * s - 1.0;
        }
        for (var j = 0u; j < 2u; j++) {
            let k = 2u * g + j + 1u;
            if k <= m {
                let sc = sin_cos_pi(f32(2u * k - 1u) * dd);
                sum += tp(7u + k) * (sc.y * s[2u * j] - sc.x * s[2u * j + 1u]);
            }
        }
    }
    let f = 0.5 + sum;
    return clamp(tp(4u) + tp(3u) * (f - tp(4u)), 0.0, 1.0);
}
