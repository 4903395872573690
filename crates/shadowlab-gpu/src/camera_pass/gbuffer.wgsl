// The GPU camera pass, stage `gbuffer`: the hardware rasterizer draws the scene from the
// camera into a G-buffer of triangle id, world position, face normal turned towards the
// camera, view depth, and the screen-space derivatives of the position (the hardware's
// dpdx/dpdy). The nearest surface wins the depth test; on equal depth the triangle drawn
// first (the lower index). Alpha-masked surfaces are discarded where cut out. Composed
// after shaders/common/{ray_offset, alpha_mask}.wgsl.

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

fn corner(tri: u32, k: u32) -> vec3<f32> {
    let i = tri * 9u + k * 3u;
    return vec3<f32>(tris[i], tris[i + 1u], tris[i + 2u]);
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Varyings {
    let tri = vi / 3u;
    let k = vi % 3u;
    let p = corner(tri, k);
    var out: Varyings;
    out.clip = cam.clip_from_world * vec4<f32>(p, 1.0);
    out.world = p;
    out.bary = vec3<f32>(f32(k == 0u), f32(k == 1u), f32(k == 2u));
    out.tri = tri;
    return out;
}

fn cut_out(tri: u32, b: vec3<f32>) -> bool {
    let m = materials[tri_material[tri]];
    if cam.masks == 0u || m.masked == 0u {
        return false;
    }
    let i = tri * 6u;
    let uv = vec2<f32>(uvs[i], uvs[i + 1u]) * b.x + vec2<f32>(uvs[i + 2u], uvs[i + 3u]) * b.y
        + vec2<f32>(uvs[i + 4u], uvs[i + 5u]) * b.z;
    let x = wrap_texel(m.wrap_u, uv.x * f32(m.width), m.width);
    let y = wrap_texel(m.wrap_v, uv.y * f32(m.height), m.height);
    let byte = m.texel_offset + y * m.width + x;
    let a = (texels[byte / 4u] >> ((byte % 4u) * 8u)) & 0xffu;
    return !(f32(a) / 255.0 * m.factor >= m.cutoff);
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
    if cut_out(v.tri, v.bary) {
        discard;
    }
    let v0 = corner(v.tri, 0u);
    let e1 = corner(v.tri, 1u) - v0;
    let e2 = corner(v.tri, 2u) - v0;
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
