// gpu:subpixel, shared by every stage: one bind group for the whole frame (every stage
// reads what it needs of it), the frame's uniform and the light views. Composed after
// shaders/common/{ray_offset, light, alpha_mask, triangles}.wgsl.

struct FrameU {
    light: LightU,
    // The camera's rays as affine functions of the image position (the library's
    // `RayPlane`): origins o0 + ox·x + oy·y, directions d0 + dx·x + dy·y.
    o0: vec3<f32>,
    parallel: u32,
    ox: vec3<f32>,
    width: u32,
    oy: vec3<f32>,
    height: u32,
    d0: vec3<f32>,
    // Side of the depth and silhouette mask maps.
    res: u32,
    dx: vec3<f32>,
    views: u32,
    dy: vec3<f32>,
    // Sub-samples a pixel.
    samples: u32,
    // The camera's clip_from_world (the screen map of the crease test).
    screen: mat4x4<f32>,
    // The centre sample's index.
    centre: u32,
    bias: f32,
    slope_bias: f32,
    // 1 when some material is alpha-masked.
    masks: u32,
    edges: u32,
    triangles: u32,
    // Pixels, and threads per dispatch row.
    pixels: u32,
    row: u32,
    // Directional light: the unit vector towards it; else its position (`Toward`).
    toward: vec3<f32>,
    toward_is_dir: u32,
}

struct ViewS {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    clip_from_light: mat4x4<f32>,
    ortho: u32,
    near: f32,
    extent: f32,
    // The depth map holds linear depths over this.
    depth_scale: f32,
}

struct FacetU {
    p: vec3<f32>,
    k: u32,
    n: vec3<f32>,
    view: u32,
    x: f32,
    y: f32,
    own: u32,
    // 0 once the pixel–texel pairs sent the pixel back to the depth-map test.
    alive: u32,
    an: f32,
    bn: f32,
    cn: f32,
    beta: f32,
    valid: vec4<u32>,
    depth_max: f32,
    poly_n: u32,
    // The visibility evaluation's items over this facet (`count_items`).
    items: u32,
    _pad1: u32,
    poly: array<vec4<f32>, 12>,
}

@group(0) @binding(0) var<uniform> fr: FrameU;
@group(0) @binding(1) var<storage, read_write> lviews: array<ViewS>;
@group(0) @binding(2) var<storage, read_write> view: array<f32>;
@group(0) @binding(3) var map: texture_depth_2d_array;
@group(0) @binding(4) var<storage, read_write> tris: array<f32>;
@group(0) @binding(5) var<storage, read_write> tri_material: array<u32>;
@group(0) @binding(6) var<storage, read_write> materials: array<MaterialU>;
@group(0) @binding(7) var<storage, read_write> uvs: array<f32>;
@group(0) @binding(8) var<storage, read_write> texels: array<u32>;
// Per edge, its ends (six floats); and 1 when it has two faces, then their opposite
// vertices (seven floats). Two bindings, so a large scene's edges fit the adapter's
// largest binding twice as far.
@group(0) @binding(9) var<storage, read_write> edge_ends: array<f32>;
@group(0) @binding(24) var<storage, read_write> edge_faces: array<f32>;
@group(0) @binding(10) var<storage, read_write> lut: array<vec4<u32>>;
@group(0) @binding(11) var<storage, read_write> lut_samples: array<vec2<f32>>;
// Per texel of every view: the nearest silhouette edge's depth bits, inverted (0: none).
@group(0) @binding(12) var<storage, read_write> nearest: array<atomic<u32>>;
// Per texel: 0 no silhouette, 1 a visible silhouette, 2 a hidden one.
@group(0) @binding(13) var<storage, read_write> sil_mask: array<u32>;
// Per view, the (res + 1)² summed-area table of the visible silhouette texels.
@group(0) @binding(14) var<storage, read_write> sat: array<u32>;
@group(0) @binding(15) var<storage, read_write> out: array<f32>;
@group(0) @binding(16) var<storage, read_write> facets: array<FacetU>;
// [facets, slots, pairs, the pairs pass's mode, blocks of large triangles, blocks
// listed, evaluation items, items listed].
@group(0) @binding(17) var<storage, read_write> counters: array<atomic<u32>>;
// Per texel: the farthest facet depth bits over it (0: no facet).
@group(0) @binding(18) var<storage, read_write> max_depth: array<atomic<u32>>;
// Per texel: its slot + 1 (0: no facet).
@group(0) @binding(19) var<storage, read_write> slot: array<u32>;
// Per slot: triangles counted, then filled.
@group(0) @binding(20) var<storage, read_write> slot_fill: array<atomic<u32>>;
// Per slot: the first of its triangles in `pairs`.
@group(0) @binding(21) var<storage, read_write> slot_start: array<u32>;
@group(0) @binding(22) var<storage, read_write> pairs: array<u32>;
// Per pixel, the camera pass's depth.
@group(0) @binding(23) var<storage, read_write> cam_depth: array<f32>;
// The blocks of rows of the large triangles: (triangle-view pair, block).
@group(0) @binding(25) var<storage, read_write> big: array<vec2<u32>>;
// The visibility evaluation's items: (facet, texel slot + 1, chunk, 0).
@group(0) @binding(26) var<storage, read_write> items: array<vec4<u32>>;
// Per facet: its occluded samples, then the samples a blocker made invalid (four words
// each, ORed by the evaluation's items; zero at the start of the frame).
@group(0) @binding(27) var<storage, read_write> masks: array<atomic<u32>>;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
const MIN_COSINE: f32 = 1e-6;
const MAX_SLOPE: f32 = 10.0;
const BIG: f32 = 3.0e38;

