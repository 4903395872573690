// gpu:lispsm, stage `lookup` (Wimmer et al. 2004): each covered pixel the light reaches
// projects itself through the warped light view, subtracts `sm`'s bias in texels of the
// warped map at its light-space `y` (the larger of the texel's two sides: along `x` it
// grows as y′, along `y` as y′², y′ = y − the warp's eye) and compares with the map,
// nearest texel or PCF. Composed after shaders/common/{ray_offset, light,
// map_compare}.wgsl.

struct Params {
    clip_from_world: mat4x4<f32>,
    // World to light space (the warp's basis): `y` and the linear depth −z.
    light_from_world: mat4x4<f32>,
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    // Stored depths are linear depths divided by this (the view's far plane).
    depth_scale: f32,
    // The warp's eye `y`.
    eye_y: f32,
    // Texel side along `x` per unit of y′, and along `y` per unit of y′².
    texel_x: f32,
    texel_y: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var map: texture_depth_2d_array;
@group(0) @binding(2) var compare: sampler_comparison;
@group(0) @binding(3) var<storage, read> view: array<f32>;
@group(0) @binding(4) var<storage, read_write> out: array<f32>;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;

fn shadow_term(p: vec3<f32>, n: vec3<f32>) -> f32 {
    let h = vec4<f32>(p, 1.0);
    let c = params.clip_from_world * h;
    let inv_w = 1.0 / c.w;
    let u = c.x * inv_w * 0.5 + 0.5;
    let v = 0.5 - c.y * inv_w * 0.5;
    let q = params.light_from_world * h;
    let depth = -q.z;
    let yp = max(q.y - params.eye_y, 1e-12);
    let texel = max(params.texel_x * yp, params.texel_y * yp * yp);
    let l = shadow_ray(params.light, p).dir;
    let d = depth - map_receiver_bias(texel, n, l, params.bias, params.slope_bias);
    if !map_finite(u, v, d) {
        return 1.0;
    }
    let r = d / params.depth_scale;
    return map_compare(map, compare, 0u, params.res, params.kernel, u, v, r);
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
