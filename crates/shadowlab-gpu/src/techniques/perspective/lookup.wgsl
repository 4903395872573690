// gpu:psm, stage `lookup` (Stamminger & Drettakis 2002, Section 3; inverted lights
// "handled as point lights with their shadow map depth test reversed"): each covered
// pixel the light reaches is taken into post-perspective space, to its map (the cube face
// of its direction from `q` when there is a cube), and compared with the stored depth
// after the paper's offset in shadow map space: `texel′ · (bias + slope_bias · tan θ′)`,
// texel′ the post-space texel at the receiver and θ′ the post-space angle between its
// plane and the light. The library's `psm` look-up, line for line. Composed after
// shaders/common/{ray_offset, light, map_compare, map_pixels}.wgsl.

struct MapU {
    // World to the map's clip space times w_p.
    clip_from_world: mat4x4<f32>,
    // The post-space linear depth beyond the near plane times w_p.
    depth_world: vec4<f32>,
    // Texel size in post units: absolute (orthographic) or per unit distance from q.
    texel: f32,
    // Distance of the near plane from q (0 for orthographic maps).
    near: f32,
    // Far minus near plane: stored depths are depths over this.
    span: f32,
    // 1 for a map along a post-space directional light.
    ortho: u32,
}

const POST_POINT: u32 = 0u;
const POST_INVERTED: u32 = 1u;
const POST_DIRECTIONAL: u32 = 2u;
const NO_FACE: u32 = 0xffffffffu;

struct Params {
    post_from_world: mat4x4<f32>,
    // Transposed inverse of post_from_world: world planes to post planes.
    post_planes: mat4x4<f32>,
    w_row: vec4<f32>,
    // The post-space light position q (w unused).
    q: vec4<f32>,
    // Unit direction towards a directional post-space light (w unused).
    dir: vec4<f32>,
    // For a cube: the map of each of the six faces (NO_FACE when skipped).
    faces_a: vec4<u32>,
    faces_b: vec4<u32>,
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    // POST_POINT, POST_INVERTED or POST_DIRECTIONAL.
    kind: u32,
    bias: f32,
    slope_bias: f32,
    // 1 when the maps are a cube's faces.
    cube: u32,
    _pad0: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> maps: array<MapU>;
@group(0) @binding(2) var map: texture_depth_2d_array;
@group(0) @binding(3) var<storage, read> view: array<f32>;
@group(0) @binding(4) var<storage, read_write> out: array<f32>;

fn face_map(f: u32) -> u32 {
    if f < 4u {
        return params.faces_a[f];
    }
    return params.faces_b[f - 4u];
}

fn shadow_term(p: vec3<f32>, nw: vec3<f32>) -> f32 {
    let h = vec4<f32>(p, 1.0);
    let inv_wp = 1.0 / dot(params.w_row, h);
    let kind = params.kind;
    var pp = vec3<f32>(0.0);
    if kind != POST_DIRECTIONAL {
        pp = (params.post_from_world * h).xyz * inv_wp;
    }
    var i = 0u;
    if params.cube == 1u {
        i = face_map(map_cube_face(pp - params.q.xyz));
        if i == NO_FACE {
            return 1.0;
        }
    }
    let m = maps[i];
    let c = (m.clip_from_world * h) * inv_wp;
    let depth = dot(m.depth_world, h) * inv_wp;
    let inv_cw = 1.0 / c.w;
    let u = c.x * inv_cw * 0.5 + 0.5;
    let v = 0.5 - c.y * inv_cw * 0.5;
    let np = map_normalize_or_zero((params.post_planes * vec4<f32>(nw, -dot3(nw, p))).xyz);
    var l = params.dir.xyz;
    if kind == POST_POINT {
        l = map_normalize_or_zero(params.q.xyz - pp);
    } else if kind == POST_INVERTED {
        l = map_normalize_or_zero(pp - params.q.xyz);
    }
    var texel = m.texel;
    if m.ortho == 0u {
        texel = m.texel * max(depth + m.near, m.near);
    }
    let offset = map_receiver_bias(texel, np, l, params.bias, params.slope_bias);
    // The stored units: depth over the span, mirrored for an inverted light.
    var r = (depth - offset) / m.span;
    if kind == POST_INVERTED {
        r = 1.0 + (-depth - offset) / m.span;
    }
    return map_nearest(map, i, params.res, u, v, r);
}
