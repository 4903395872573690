// What every stage of the filtered maps shares: the technique's own parameters (`tech`,
// forty numbers whose meaning each technique's files give) and the storage formats every
// write rounds to, as the library's `Channel` formats and a GPU render target do.

const STORE_F32: u32 = 0u;
const STORE_F16: u32 = 1u;
// 16-bit unsigned normalized, held as its code 0..=65535.
const STORE_UNORM16: u32 = 2u;
// 8-bit unsigned normalized, held as its code 0..=255.
const STORE_U8: u32 = 3u;

const F16_MAX: f32 = 65504.0;

struct TechU {
    v: array<vec4<f32>, 10>,
}

// The technique's parameter `i`.
fn tp(i: u32) -> f32 {
    return tech.v[i / 4u][i % 4u];
}

// `v` rounded to what the format stores: half floats clamped to the largest finite value
// (a render target's clamp), codes rounded half up and saturated (the library's `as`).
fn store(v: vec4<f32>, format: u32) -> vec4<f32> {
    if format == STORE_F16 {
        return quantizeToF16(clamp(v, vec4<f32>(-F16_MAX), vec4<f32>(F16_MAX)));
    }
    if format == STORE_UNORM16 {
        return floor(clamp(v + 0.5, vec4<f32>(0.0), vec4<f32>(65535.0)));
    }
    if format == STORE_U8 {
        return floor(clamp(v + 0.5, vec4<f32>(0.0), vec4<f32>(255.0)));
    }
    return v;
}
