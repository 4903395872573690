// gpu:vsm, the encoder of stage `encode`: the first two moments of the normalized depth,
// the second with the depth variance across the texel (the library's `vsm` encoder).
// Composed into filtering/{encode, lookup}.wgsl after filtering/filtered.wgsl.

fn encode_texel(z: f32, variance: f32, group: u32) -> vec4<f32> {
    return vec4<f32>(z, z * z + variance, 0.0, 0.0);
}
