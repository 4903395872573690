// gpu:pcss, stage `filtering`: percentage-closer filtering over the penumbra the blocker
// search estimated, the library's `pcss` filter: a square grid of taps spread over
// `radius` texels about the look-up, each a 2×2 comparison weighted bilinearly by the
// hardware (a comparison sampler, clamped at the map's edge as the CPU clamps), against
// the receiver's depth less a bias whose slope term grows with the kernel, as in `pcf`.
// Composed after shaders/common/{ray_offset, light}.wgsl and pcss/receiver.wgsl.

@group(0) @binding(4) var compare: sampler_comparison;
@group(0) @binding(5) var<storage, read> radii: array<f32>;
@group(0) @binding(6) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let radius = radii[k];
    if radius <= 0.0 {
        return;
    }
    let r = receiver(k);
    let d = r.depth - receiver_bias(r.texel, r.n, r.l, params.bias, params.slope_bias * (radius + 1.0));
    let d_ref = d / views[r.face].depth_scale;
    let nf = f32(params.res);
    let fx = r.u * nf;
    let fy = r.v * nf;
    let side = params.filter_side;
    var sum = 0.0;
    for (var j = 0u; j < side; j++) {
        let ty = fy + grid_offset(j, side) * radius;
        for (var i = 0u; i < side; i++) {
            let tx = fx + grid_offset(i, side) * radius;
            sum += textureSampleCompareLevel(map, compare, vec2<f32>(tx, ty) / nf, r.face, d_ref);
        }
    }
    let s = sum / f32(side * side);
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}
