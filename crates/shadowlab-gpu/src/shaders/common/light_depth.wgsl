// The light-view depth pass every hardware-rasterized map shares (gpu:sm's and the warped
// and split maps' `depth` stage, the filtered maps' `depth` stage, gpu:pcss, gpu:subpixel):
// one render pass per light view (a layer of the map array), the scene's triangles drawn
// by vertex index, each vertex carrying its linear light depth (distance from the view's
// eye plane), its barycentric corner for alpha-mask look-ups and its triangle. Composed
// after shaders/common/{alpha_mask, triangles}.wgsl; the stage adds the fragment shader.

struct FaceU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // Linear depths are divided by this before they are stored (the view's far plane).
    depth_scale: f32,
    // 1 when some material is alpha-masked.
    masks: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> face: FaceU;
@group(0) @binding(1) var<storage, read> tris: array<f32>;
@group(0) @binding(2) var<storage, read> tri_material: array<u32>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(4) var<storage, read> uvs: array<f32>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) depth: f32,
    @location(1) bary: vec3<f32>,
    @location(2) @interpolate(flat) tri: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Varyings {
    let tri = vi / 3u;
    let k = vi % 3u;
    let p = vec4<f32>(vertex(tri, k), 1.0);
    var out: Varyings;
    out.clip = face.clip_from_world * p;
    out.depth = -(face.light_from_world * p).z;
    out.bary = vec3<f32>(f32(k == 0u), f32(k == 1u), f32(k == 2u));
    out.tri = tri;
    return out;
}
