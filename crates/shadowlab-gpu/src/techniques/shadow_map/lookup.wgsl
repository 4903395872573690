// gpu:sm / gpu:pcf, stage `lookup`: each covered pixel of the camera pass finds its light
// view (a point light's cube face), projects itself, subtracts the CPU's bias (constant
// plus slope-scaled, in texels of the map at the receiver) and compares with the map:
// `sm` reads the nearest texel, `pcf` takes kernel × kernel hardware 2×2 bilinear
// comparisons (a comparison sampler) around the look-up, the CPU's kernel. Composed after
// shaders/common/{ray_offset, light, map_compare, map_pixels}.wgsl.

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
@group(0) @binding(2) var map: texture_depth_2d_array;
@group(0) @binding(3) var compare: sampler_comparison;
@group(0) @binding(4) var<storage, read> view: array<f32>;
@group(0) @binding(5) var<storage, read_write> out: array<f32>;

fn shadow_term(p: vec3<f32>, n: vec3<f32>) -> f32 {
    var i = 0u;
    if params.light.kind == LIGHT_POINT {
        i = map_cube_face(p - params.light.pos_or_dir);
    }
    let v = views[i];
    let c = v.clip_from_world * vec4<f32>(p, 1.0);
    let inv_w = 1.0 / c.w;
    let u = c.x * inv_w * 0.5 + 0.5;
    let vv = 0.5 - c.y * inv_w * 0.5;
    let depth = -(v.light_from_world * vec4<f32>(p, 1.0)).z;
    let texel = map_view_texel(v.extent, v.near, v.ortho, depth, params.res);
    let l = shadow_ray(params.light, p).dir;
    let d = depth - map_receiver_bias(texel, n, l, params.bias, params.slope_bias);
    if !map_finite(u, vv, d) {
        // No texel to compare with (the CPU's answer for a non-finite look-up).
        return 1.0;
    }
    return map_compare(map, compare, i, params.res, params.kernel, u, vv, d / v.depth_scale);
}
