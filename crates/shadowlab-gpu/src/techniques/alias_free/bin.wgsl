// gpu:afsm, stage `bin` (the paper's light-space hierarchy, Section 5.1, as a uniform
// grid): the plan sizes each light plane's grid to its samples; a counting sort (a count
// per cell, a prefix sum, a scatter) lays every cell's samples out contiguously, with no
// linked list; each cell's list is cut into chunks of at most `leaf` samples, each with
// the tight rectangle and greatest depth of its samples and a count of samples still
// lit; a summed-area table of chunk counts lets a triangle count, and its threads find,
// the chunks under any rectangle of cells in constant and logarithmic time. Composed
// after shaders/common/{ray_offset, light}.wgsl and grid.wgsl.

@group(0) @binding(0) var<uniform> params: AfsmParams;
@group(0) @binding(1) var<storage, read_write> planes: array<u32>;
@group(0) @binding(2) var<storage, read> s_uvz: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> s_ray: array<u32>;
@group(0) @binding(4) var<storage, read_write> s_cell: array<u32>;
@group(0) @binding(5) var<storage, read_write> s_rank: array<u32>;
@group(0) @binding(6) var<storage, read_write> cell_start: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> chunk_start: array<u32>;
@group(0) @binding(8) var<storage, read_write> chunks: array<u32>;
@group(0) @binding(9) var<storage, read_write> chunk_live: array<u32>;
@group(0) @binding(10) var<storage, read_write> sat: array<u32>;
@group(0) @binding(11) var<storage, read_write> sorted_uvz: array<vec4<u32>>;
@group(0) @binding(12) var<storage, read_write> sorted_ray: array<u32>;
@group(0) @binding(13) var<storage, read> samples: array<u32>;

// Words a chunk record holds: first sample, count, lo u, lo v, hi u, hi v, greatest
// depth, cell.
const CHUNK_STRIDE: u32 = 8u;

// One thread: each plane's grid, as square in cells as its samples' rectangle allows,
// about `cell_target` samples a cell, and where its cells and summed-area table start.
@compute @workgroup_size(1)
fn plan() {
    var cells = 0u;
    var sat_words = 0u;
    var far = 0u;
    for (var pl = 0u; pl < params.n_planes; pl++) {
        let b = pl * PLANE_STRIDE;
        let n = planes[b + PL_COUNT];
        far = max(far, planes[b + PL_FAR]);
        var gx = 0u;
        var gy = 0u;
        var org = vec2<f32>(0.0);
        var inv = vec2<f32>(0.0);
        if n > 0u {
            let lo = vec2<f32>(dec(planes[b + PL_LO_U]), dec(planes[b + PL_LO_V]));
            let hi = vec2<f32>(dec(planes[b + PL_HI_U]), dec(planes[b + PL_HI_V]));
            let ext = hi - lo;
            let want = max(1u, u32(f32(n) / params.cell_target));
            let side = min(want, MAX_SIDE);
            if ext.x > 0.0 && ext.y > 0.0 && finite(ext.x) && finite(ext.y) {
                let g = sqrt(f32(want) * (ext.x / ext.y));
                gx = clamp(u32(round(g)), 1u, side);
            } else if ext.x > 0.0 && finite(ext.x) {
                gx = side;
            } else {
                gx = 1u;
            }
            gy = clamp(want / gx, 1u, MAX_SIDE);
            org = lo;
            if ext.x > 0.0 && finite(ext.x) {
                inv.x = f32(gx) / ext.x;
            }
            if ext.y > 0.0 && finite(ext.y) {
                inv.y = f32(gy) / ext.y;
            }
        }
        planes[b + PL_GX] = gx;
        planes[b + PL_GY] = gy;
        planes[b + PL_CELL_BASE] = cells;
        planes[b + PL_SAT_BASE] = sat_words;
        planes[b + PL_ORG_U] = bitcast<u32>(org.x);
        planes[b + PL_ORG_V] = bitcast<u32>(org.y);
        planes[b + PL_INV_U] = bitcast<u32>(inv.x);
        planes[b + PL_INV_V] = bitcast<u32>(inv.y);
        cells += gx * gy;
        if gx > 0u {
            sat_words += (gx + 1u) * (gy + 1u);
        }
    }
    planes[PL_FAR] = far;
    planes[PL_TOTAL_CELLS] = cells;
}

// The global cell of a sample at `(u, v)` on plane `pl`.
fn sample_cell(pl: u32, u: f32, v: f32) -> u32 {
    let b = pl * PLANE_STRIDE;
    let gx = planes[b + PL_GX];
    let gy = planes[b + PL_GY];
    let cx = cell_of(u, bitcast<f32>(planes[b + PL_ORG_U]), bitcast<f32>(planes[b + PL_INV_U]), gx);
    let cy = cell_of(v, bitcast<f32>(planes[b + PL_ORG_V]), bitcast<f32>(planes[b + PL_INV_V]), gy);
    return planes[b + PL_CELL_BASE] + cy * gx + cx;
}

