// gpu:vsm / evsm / msm / csm, stage `fit`: the depth range each map is normalized over,
// fitted to the receivers that may be shadowed, as the library's `ReceiverDepths` and
// `DepthRange::fitted` fit it (Annen et al. 2007, Section 5: a "tightly fitted" light
// frustum). Entries, in order: `base` copies each map's depths into level 0 of its min
// pyramid and reduces the map's finite depth range; `reduce` makes one pyramid level;
// `receivers` visits each pixel the light reaches, bounds the nearest texel under its
// filter support with the pyramid and tests it against the receiver's own tangent plane;
// `ranges` turns each view's sums into its range. Minima and maxima go through integer
// atomics on order-keeping float bits and counts through integer sums, so the result does
// not depend on the threads' order. Composed after shaders/common/{ray_offset, light,
// order_key}.wgsl and filtering/{views, pyramid}.wgsl.

@group(0) @binding(0) var<uniform> fit: FitU;
@group(0) @binding(1) var<storage, read> views: array<ViewU>;
@group(0) @binding(2) var depth_map: texture_2d_array<u32>;
@group(0) @binding(3) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(4) var<storage, read> levels: array<vec4<u32>>;
// Per view: nearest and farthest receiver (keys), nearest and farthest shadowable one
// (keys), receivers, shadowable receivers, the map's nearest and farthest finite depth
// (keys).
@group(0) @binding(5) var<storage, read_write> acc: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read> view: array<f32>;
@group(0) @binding(7) var<storage, read> derivs: array<f32>;
@group(0) @binding(8) var<storage, read_write> ranges: array<RangeU>;

const ACC: u32 = 8u;
const NO_TRIANGLE: u32 = 0xffffffffu;
const EXPONENT_MASK: u32 = 0x7f800000u;
const FILTER_ANISOTROPIC: u32 = 2u;
const FILTER_TRILINEAR: u32 = 1u;
// The library's MAX_RECEIVER_SLOPE, MAX_SUPPORT_LEVEL, MIN_RANGE_RELATIVE and
// FITTED_RANGE_SLACK.
const MAX_RECEIVER_SLOPE: f32 = 8.0;
const MAX_SUPPORT_LEVEL: f32 = 30.0;
const MIN_RANGE_RELATIVE: f32 = 1e-3;
const FITTED_RANGE_SLACK: f32 = 0.005;

var<workgroup> group_min: atomic<u32>;
var<workgroup> group_max: atomic<u32>;

@compute @workgroup_size(8, 8)
fn base(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&group_min, order_key(FLT_MAX));
        atomicStore(&group_max, order_key(-FLT_MAX));
    }
    workgroupBarrier();
    let n = fit.side;
    let v = gid.z;
    if gid.x < n && gid.y < n {
        let bits = textureLoad(depth_map, vec2<i32>(gid.xy), i32(v), 0).x;
        let d = bitcast<f32>(bits);
        pyramid[v * fit.stride + gid.y * n + gid.x] = d;
        if (bits & EXPONENT_MASK) != EXPONENT_MASK {
            atomicMin(&group_min, order_key(d));
            atomicMax(&group_max, order_key(d));
        }
    }
    workgroupBarrier();
    if li == 0u {
        atomicMin(&acc[v * ACC + 6u], atomicLoad(&group_min));
        atomicMax(&acc[v * ACC + 7u], atomicLoad(&group_max));
    }
}

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) gid: vec3<u32>) {
    let src = levels[fit.level - 1u];
    let dst = levels[fit.level];
    if gid.x >= dst.x || gid.y >= dst.y {
        return;
    }
    let v = gid.z;
    let x0 = 2u * gid.x;
    let y0 = 2u * gid.y;
    // An odd last row or column pairs with itself.
    let x1 = min(x0 + 1u, src.x - 1u);
    let y1 = min(y0 + 1u, src.y - 1u);
    let l = fit.level - 1u;
    let m = min(
        min(pyramid_at(v, l, x0, y0), pyramid_at(v, l, x1, y0)),
        min(pyramid_at(v, l, x0, y1), pyramid_at(v, l, x1, y1)),
    );
    pyramid[v * fit.stride + dst.z + gid.y * dst.x + gid.x] = min(m, FLT_MAX);
}

// The library's `level_of_detail` λ (unclamped) and whether the look-up is anisotropic.
fn support_lambda(dx: vec2<f32>, dy: vec2<f32>) -> f32 {
    let n = f32(fit.side);
    let px = length(dx) * n;
    let py = length(dy) * n;
    let pmax = max(px, py);
    let pmin = min(px, py);
    if fit.filtering == FILTER_TRILINEAR {
        return log2(pmax);
    }
    if fit.filtering == FILTER_ANISOTROPIC {
        var probes = 1u;
        if pmax > 1.0 {
            if pmin > 0.0 {
                probes = u32(clamp(ceil(pmax / pmin), 1.0, f32(fit.max_aniso)));
            } else {
                probes = fit.max_aniso;
            }
        }
        return log2(pmax / f32(probes));
    }
    return -FLT_MAX;
}

