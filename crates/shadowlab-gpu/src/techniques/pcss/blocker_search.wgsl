// gpu:pcss, stages `blocker search` and `penumbra estimation` (Fernando 2005), the
// library's `BlockerSearch::penumbra_radius`: the region of the map that can hold casters
// between a receiver and the light (the light's cone from the receiver, cut at the
// nearest depth the min-depth pyramid bounds there, twice, each region inside the last;
// at most MAX_SEARCH_FRACTION of the map wide) is read on a regular grid of taps; the
// texels nearer than the receiver's biased depth give the mean blocker depth, and
// similar triangles the penumbra's half width in texels. A receiver with no blocker is
// lit here; the others keep their radius for `filter`. Composed after
// shaders/common/{ray_offset, light}.wgsl and pcss/receiver.wgsl.

@group(0) @binding(4) var<storage, read> levels: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read> pyramid: array<f32>;
@group(0) @binding(6) var<storage, read_write> radii: array<f32>;
@group(0) @binding(7) var<storage, read_write> out: array<f32>;

// Texel (x, y) of pyramid level l of `layer`, as the map stores it (over depth_scale).
fn level_texel(layer: u32, l: u32, x: u32, y: u32) -> f32 {
    if l == 0u {
        return textureLoad(map, vec2<u32>(x, y), layer, 0);
    }
    let lv = levels[l];
    return pyramid[layer * params.layer_stride + lv.y + y * lv.x + x];
}

// The library's `MinPyramid::min_in`: the nearest depth of the finest block of at most
// 2×2 texels of one level covering the texel rectangle [x0, x1] × [y0, y1].
fn min_in(layer: u32, x0: u32, x1: u32, y0: u32, y1: u32) -> f32 {
    let extent = max(x1 - x0, y1 - y0);
    var l = 0u;
    if extent > 1u {
        l = min(firstLeadingBit(extent), params.levels - 1u);
    }
    while l + 1u < params.levels && ((x1 >> l) - (x0 >> l) > 1u || (y1 >> l) - (y0 >> l) > 1u) {
        l++;
    }
    let side = levels[l].x;
    let xa = x0 >> l;
    let xb = min(x1 >> l, side - 1u);
    let ya = y0 >> l;
    let yb = min(y1 >> l, side - 1u);
    var m = 3.0e38;
    for (var y = ya; y <= yb; y++) {
        for (var x = xa; x <= xb; x++) {
            m = min(m, level_texel(layer, l, x, y));
        }
    }
    return m;
}

// A texel coordinate floored and clamped to the map.
fn texel_index(f: f32) -> u32 {
    return u32(clamp(floor(f), 0.0, f32(params.res - 1u)));
}

// The library's `BlockerSearch::nearest_in`, as a linear depth.
fn nearest_in(face: u32, fx: f32, fy: f32, radius: f32) -> f32 {
    let m = min_in(face, texel_index(fx - radius), texel_index(fx + radius), texel_index(fy - radius), texel_index(fy + radius));
    return m * views[face].depth_scale;
}

// The library's `search_width`.
fn search_width(ortho: bool, width: f32, receiver: f32, z: f32) -> f32 {
    let gap = max(receiver - z, 0.0);
    if ortho {
        return gap * width;
    }
    return width * gap / max(receiver, 1.17549435e-38);
}

// The library's `penumbra_width`.
fn penumbra_width(ortho: bool, width: f32, receiver: f32, blocker: f32) -> f32 {
    let gap = max(receiver - blocker, 0.0);
    if ortho {
        return gap * width;
    }
    return gap * width / max(blocker, 1.17549435e-38);
}

// The library's `clamp_radius`.
fn clamp_radius(r: f32, max_r: f32) -> f32 {
    if r != r {
        return max_r;
    }
    return clamp(r, 0.5, max_r);
}

// The penumbra's half width in texels for receiver `r` at biased depth `d`; 0 when the
// search finds no blocker.
fn penumbra_radius(r: Receiver, d: f32) -> f32 {
    let v = views[r.face];
    let ortho = v.ortho == 1u;
    let res = f32(params.res);
    let max_radius = MAX_SEARCH_FRACTION * res;
    let fx = r.u * res;
    let fy = r.v * res;
    var search = max_radius;
    for (var round = 0; round < 2; round++) {
        let z = min(nearest_in(r.face, fx, fy, search), r.depth);
        let cone = 0.5 * search_width(ortho, params.width, r.depth, z);
        search = clamp_radius(cone / texel_size(v, z), search);
    }
    // Blocker search: the mean depth of the taps nearer than the receiver.
    let side = params.search_side;
    var sum = 0.0;
    var count = 0u;
    for (var j = 0u; j < side; j++) {
        let y = texel_index(fy + grid_offset(j, side) * search);
        for (var i = 0u; i < side; i++) {
            let x = texel_index(fx + grid_offset(i, side) * search);
            let t = textureLoad(map, vec2<u32>(x, y), r.face, 0) * v.depth_scale;
            if t < d {
                sum += t;
                count++;
            }
        }
    }
    if count == 0u {
        return 0.0;
    }
    // Penumbra estimation by similar triangles.
    let w = penumbra_width(ortho, params.width, r.depth, sum / f32(count));
    return clamp_radius(0.5 * w / texel_size(v, r.depth), max_radius);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let r = receiver(k);
    var term = r.term;
    var radius = 0.0;
    if term < 0.0 {
        let d = r.depth - receiver_bias(r.texel, r.n, r.l, params.bias, params.slope_bias);
        radius = penumbra_radius(r, d);
        if radius == 0.0 {
            term = 1.0;
        }
    }
    radii[k] = radius;
    if radius == 0.0 {
        out[k * 3u] = term;
        out[k * 3u + 1u] = term;
        out[k * 3u + 2u] = term;
    }
}
