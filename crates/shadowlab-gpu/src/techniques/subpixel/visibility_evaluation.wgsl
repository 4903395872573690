// gpu:subpixel, stage `visibility_evaluation` (Pan et al. 2009, Section 3.4, Figures 6
// and 7; the library's `blockers.rs` and `visibility_evaluation.rs`): one thread a chunk
// of one texel's triangles against one facet (see CHUNK). Each triangle paired with the
// facet's texels becomes a blocker (the planes through its
// edges and the light, and its own plane), each plane a half-plane on the screen through
// the facet's tangent plane, each half-plane a bitmask from the look-up table; their AND
// is ORed into the occlusion mask. The validity mask drops samples beyond the line where
// a triangle that cuts the facet inside the pixel rises above it; an alpha-masked
// blocker's covered samples are tested exactly against its mask. A triangle met through
// several texels is evaluated again: OR and AND are idempotent, so the mask is the CPU's,
// which evaluates it once. Shadow = 1 − |occlusion ∩ valid| / |valid|. Composed after
// subpixel/{bindings, rasterization, ray_plane, lookup_table}.wgsl.

// The library's EDGE_ON_SINE and COPLANAR_TOLERANCE.
const EDGE_ON_SINE: f32 = 1e-6;
const COPLANAR_TOLERANCE: f32 = 1e-5;

// Written without indexing arrays or vectors by a variable: a software adapter was seen
// to compile such indexing differently for different invocations.
struct Blocker {
    ok: bool,
    v0: vec3<f32>,
    v1: vec3<f32>,
    v2: vec3<f32>,
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    p3: vec4<f32>,
}

// Lexicographic `<` of two points (the library orders an edge's ends so).
fn before(p: vec3<f32>, q: vec3<f32>) -> bool {
    if p.x != q.x {
        return p.x < q.x;
    }
    if p.y != q.y {
        return p.y < q.y;
    }
    return p.z < q.z;
}

struct EdgePlane {
    ok: bool,
    plane: vec4<f32>,
}

// The plane through edge p–q and the light, facing the third vertex r (`Blocker::new`).
fn edge_plane(p0: vec3<f32>, q0: vec3<f32>, r: vec3<f32>) -> EdgePlane {
    var p = p0;
    var q = q0;
    if !before(p, q) {
        p = q0;
        q = p0;
    }
    var m = cross(q - p, toward_at(p));
    let s = dot3(m, r - p);
    if s != s || abs(s) <= EDGE_ON_SINE * length(m) * length(r - p) {
        return EdgePlane(false, vec4<f32>(0.0));
    }
    if s < 0.0 {
        m = -m;
    }
    return EdgePlane(true, plane_part(m, p));
}

// The library's `Blocker::new`.
fn blocker(tri: u32) -> Blocker {
    var bl: Blocker;
    bl.ok = false;
    let a = vertex(tri, 0u);
    let b = vertex(tri, 1u);
    let c = vertex(tri, 2u);
    bl.v0 = a;
    bl.v1 = b;
    bl.v2 = c;
    var m4 = cross(b - a, c - a);
    let ta = toward_at(a);
    let side = dot3(m4, ta);
    if side != side || abs(side) <= EDGE_ON_SINE * length(m4) * length(ta) {
        return bl;
    }
    if side > 0.0 {
        m4 = -m4;
    }
    let e0 = edge_plane(a, b, c);
    let e1 = edge_plane(b, c, a);
    let e2 = edge_plane(c, a, b);
    if !(e0.ok && e1.ok && e2.ok) {
        return bl;
    }
    bl.p0 = e0.plane;
    bl.p1 = e1.plane;
    bl.p2 = e2.plane;
    bl.p3 = plane_part(m4, a);
    bl.ok = true;
    return bl;
}

struct ScreenPoint {
    ok: bool,
    s: vec2<f32>,
}

// `ScreenMap::pixel`.
fn screen_pixel(p: vec3<f32>) -> ScreenPoint {
    let c = fr.screen * vec4<f32>(p, 1.0);
    if !(c.w > 0.0) {
        return ScreenPoint(false, vec2<f32>(0.0));
    }
    let u = c.x / c.w * 0.5 + 0.5;
    let v = 0.5 - c.y / c.w * 0.5;
    return ScreenPoint(true, vec2<f32>(u * f32(fr.width), v * f32(fr.height)));
}

// One side of the Liang–Barsky clip of `segment_meets_pixel`: the parameter range t
// (x: from, y: to) narrowed by p·t ≤ q; y < x once the segment misses.
fn clip_side(t: vec2<f32>, p: f32, q: f32) -> vec2<f32> {
    if p == 0.0 {
        if q < 0.0 {
            return vec2<f32>(1.0, 0.0);
        }
        return t;
    }
    let r = q / p;
    if p < 0.0 {
        return vec2<f32>(max(t.x, r), t.y);
    }
    return vec2<f32>(t.x, min(t.y, r));
}

