// gpu:subpixel, stage `silhouette_edges` (Pan et al. 2009, Section 3.2; the library's
// `silhouette_edges.rs` and the drawing half of `silhouette_mask_map.rs`): each edge of
// the scene's adjacency (built once per scene on the CPU, as the CPU technique builds it)
// is a silhouette seen from the light when its two faces lie on one side of the plane
// through it and the light (boundary and non-manifold edges always are); each silhouette
// edge is rasterized conservatively into every light view's texels, keeping per texel
// the nearest edge depth (an integer max of inverted depth bits: order-independent).
// Composed after subpixel/{bindings, rasterization}.wgsl.

fn edge_point(buf_ends: bool, e: u32, k: u32) -> vec3<f32> {
    if buf_ends {
        let i = 6u * e + 3u * k;
        return vec3<f32>(edge_ends[i], edge_ends[i + 1u], edge_ends[i + 2u]);
    }
    let i = 7u * e + 1u + 3u * k;
    return vec3<f32>(edge_faces[i], edge_faces[i + 1u], edge_faces[i + 2u]);
}

fn is_silhouette(e: u32) -> bool {
    if edge_faces[7u * e] == 0.0 {
        return true;
    }
    let a = edge_point(true, e, 0u);
    let b = edge_point(true, e, 1u);
    let m = cross(b - a, toward_at(a));
    let s0 = dot3(m, edge_point(false, e, 0u) - a);
    let s1 = dot3(m, edge_point(false, e, 1u) - a);
    return s0 == 0.0 || s1 == 0.0 || (s0 > 0.0) == (s1 > 0.0);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = thread_index(gid);
    if e >= fr.edges || !is_silhouette(e) {
        return;
    }
    let r2 = fr.res * fr.res;
    var pts: array<vec3<f32>, 4>;
    pts[0] = edge_point(true, e, 0u);
    pts[1] = edge_point(true, e, 1u);
    for (var vi = 0u; vi < fr.views; vi++) {
        let poly = project(vi, pts, 2u);
        let rows = row_range(poly);
        for (var y = rows.x; y <= rows.y && rows.x <= rows.y; y++) {
            let s = row_span(poly, rows, y);
            if !s.some {
                continue;
            }
            let d = ~depth_bits(depth_span(vi, s.k0, s.k1).x);
            for (var x = s.x0; x <= s.x1; x++) {
                atomicMax(&nearest[vi * r2 + y * fr.res + x], d);
            }
        }
    }
}
