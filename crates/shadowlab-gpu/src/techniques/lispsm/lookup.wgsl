// gpu:lispsm, stage `lookup` (Wimmer et al. 2004): each covered pixel the light reaches
// projects itself through the warped light view, subtracts `sm`'s bias in texels of the
// warped map at its light-space `y` (the larger of the texel's two sides: along `x` it
// grows as y′, along `y` as y′², y′ = y − the warp's eye) and compares with the map,
// nearest texel or PCF. Composed after shaders/common/{ray_offset, light,
// map_compare, map_pixels}.wgsl.

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
