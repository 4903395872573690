// gpu:subpixel, stage `silhouette_mask_map` (Pan et al. 2009, Section 3.2, Figure 4; the
// library's `silhouette_mask_map.rs`): a texel crossed by a silhouette edge is dropped as
// hidden when the depth map is nearer than the edge, by HIDDEN_SILHOUETTE_BIAS texels, at
// all 3×3 texel centres around it (`hidden`); then the summed-area table of the visible
// silhouette texels, a row pass and a column pass of integer sums (`sat_rows`,
// `sat_columns`). Composed after subpixel/{bindings, rasterization}.wgsl.

// The library's HIDDEN_SILHOUETTE_BIAS.
const HIDDEN_SILHOUETTE_BIAS: f32 = 2.0;

@compute @workgroup_size(64)
fn hidden(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = thread_index(gid);
    let r = fr.res;
    if t >= r * r * fr.views {
        return;
    }
    let inv = atomicLoad(&nearest[t]);
    if inv == 0u {
        sil_mask[t] = 0u;
        return;
    }
    let e = bitcast<f32>(~inv);
    if !finite(e) {
        sil_mask[t] = 0u;
        return;
    }
    let vi = t / (r * r);
    let x = t % r;
    let y = (t / r) % r;
    let bias = HIDDEN_SILHOUETTE_BIAS * texel_size(lviews[vi], e);
    var far = -BIG;
    for (var yy = max(y, 1u) - 1u; yy < min(y + 2u, r); yy++) {
        for (var xx = max(x, 1u) - 1u; xx < min(x + 2u, r); xx++) {
            far = max(far, map_depth(vi, xx, yy));
        }
    }
    let border = x == 0u || y == 0u || x + 1u == r || y + 1u == r;
    sil_mask[t] = select(1u, 2u, !border && far < e - bias);
}

@compute @workgroup_size(64)
fn sat_rows(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = thread_index(gid);
    let r = fr.res;
    if i >= r * fr.views {
        return;
    }
    let vi = i / r;
    let y = i % r;
    let w = r + 1u;
    let base = vi * w * w;
    var row = 0u;
    for (var x = 0u; x < r; x++) {
        row += u32(sil_mask[vi * r * r + y * r + x] == 1u);
        sat[base + (y + 1u) * w + x + 1u] = row;
    }
}

@compute @workgroup_size(64)
fn sat_columns(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = thread_index(gid);
    let r = fr.res;
    if i >= r * fr.views {
        return;
    }
    let vi = i / r;
    let x = i % r + 1u;
    let w = r + 1u;
    let base = vi * w * w;
    for (var y = 1u; y <= r; y++) {
        sat[base + y * w + x] += sat[base + (y - 1u) * w + x];
    }
}
