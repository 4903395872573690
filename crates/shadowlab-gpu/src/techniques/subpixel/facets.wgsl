// gpu:subpixel, stage `facets` (Pan et al. 2009, Sections 3.1 and 3.3; the library's
// `facets.rs`): each covered pixel the light reaches first checks a box that provably
// holds its projected facet against the silhouette mask map's summed-area table; a pixel
// with no silhouette texel there takes the depth-map test. The others build their facet
// (the pixel's footprint on the tangent plane through its centre sample, shrunk where a
// corner ray grazes it), project it into their light view, and, when its bounding
// rectangle holds a silhouette texel, are stored as facets at their pixel's index. Composed after
// subpixel/{bindings, rasterization, ray_plane, lookup_table}.wgsl.

// The library's MAX_FACET_STRETCH, FACET_SHRINK_STEPS and MAX_DIVISION_SPREAD.
const MAX_FACET_STRETCH: f32 = 16.0;
const FACET_SHRINK_STEPS: u32 = 4u;
const MAX_DIVISION_SPREAD: f32 = 0.5;

// `FrameState::facet_bound`: half extents (texels) of a box about the centre's look-up
// that holds the projected facet; w < 0 when there is none.
fn facet_bound(k: u32, x: f32, y: f32, lv: ViewS, c: vec4<f32>) -> vec3<f32> {
    let none = vec3<f32>(0.0, 0.0, -1.0);
    let p = sample_pos(k);
    let n = sample_normal(k);
    let j = tangent_jacobian(n, p, x + 0.5, y + 0.5);
    if !j.ok || j.r >= MAX_DIVISION_SPREAD {
        return none;
    }
    let f = 1.0 / (1.0 - j.r);
    let mx = lv.clip_from_world * vec4<f32>(j.jx, 0.0);
    let my = lv.clip_from_world * vec4<f32>(j.jy, 0.0);
    let rho = f * 0.5 * (abs(mx.w) + abs(my.w)) / abs(c.w);
    if rho != rho || rho >= MAX_DIVISION_SPREAD {
        return none;
    }
    let scale = f / (1.0 - rho) * 0.5 * (0.5 * f32(fr.res)) / (c.w * c.w);
    let ex = (abs(mx.x * c.w - c.x * mx.w) + abs(my.x * c.w - c.x * my.w)) * scale;
    let ey = (abs(mx.y * c.w - c.y * mx.w) + abs(my.y * c.w - c.y * my.w)) * scale;
    if !(finite(ex) && finite(ey)) {
        return none;
    }
    return vec3<f32>(ex, ey, 1.0);
}

// `MaskMap::count_around`.
fn count_around(vi: u32, tx: f32, ty: f32, ex: f32, ey: f32) -> u32 {
    let r = f32(fr.res);
    let x0 = tx - ex - RASTER_EPS;
    let x1 = tx + ex + RASTER_EPS;
    let y0 = ty - ey - RASTER_EPS;
    let y1 = ty + ey + RASTER_EPS;
    if !(x1 >= 0.0 && y1 >= 0.0 && x0 < r && y0 < r) {
        return 0u;
    }
    return sat_count(vi, u32(clamp(x0, 0.0, r - 1.0)), u32(clamp(y0, 0.0, r - 1.0)), u32(clamp(x1, 0.0, r - 1.0)), u32(clamp(y1, 0.0, r - 1.0)));
}

// `FrameState::bounded_depth_test`: the depth-map test, or -1 when the box holds a
// silhouette texel (the pixel builds its facet).
fn bounded_depth_test(k: u32, x: f32, y: f32) -> f32 {
    let p = sample_pos(k);
    let vi = view_of(p);
    let lv = lviews[vi];
    let c = lv.clip_from_world * vec4<f32>(p, 1.0);
    let u = c.x / c.w * 0.5 + 0.5;
    let v = 0.5 - c.y / c.w * 0.5;
    let b = facet_bound(k, x, y, lv, c);
    if b.z > 0.0 && count_around(vi, u * f32(fr.res), v * f32(fr.res), b.x, b.y) == 0u {
        return depth_lookup(k, vi, u, v, light_depth(lv, p));
    }
    return -1.0;
}

struct Corner {
    ok: bool,
    c: vec3<f32>,
}

