// gpu:evsm, the encoder of stage `encode` (Lauritzen & McCool 2008, Section 5): the
// exponential warps of the normalized depth mapped to [-1, 1], w+ = exp(c+ t) and
// w- = -exp(-c- t), and their second moments with the texel's depth variance carried
// through the warps' derivatives (the library's `evsm` encoder). Parameters: tp(0) c+,
// tp(1) c- (both clamped to the storage's), tp(2) the moment count (2 or 4), tp(3) the
// variance floor, tp(4) the light-bleeding reduction.

fn evsm_warp(d: f32) -> vec2<f32> {
    let t = 2.0 * d - 1.0;
    return vec2<f32>(exp(tp(0u) * t), -exp(-tp(1u) * t));
}

fn encode_texel(z: f32, variance: f32, group: u32) -> vec4<f32> {
    let w = evsm_warp(z);
    let sp = 2.0 * tp(0u) * w.x;
    let sn = 2.0 * tp(1u) * w.y;
    var out = vec4<f32>(w.x, w.x * w.x + sp * sp * variance, 0.0, 0.0);
    if tp(2u) > 3.0 {
        out.z = w.y;
        out.w = w.y * w.y + sn * sn * variance;
    }
    return out;
}
