// gpu:afsm, stage `raster` ("Rasterization of blockers", the set-up half): each caster
// triangle's footprint on each light plane — bounding rectangle, three edge functions and
// least depth, widened exactly as the CPU `afsm`'s set-up widens them so no test that uses
// it can drop a sample the exact shadow-ray test would count — and the number of chunks
// under its rectangle of cells (from the summed-area table), the triangle's share of the
// triangle–chunk work queue. Composed after shaders/common/{ray_offset, light}.wgsl and
// grid.wgsl.

@group(0) @binding(0) var<uniform> params: AfsmParams;
@group(0) @binding(1) var<storage, read> planes: array<u32>;
@group(0) @binding(2) var<storage, read> projs: array<Proj>;
@group(0) @binding(3) var<storage, read> tris: array<f32>;
@group(0) @binding(4) var<storage, read> chunk_start: array<u32>;
@group(0) @binding(5) var<storage, read> sat: array<u32>;
@group(0) @binding(6) var<storage, read_write> records: array<u32>;
@group(0) @binding(7) var<storage, read_write> items: array<u32>;
@group(0) @binding(8) var<storage, read_write> args: array<u32>;

// The library's CULL_TOLERANCE: 64 ulps of the distances involved.
const CULL_TOLERANCE: f32 = 7.62939453125e-6;
// The CPU set-up's widening constants (see the library's alias_free/setup.rs).
const ORTHO_EDGE_WIDENING: f32 = 2.0;
const ORTHO_AREA_ERROR: f32 = 4.0;
const DELTA: f32 = 2.0;
const BEHIND: f32 = 2.0;
const FRONT: f32 = 4.0;
const NEAR_LIGHT: f32 = 16.0;
const PROJECTED_WIDENING: f32 = 2.0;
const EDGE_PLANE_WIDENING: f32 = 2.0;
const SLAB_WIDENING: f32 = 2.0;
const F32_EPSILON: f32 = 1.1920929e-7;
const BIG: f32 = 3.0e38;
// Words a record holds: three edge functions, the rectangle, the least depth, the cell
// rectangle (two words of two 16-bit ends), the plane and the triangle.
const RECORD_STRIDE: u32 = 18u;
// A record over at most this many chunks is one work item.
const SMALL_RECORD: u32 = 8u;

struct Foot {
    ok: bool,
    e0: vec3<f32>,
    e1: vec3<f32>,
    e2: vec3<f32>,
    lo: vec2<f32>,
    hi: vec2<f32>,
    zmin: f32,
}

const PASS_ALL: vec3<f32> = vec3<f32>(0.0, 0.0, 1.0);

fn none() -> Foot {
    return Foot(false, PASS_ALL, PASS_ALL, PASS_ALL, vec2<f32>(0.0), vec2<f32>(0.0), 0.0);
}

fn vertex(tri: u32, k: u32) -> vec3<f32> {
    let i = tri * 9u + k * 3u;
    return vec3<f32>(tris[i], tris[i + 1u], tris[i + 2u]);
}

fn coords(pl: u32, p: vec3<f32>) -> vec3<f32> {
    let pr = projs[pl];
    let q = p - pr.o;
    return vec3<f32>(dot3(q, pr.s), dot3(q, pr.t), dot3(q, pr.w));
}

fn plane_f(pl: u32, f: u32) -> f32 {
    return dec(planes[pl * PLANE_STRIDE + f]);
}

