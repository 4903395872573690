// gpu:csm, the encoder of stage `encode` (Annen et al. 2007, Section 4.1, Eq. 14): the
// basis images sin(c_k z), cos(c_k z) with c_k = π(2k − 1), two terms (four channels) a
// group, stored as 8-bit codes of [-1, 1] (the paper's) or as f32. Parameters: tp(0) the
// order M, tp(1) 1 for 8-bit storage, tp(2) the offset, tp(3) the scale, tp(4) the pivot,
// tp(8..24) the coefficients' factors 2σ_k/c_k.

const CSM_PI: f32 = 3.14159265358979;

// sin(πx) and cos(πx), reduced to πr with r = x − round(x) first (the library's
// `sin_cos_pi`).
fn sin_cos_pi(x: f32) -> vec2<f32> {
    let n = floor(x + 0.5);
    let r = (x - n) * CSM_PI;
    let sc = vec2<f32>(sin(r), cos(r));
    if (i32(n) & 1) != 0 {
        return -sc;
    }
    return sc;
}

fn encode_texel(z: f32, variance: f32, group: u32) -> vec4<f32> {
    let m = u32(tp(0u));
    var out = vec4<f32>(0.0);
    for (var j = 0u; j < 2u; j++) {
        let k = 2u * group + j + 1u;
        if k <= m {
            let sc = sin_cos_pi(f32(2u * k - 1u) * z);
            out[2u * j] = sc.x;
            out[2u * j + 1u] = sc.y;
        }
    }
    if tp(1u) > 0.5 {
        return (out + 1.0) * 127.5;
    }
    return out;
}
