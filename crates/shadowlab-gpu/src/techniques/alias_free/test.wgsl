// gpu:afsm, stage `test` ("Rasterization of blockers", the per-sample half): one thread
// per item of the triangle–chunk work queue finds its triangle (binary search over the
// triangles' work prefix) and its chunk (binary search over the rows of the summed-area
// table), skips the chunk when all its samples are dark (the paper's occlusion culling),
// lie in front of the triangle, or lie outside its footprint, and decides every live
// sample under the footprint by the watertight test on the sample's own shadow ray, as
// gpu:raytrace decides it. `resolve` then averages each pixel's samples. Composed after
// shaders/common/{ray_offset, light, watertight, alpha_mask, triangles}.wgsl and grid.wgsl.

@group(0) @binding(0) var<uniform> params: AfsmParams;
@group(0) @binding(1) var<storage, read> planes: array<u32>;
@group(0) @binding(2) var<storage, read> tris: array<f32>;
@group(0) @binding(3) var<storage, read> tri_material: array<u32>;
@group(0) @binding(4) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(5) var<storage, read> uvs: array<f32>;
@group(0) @binding(6) var<storage, read> texels: array<u32>;
@group(0) @binding(7) var<storage, read> mat_q: array<u32>;
@group(0) @binding(8) var<storage, read> records: array<u32>;
@group(0) @binding(9) var<storage, read> items: array<u32>;
@group(0) @binding(10) var<storage, read> sat: array<u32>;
@group(0) @binding(11) var<storage, read> chunk_start: array<u32>;
@group(0) @binding(12) var<storage, read> chunks: array<u32>;
@group(0) @binding(13) var<storage, read_write> chunk_live: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> chunk_culled: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read> sorted_uvz: array<vec4<u32>>;
@group(0) @binding(16) var<storage, read> sorted_ray: array<u32>;
@group(0) @binding(17) var<storage, read_write> dark: array<atomic<u32>>;
@group(0) @binding(18) var<storage, read_write> logs: array<atomic<u32>>;
@group(0) @binding(19) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(20) var<storage, read> s_cell: array<u32>;
@group(0) @binding(21) var<storage, read> s_rank: array<u32>;
@group(0) @binding(22) var<storage, read> cell_start: array<u32>;
@group(0) @binding(23) var<storage, read> pixel_start: array<u32>;
@group(0) @binding(24) var<storage, read_write> out: array<f32>;

const RECORD_STRIDE: u32 = 18u;
const CHUNK_STRIDE: u32 = 8u;
// Semi-transparent casters: each channel's transmittance as −log2 in units of 2^-20
// (formed on the CPU), summed with saturating integer atomics: the sum of the same terms
// in any order, so the product is the same bits whatever order threads meet its casters.
const LOG_UNIT: f32 = 1048576.0;
// A channel whose sum reaches this (a transmittance below 2^-150) is black.
const LOG_CAP: u32 = 157286400u;
// Counters, each two words (low, high): cells visited, cells skipped because every
// sample was dark (occlusion culling), cells skipped because every sample lay in front
// of the triangle, samples tested, exact ray tests, work items.
const C_VISITED: u32 = 0u;
const C_CULLED: u32 = 1u;
const C_DEPTH: u32 = 2u;
const C_TESTED: u32 = 3u;
const C_RAYS: u32 = 4u;
const C_ITEMS: u32 = 5u;
const N_COUNTERS: u32 = 6u;

var<workgroup> wcount: array<atomic<u32>, 6>;

// Adds `q` to the channel word `w`, saturating at LOG_CAP; the new value.
fn add_log(w: u32, q: u32) -> u32 {
    var old = atomicLoad(&logs[w]);
    loop {
        if old >= LOG_CAP {
            return LOG_CAP;
        }
        let next = min(old + min(q, LOG_CAP), LOG_CAP);
        let r = atomicCompareExchangeWeak(&logs[w], old, next);
        if r.exchanged {
            return next;
        }
        old = r.old_value;
    }
    return LOG_CAP;
}

// Sample `pos` (of chunk `chunk`) goes dark; the first to darken it counts it off the
// chunk's live samples.
fn darken(pos: u32, chunk: u32) {
    if atomicMax(&dark[pos], 1u) == 0u {
        atomicSub(&chunk_live[chunk], 1u);
    }
}

fn sat_at(sb: u32, gx: u32, r: u32, c: u32) -> u32 {
    return sat[sb + r * (gx + 1u) + c];
}

struct Local {
    visited: u32,
    culled: u32,
    depth: u32,
    tested: u32,
    rays: u32,
}

fn rec_f(o: u32) -> f32 {
    return bitcast<f32>(records[o]);
}