// `segment_meets_pixel`: the segment a–b touches pixel square (x, y).
fn segment_meets_pixel(a: vec2<f32>, b: vec2<f32>, x: f32, y: f32) -> bool {
    let d = b - a;
    var t = vec2<f32>(0.0, 1.0);
    t = clip_side(t, -d.x, a.x - x);
    t = clip_side(t, d.x, x + 1.0 - a.x);
    t = clip_side(t, -d.y, a.y - y);
    t = clip_side(t, d.y, y + 1.0 - a.y);
    return t.x <= t.y;
}

fn facet_half(fi: u32, pl: vec4<f32>) -> vec4<u32> {
    let f = facets[fi];
    let a = pl.x * f.an + f.beta * pl.y;
    let b = pl.x * f.bn + f.beta * pl.z;
    let c = pl.x * f.cn + f.beta * (pl.w + f.x * pl.y + f.y * pl.z);
    return half_plane(a, b, c);
}

// `kept_by_mask`: the samples of `m` whose shadow ray meets the masked blocker where its
// texture keeps it.
fn kept_by_mask(m: vec4<u32>, fi: u32, tri: u32, bl: Blocker) -> vec4<u32> {
    let f = facets[fi];
    var kept = m;
    for (var i = 0u; i < fr.samples; i++) {
        if is_zero(m & bit(i)) {
            continue;
        }
        let s = lut_samples[i];
        let r = ray_at(f.x + s.x, f.y + s.y);
        let t = dot3(f.n, f.p - r.o) / dot3(f.n, r.d);
        let x = r.o + r.d * t;
        let dir = shadow_ray(fr.light, x).dir;
        // The library's `intersect_plane`.
        let e1 = bl.v1 - bl.v0;
        let e2 = bl.v2 - bl.v0;
        let pv = cross(dir, e2);
        let det = dot3(e1, pv);
        var cut = true;
        if det != 0.0 && finite(det) {
            let inv = 1.0 / det;
            let sv = x - bl.v0;
            let b1 = dot3(sv, pv) * inv;
            let qv = cross(sv, e1);
            let b2 = dot3(dir, qv) * inv;
            cut = cut_out(fr.masks, tri, vec3<f32>(1.0 - b1 - b2, b1, b2));
        }
        if cut || !finite(t) {
            kept &= ~bit(i);
        }
    }
    return kept;
}

struct Masks {
    occ: vec4<u32>,
    valid: vec4<u32>,
}

struct CutPoint {
    ok: bool,
    p: vec3<f32>,
}

// Where edge vi–vj meets the facet's plane (signed distances di, dj), as the library's
// crease test finds it: vi itself when it lies on the plane.
fn cut_point(vi: vec3<f32>, vj: vec3<f32>, di: f32, dj: f32, eps: f32) -> CutPoint {
    if abs(di) <= eps {
        return CutPoint(true, vi);
    }
    if abs(dj) > eps && (di > 0.0) != (dj > 0.0) {
        return CutPoint(true, vi + (vj - vi) * (di / (di - dj)));
    }
    return CutPoint(false, vi);
}

// One blocker's part of facet `fi`'s masks.
fn evaluate(fi: u32, tri: u32, acc: Masks) -> Masks {
    var r = acc;
    let f = facets[fi];
    if tri == f.own {
        return r;
    }
    let bl = blocker(tri);
    if !bl.ok {
        return r;
    }
    let r0 = bl.v0 - f.p;
    let r1 = bl.v1 - f.p;
    let r2 = bl.v2 - f.p;
    let d = vec3<f32>(dot3(f.n, r0), dot3(f.n, r1), dot3(f.n, r2));
    let a0 = abs(r0);
    let a1 = abs(r1);
    let a2 = abs(r2);
    let scale = max(max(max(a0.x, a0.y), a0.z), max(max(max(a1.x, a1.y), a1.z), max(max(a2.x, a2.y), a2.z)));
    let eps = COPLANAR_TOLERANCE * scale;
    if max(max(d.x, d.y), d.z) <= eps {
        return r;
    }
    var behind = vec4<u32>(0u);
    var has_behind = false;
    if min(min(d.x, d.y), d.z) <= eps {
        let c0 = cut_point(bl.v0, bl.v1, d.x, d.y, eps);
        let c1 = cut_point(bl.v1, bl.v2, d.y, d.z, eps);
        let c2 = cut_point(bl.v2, bl.v0, d.z, d.x, eps);
        var np = 0u;
        var q0 = vec3<f32>(0.0);
        var q1 = vec3<f32>(0.0);
        if c0.ok {
            q0 = c0.p;
            np = 1u;
        }
        if c1.ok {
            if np == 0u {
                q0 = c1.p;
            } else {
                q1 = c1.p;
            }
            np += 1u;
        }
        if c2.ok {
            if np == 0u {
                q0 = c2.p;
            } else if np == 1u {
                q1 = c2.p;
            }
            np += 1u;
        }
        if np >= 2u {
            let a = screen_pixel(q0);
            let b = screen_pixel(q1);
            if a.ok && b.ok && segment_meets_pixel(a.s, b.s, f.x, f.y) {
                behind = facet_half(fi, bl.p3);
                has_behind = true;
                if is_zero(behind & bit(fr.centre)) {
                    r.valid &= ~behind;
                }
            }
        }
    }
    var m = all_mask() & facet_half(fi, bl.p0);
    if !is_zero(m) {
        m &= facet_half(fi, bl.p1);
    }
    if !is_zero(m) {
        m &= facet_half(fi, bl.p2);
    }
    if !is_zero(m) {
        if has_behind {
            m &= behind;
        } else {
            m &= facet_half(fi, bl.p3);
        }
    }
    if !is_zero(m) && fr.masks != 0u && materials[tri_material[tri]].masked != 0u {
        m = kept_by_mask(m, fi, tri, bl);
    }
    r.occ |= m;
    return r;
}

