// gpu:vsm-soft / evsm-soft / msm-soft / csm-soft, stage `blocker_search` (Fernando 2005, as
// the library's `blocker_search` runs it for the soft filtered maps): for each pixel the
// light reaches, the region of the map that can hold its blockers (the light's cone cut
// at the nearest depth the min pyramid bounds there, twice), the mean depth of the texels
// nearer than the biased receiver on an 8 × 8 grid over it, and the penumbra's width by
// similar triangles: the side of the pixel's filter footprint in map coordinates (−1 when
// no blocker is found: the pixel is lit; 0 where the light does not reach). Composed after
// shaders/common/{ray_offset, light, order_key}.wgsl and filtering/{views, pyramid}.wgsl.

@group(0) @binding(0) var<uniform> fit: FitU;
@group(0) @binding(1) var<storage, read> views: array<ViewU>;
@group(0) @binding(3) var<storage, read> pyramid: array<f32>;
@group(0) @binding(4) var<storage, read> levels: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read> view: array<f32>;
@group(0) @binding(7) var<storage, read> derivs: array<f32>;
@group(0) @binding(9) var<storage, read_write> widths: array<f32>;

const NO_TRIANGLE: u32 = 0xffffffffu;
// The library's SOFT_BLOCKER_SAMPLES grid side, MAX_SEARCH_FRACTION, MIN_COSINE, MAX_SLOPE.
const GRID: u32 = 8u;
const MAX_SEARCH_FRACTION: f32 = 0.125;
const MIN_COSINE: f32 = 1e-6;
const MAX_SLOPE: f32 = 10.0;
const MIN_POSITIVE: f32 = 1.17549435e-38;

fn clamp_radius(r: f32, max_r: f32) -> f32 {
    if r != r {
        return max_r;
    }
    return clamp(r, 0.5, max_r);
}

fn search_width(ortho: bool, receiver: f32, z: f32) -> f32 {
    let gap = max(receiver - z, 0.0);
    if ortho {
        return gap * fit.light_width;
    }
    return fit.light_width * gap / max(receiver, MIN_POSITIVE);
}

fn penumbra_width(ortho: bool, receiver: f32, blocker: f32) -> f32 {
    let gap = max(receiver - blocker, 0.0);
    if ortho {
        return gap * fit.light_width;
    }
    return gap * fit.light_width / max(blocker, MIN_POSITIVE);
}

fn texel_floor(v: f32) -> u32 {
    return u32(clamp(floor(v), 0.0, f32(fit.side) - 1.0));
}

fn width(k: u32) -> f32 {
    let b = k * 10u;
    let tri = bitcast<u32>(view[b + 9u]);
    if tri == NO_TRIANGLE {
        return 0.0;
    }
    let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
    let normal = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
    if !illuminates(fit.light, p, normal) {
        return 0.0;
    }
    let i = view_of(fit.light, p);
    let lv = views[i];
    let ortho = lv.ortho == 1u;
    let uv = project(lv, p);
    let s_depth = light_depth(lv, p);
    let res = f32(fit.side);
    // The library's `receiver_bias` at the default constant and slope terms.
    let l = shadow_ray(fit.light, p).dir;
    let c = clamp(dot3(normal, l), MIN_COSINE, 1.0);
    let t = min(sqrt(max(1.0 - c * c, 0.0)) / c, MAX_SLOPE);
    let depth = s_depth - texel_size(lv, res, s_depth) * (fit.bias + fit.slope_bias * t);
    let max_radius = MAX_SEARCH_FRACTION * res;
    let fx = uv.x * res;
    let fy = uv.y * res;
    var search = max_radius;
    var block: vec4<u32>;
    for (var round = 0; round < 2; round++) {
        let nearest = min_in(
            i,
            texel_floor(fx - search),
            texel_floor(fx + search),
            texel_floor(fy - search),
            texel_floor(fy + search),
            &block,
        );
        let z = min(nearest, s_depth);
        let cone = 0.5 * search_width(ortho, s_depth, z);
        search = clamp_radius(cone / texel_size(lv, res, z), search);
    }
    var sum = 0.0;
    var count = 0u;
    for (var j = 0u; j < GRID; j++) {
        for (var g = 0u; g < GRID; g++) {
            let x = texel_floor(fx + ((2.0 * f32(g) + 1.0) / f32(GRID) - 1.0) * search);
            let y = texel_floor(fy + ((2.0 * f32(j) + 1.0) / f32(GRID) - 1.0) * search);
            let d = pyramid_at(i, 0u, x, y);
            if d < depth {
                sum += d;
                count++;
            }
        }
    }
    if count == 0u {
        return -1.0;
    }
    let blocker = sum / f32(count);
    let w = penumbra_width(ortho, s_depth, blocker);
    let radius = clamp_radius(0.5 * w / texel_size(lv, res, s_depth), max_radius);
    return 2.0 * radius / res;
}

@compute @workgroup_size(64)
fn search(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * fit.row + gid.x;
    if k < fit.count {
        widths[k] = width(k);
    }
}
