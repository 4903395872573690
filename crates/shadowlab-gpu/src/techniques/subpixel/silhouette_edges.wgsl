// gpu:subpixel, stage `silhouette_edges` (Pan et al. 2009, Section 3.2; the library's
// `silhouette_edges.rs` and the drawing half of `silhouette_mask_map.rs`): each edge of
// the scene's adjacency (built once per scene on the CPU, as the CPU technique builds it)
// is a silhouette seen from the light when its two faces lie on one side of the plane
// through it and the light (boundary and non-manifold edges always are); each silhouette
// edge is rasterized conservatively into every light view's texels, keeping per texel
// the nearest edge depth (an integer max of inverted depth bits: order-independent).
// Composed after subpixel/{bindings, rasterization}.wgsl.

fn is_silhouette(e: u32) -> bool {
    let a = edges[4u * e];
    if a.w == 0.0 {
        return true;
    }
    let b = edges[4u * e + 1u].xyz;
    let m = cross(b - a.xyz, toward_at(a.xyz));
    let s0 = dot3(m, edges[4u * e + 2u].xyz - a.xyz);
    let s1 = dot3(m, edges[4u * e + 3u].xyz - a.xyz);
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
    pts[0] = edges[4u * e].xyz;
    pts[1] = edges[4u * e + 1u].xyz;
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