// Work items: each is one texel slot's triangles, a chunk of at most CHUNK of them,
// against one facet. Software adapters end every loop of an invocation once its loops
// together have turned 65535 times (llvmpipe's LP_MAX_TGSI_LOOP_ITERATIONS), and a facet
// over finely tessellated casters meets thousands of triangles: one invocation a facet
// would lose the last of them. A chunk's evaluations stay far below that count (a few
// dozen turns each, the samples of an alpha-masked blocker at most 128), and on a hardware
// GPU the chunks spread a busy facet's work over many threads. Each item ORs its
// occluded and its invalidated samples into the facet's masks, which is order-free, so
// the result does not depend on which item runs first.
const CHUNK: u32 = 64u;

// The items of facet `fi`: listed from `at` when `list`; returns their number.
fn facet_items(fi: u32, list: bool, at: u32) -> u32 {
    let poly = facet_poly(fi);
    let base = facets[fi].view * fr.res * fr.res;
    let rows = row_range(poly);
    var count = 0u;
    for (var y = rows.x; y <= rows.y && rows.x <= rows.y; y++) {
        let s = row_span(poly, rows, y);
        for (var x = s.x0; x <= s.x1 && s.some; x++) {
            let sl = slot[base + y * fr.res + x];
            if sl == 0u {
                continue;
            }
            let chunks = (slot_start[sl] - slot_start[sl - 1u] + CHUNK - 1u) / CHUNK;
            for (var c = 0u; c < chunks && list; c++) {
                items[at + count + c] = vec4<u32>(fi, sl, c, 0u);
            }
            count += chunks;
        }
    }
    return count;
}

// Words `w`..`w + 3` of the facets' masks: ORed with `m`, or read.
fn or_words(w: u32, m: vec4<u32>) {
    atomicOr(&masks[w], m.x);
    atomicOr(&masks[w + 1u], m.y);
    atomicOr(&masks[w + 2u], m.z);
    atomicOr(&masks[w + 3u], m.w);
}

fn words(w: u32) -> vec4<u32> {
    return vec4<u32>(atomicLoad(&masks[w]), atomicLoad(&masks[w + 1u]), atomicLoad(&masks[w + 2u]), atomicLoad(&masks[w + 3u]));
}

// Per facet: its items counted, into counters[6] and the facet.
@compute @workgroup_size(64)
fn count_items(@builtin(global_invocation_id) gid: vec3<u32>) {
    let fi = thread_index(gid);
    if fi >= fr.pixels || facets[fi].alive == 0u {
        return;
    }
    let n = facet_items(fi, false, 0u);
    facets[fi].items = n;
    atomicAdd(&counters[6], n);
}

// Per facet: its items listed.
@compute @workgroup_size(64)
fn list_items(@builtin(global_invocation_id) gid: vec3<u32>) {
    let fi = thread_index(gid);
    if fi >= fr.pixels || facets[fi].alive == 0u {
        return;
    }
    let n = facets[fi].items;
    facet_items(fi, true, atomicAdd(&counters[7], n));
}

// Per item: its chunk of blockers evaluated against its facet, the occluded samples and
// the samples made invalid ORed into the facet's masks.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = thread_index(gid);
    if e >= atomicLoad(&counters[6]) {
        return;
    }
    let it = items[e];
    let fi = it.x;
    let first = slot_start[it.y - 1u] + it.z * CHUNK;
    let last = min(slot_start[it.y], first + CHUNK);
    var acc = Masks(vec4<u32>(0u), all_mask());
    for (var j = first; j < last; j++) {
        acc = evaluate(fi, pairs[j], acc);
    }
    or_words(fi * 8u, acc.occ);
    or_words(fi * 8u + 4u, all_mask() & ~acc.valid);
}

// Per facet: Shadow = 1 − |occlusion ∩ valid| / |valid|, valid being the facet's own
// samples less those its items made invalid.
@compute @workgroup_size(64)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    let fi = thread_index(gid);
    if fi >= fr.pixels || facets[fi].alive == 0u {
        return;
    }
    let valid = facets[fi].valid & all_mask() & ~words(fi * 8u + 4u);
    write_out(facets[fi].k, 1.0 - f32(ones(words(fi * 8u) & valid)) / f32(ones(valid)));
}