fn visit(k: u32) {
    let b = k * 10u;
    let tri = bitcast<u32>(view[b + 9u]);
    if tri == NO_TRIANGLE {
        return;
    }
    let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
    let normal = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
    if !illuminates(fit.light, p, normal) {
        return;
    }
    let i = view_of(fit.light, p);
    let lv = views[i];
    let uv = project(lv, p);
    let depth = light_depth(lv, p);
    if !(abs(uv.x) < BIG && abs(uv.y) < BIG && abs(depth) < BIG) {
        return;
    }
    let fp = pixel_footprint(lv, k, p);
    let n = f32(fit.side);
    let lambda = support_lambda(fp.xy, fp.zw);
    var level = 0u;
    if abs(lambda) < BIG {
        level = u32(ceil(clamp(lambda, 0.0, MAX_SUPPORT_LEVEL)));
    }
    let spill = f32(2u << level) + f32(fit.blur_pad);
    var ex = 0.0;
    var ey = 0.0;
    if fit.filtering == FILTER_ANISOTROPIC {
        ex = 0.5 * (abs(fp.x) + abs(fp.z)) * n;
        ey = 0.5 * (abs(fp.y) + abs(fp.w)) * n;
    }
    let hx = ex + spill;
    let hy = ey + spill;
    let cx = uv.x * n;
    let cy = uv.y * n;
    let last = n - 1.0;
    var block: vec4<u32>;
    let zmin = min_in(
        i,
        u32(clamp(floor(cx - hx), 0.0, last)),
        u32(clamp(floor(cx + hx), 0.0, last)),
        u32(clamp(floor(cy - hy), 0.0, last)),
        u32(clamp(floor(cy + hy), 0.0, last)),
        &block,
    );
    // The receiver's own depth change across the block read, plus one texel.
    let bx = max(max(cx - f32(block.x), f32(block.y) - cx), 0.0);
    let by = max(max(cy - f32(block.z), f32(block.w) - cy), 0.0);
    let texel = texel_size(lv, n, depth);
    let nl = (lv.light_from_world * vec4<f32>(normal, 0.0)).xyz;
    let slope = (abs(nl.x) * bx + abs(nl.y) * by) * texel;
    var own = -FLT_MAX;
    if abs(nl.z) * MAX_RECEIVER_SLOPE >= max(abs(nl.x), abs(nl.y)) {
        own = slope / abs(nl.z) + texel;
    }
    let a = i * ACC;
    atomicAdd(&acc[a + 4u], 1u);
    atomicMax(&acc[a + 1u], order_key(depth));
    atomicMin(&acc[a], order_key(min(zmin, depth)));
    if zmin < depth - own {
        atomicAdd(&acc[a + 5u], 1u);
        atomicMax(&acc[a + 3u], order_key(depth));
        atomicMin(&acc[a + 2u], order_key(zmin));
    }
}

@compute @workgroup_size(64)
fn receivers(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * fit.row + gid.x;
    if k < fit.count {
        visit(k);
    }
}

fn min_width(near: f32, far: f32) -> f32 {
    return MIN_RANGE_RELATIVE * max(max(abs(near), abs(far)), 1.0842022e-19);
}

@compute @workgroup_size(1)
fn fitted(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = gid.x;
    if v >= fit.views {
        return;
    }
    let a = v * ACC;
    let shadowable = atomicLoad(&acc[a + 5u]);
    var near = from_key(atomicLoad(&acc[a]));
    var far = from_key(atomicLoad(&acc[a + 1u]));
    if shadowable > 0u {
        near = from_key(atomicLoad(&acc[a + 2u]));
        far = from_key(atomicLoad(&acc[a + 3u]));
    }
    let finite = abs(near) < BIG && abs(far) < BIG;
    if atomicLoad(&acc[a + 4u]) == 0u || !finite || near > far {
        // The library's `DepthRange::of_map`: the map's own finite depths, else the view's.
        var n = from_key(atomicLoad(&acc[a + 6u]));
        var f = from_key(atomicLoad(&acc[a + 7u]));
        if n > f {
            n = views[v].near;
            f = views[v].far;
        }
        f = max(f, n + min_width(n, f));
        ranges[v] = RangeU(n, f, fit.span, 0.0);
        return;
    }
    near = min(near, far - min_width(near, far));
    let slack = (far - near) * FITTED_RANGE_SLACK;
    ranges[v] = RangeU(near - slack, far + slack, fit.span, 0.0);
}
