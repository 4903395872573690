// What the map look-ups (gpu:sm, gpu:pcf, gpu:psm, gpu:lispsm, gpu:cascaded) share: the
// library's `receiver_bias` and `cube_face`, its nearest-texel test and PCF's kernel of
// hardware 2×2 comparisons, on one layer of a depth array texture holding depths in the
// stored units (the caller divides the receiver's depth likewise). Composed after
// ray_offset.wgsl (dot3).

// The library's MIN_COSINE and MAX_SLOPE (techniques/shadow_map.rs).
const MAP_MIN_COSINE: f32 = 1e-6;
const MAP_MAX_SLOPE: f32 = 10.0;

// The library's `receiver_bias`, in world (or post-space) units.
fn map_receiver_bias(texel: f32, n: vec3<f32>, l: vec3<f32>, bias: f32, slope: f32) -> f32 {
    let c = clamp(dot3(n, l), MAP_MIN_COSINE, 1.0);
    let t = min(sqrt(max(1.0 - c * c, 0.0)) / c, MAP_MAX_SLOPE);
    return texel * (bias + slope * t);
}

// A light view's texel size at light depth `depth`: its extent over the map side, times
// the depth (no nearer than its near plane) for a perspective view.
fn map_view_texel(extent: f32, near: f32, ortho: u32, depth: f32, res: u32) -> f32 {
    if ortho == 0u {
        return extent * max(depth, near) / f32(res);
    }
    return extent / f32(res);
}

// The library's `cube_face`: the major axis of `d`.
fn map_cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x >= 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

// glam's `normalize_or_zero`.
fn map_normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len2 = dot3(v, v);
    if len2 > 0.0 && len2 < 3.0e38 {
        return v / sqrt(len2);
    }
    return vec3<f32>(0.0);
}

// True when a look-up's coordinates and depth are finite (the CPU's answer otherwise: lit).
fn map_finite(u: f32, v: f32, d: f32) -> bool {
    let big = 3.0e38;
    return abs(u) < big && abs(v) < big && abs(d) < big;
}

// The library's `lookup_nearest`: 1 when `r` is not behind the texel `(u, v)` falls in.
fn map_nearest(map: texture_depth_2d_array, layer: u32, res: u32, u: f32, v: f32, r: f32) -> f32 {
    let nf = f32(res);
    let last = i32(res) - 1;
    let x = clamp(i32(clamp(floor(u * nf), -1.0, nf)), 0, last);
    let y = clamp(i32(clamp(floor(v * nf), -1.0, nf)), 0, last);
    let stored = textureLoad(map, vec2<i32>(x, y), i32(layer), 0);
    return select(1.0, 0.0, r > stored);
}

// The library's `lookup_pcf`: `kernel × kernel` taps at whole-texel offsets from the
// look-up, each a hardware bilinear 2×2 comparison through a comparison sampler.
fn map_pcf(
    map: texture_depth_2d_array,
    cmp: sampler_comparison,
    layer: u32,
    res: u32,
    kernel: u32,
    u: f32,
    v: f32,
    r: f32,
) -> f32 {
    let nf = f32(res);
    let k = i32(kernel);
    let half = (k - 1) / 2;
    var sum = 0.0;
    for (var dy = -half; dy < k - half; dy++) {
        for (var dx = -half; dx < k - half; dx++) {
            let at = vec2<f32>(u + f32(dx) / nf, v + f32(dy) / nf);
            sum += textureSampleCompareLevel(map, cmp, at, i32(layer), r);
        }
    }
    return sum / f32(k * k);
}

// The nearest test for `kernel` 0, else PCF.
fn map_compare(
    map: texture_depth_2d_array,
    cmp: sampler_comparison,
    layer: u32,
    res: u32,
    kernel: u32,
    u: f32,
    v: f32,
    r: f32,
) -> f32 {
    if kernel == 0u {
        return map_nearest(map, layer, res, u, v, r);
    }
    return map_pcf(map, cmp, layer, res, kernel, u, v, r);
}
