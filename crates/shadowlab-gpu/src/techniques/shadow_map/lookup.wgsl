// gpu:sm / gpu:pcf, stage `lookup`: each covered pixel of the camera pass finds its light
// view (a point light's cube face), projects itself, subtracts the CPU's bias (constant
// plus slope-scaled, in texels of the map at the receiver) and compares with the map:
// `sm` reads the nearest texel, `pcf` takes kernel × kernel hardware 2×2 bilinear
// comparisons (a comparison sampler) around the look-up, the CPU's kernel. Composed after
// shaders/common/{ray_offset, light}.wgsl.

struct ViewU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // 1 for an orthographic view.
    ortho: u32,
    near: f32,
    extent: f32,
    depth_scale: f32,
}

struct Params {
    light: LightU,
    count: u32,
    row: u32,
    // Map side in texels.
    res: u32,
    // PCF kernel side; 0 for the unfiltered map.
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> views: array<ViewU>;
@group(0) @binding(2) var<storage, read> view: array<f32>;
@group(0) @binding(3) var map: texture_depth_2d_array;
@group(0) @binding(4) var compare: sampler_comparison;
@group(0) @binding(5) var<storage, read_write> out: array<f32>;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
// The library's MIN_COSINE and MAX_SLOPE (techniques/shadow_map.rs).
const MIN_COSINE: f32 = 1e-6;
const MAX_SLOPE: f32 = 10.0;

// The library's `cube_face`: the major axis of the direction from the light.
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x >= 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

// The library's `receiver_bias`, in world units.
fn receiver_bias(texel: f32, n: vec3<f32>, l: vec3<f32>, bias: f32, slope: f32) -> f32 {
    let c = clamp(dot3(n, l), MIN_COSINE, 1.0);
    let t = min(sqrt(max(1.0 - c * c, 0.0)) / c, MAX_SLOPE);
    return texel * (bias + slope * t);
}

fn shadow_term(p: vec3<f32>, n: vec3<f32>) -> f32 {
    var i = 0u;
    if params.light.kind == LIGHT_POINT {
        i = cube_face(p - params.light.pos_or_dir);
    }
    let v = views[i];
    let c = v.clip_from_world * vec4<f32>(p, 1.0);
    let inv_w = 1.0 / c.w;
    let u = c.x * inv_w * 0.5 + 0.5;
    let vv = 0.5 - c.y * inv_w * 0.5;
    let depth = -(v.light_from_world * vec4<f32>(p, 1.0)).z;
    let nf = f32(params.res);
    var texel = v.extent / nf;
    if v.ortho == 0u {
        texel = v.extent * max(depth, v.near) / nf;
    }
    let l = shadow_ray(params.light, p).dir;
    let d = depth - receiver_bias(texel, n, l, params.bias, params.slope_bias);
    let big = 3.0e38;
    if !(abs(u) < big && abs(vv) < big && abs(d) < big) {
        // No texel to compare with (the CPU's answer for a non-finite look-up).
        return 1.0;
    }
    let r = d / v.depth_scale;
    if params.kernel == 0u {
        let last = i32(params.res) - 1;
        let x = clamp(i32(clamp(floor(u * nf), -1.0, nf)), 0, last);
        let y = clamp(i32(clamp(floor(vv * nf), -1.0, nf)), 0, last);
        let stored = textureLoad(map, vec2<i32>(x, y), i32(i), 0);
        return select(1.0, 0.0, r > stored);
    }
    // The CPU's kernel: taps at whole-texel offsets from the look-up, each a bilinear 2×2.
    let k = i32(params.kernel);
    let half = (k - 1) / 2;
    var sum = 0.0;
    for (var dy = -half; dy < k - half; dy++) {
        for (var dx = -half; dx < k - half; dx++) {
            let at = vec2<f32>(u + f32(dx) / nf, vv + f32(dy) / nf);
            sum += textureSampleCompareLevel(map, compare, at, i32(i), r);
        }
    }
    return sum / f32(k * k);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let tri = bitcast<u32>(view[b + 9u]);
    var s = 1.0;
    if tri != NO_TRIANGLE {
        let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
        let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
        if illuminates(params.light, p, n) {
            s = shadow_term(p, n);
        } else {
            s = 0.0;
        }
    }
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}
