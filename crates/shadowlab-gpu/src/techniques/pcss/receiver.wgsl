// gpu:pcss, shared by `blocker_search` and `filter`: the parameters, the light views, the
// map and its min-depth pyramid, and a receiver as the library's `pcss` sees it (its
// light view, its projection, its texel size, its normal and light direction). Composed
// after shaders/common/{ray_offset, light}.wgsl.

struct ViewU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // 1 for an orthographic view.
    ortho: u32,
    near: f32,
    extent: f32,
    // The map holds linear depths divided by this.
    depth_scale: f32,
}

struct Params {
    light: LightU,
    count: u32,
    row: u32,
    // Map side in texels.
    res: u32,
    // Sides of the blocker search's and the filter's square tap grids.
    search_side: u32,
    filter_side: u32,
    bias: f32,
    slope_bias: f32,
    // The light's width (a distant light: its angular width); 0 under a punctual light.
    width: f32,
    // Levels of the min-depth pyramid, level 0 (the map) included.
    levels: u32,
    // Floats of one layer's pyramid (levels 1 and on).
    layer_stride: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> views: array<ViewU>;
@group(0) @binding(2) var<storage, read> view: array<f32>;
@group(0) @binding(3) var map: texture_depth_2d_array;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
// The library's MIN_COSINE and MAX_SLOPE (techniques/shadow_map.rs).
const MIN_COSINE: f32 = 1e-6;
const MAX_SLOPE: f32 = 10.0;
// The library's MAX_SEARCH_FRACTION (techniques/filtering/blocker_search.rs).
const MAX_SEARCH_FRACTION: f32 = 0.125;

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

// The library's `LightView::texel_size` for the map's side.
fn texel_size(v: ViewU, depth: f32) -> f32 {
    let nf = f32(params.res);
    if v.ortho == 1u {
        return v.extent / nf;
    }
    return v.extent * max(depth, v.near) / nf;
}

struct Receiver {
    // The shadow term when no look-up is needed (1: no surface or no texel to compare
    // with, 0: the light cannot reach the surface); -1 when the map decides.
    term: f32,
    face: u32,
    // Map coordinates in [0, 1] and the linear light depth.
    u: f32,
    v: f32,
    depth: f32,
    // World size of a texel at the receiver.
    texel: f32,
    n: vec3<f32>,
    l: vec3<f32>,
}

// Pixel `k` of the camera pass as the library's `pcss` reads it.
fn receiver(k: u32) -> Receiver {
    var r: Receiver;
    r.term = -1.0;
    let b = k * VIEW_STRIDE;
    let tri = bitcast<u32>(view[b + 9u]);
    if tri == NO_TRIANGLE {
        r.term = 1.0;
        return r;
    }
    let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
    r.n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
    if !illuminates(params.light, p, r.n) {
        r.term = 0.0;
        return r;
    }
    r.face = 0u;
    if params.light.kind == LIGHT_POINT {
        r.face = cube_face(p - params.light.pos_or_dir);
    }
    let v = views[r.face];
    let c = v.clip_from_world * vec4<f32>(p, 1.0);
    let inv_w = 1.0 / c.w;
    r.u = c.x * inv_w * 0.5 + 0.5;
    r.v = 0.5 - c.y * inv_w * 0.5;
    r.depth = -(v.light_from_world * vec4<f32>(p, 1.0)).z;
    let big = 3.0e38;
    if !(abs(r.u) < big && abs(r.v) < big && abs(r.depth) < big) {
        r.term = 1.0;
        return r;
    }
    r.texel = texel_size(v, r.depth);
    r.l = shadow_ray(params.light, p).dir;
    return r;
}

// The library's `grid_offset`: the i-th of `side` tap offsets across [-1, 1].
fn grid_offset(i: u32, side: u32) -> f32 {
    return (2.0 * f32(i) + 1.0) / f32(side) - 1.0;
}
