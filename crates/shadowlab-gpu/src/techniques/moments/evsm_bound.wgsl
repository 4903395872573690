// gpu:evsm, the test of stage `lookup`: the smaller of the two warps' Chebyshev bounds,
// each with the variance floor carried into warped space by the warp's derivative at the
// receiver (the library's `evsm::lit`). Composed after variance/chebyshev.wgsl and
// moments/evsm_warp.wgsl.

fn shade(d: f32, view_index: u32) -> f32 {
    let m = fetch(0u);
    let w = evsm_warp(d);
    let sp = 2.0 * tp(0u) * w.x;
    let p = chebyshev(w.x, m.x, m.y, tp(3u) * sp * sp, tp(4u));
    if tp(2u) < 3.0 {
        return p;
    }
    let sn = 2.0 * tp(1u) * w.y;
    return min(p, chebyshev(w.y, m.z, m.w, tp(3u) * sn * sn, tp(4u)));
}
