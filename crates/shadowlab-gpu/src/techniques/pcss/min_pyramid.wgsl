// gpu:pcss, stage `min_pyramid`: one level of the min-depth pyramid the blocker search
// bounds its region with (the library's `MinPyramid`): texel (x, y) of level l + 1 is the
// nearest of texels (2x, 2y) to (2x + 1, 2y + 1) of level l, an odd last row or column
// paired with itself. Level 0 is the map; the levels after it lie in one buffer, each
// layer's levels together. No common files.

struct Reduce {
    // Sides of the level read and the level written.
    side_in: u32,
    side_out: u32,
    // Offsets of the two levels in a layer's part of the pyramid (level 0: the map).
    offset_in: u32,
    offset_out: u32,
    layer_stride: u32,
    layers: u32,
    row: u32,
    // 1 when the level read is the map.
    from_map: u32,
}

@group(0) @binding(0) var<uniform> r: Reduce;
@group(0) @binding(1) var map: texture_depth_2d_array;
@group(0) @binding(2) var<storage, read_write> pyramid: array<f32>;

fn read(layer: u32, x: u32, y: u32) -> f32 {
    if r.from_map == 1u {
        return textureLoad(map, vec2<u32>(x, y), layer, 0);
    }
    return pyramid[layer * r.layer_stride + r.offset_in + y * r.side_in + x];
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * r.row + gid.x;
    let per_layer = r.side_out * r.side_out;
    if k >= per_layer * r.layers {
        return;
    }
    let layer = k / per_layer;
    let i = k % per_layer;
    let x = i % r.side_out;
    let y = i / r.side_out;
    let x0 = 2u * x;
    let y0 = 2u * y;
    let x1 = min(x0 + 1u, r.side_in - 1u);
    let y1 = min(y0 + 1u, r.side_in - 1u);
    let m = min(min(read(layer, x0, y0), read(layer, x1, y0)), min(read(layer, x0, y1), read(layer, x1, y1)));
    pyramid[layer * r.layer_stride + r.offset_out + y * r.side_out + x] = m;
}
