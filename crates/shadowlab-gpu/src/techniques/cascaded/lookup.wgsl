// gpu:cascaded, stage `lookup` (Engel 2006; Dimitrov 2007): each covered pixel the light
// reaches takes the cascade of its view depth (the library's `cascade_of` over the
// slices), reads it with `sm`'s bias in texels of that cascade (nearest texel, or PCF
// with hardware 2×2 comparisons), and across the band at its slice's far end blends
// towards the next cascade's reading, as the CPU does. Every cascade is a layer of one
// depth array texture. Composed after shaders/common/{ray_offset, light,
// map_compare, map_pixels}.wgsl.

struct CascadeU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // 1 for an orthographic view.
    ortho: u32,
    near: f32,
    extent: f32,
    // Stored depths are linear depths divided by this (the view's far plane).
    depth_scale: f32,
    // The view depth slice [d0, d1) the cascade covers.
    d0: f32,
    d1: f32,
    _pad0: u32,
    _pad1: u32,
}

struct Params {
    light: LightU,
    // The camera's eye and unit forward axis (w unused).
    eye: vec4<f32>,
    forward: vec4<f32>,
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    blend: f32,
    cascades: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> cascades: array<CascadeU>;
@group(0) @binding(2) var map: texture_depth_2d_array;
@group(0) @binding(3) var compare: sampler_comparison;
@group(0) @binding(4) var<storage, read> view: array<f32>;
@group(0) @binding(5) var<storage, read_write> out: array<f32>;

// The lit fraction of receiver `p` read from cascade `i` (the CPU's `Cascaded::read`).
fn read_cascade(i: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let c = cascades[i];
    let h = vec4<f32>(p, 1.0);
    let q = c.clip_from_world * h;
    let inv_w = 1.0 / q.w;
    let u = q.x * inv_w * 0.5 + 0.5;
    let v = 0.5 - q.y * inv_w * 0.5;
    let depth = -(c.light_from_world * h).z;
    let texel = map_view_texel(c.extent, c.near, c.ortho, depth, params.res);
    let l = shadow_ray(params.light, p).dir;
    let d = depth - map_receiver_bias(texel, n, l, params.bias, params.slope_bias);
    if !map_finite(u, v, d) {
        return 1.0;
    }
    return map_compare(map, compare, i, params.res, params.kernel, u, v, d / c.depth_scale);
}

fn shadow_term(p: vec3<f32>, n: vec3<f32>) -> f32 {
    let z = dot3(p - params.eye.xyz, params.forward.xyz);
    // The library's `cascade_of`: the last slice whose near bound `z` has reached.
    var i = 0u;
    while i + 1u < params.cascades && z >= cascades[i].d1 {
        i++;
    }
    var lit = read_cascade(i, p, n);
    let c = cascades[i];
    let band = params.blend * (c.d1 - c.d0);
    if i + 1u < params.cascades && band > 0.0 && z > c.d1 - band {
        let t = min((z - (c.d1 - band)) / band, 1.0);
        lit += t * (read_cascade(i + 1u, p, n) - lit);
    }
    return lit;
}
