// gpu:subpixel, the library's `rasterization.rs`: small convex polygons projected into a
// light view's texel grid (x, y in texels, z the depth key: depth for an orthographic
// view, 1/depth for a perspective one) and walked row by row, every texel whose closed
// square they touch. Composed after subpixel/bindings.wgsl.

const RASTER_EPS: f32 = 2e-3;
const MAX_POLY: u32 = 12u;

struct Poly {
    v: array<vec3<f32>, 12>,
    n: u32,
}

fn poly_push(p: ptr<function, Poly>, q: vec3<f32>) {
    if (*p).n < MAX_POLY {
        (*p).v[(*p).n] = q;
        (*p).n += 1u;
    }
}

// Clipped to f(q) >= 0 with f(q) = dot(q, plane.xyz) + plane.w.
fn poly_clip(p: Poly, plane: vec4<f32>) -> Poly {
    var out: Poly;
    out.n = 0u;
    for (var i = 0u; i < p.n; i++) {
        let a = p.v[i];
        let b = p.v[(i + 1u) % p.n];
        let fa = dot(a, plane.xyz) + plane.w;
        let fb = dot(b, plane.xyz) + plane.w;
        if fa >= 0.0 {
            poly_push(&out, a);
        }
        if (fa >= 0.0) != (fb >= 0.0) {
            poly_push(&out, a + (b - a) * (fa / (fa - fb)));
        }
    }
    return out;
}

struct Bounds {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

fn poly_bounds(p: Poly) -> Bounds {
    var b = Bounds(vec3<f32>(BIG), vec3<f32>(-BIG));
    for (var i = 0u; i < p.n; i++) {
        b.lo = min(b.lo, p.v[i]);
        b.hi = max(b.hi, p.v[i]);
    }
    return b;
}

// The library's `Projector::project` of `count` world points in view `vi`.
fn project(vi: u32, world: array<vec3<f32>, 4>, count: u32) -> Poly {
    let lv = lviews[vi];
    var p: Poly;
    p.n = 0u;
    for (var i = 0u; i < count; i++) {
        poly_push(&p, (lv.light_from_world * vec4<f32>(world[i], 1.0)).xyz);
    }
    if lv.ortho == 0u {
        // -q.z - near >= 0
        p = poly_clip(p, vec4<f32>(0.0, 0.0, -1.0, -lv.near));
    }
    var out: Poly;
    out.n = 0u;
    let res = f32(fr.res);
    for (var i = 0u; i < p.n; i++) {
        let q = p.v[i];
        let c = lv.clip_from_light * vec4<f32>(q, 1.0);
        let depth = -q.z;
        var key = depth;
        if lv.ortho == 0u {
            key = 1.0 / depth;
        }
        let u = c.x / c.w * 0.5 + 0.5;
        let v = 0.5 - c.y / c.w * 0.5;
        let t = vec3<f32>(u * res, v * res, key);
        if finite(t.x) && finite(t.y) && finite(t.z) {
            poly_push(&out, t);
        }
    }
    return out;
}

// The library's `Projector::depth_span`: the (nearest, farthest) linear depths of keys.
fn depth_span(vi: u32, k0: f32, k1: f32) -> vec2<f32> {
    if lviews[vi].ortho == 1u {
        return vec2<f32>(k0, k1);
    }
    return vec2<f32>(1.0 / k1, 1.0 / k0);
}

// The rows a polygon's spans cover: (y0, y1), empty when y0 > y1.
fn row_range(p: Poly) -> vec2<u32> {
    if p.n == 0u {
        return vec2<u32>(1u, 0u);
    }
    let b = poly_bounds(p);
    let r = f32(fr.res);
    if !(finite(b.lo.x) && finite(b.lo.y) && finite(b.hi.x) && finite(b.hi.y) && finite(b.lo.z) && finite(b.hi.z)) || b.hi.x < -RASTER_EPS || b.hi.y < -RASTER_EPS || b.lo.x > r + RASTER_EPS || b.lo.y > r + RASTER_EPS {
        return vec2<u32>(1u, 0u);
    }
    let y0 = u32(max(floor(b.lo.y - RASTER_EPS), 0.0));
    let y1 = u32(min(floor(b.hi.y + RASTER_EPS), r - 1.0));
    return vec2<u32>(y0, y1);
}

struct Span {
    // False when the row holds none of the polygon.
    some: bool,
    x0: u32,
    x1: u32,
    k0: f32,
    k1: f32,
}

fn span_of(lo: vec3<f32>, hi: vec3<f32>) -> Span {
    let r = f32(fr.res);
    let a = max(floor(lo.x - RASTER_EPS), 0.0);
    let b = min(floor(hi.x + RASTER_EPS), r - 1.0);
    if a > b {
        return Span(false, 0u, 0u, 0.0, 0.0);
    }
    return Span(true, u32(a), u32(b), lo.z, hi.z);
}

// The library's `row_spans` at row y of the rows `rows` (from `row_range`).
fn row_span(p: Poly, rows: vec2<u32>, y: u32) -> Span {
    if rows.x == rows.y {
        let b = poly_bounds(p);
        return span_of(b.lo, b.hi);
    }
    let top = f32(y) - RASTER_EPS;
    let bottom = f32(y) + 1.0 + RASTER_EPS;
    let band = poly_clip(poly_clip(p, vec4<f32>(0.0, 1.0, 0.0, -top)), vec4<f32>(0.0, -1.0, 0.0, bottom));
    if band.n == 0u {
        return Span(false, 0u, 0u, 0.0, 0.0);
    }
    let b = poly_bounds(band);
    return span_of(b.lo, b.hi);
}

// The library's `depth_bits`.
fn depth_bits(d: f32) -> u32 {
    return bitcast<u32>(max(d, 0.0));
}