// One corner of the footprint of a square `s` pixels wide about the pixel's centre on the
// tangent plane (offsets ox, oy of ±1), or none when its ray grazes the plane or meets it
// more than `cap` away.
fn corner(p: vec3<f32>, n: vec3<f32>, x: f32, y: f32, s: f32, cap: f32, ox: f32, oy: f32) -> Corner {
    let r = ray_at(x + 0.5 + 0.5 * s * ox, y + 0.5 + 0.5 * s * oy);
    let nd = dot3(n, r.d);
    if nd != nd || nd >= 0.0 {
        return Corner(false, p);
    }
    let c = r.o + r.d * (dot3(n, p - r.o) / nd);
    let dist = length(c - p);
    if dist != dist || dist > cap {
        return Corner(false, p);
    }
    return Corner(true, c);
}

// `FrameState::build_facet`: true when pixel k became facet `f`; else its term is written.
fn build_facet(k: u32) {
    let p = sample_pos(k);
    let n = sample_normal(k);
    let vi = view_of(p);
    let x = f32(k % fr.width);
    let y = f32(k / fr.width);
    let cap = pixel_widths(MAX_FACET_STRETCH, cam_depth[k]);
    var scale = 0.0;
    var corners = array<vec3<f32>, 4>(p, p, p, p);
    var s = 1.0;
    for (var i = 0u; i <= FACET_SHRINK_STEPS; i++) {
        let c0 = corner(p, n, x, y, s, cap, -1.0, -1.0);
        let c1 = corner(p, n, x, y, s, cap, 1.0, -1.0);
        let c2 = corner(p, n, x, y, s, cap, 1.0, 1.0);
        let c3 = corner(p, n, x, y, s, cap, -1.0, 1.0);
        if c0.ok && c1.ok && c2.ok && c3.ok {
            scale = s;
            corners = array<vec3<f32>, 4>(c0.c, c1.c, c2.c, c3.c);
            break;
        }
        s *= 0.5;
    }
    let poly = project(vi, corners, 4u);
    if poly.n == 0u {
        write_out(k, depth_test(k, vi));
        return;
    }
    let b = poly_bounds(poly);
    let rf = f32(fr.res);
    if b.hi.x < 0.0 || b.hi.y < 0.0 || b.lo.x >= rf || b.lo.y >= rf {
        write_out(k, depth_test(k, vi));
        return;
    }
    let count = sat_count(vi, u32(clamp(b.lo.x - RASTER_EPS, 0.0, rf - 1.0)), u32(clamp(b.lo.y - RASTER_EPS, 0.0, rf - 1.0)), u32(clamp(b.hi.x + RASTER_EPS, 0.0, rf - 1.0)), u32(clamp(b.hi.y + RASTER_EPS, 0.0, rf - 1.0)));
    if count == 0u {
        write_out(k, depth_test(k, vi));
        return;
    }
    var f: FacetU;
    f.valid = vec4<u32>(0u);
    for (var i = 0u; i < fr.samples; i++) {
        let o = abs(lut_samples[i] - vec2<f32>(0.5));
        if i == fr.centre || (o.x <= 0.5 * scale && o.y <= 0.5 * scale) {
            f.valid |= bit(i);
        }
    }
    let fp = facet_part(n, p, x, y);
    f.p = p;
    f.k = k;
    f.n = n;
    f.view = vi;
    f.x = x;
    f.y = y;
    f.own = sample_triangle(k);
    f.alive = 1u;
    f.an = fp.x;
    f.bn = fp.y;
    f.cn = fp.z;
    f.beta = fp.w;
    f.depth_max = depth_span(vi, b.lo.z, b.hi.z).y;
    f.poly_n = poly.n;
    for (var i = 0u; i < poly.n; i++) {
        f.poly[i] = vec4<f32>(poly.v[i], 0.0);
    }
    atomicAdd(&counters[0], 1u);
    facets[k] = f;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = thread_index(gid);
    if k >= fr.pixels {
        return;
    }
    if sample_triangle(k) == NO_TRIANGLE {
        write_out(k, 1.0);
        return;
    }
    if !illuminates(fr.light, sample_pos(k), sample_normal(k)) {
        write_out(k, 0.0);
        return;
    }
    let t = bounded_depth_test(k, f32(k % fr.width), f32(k / fr.width));
    if t >= 0.0 {
        write_out(k, t);
        return;
    }
    build_facet(k);
}
