// gpu:sm / gpu:pcf, stage `depth`: the light's depth map drawn by the hardware
// rasterizer, one render pass per light view (a layer of the map array). The map holds the
// library's linear depth (distance from the view's eye plane) divided by the view's
// `depth_scale`, written as the fragment's depth, so the nearest caster wins the hardware
// depth test and the look-up compares linear depths as the CPU does. Alpha-masked
// casters are discarded where their texture cuts them out, at the fragment's perspective-
// correct barycentrics. Composed after shaders/common/{alpha_mask, triangles,
// light_depth}.wgsl.

@fragment
fn fs(v: Varyings) -> @builtin(frag_depth) f32 {
    if cut_out(face.masks, v.tri, v.bary) {
        discard;
    }
    return clamp(v.depth / face.depth_scale, 0.0, 1.0);
}
