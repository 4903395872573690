// gpu:subpixel, stage `pairs` (Pan et al. 2009, Section 3.3; the library's `pairs.rs`):
// pixel–texel pairs, each facet rasterized conservatively into its view's texels; a facet
// that touches no silhouette texel after all takes the depth-map test, the others mark
// their texels with their farthest depth (`pixel_texels`); the marked texels get slots
// (`slots`); triangle–texel pairs, every triangle rasterized the same way against the
// slotted texels it can be nearer than (a large one by blocks of rows, `big_blocks`),
// counted per slot, the counts scanned into starts (`scan_blocks`, `scan`, `scan_slots`),
// filled (`triangle_texels_main` and `big_blocks` again). Slot numbers and the order of a
// slot's triangles vary from run to run; what a slot holds does not, and the evaluation
// does not depend on the order. Composed after subpixel/{bindings, rasterization}.wgsl.

// A triangle pairs with a texel when it is nearer than the farthest facet there, by this
// share of that depth more than the CPU asks: the GPU may round a facet's or a
// triangle's light depth differently, and a caster standing on the receiver (a chess
// piece on the board) is as deep as the facets under it, where the rounding would decide
// whether it is paired and so whether its crease drops samples. A pair too many is only
// evaluated (the evaluation is exact), a pair too few loses a blocker.
const PAIR_DEPTH_MARGIN: f32 = 1e-5;

@compute @workgroup_size(64)
fn pixel_texels(@builtin(global_invocation_id) gid: vec3<u32>) {
    let fi = thread_index(gid);
    if fi >= fr.pixels || facets[fi].alive == 0u {
        return;
    }
    let poly = facet_poly(fi);
    let vi = facets[fi].view;
    let base = vi * fr.res * fr.res;
    let rows = row_range(poly);
    var touches = false;
    for (var y = rows.x; y <= rows.y && rows.x <= rows.y && !touches; y++) {
        let s = row_span(poly, rows, y);
        for (var x = s.x0; x <= s.x1 && s.some; x++) {
            touches = touches || sil_mask[base + y * fr.res + x] == 1u;
        }
    }
    if !touches {
        facets[fi].alive = 0u;
        write_out(facets[fi].k, depth_test(facets[fi].k, vi));
        return;
    }
    let d = depth_bits(facets[fi].depth_max);
    for (var y = rows.x; y <= rows.y && rows.x <= rows.y; y++) {
        let s = row_span(poly, rows, y);
        for (var x = s.x0; x <= s.x1 && s.some; x++) {
            atomicMax(&max_depth[base + y * fr.res + x], d);
        }
    }
}

@compute @workgroup_size(64)
fn slots(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = thread_index(gid);
    if t >= fr.res * fr.res * fr.views {
        return;
    }
    if atomicLoad(&max_depth[t]) == 0u {
        slot[t] = 0u;
    } else {
        slot[t] = atomicAdd(&counters[1], 1u) + 1u;
    }
}

// Software adapters end every loop of an invocation once its loops together have turned
// 65535 times (llvmpipe's LP_MAX_TGSI_LOOP_ITERATIONS, one count shared by every loop of
// a shader): a triangle as large as the map (a ground plane) would lose the rows past
// that count, and with them its pairs. So a triangle whose texel rows do not fit one
// block of about BLOCK_TEXELS texels is listed by its blocks of rows, each rasterized by
// its own invocation (`big_blocks`); on a hardware GPU this also spreads a large
// triangle's work over many threads.
const BLOCK_TEXELS: u32 = 32768u;

// Rows a block holds at this resolution (one row at least: a row of the largest map an
// adapter allows is within the count).
fn block_rows() -> u32 {
    return max(1u, BLOCK_TEXELS / (fr.res + 16u));
}

// Triangle-view pair `i` (triangle `i / views` in view `i % views`): its projected
// polygon and the rows it covers.
struct Footprint {
    tri: u32,
    vi: u32,
    poly: Poly,
    rows: vec2<u32>,
}

fn footprint(i: u32) -> Footprint {
    let tri = i / fr.views;
    let vi = i % fr.views;
    var pts: array<vec3<f32>, 4>;
    pts[0] = vertex(tri, 0u);
    pts[1] = vertex(tri, 1u);
    pts[2] = vertex(tri, 2u);
    let poly = project(vi, pts, 3u);
    return Footprint(tri, vi, poly, row_range(poly));
}

