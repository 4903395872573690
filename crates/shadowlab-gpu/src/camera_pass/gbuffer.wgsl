// The GPU camera pass, stage `gbuffer`: the hardware rasterizer draws the scene from the
// camera into a G-buffer of triangle id, world position, face normal turned towards the
// camera, view depth, and the screen-space derivatives of the position (the hardware's
// dpdx/dpdy). The nearest surface wins the depth test; on equal depth the triangle drawn
// first (the lower index). Alpha-masked surfaces are discarded where cut out. Composed
// after shaders/common/{ray_offset, alpha_mask, triangles}.wgsl.

struct CameraU {
    clip_from_world: mat4x4<f32>,
    eye: vec3<f32>,
    // 1 for an orthographic camera (depth along `forward` from the eye's plane).
    ortho: u32,
    forward: vec3<f32>,
    masks: u32,
}

@group(0) @binding(0) var<uniform> cam: CameraU;
@group(0) @binding(1) var<storage, read> tris: array<f32>;
@group(0) @binding(2) var<storage, read> tri_material: array<u32>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(4) var<storage, read> uvs: array<f32>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) bary: vec3<f32>,
    @location(2) @interpolate(flat) tri: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Varyings {
    let tri = vi / 3u;
    let k = vi % 3u;
    let p = vertex(tri, k);
    var out: Varyings;
    out.clip = cam.clip_from_world * vec4<f32>(p, 1.0);
    out.world = p;
    out.bary = vec3<f32>(f32(k == 0u), f32(k == 1u), f32(k == 2u));
    out.tri = tri;
    return out;
}

struct GBuffer {
    @location(0) tri: u32,
    @location(1) position: vec4<f32>,
    @location(2) normal: vec4<f32>,
    @location(3) dpdx: vec4<f32>,
    @location(4) dpdy: vec4<f32>,
}

@fragment
fn fs(v: Varyings) -> GBuffer {
    // Derivatives before any discard, so neighbouring lanes stay in step.
    let dx = dpdx(v.world);
    let dy = dpdy(v.world);
    if cut_out(cam.masks, v.tri, v.bary) {
        discard;
    }
    let v0 = vertex(v.tri, 0u);
    let e1 = vertex(v.tri, 1u) - v0;
    let e2 = vertex(v.tri, 2u) - v0;
    var n = normalize(cross(e1, e2));
    var to_eye = cam.eye - v.world;
    if cam.ortho != 0u {
        to_eye = -cam.forward;
    }
    if dot(n, to_eye) < 0.0 {
        n = -n;
    }
    let depth = dot3(v.world - cam.eye, cam.forward);
    var g: GBuffer;
    g.tri = v.tri;
    g.position = vec4<f32>(v.world, depth);
    g.normal = vec4<f32>(n, 0.0);
    g.dpdx = vec4<f32>(dx, 0.0);
    g.dpdy = vec4<f32>(dy, 0.0);
    return g;
}

// The triangle id alone, for the pass whose samples stage `samples` forms on the device
// (`samples.wgsl`): one target of four bytes a pixel instead of the G-buffer's 68.
@fragment
fn fs_ids(v: Varyings) -> @location(0) u32 {
    if cut_out(cam.masks, v.tri, v.bary) {
        discard;
    }
    return v.tri;
}