// Work item `j`: the triangle of its record against one chunk of one cell, or, for a
// record marked small, against every chunk under its rectangle in turn.
fn item(j: u32, acc: ptr<function, Local>) {
    let n_rec = params.tri_count * params.n_planes;
    var lo = 0u;
    var hi = n_rec - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if items[mid + 1u] > j {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    let rec = lo;
    let jr = j - items[rec];
    let o = rec * RECORD_STRIDE;
    let cc = records[o + 14u];
    let rr = records[o + 15u];
    let c0 = cc & 0xffffu;
    let c1 = cc >> 16u;
    let r0 = rr & 0xffffu;
    let r1 = rr >> 16u;
    let pl = records[o + 16u] & 0x7fffffffu;
    let small = (records[o + 16u] >> 31u) != 0u;
    let tri = records[o + 17u];
    let b = pl * PLANE_STRIDE;
    let gx = planes[b + PL_GX];
    let base = planes[b + PL_CELL_BASE];
    if small {
        for (var r = r0; r <= r1; r++) {
            let first = chunk_start[base + r * gx + c0];
            let end = chunk_start[base + r * gx + c1 + 1u];
            for (var chunk = first; chunk < end; chunk++) {
                chunk_test(o, tri, chunk, acc);
            }
        }
        return;
    }
    let sb = planes[b + PL_SAT_BASE];
    let base0 = sat_at(sb, gx, r0, c1 + 1u) - sat_at(sb, gx, r0, c0);
    // The row: the first whose rows up to it hold more than `jr` chunks.
    var ra = r0;
    var rb = r1;
    while ra < rb {
        let mid = (ra + rb) / 2u;
        let upto = (sat_at(sb, gx, mid + 1u, c1 + 1u) - sat_at(sb, gx, mid + 1u, c0)) - base0;
        if upto > jr {
            rb = mid;
        } else {
            ra = mid + 1u;
        }
    }
    let row = ra;
    let before = (sat_at(sb, gx, row, c1 + 1u) - sat_at(sb, gx, row, c0)) - base0;
    chunk_test(o, tri, chunk_start[base + row * gx + c0] + (jr - before), acc);
}

// The triangle of the record at `o` (triangle `tri`) against chunk `chunk`.
fn chunk_test(o: u32, tri: u32, chunk: u32, acc: ptr<function, Local>) {
    let ch = chunk * CHUNK_STRIDE;
    let zmin = rec_f(o + 13u);
    if zmin > bitcast<f32>(chunks[ch + 6u]) {
        (*acc).depth += 1u;
        return;
    }
    if atomicLoad(&chunk_live[chunk]) == 0u {
        (*acc).culled += 1u;
        atomicAdd(&chunk_culled[chunk], 1u);
        return;
    }
    let blo = bitcast<vec2<f32>>(vec2<u32>(chunks[ch + 2u], chunks[ch + 3u]));
    let bhi = bitcast<vec2<f32>>(vec2<u32>(chunks[ch + 4u], chunks[ch + 5u]));
    let tlo = vec2<f32>(rec_f(o + 9u), rec_f(o + 10u));
    let thi = vec2<f32>(rec_f(o + 11u), rec_f(o + 12u));
    if tlo.x > bhi.x || thi.x < blo.x || tlo.y > bhi.y || thi.y < blo.y {
        return;
    }
    let e0 = vec3<f32>(rec_f(o), rec_f(o + 1u), rec_f(o + 2u));
    let e1 = vec3<f32>(rec_f(o + 3u), rec_f(o + 4u), rec_f(o + 5u));
    let e2 = vec3<f32>(rec_f(o + 6u), rec_f(o + 7u), rec_f(o + 8u));
    let es = array<vec3<f32>, 3>(e0, e1, e2);
    for (var k = 0u; k < 3u; k++) {
        let e = es[k];
        let m = e.z + max(e.x * blo.x, e.x * bhi.x) + max(e.y * blo.y, e.y * bhi.y);
        if m < 0.0 {
            return;
        }
    }
    (*acc).visited += 1u;
    let v0 = vertex(tri, 0u);
    let v1 = vertex(tri, 1u);
    let v2 = vertex(tri, 2u);
    let mat = tri_material[tri];
    let opaque = materials[mat].opaque != 0u;
    let first = chunks[ch];
    let n = chunks[ch + 1u];
    for (var k = 0u; k < n; k++) {
        let pos = first + k;
        if atomicLoad(&dark[pos]) != 0u {
            continue;
        }
        (*acc).tested += 1u;
        let s = sorted_uvz[pos];
        let u = bitcast<f32>(s.x);
        let v = bitcast<f32>(s.y);
        let z = bitcast<f32>(s.z);
        let inside = z >= zmin && u >= tlo.x && u <= thi.x && v >= tlo.y && v <= thi.y
            && e0.x * u + e0.y * v + e0.z >= 0.0
            && e1.x * u + e1.y * v + e1.z >= 0.0
            && e2.x * u + e2.y * v + e2.z >= 0.0;
        if !inside || s.w == tri {
            continue;
        }
        (*acc).rays += 1u;
        let rb8 = pos * 8u;
        let ro = bitcast<vec3<f32>>(vec3<u32>(sorted_ray[rb8], sorted_ray[rb8 + 1u], sorted_ray[rb8 + 2u]));
        let kk = sorted_ray[rb8 + 3u];
        let sh = Shear(vec3<u32>(kk & 3u, (kk >> 2u) & 3u, (kk >> 4u) & 3u),
                       bitcast<vec3<f32>>(vec3<u32>(sorted_ray[rb8 + 4u], sorted_ray[rb8 + 5u], sorted_ray[rb8 + 6u])));
        let t_max = bitcast<f32>(sorted_ray[rb8 + 7u]);
        let h = intersect_sheared(ro, sh, 0.0, t_max, v0, v1, v2);
        if !h.ok || cut_out(params.masks, tri, h.b) {
            continue;
        }
        if opaque {
            darken(pos, chunk);
        } else {
            let r = add_log(pos * 3u, mat_q[mat * 4u]);
            let g = add_log(pos * 3u + 1u, mat_q[mat * 4u + 1u]);
            let bl = add_log(pos * 3u + 2u, mat_q[mat * 4u + 2u]);
            if r >= LOG_CAP && g >= LOG_CAP && bl >= LOG_CAP {
                darken(pos, chunk);
            }
        }
    }
}

fn count64(c: u32, v: u32) {
    if v == 0u {
        return;
    }
    let old = atomicAdd(&counters[2u * c], v);
    if old + v < old {
        atomicAdd(&counters[2u * c + 1u], 1u);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    if li < N_COUNTERS {
        atomicStore(&wcount[li], 0u);
    }
    workgroupBarrier();
    let j = linear_id(gid);
    var acc = Local(0u, 0u, 0u, 0u, 0u);
    if j < items[params.tri_count * params.n_planes] {
        item(j, &acc);
        atomicAdd(&wcount[C_ITEMS], 1u);
    }
    atomicAdd(&wcount[C_VISITED], acc.visited);
    atomicAdd(&wcount[C_CULLED], acc.culled);
    atomicAdd(&wcount[C_DEPTH], acc.depth);
    atomicAdd(&wcount[C_TESTED], acc.tested);
    atomicAdd(&wcount[C_RAYS], acc.rays);
    workgroupBarrier();
    if li < N_COUNTERS {
        count64(li, atomicLoad(&wcount[li]));
    }
}

// A lit sample's transmittance from its state: dark, else 2^-(its channels' sums).
fn sample_value(i: u32) -> vec3<f32> {
    let cell = s_cell[i];
    if cell == UNCOVERED {
        return vec3<f32>(1.0);
    }
    if cell == UNLIT {
        return vec3<f32>(0.0);
    }
    let pos = cell_start[cell] + s_rank[i];
    if atomicLoad(&dark[pos]) != 0u {
        return vec3<f32>(0.0);
    }
    var t = vec3<f32>(1.0);
    for (var c = 0u; c < 3u; c++) {
        let s = atomicLoad(&logs[pos * 3u + c]);
        if s >= LOG_CAP {
            t[c] = 0.0;
        } else if s > 0u {
            t[c] = exp2(-f32(s >> 20u)) * exp2(-f32(s & 0xfffffu) / LOG_UNIT);
        }
    }
    return t;
}

// Each pixel's shadow term: its one sample, or the mean of its sub-pixel samples in the
// pattern's order (the reference's sum), 1 for a pixel that shows no surface.
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = linear_id(gid);
    if k >= params.n_pixels {
        return;
    }
    var first = k;
    var end = k + 1u;
    if params.identity == 0u {
        first = pixel_start[k];
        end = pixel_start[k + 1u];
    }
    var v = vec3<f32>(1.0);
    if end == first + 1u {
        v = sample_value(first);
    } else if end > first {
        var sum = vec3<f32>(0.0);
        for (var i = first; i < end; i++) {
            sum += sample_value(i);
        }
        v = sum / f32(end - first);
    }
    out[k * 3u] = v.x;
    out[k * 3u + 1u] = v.y;
    out[k * 3u + 2u] = v.z;
}
