// gpu:vsm / evsm / msm / csm, stage `depth`: the light's depth map drawn by the hardware
// rasterizer, one render pass per light view (a layer of the map array), as gpu:sm draws
// it, but keeping what the encoders read: each texel's linear light depth (its bits) and
// its triangle, so the variance encoders find the neighbours on the same triangle as the
// library's do. The hardware depth test keeps the nearest caster (depth over the view's
// far plane); alpha-masked casters are discarded where cut. Composed after
// shaders/common/{alpha_mask, triangles, light_depth}.wgsl.

struct Texel {
    // The linear depth's bits and the triangle.
    @location(0) texel: vec2<u32>,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs(v: Varyings) -> Texel {
    if cut_out(face.masks, v.tri, v.bary) {
        discard;
    }
    var out: Texel;
    out.texel = vec2<u32>(bitcast<u32>(v.depth), v.tri);
    out.depth = clamp(v.depth / face.depth_scale, 0.0, 1.0);
    return out;
}
