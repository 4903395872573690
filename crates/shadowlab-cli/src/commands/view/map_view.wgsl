// A layer of a technique's depth maps as a grey picture for the panel: each texel of the
// picture reads the map's texel at the same place scaled (nearest), near dark, far white.

struct Pick {
    // The layer shown.
    layer: u32,
    // The map's side in texels.
    side: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var map: texture_depth_2d_array;
@group(0) @binding(1) var picture: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(2) var<uniform> pick: Pick;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(picture);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let at = vec2<i32>(id.xy * pick.side / size);
    let d = textureLoad(map, at, i32(pick.layer), 0);
    textureStore(picture, vec2<i32>(id.xy), vec4<f32>(d, d, d, 1.0));
}