// The set-up on an orthographic plane (the CPU's `ortho`).
fn ortho(pl: u32, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> Foot {
    var f = none();
    let tol = CULL_TOLERANCE * params.ortho_scale;
    f.zmin = min(min(p0.z, p1.z), p2.z) - tol;
    if f.zmin > plane_f(pl, PL_ZMAX) {
        return f;
    }
    f.lo = min(min(p0.xy, p1.xy), p2.xy) - vec2<f32>(tol);
    f.hi = max(max(p0.xy, p1.xy), p2.xy) + vec2<f32>(tol);
    let area2 = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
    let p = array<vec3<f32>, 3>(p0, p1, p2);
    var ed: array<vec3<f32>, 3>;
    var ecs: array<f32, 3>;
    var perimeter = 0.0;
    for (var i = 0u; i < 3u; i++) {
        let a = p[i];
        let b = p[(i + 1u) % 3u];
        let ea = a.y - b.y;
        let eb = b.x - a.x;
        let len = sqrt(ea * ea + eb * eb);
        ed[i] = vec3<f32>(ea, eb, len);
        ecs[i] = -(ea * a.x + eb * a.y);
        perimeter += len;
    }
    let area_error = ORTHO_AREA_ERROR * tol * perimeter;
    var e = array<vec3<f32>, 3>(PASS_ALL, PASS_ALL, PASS_ALL);
    if abs(area2) > area_error {
        let sigma = sign(area2);
        for (var i = 0u; i < 3u; i++) {
            e[i] = vec3<f32>(sigma * ed[i].x, sigma * ed[i].y,
                             sigma * ecs[i] + ORTHO_EDGE_WIDENING * tol * ed[i].z);
        }
    } else {
        // Nearly edge-on: the slab along the longest edge, as wide as the height.
        var i = 0u;
        if ed[1].z > ed[i].z { i = 1u; }
        if ed[2].z > ed[i].z { i = 2u; }
        let w = abs(area2) + area_error + ORTHO_EDGE_WIDENING * tol * ed[i].z;
        e[0] = vec3<f32>(ed[i].x, ed[i].y, ecs[i] + w);
        e[1] = vec3<f32>(-ed[i].x, -ed[i].y, -ecs[i] + w);
    }
    f.e0 = e[0];
    f.e1 = e[1];
    f.e2 = e[2];
    f.ok = true;
    return f;
}

struct Rect {
    ok: bool,
    lo: vec2<f32>,
    hi: vec2<f32>,
}

fn grow(r: Rect, p: vec3<f32>, delta: f32) -> Rect {
    let u = p.x / p.z;
    let v = p.y / p.z;
    let du = PROJECTED_WIDENING * delta * (1.0 + abs(u) + abs(v)) / p.z;
    return Rect(true, min(r.lo, vec2<f32>(u - du, v - du)), max(r.hi, vec2<f32>(u + du, v + du)));
}

// The CPU's `perspective_rect`: the footprint's rectangle on the plane z = 1, unbounded
// where the triangle may pass close to the light, `ok` false when no part is in front.
fn perspective_rect(q: array<vec3<f32>, 3>, delta: f32, d_max: f32) -> Rect {
    let front = FRONT * delta;
    var r = Rect(false, vec2<f32>(BIG), vec2<f32>(-BIG));
    if q[0].z > front && q[1].z > front && q[2].z > front {
        for (var i = 0u; i < 3u; i++) {
            r = grow(r, q[i], delta);
        }
        return r;
    }
    let normal = cross(q[1] - q[0], q[2] - q[0]);
    let centroid = (q[0] + q[1] + q[2]) / 3.0;
    var radius = 0.0;
    for (var i = 0u; i < 3u; i++) {
        let d = q[i] - centroid;
        radius = max(radius, sqrt(dot3(d, d)));
    }
    let plane_dist = abs(dot3(q[0], normal)) / sqrt(dot3(normal, normal));
    let r_min = max(plane_dist, sqrt(dot3(centroid, centroid)) - radius);
    if r_min > NEAR_LIGHT * delta * d_max {
        for (var i = 0u; i < 3u; i++) {
            let a = q[i];
            let b = q[(i + 1u) % 3u];
            if a.z >= front {
                r = grow(r, a, delta);
            }
            if (a.z >= front) != (b.z >= front) {
                r = grow(r, a + (b - a) * ((front - a.z) / (b.z - a.z)), delta);
            }
        }
        return r;
    }
    return Rect(true, vec2<f32>(-BIG), vec2<f32>(BIG));
}

// The set-up on a perspective plane (the CPU's `perspective` and `edge_planes`).
fn perspective(pl: u32, q0: vec3<f32>, q1: vec3<f32>, q2: vec3<f32>) -> Foot {
    var f = none();
    let q = array<vec3<f32>, 3>(q0, q1, q2);
    let ql = vec3<f32>(sqrt(dot3(q0, q0)), sqrt(dot3(q1, q1)), sqrt(dot3(q2, q2)));
    let scale = bitcast<f32>(planes[PL_FAR]) + params.far_corner;
    let delta = DELTA * CULL_TOLERANCE * (scale + max(max(ql.x, ql.y), ql.z));
    f.zmin = min(min(q0.z, q1.z), q2.z) - delta;
    if f.zmin > plane_f(pl, PL_ZMAX) {
        return f;
    }
    if q0.z < -BEHIND * delta && q1.z < -BEHIND * delta && q2.z < -BEHIND * delta {
        return f;
    }
    let lo = vec2<f32>(plane_f(pl, PL_LO_U), plane_f(pl, PL_LO_V));
    let hi = vec2<f32>(plane_f(pl, PL_HI_U), plane_f(pl, PL_HI_V));
    let m = max(abs(lo), abs(hi));
    let d_max = sqrt(1.0 + m.x * m.x + m.y * m.y);
    let r = perspective_rect(q, delta, d_max);
    if !r.ok {
        return f;
    }
    f.lo = r.lo;
    f.hi = r.hi;
    let n = array<vec3<f32>, 3>(cross(q0, q1), cross(q1, q2), cross(q2, q0));
    let nl = vec3<f32>(sqrt(dot3(n[0], n[0])), sqrt(dot3(n[1], n[1])), sqrt(dot3(n[2], n[2])));
    var margin: array<f32, 3>;
    for (var i = 0u; i < 3u; i++) {
        margin[i] = EDGE_PLANE_WIDENING * delta * (ql[i] + ql[(i + 1u) % 3u]) * d_max;
    }
    let det = dot3(q0, n[1]);
    let det_error = 2.0 * delta * (nl.x + nl.y + nl.z)
        + 6.0 * delta * delta * (ql.x + ql.y + ql.z)
        + 8.0 * F32_EPSILON * ql.x * ql.y * ql.z;
    var e = array<vec3<f32>, 3>(PASS_ALL, PASS_ALL, PASS_ALL);
    if abs(det) > det_error {
        let sigma = sign(det);
        for (var i = 0u; i < 3u; i++) {
            e[i] = vec3<f32>(sigma * n[i].x, sigma * n[i].y, sigma * n[i].z + margin[i]);
        }
    } else if q0.z > FRONT * delta && q1.z > FRONT * delta && q2.z > FRONT * delta {
        var i = 0u;
        if nl[1] > nl[i] { i = 1u; }
        if nl[2] > nl[i] { i = 2u; }
        let w = SLAB_WIDENING * (abs(det) + det_error) / q[(i + 2u) % 3u].z + margin[i];
        e[0] = vec3<f32>(n[i].x, n[i].y, n[i].z + w);
        e[1] = vec3<f32>(-n[i].x, -n[i].y, -n[i].z + w);
    }
    f.e0 = e[0];
    f.e1 = e[1];
    f.e2 = e[2];
    f.ok = true;
    return f;
}

fn sat_at(sb: u32, gx: u32, r: u32, c: u32) -> u32 {
    return sat[sb + r * (gx + 1u) + c];
}

@compute @workgroup_size(64)
fn setup(@builtin(global_invocation_id) gid: vec3<u32>) {
    let rec = linear_id(gid);
    if rec >= params.tri_count * params.n_planes {
        return;
    }
    let tri = params.tri_first + rec / params.n_planes;
    let pl = rec % params.n_planes;
    let b = pl * PLANE_STRIDE;
    let gx = planes[b + PL_GX];
    let gy = planes[b + PL_GY];
    items[rec] = 0u;
    if gx == 0u {
        return;
    }
    let p0 = coords(pl, vertex(tri, 0u));
    let p1 = coords(pl, vertex(tri, 1u));
    let p2 = coords(pl, vertex(tri, 2u));
    var f: Foot;
    if projs[pl].persp == 0u {
        f = ortho(pl, p0, p1, p2);
    } else {
        f = perspective(pl, p0, p1, p2);
    }
    if !f.ok {
        return;
    }
    let plo = vec2<f32>(plane_f(pl, PL_LO_U), plane_f(pl, PL_LO_V));
    let phi = vec2<f32>(plane_f(pl, PL_HI_U), plane_f(pl, PL_HI_V));
    if f.lo.x > phi.x || f.hi.x < plo.x || f.lo.y > phi.y || f.hi.y < plo.y {
        return;
    }
    let org = vec2<f32>(bitcast<f32>(planes[b + PL_ORG_U]), bitcast<f32>(planes[b + PL_ORG_V]));
    let inv = vec2<f32>(bitcast<f32>(planes[b + PL_INV_U]), bitcast<f32>(planes[b + PL_INV_V]));
    let c0 = cell_of(f.lo.x, org.x, inv.x, gx);
    let c1 = cell_of(f.hi.x, org.x, inv.x, gx);
    let r0 = cell_of(f.lo.y, org.y, inv.y, gy);
    let r1 = cell_of(f.hi.y, org.y, inv.y, gy);
    let sb = planes[b + PL_SAT_BASE];
    let count = (sat_at(sb, gx, r1 + 1u, c1 + 1u) - sat_at(sb, gx, r0, c1 + 1u))
        - (sat_at(sb, gx, r1 + 1u, c0) - sat_at(sb, gx, r0, c0));
    let o = rec * RECORD_STRIDE;
    records[o] = bitcast<u32>(f.e0.x);
    records[o + 1u] = bitcast<u32>(f.e0.y);
    records[o + 2u] = bitcast<u32>(f.e0.z);
    records[o + 3u] = bitcast<u32>(f.e1.x);
    records[o + 4u] = bitcast<u32>(f.e1.y);
    records[o + 5u] = bitcast<u32>(f.e1.z);
    records[o + 6u] = bitcast<u32>(f.e2.x);
    records[o + 7u] = bitcast<u32>(f.e2.y);
    records[o + 8u] = bitcast<u32>(f.e2.z);
    records[o + 9u] = bitcast<u32>(f.lo.x);
    records[o + 10u] = bitcast<u32>(f.lo.y);
    records[o + 11u] = bitcast<u32>(f.hi.x);
    records[o + 12u] = bitcast<u32>(f.hi.y);
    records[o + 13u] = bitcast<u32>(f.zmin);
    records[o + 14u] = c0 | (c1 << 16u);
    records[o + 15u] = r0 | (r1 << 16u);
    // A triangle over few chunks is one work item that visits them in turn (one search
    // for its record instead of one a chunk); a larger one is an item a chunk.
    let small = count > 0u && count <= SMALL_RECORD;
    records[o + 16u] = pl | select(0u, 0x80000000u, small);
    records[o + 17u] = tri;
    items[rec] = select(count, 1u, small);
}

// One thread: the test's indirect dispatch for this batch's work items, 64 a workgroup,
// in rows of ROW threads; the item count in the fourth word.
@compute @workgroup_size(1)
fn dispatch_args() {
    let total = items[params.tri_count * params.n_planes];
    let groups = (total + 63u) / 64u;
    let x = min(groups, ROW / 64u);
    args[0] = x;
    args[1] = select(0u, (groups + x - 1u) / max(x, 1u), groups > 0u);
    args[2] = 1u;
    args[3] = total;
}
