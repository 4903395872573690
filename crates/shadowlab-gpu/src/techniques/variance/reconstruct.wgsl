// gpu:vsm, the test of stage `lookup`: Chebyshev's bound on the filtered moments.
// Parameters: tp(0) the variance floor, tp(1) the light-bleeding reduction.

fn shade(d: f32, view_index: u32) -> f32 {
    let m = fetch(0u);
    return chebyshev(d, m.x, m.y, tp(0u), tp(1u));
}
