// gpu:psm, stage `post_map` (Stamminger & Drettakis 2002, Section 2: "generate a standard
// shadow map in this space by rendering a view from the transformed light source"): the
// hardware rasterizer draws the scene into one post-perspective map (a layer of the map
// array). A vertex's clip position is `clip_from_post · post_from_world · p`: the map's
// clip coordinates times the virtual camera's `w_p`, a positive factor wherever the map
// is defined, so the hardware's division lands where the CPU's does and its clipping
// (0 ≤ z ≤ w and the window) is the CPU's near, far and window clipping. Interpolated
// perspective-correctly, the varyings are affine in world space, so the fragment's
// post-space linear depth `(depth_world · p) / (w_row · p)` is exact, as on the CPU.
// Fragments nearer the virtual eye than the clip depth are discarded: the CPU clips the
// triangles there in world space before dividing, which the hardware cannot (its
// clipping is in the map's clip space); both keep the same part of each triangle.
// Depths are stored over the map's span (far − near), mirrored for an inverted light
// (the CPU negates them) so the hardware's `Less` test keeps the surface farthest from
// the light's image `q`. Composed after shaders/common/{alpha_mask, triangles}.wgsl.

struct PostFaceU {
    // clip_from_post · post_from_world: the map's clip coordinates times w_p.
    clip_from_world: mat4x4<f32>,
    // The post-space linear depth beyond the map's near plane times w_p.
    depth_world: vec4<f32>,
    // The virtual camera's w_p as a row on world points.
    w_row: vec4<f32>,
    // Fragments with w_p below this are discarded.
    clip_depth: f32,
    // The map's far minus near plane.
    span: f32,
    // 1 for an inverted post-space light.
    inverted: u32,
    // 1 when some material is alpha-masked.
    masks: u32,
}

@group(0) @binding(0) var<uniform> face: PostFaceU;
@group(0) @binding(1) var<storage, read> tris: array<f32>;
@group(0) @binding(2) var<storage, read> tri_material: array<u32>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(4) var<storage, read> uvs: array<f32>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    // depth_world · p and w_row · p: their ratio is the post-space linear depth.
    @location(0) depth_w: f32,
    @location(1) wp: f32,
    @location(2) bary: vec3<f32>,
    @location(3) @interpolate(flat) tri: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Varyings {
    let tri = vi / 3u;
    let k = vi % 3u;
    let p = vec4<f32>(vertex(tri, k), 1.0);
    var out: Varyings;
    out.clip = face.clip_from_world * p;
    out.depth_w = dot(face.depth_world, p);
    out.wp = dot(face.w_row, p);
    out.bary = vec3<f32>(f32(k == 0u), f32(k == 1u), f32(k == 2u));
    out.tri = tri;
    return out;
}

@fragment
fn fs(v: Varyings) -> @builtin(frag_depth) f32 {
    if !(v.wp >= face.clip_depth) || cut_out(face.masks, v.tri, v.bary) {
        discard;
    }
    let d = v.depth_w / v.wp / face.span;
    return clamp(select(d, 1.0 - d, face.inverted == 1u), 0.0, 1.0);
}
