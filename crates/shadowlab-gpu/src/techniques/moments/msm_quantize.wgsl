// gpu:msm, the encoder of stage `encode` (Peters & Klein 2015, Section 4.3): the four
// power moments of the normalized depth, at 16 bits through the paper's optimized
// quantization b' = Θ·b + (0.0359558848, 0, 0, 0), each row of Θ evaluated by Horner's
// rule, stored as 16-bit codes; at 32 bits the plain moments. Parameters: tp(0) 1 for
// the quantized 16-bit storage, tp(1) the moment bias α, tp(2) the depth bias, tp(3) the
// offset of the first quantized channel, tp(4..20) Θ by rows, tp(20..36) Θ⁻¹ by columns.

fn encode_texel(z: f32, variance: f32, group: u32) -> vec4<f32> {
    if tp(0u) < 0.5 {
        let z2 = z * z;
        return vec4<f32>(z, z2, z2 * z, z2 * z2);
    }
    var q = vec4<f32>(0.0);
    for (var r = 0u; r < 4u; r++) {
        let t = 4u + 4u * r;
        q[r] = z * (tp(t) + z * (tp(t + 1u) + z * (tp(t + 2u) + z * tp(t + 3u))));
    }
    q.x += tp(3u);
    return q * 65535.0;
}