// Counting sort, pass one: each lit sample's cell and its rank among the cell's samples.
@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = linear_id(gid);
    if i >= params.n_samples {
        return;
    }
    let s = s_uvz[i];
    let state = s.w;
    if state >= UNCOVERED {
        s_cell[i] = state;
        return;
    }
    let cell = sample_cell(state, bitcast<f32>(s.x), bitcast<f32>(s.y));
    s_cell[i] = cell;
    s_rank[i] = atomicAdd(&cell_start[cell], 1u);
}

// Counting sort, pass two (after the prefix sum of the counts): every lit sample's
// position, shadow ray and own triangle moved to its place in its cell's list.
@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = linear_id(gid);
    if i >= params.n_samples {
        return;
    }
    let cell = s_cell[i];
    if cell >= UNCOVERED {
        return;
    }
    let pos = atomicLoad(&cell_start[cell]) + s_rank[i];
    let s = s_uvz[i];
    sorted_uvz[pos] = vec4<u32>(s.xyz, samples[i * 10u + 9u]);
    for (var k = 0u; k < 8u; k++) {
        sorted_ray[pos * 8u + k] = s_ray[i * 8u + k];
    }
}

fn cell_samples(c: u32) -> vec2<u32> {
    let first = atomicLoad(&cell_start[c]);
    return vec2<u32>(first, atomicLoad(&cell_start[c + 1u]) - first);
}

// Each cell's chunks: its samples in runs of at most `leaf`.
@compute @workgroup_size(64)
fn chunk_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = linear_id(gid);
    if c >= planes[PL_TOTAL_CELLS] {
        return;
    }
    let n = cell_samples(c).y;
    chunk_start[c] = (n + params.leaf - 1u) / params.leaf;
}

// After the prefix sum of chunk counts: each chunk's samples and cell.
@compute @workgroup_size(64)
fn chunk_cells(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = linear_id(gid);
    if c >= planes[PL_TOTAL_CELLS] {
        return;
    }
    let cs = cell_samples(c);
    let first = chunk_start[c];
    let n = chunk_start[c + 1u] - first;
    for (var j = 0u; j < n; j++) {
        let r = (first + j) * CHUNK_STRIDE;
        chunks[r] = cs.x + j * params.leaf;
        chunks[r + 1u] = min(params.leaf, cs.y - j * params.leaf);
        chunks[r + 7u] = c;
    }
}

// Each chunk's tight rectangle and greatest depth; all its samples start lit.
@compute @workgroup_size(64)
fn chunk_boxes(@builtin(global_invocation_id) gid: vec3<u32>) {
    let id = linear_id(gid);
    if id >= chunk_start[planes[PL_TOTAL_CELLS]] {
        return;
    }
    let r = id * CHUNK_STRIDE;
    let first = chunks[r];
    let n = chunks[r + 1u];
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    var zmax = -3.0e38;
    for (var k = 0u; k < n; k++) {
        let s = bitcast<vec3<f32>>(sorted_uvz[first + k].xyz);
        lo = min(lo, s.xy);
        hi = max(hi, s.xy);
        zmax = max(zmax, s.z);
    }
    chunks[r + 2u] = bitcast<u32>(lo.x);
    chunks[r + 3u] = bitcast<u32>(lo.y);
    chunks[r + 4u] = bitcast<u32>(hi.x);
    chunks[r + 5u] = bitcast<u32>(hi.y);
    chunks[r + 6u] = bitcast<u32>(zmax);
    chunk_live[id] = n;
}

// The summed-area table of chunk counts, one thread a column of a plane's grid (and the
// column past its last): entry (r, c) counts the chunks of the cells in rows below r and
// columns below c.
@compute @workgroup_size(64)
fn sat_columns(@builtin(global_invocation_id) gid: vec3<u32>) {
    var idx = linear_id(gid);
    var pl = 0u;
    loop {
        if pl >= params.n_planes {
            return;
        }
        let gx = planes[pl * PLANE_STRIDE + PL_GX];
        let w = select(0u, gx + 1u, gx > 0u);
        if idx < w {
            break;
        }
        idx -= w;
        pl++;
    }
    let b = pl * PLANE_STRIDE;
    let gx = planes[b + PL_GX];
    let gy = planes[b + PL_GY];
    let base = planes[b + PL_CELL_BASE];
    let sb = planes[b + PL_SAT_BASE];
    var acc = 0u;
    for (var r = 0u; r < gy; r++) {
        sat[sb + r * (gx + 1u) + idx] = acc;
        let row = base + r * gx;
        acc += chunk_start[row + idx] - chunk_start[row];
    }
    sat[sb + gy * (gx + 1u) + idx] = acc;
}