fn finite(x: f32) -> bool {
    return abs(x) < BIG;
}

fn thread_index(gid: vec3<u32>) -> u32 {
    return gid.y * fr.row + gid.x;
}

fn sample_pos(k: u32) -> vec3<f32> {
    let b = k * VIEW_STRIDE;
    return vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
}

fn sample_normal(k: u32) -> vec3<f32> {
    let b = k * VIEW_STRIDE;
    return vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
}

fn sample_triangle(k: u32) -> u32 {
    return bitcast<u32>(view[k * VIEW_STRIDE + 9u]);
}

// The library's `Toward::at`.
fn toward_at(p: vec3<f32>) -> vec3<f32> {
    if fr.toward_is_dir == 1u {
        return fr.toward;
    }
    return fr.toward - p;
}

// The library's `cube_face`.
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

fn view_of(p: vec3<f32>) -> u32 {
    if fr.light.kind == LIGHT_POINT {
        return cube_face(p - fr.light.pos_or_dir);
    }
    return 0u;
}

fn texel_size(v: ViewS, depth: f32) -> f32 {
    if v.ortho == 1u {
        return v.extent / f32(fr.res);
    }
    return v.extent * max(depth, v.near) / f32(fr.res);
}

fn light_depth(v: ViewS, p: vec3<f32>) -> f32 {
    return -(v.light_from_world * vec4<f32>(p, 1.0)).z;
}

// The map's linear depth at texel (x, y) of view `vi`.
fn map_depth(vi: u32, x: u32, y: u32) -> f32 {
    return textureLoad(map, vec2<u32>(x, y), vi, 0) * lviews[vi].depth_scale;
}

// The library's `FrameState::depth_lookup`: the biased nearest-texel test of pixel k.
fn depth_lookup(k: u32, vi: u32, u: f32, v: f32, depth: f32) -> f32 {
    let lv = lviews[vi];
    let p = sample_pos(k);
    let l = shadow_ray(fr.light, p).dir;
    let c = clamp(dot3(sample_normal(k), l), MIN_COSINE, 1.0);
    let t = min(sqrt(max(1.0 - c * c, 0.0)) / c, MAX_SLOPE);
    let d = depth - texel_size(lv, depth) * (fr.bias + fr.slope_bias * t);
    let nf = f32(fr.res);
    let x = u32(clamp(floor(u * nf), 0.0, nf - 1.0));
    let y = u32(clamp(floor(v * nf), 0.0, nf - 1.0));
    return select(1.0, 0.0, d > map_depth(vi, x, y));
}

// The library's `FrameState::depth_test` of pixel k in view vi.
fn depth_test(k: u32, vi: u32) -> f32 {
    let p = sample_pos(k);
    let lv = lviews[vi];
    let c = lv.clip_from_world * vec4<f32>(p, 1.0);
    let u = c.x / c.w * 0.5 + 0.5;
    let v = 0.5 - c.y / c.w * 0.5;
    return depth_lookup(k, vi, u, v, light_depth(lv, p));
}

fn write_out(k: u32, s: f32) {
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}

// The library's `MaskMap::count`: visible silhouette texels in [x0, x1] × [y0, y1].
fn sat_count(vi: u32, x0: u32, y0: u32, x1: u32, y1: u32) -> u32 {
    let w = fr.res + 1u;
    let base = vi * w * w;
    return sat[base + (y1 + 1u) * w + x1 + 1u] + sat[base + y0 * w + x0] - sat[base + y0 * w + x1 + 1u] - sat[base + (y1 + 1u) * w + x0];
}

// Facet `fi`'s projected polygon.
fn facet_poly(fi: u32) -> Poly {
    var p: Poly;
    p.n = facets[fi].poly_n;
    for (var i = 0u; i < p.n; i++) {
        p.v[i] = facets[fi].poly[i].xyz;
    }
    return p;
}
