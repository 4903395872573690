// gpu:vsm / evsm / msm / csm, stage `lookup` (Annen et al. 2007, Section 4.1: "tri-linear
// and anisotropic filtering" of the pre-filtered maps): each covered pixel the light
// reaches finds its light view (a point light's cube face), projects itself, takes its
// footprint in the map from the camera pass's screen-space derivatives as the library's
// `light_footprint` does (widened, for the soft variants, to the penumbra its blocker
// search found), and reads the map there as the library's look-up does: the level of
// detail and the anisotropic probes along the footprint's major axis placed here, each
// probe a hardware tri-linear sample of the mip chain. The technique's `shade(d, view)` reads the filtered values of its
// channel groups through `fetch` and returns the lit fraction for the normalized receiver
// depth `d`. Composed after shaders/common/{ray_offset, light}.wgsl, filtering/filtered.wgsl
// and the technique's reconstruction.

struct Params {
    light: LightU,
    count: u32,
    row: u32,
    // Channel groups (texture layers) a view has.
    groups: u32,
    // FILTER_*: the look-up filter.
    filtering: u32,
    // 1 when `soft` holds each pixel's penumbra footprint.
    soft: u32,
    // Most probes of an anisotropic look-up.
    max_aniso: u32,
    // The coarsest level of the chain, and the map side.
    top: f32,
    side: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> tech: TechU;
@group(0) @binding(2) var<storage, read> views: array<ViewU>;
@group(0) @binding(9) var<storage, read> ranges: array<RangeU>;
@group(0) @binding(3) var<storage, read> view: array<f32>;
@group(0) @binding(4) var<storage, read> derivs: array<f32>;
@group(0) @binding(5) var<storage, read> soft: array<f32>;
@group(0) @binding(6) var maps: texture_2d_array<f32>;
@group(0) @binding(7) var filtered: sampler;
@group(0) @binding(8) var<storage, read_write> out: array<f32>;

const FILTER_BILINEAR: u32 = 0u;
const FILTER_TRILINEAR: u32 = 1u;
const FILTER_ANISOTROPIC: u32 = 2u;
const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;

// The look-up of the pixel being shaded: map coordinates, level of detail, probes and the
// axis they are spread along, first layer.
var<private> at_uv: vec2<f32>;
var<private> at_lambda: f32;
var<private> at_probes: u32;
var<private> at_axis: vec2<f32>;
var<private> at_layer: u32;

// The filtered values of channel group `g` at the pixel's look-up: the mean of its
// probes, each a hardware tri-linear sample at the look-up's level of detail.
fn fetch(g: u32) -> vec4<f32> {
    let layer = i32(at_layer + g);
    if at_probes <= 1u {
        return textureSampleLevel(maps, filtered, at_uv, layer, at_lambda);
    }
    let w = 1.0 / f32(at_probes);
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < at_probes; i++) {
        let s = (f32(i) + 0.5) * w - 0.5;
        sum += w * textureSampleLevel(maps, filtered, at_uv + at_axis * s, layer, at_lambda);
    }
    return sum;
}

// The library's `level_of_detail` of a footprint `(dx, dy)`, as `EXT_texture_filter_anisotropic`
// describes it: λ of the longer axis for tri-linear look-ups; for anisotropic ones
// min(⌈Pmax/Pmin⌉, max-aniso) probes along the longer axis at λ = log2(Pmax / probes).
// λ is clamped to the chain (0 for bilinear look-ups, which never leave level 0).
fn level_of_detail(dx: vec2<f32>, dy: vec2<f32>) {
    let px = length(dx) * params.side;
    let py = length(dy) * params.side;
    var pmax = px;
    var pmin = py;
    at_axis = dx;
    if py > px {
        pmax = py;
        pmin = px;
        at_axis = dy;
    }
    at_probes = 1u;
    var lambda = 0.0;
    if params.filtering == FILTER_TRILINEAR {
        lambda = log2(pmax);
    } else if params.filtering == FILTER_ANISOTROPIC {
        if pmax > 1.0 {
            if pmin > 0.0 {
                at_probes = u32(clamp(ceil(pmax / pmin), 1.0, f32(params.max_aniso)));
            } else {
                at_probes = params.max_aniso;
            }
        }
        lambda = log2(pmax / f32(at_probes));
    }
    if !(lambda >= 0.0) {
        // Magnified, or a footprint of nothing (NaN): level 0.
        lambda = 0.0;
    }
    at_lambda = min(lambda, params.top);
}

fn shadow_term(k: u32, p: vec3<f32>) -> f32 {
    let i = view_of(params.light, p);
    let v = views[i];
    let r = ranges[i];
    var uv = project(v, p);
    if !(abs(uv.x) < BIG && abs(uv.y) < BIG) {
        uv = vec2<f32>(0.0);
    }
    let fp = pixel_footprint(v, k, p);
    var dx = fp.xy;
    var dy = fp.zw;
    if params.soft == 1u {
        let w = soft[k];
        if w < 0.0 {
            // No blocker in the light's cone: fully lit.
            return 1.0;
        }
        // The library's `wider`: the footprint with the longer axis.
        if w >= max(length(dx), length(dy)) {
            dx = vec2<f32>(w, 0.0);
            dy = vec2<f32>(0.0, w);
        }
    }
    at_uv = uv;
    level_of_detail(dx, dy);
    at_layer = i * params.groups;
    let depth = light_depth(v, p);
    var d = r.span;
    if abs(depth) < BIG {
        d = clamp((depth - r.near) / (r.far - r.near), 0.0, 1.0) * r.span;
    }
    return shade(d, i);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    _ = tech.v[0];
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
            s = shadow_term(k, p);
        } else {
            s = 0.0;
        }
    }
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}
