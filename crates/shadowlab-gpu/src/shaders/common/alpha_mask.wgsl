// Alpha-masked casters, as the library's `AlphaMask::keeps` decides them: the nearest
// texel at the interpolated texture coordinates, wrapped as the material says, kept where
// alpha · factor ≥ cutoff. The textures of every material lie packed in one buffer of
// bytes (four to a word).

const WRAP_REPEAT: u32 = 0u;
const WRAP_MIRRORED: u32 = 1u;
const WRAP_CLAMP: u32 = 2u;

struct MaterialU {
    transmittance: vec3<f32>,
    // 1 when the material blocks all light.
    opaque: u32,
    // 1 when the material has an alpha mask.
    masked: u32,
    // The mask's first byte in the texel buffer, its width and height.
    texel_offset: u32,
    width: u32,
    height: u32,
    wrap_u: u32,
    wrap_v: u32,
    factor: f32,
    cutoff: f32,
}

// The library's `Wrap::texel`: the texel index of coordinate `c` (in texels) on a side of
// `n` texels. Integer arithmetic stands in for f32 `rem_euclid`, which it equals for every
// index below 2^31 in magnitude; beyond, and for NaN, texel 0 (the CPU's answer for NaN).
fn wrap_texel(mode: u32, c: f32, n: u32) -> u32 {
    let i = floor(c);
    if !(abs(i) < 2147483520.0) {
        return 0u;
    }
    let ii = i32(i);
    let ni = i32(n);
    var k: i32;
    if mode == WRAP_REPEAT {
        k = ((ii % ni) + ni) % ni;
    } else if mode == WRAP_MIRRORED {
        let m = ((ii % (2 * ni)) + 2 * ni) % (2 * ni);
        if m < ni { k = m; } else { k = 2 * ni - 1 - m; }
    } else {
        k = clamp(ii, 0, ni - 1);
    }
    return min(u32(k), n - 1u);
}