// Rows y0..=y1 of footprint `fp` against the slotted texels: counts (fill = false) or
// writes (fill = true) its pairs.
fn pair_rows(fp: Footprint, y0: u32, y1: u32, fill: bool) {
    let base = fp.vi * fr.res * fr.res;
    for (var y = y0; y <= y1; y++) {
        let s = row_span(fp.poly, fp.rows, y);
        if !s.some {
            continue;
        }
        let dmin = depth_span(fp.vi, s.k0, s.k1).x;
        for (var x = s.x0; x <= s.x1; x++) {
            let t = base + y * fr.res + x;
            let sl = slot[t];
            let far = bitcast<f32>(atomicLoad(&max_depth[t]));
            if sl != 0u && dmin < far + PAIR_DEPTH_MARGIN * abs(far) {
                let at = atomicAdd(&slot_fill[sl - 1u], 1u);
                if fill {
                    pairs[slot_start[sl - 1u] + at] = fp.tri;
                }
            }
        }
    }
}

// The pass over triangle-view pairs, in the mode `counters[3]` holds: 0 counts the pairs
// of triangles within one block and the blocks of the others; 1 lists those blocks (in
// `big`, for `big_blocks`); 2 fills the pairs of the one-block triangles. Count and fill
// run the same code, so both find the same texels: a driver may round a separately
// compiled copy differently.
@compute @workgroup_size(64)
fn triangle_texels_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = thread_index(gid);
    if i >= fr.triangles * fr.views {
        return;
    }
    let mode = atomicLoad(&counters[3]);
    let fp = footprint(i);
    if fp.rows.x > fp.rows.y {
        return;
    }
    let nb = (fp.rows.y - fp.rows.x) / block_rows() + 1u;
    if nb == 1u {
        if mode != 1u {
            pair_rows(fp, fp.rows.x, fp.rows.y, mode == 2u);
        }
        return;
    }
    if mode == 0u {
        atomicAdd(&counters[4], nb);
    } else if mode == 1u {
        let at = atomicAdd(&counters[5], nb);
        for (var j = 0u; j < nb; j++) {
            big[at + j] = vec2<u32>(i, j);
        }
    }
}

// Sets mode 1 for the pass that lists the blocks.
@compute @workgroup_size(1)
fn list_mode() {
    atomicStore(&counters[3], 1u);
}

// One block of rows of a listed triangle: counts its pairs in mode 1, fills them in mode
// 2.
@compute @workgroup_size(64)
fn big_blocks(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = thread_index(gid);
    if e >= atomicLoad(&counters[4]) {
        return;
    }
    let fp = footprint(big[e].x);
    let y0 = fp.rows.x + big[e].y * block_rows();
    let y1 = min(fp.rows.y, y0 + block_rows() - 1u);
    pair_rows(fp, y0, y1, atomicLoad(&counters[3]) == 2u);
}

// Slots are scanned in blocks of SCAN_BLOCK: each block's total (`scan_blocks`, one
// thread a block), the totals into block starts (`scan`, one thread), then each block's
// own starts (`scan_slots`, one thread a block), the counts cleared for the fill. The
// block totals live in `nearest`, which the silhouette mask map no longer needs.
const SCAN_BLOCK: u32 = 256u;

@compute @workgroup_size(64)
fn scan_blocks(@builtin(global_invocation_id) gid: vec3<u32>) {
    let blk = thread_index(gid);
    let n = atomicLoad(&counters[1]);
    if blk * SCAN_BLOCK >= n {
        return;
    }
    var sum = 0u;
    for (var s = blk * SCAN_BLOCK; s < min(n, (blk + 1u) * SCAN_BLOCK); s++) {
        sum += atomicLoad(&slot_fill[s]);
    }
    atomicStore(&nearest[blk], sum);
}

@compute @workgroup_size(1)
fn scan(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = atomicLoad(&counters[1]);
    let blocks = (n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    var sum = 0u;
    for (var b = 0u; b < blocks; b++) {
        let t = atomicLoad(&nearest[b]);
        atomicStore(&nearest[b], sum);
        sum += t;
    }
    slot_start[n] = sum;
    atomicStore(&counters[2], sum);
    atomicStore(&counters[3], 2u);
}

@compute @workgroup_size(64)
fn scan_slots(@builtin(global_invocation_id) gid: vec3<u32>) {
    let blk = thread_index(gid);
    let n = atomicLoad(&counters[1]);
    if blk * SCAN_BLOCK >= n {
        return;
    }
    var sum = atomicLoad(&nearest[blk]);
    for (var s = blk * SCAN_BLOCK; s < min(n, (blk + 1u) * SCAN_BLOCK); s++) {
        slot_start[s] = sum;
        sum += atomicLoad(&slot_fill[s]);
        atomicStore(&slot_fill[s], 0u);
    }
}
