// The min-depth pyramid of each view's map (the library's `MinPyramid`), which stage `fit`
// builds and reads and the blocker search reads, and the parameters both stages take. A
// stage composed after this file declares `fit` (FitU), `levels` (each level's width,
// height and first texel within a view) and `pyramid` (every view's levels, `fit.stride`
// texels a view, level 0 the map's linear depths, +inf where empty).

// The largest finite float: stands in for an infinite depth (shader constants cannot be
// infinite), which every comparison with a finite depth treats alike.
const FLT_MAX: f32 = 3.4028235e38;

struct FitU {
    light: LightU,
    // Pixels of the camera pass and threads a dispatch row.
    count: u32,
    row: u32,
    // Map side, views, pyramid levels.
    side: u32,
    views: u32,
    levels: u32,
    // The look-up filter (FILTER_* of lookup.wgsl), its most probes.
    filtering: u32,
    max_aniso: u32,
    // Texels the blur reaches, plus one (`blur / 2 + 1`).
    blur_pad: u32,
    // Texels of one view's pyramid; the level a `reduce` dispatch makes.
    stride: u32,
    level: u32,
    _pad0: u32,
    _pad1: u32,
    // The normalized depth of the farthest texel.
    span: f32,
    // The area light's equivalent width (0: none), and the bias of the blocker search.
    light_width: f32,
    bias: f32,
    slope_bias: f32,
}

fn from_key(k: u32) -> f32 {
    if (k & 0x80000000u) != 0u {
        return bitcast<f32>(k & 0x7fffffffu);
    }
    return bitcast<f32>(~k);
}

// The depth of texel `(x, y)` of level `l` of view `v`'s pyramid.
fn pyramid_at(v: u32, l: u32, x: u32, y: u32) -> f32 {
    let lv = levels[l];
    return pyramid[v * fit.stride + lv.z + y * lv.x + x];
}

// The library's `MinPyramid::min_in`: the nearest depth of a block of at most 2 × 2 texels
// of the finest level that holds the texel rectangle [x0, x1] × [y0, y1] of view `v`, and
// the block as level-0 bounds (x_begin, x_end, y_begin, y_end), end exclusive.
fn min_in(v: u32, x0: u32, x1: u32, y0: u32, y1: u32, block: ptr<function, vec4<u32>>) -> f32 {
    let extent = max(x1 - x0, y1 - y0);
    var l = 0u;
    if extent > 1u {
        l = min(firstLeadingBit(extent), fit.levels - 1u);
    }
    while l + 1u < fit.levels && ((x1 >> l) - (x0 >> l) > 1u || (y1 >> l) - (y0 >> l) > 1u) {
        l++;
    }
    let lv = levels[l];
    let xa = x0 >> l;
    let xb = min(x1 >> l, lv.x - 1u);
    let ya = y0 >> l;
    let yb = min(y1 >> l, lv.y - 1u);
    var m = FLT_MAX;
    for (var y = ya; y <= yb; y++) {
        for (var x = xa; x <= xb; x++) {
            m = min(m, pyramid_at(v, l, x, y));
        }
    }
    let w0 = levels[0].x;
    let h0 = levels[0].y;
    *block = vec4<u32>(xa << l, min((xb + 1u) << l, w0), ya << l, min((yb + 1u) << l, h0));
    return m;
}
