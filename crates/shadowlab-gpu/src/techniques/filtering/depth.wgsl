// gpu:vsm / evsm / msm / csm, stage `depth`: the light's depth map drawn by the hardware
// rasterizer, one render pass per light view (a layer of the map array), as gpu:sm draws
// it, but keeping what the encoders read: each texel's linear light depth (its bits) and
// its triangle, so the variance encoders find the neighbours on the same triangle as the
// library's do. The hardware depth test keeps the nearest caster (depth over the view's
// far plane); alpha-masked casters are discarded where cut. Composed after
// shaders/common/{alpha_mask, triangles}.wgsl.

struct FaceU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    depth_scale: f32,
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

struct Texel {
    // The linear depth's bits and the triangle.
    @location(0) texel: vec2<u32>,
    @builtin(frag_depth) depth: f32,
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
