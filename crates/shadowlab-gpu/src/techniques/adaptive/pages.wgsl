// gpu:asm: the virtual shadow map as the analysis and the look-up read it. Each light
// view (a point light's cube face) has a virtual map of `side` texels a side, mip levels
// 0 (finest) to `levels - 1` (the coarsest, the CPU asm's root resolution, always
// resident). Every level is cut into pages of `page` texels a side; the page table holds,
// for each page of each level and face, 0 (not resident) or its slot in the physical pool
// plus one. The pool is one atlas of `atlas_cols` pages a row holding each resident page's
// triangle ids: the depth of a texel is that of its triangle's plane, found where the
// shadow ray of the receiver under test meets it. Table entries are ordered coarsest level first, then
// face, then page row and column, so that entry order is coarse-first. Composed after
// shaders/common/{ray_offset, light}.wgsl.

struct FaceV {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // 1 for an orthographic view.
    ortho: u32,
    near: f32,
    extent: f32,
    _pad0: u32,
}

struct VirtualU {
    light: LightU,
    count: u32,
    row: u32,
    // Page side in texels.
    page: u32,
    // Mip levels of the virtual map.
    levels: u32,
    // Side of the finest level in texels.
    side: u32,
    // Light views.
    faces: u32,
    // Pages a row of the pool atlas.
    atlas_cols: u32,
    // The frame's clock (the LRU stamp).
    now: u32,
    // Texels wanted across an eye pixel's footprint, per axis.
    oversampling: f32,
    bias: f32,
    slope_bias: f32,
    _pad0: u32,
    // The first table entry of each level (`level_base`), four to a vector.
    bases: array<vec4<u32>, 2>,
}

struct Hit {
    level: u32,
    slot: u32,
}

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
const NO_SLOT: u32 = 0xffffffffu;
// The library's MIN_COSINE and MAX_SLOPE (techniques/shadow_map.rs).
const MIN_COSINE: f32 = 1e-6;
const MAX_SLOPE: f32 = 10.0;

// The library's `cube_face`: the major axis of the direction from the light.
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x >= 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

fn face_of(p: vec3<f32>) -> u32 {
    if vp.light.kind == LIGHT_POINT {
        return cube_face(p - vp.light.pos_or_dir);
    }
    return 0u;
}

// Image coordinates of `p` in view `f`.
fn uv_in(f: u32, p: vec3<f32>) -> vec2<f32> {
    let c = faces[f].clip_from_world * vec4<f32>(p, 1.0);
    let inv_w = 1.0 / c.w;
    return vec2<f32>(c.x * inv_w * 0.5 + 0.5, 0.5 - c.y * inv_w * 0.5);
}

fn linear_depth(f: u32, p: vec3<f32>) -> f32 {
    return -(faces[f].light_from_world * vec4<f32>(p, 1.0)).z;
}

fn finite(x: f32) -> bool {
    return abs(x) < 3.0e38;
}

fn texels_across(l: u32) -> u32 {
    return vp.side >> l;
}

fn pages_across(l: u32) -> u32 {
    return (vp.side / vp.page) >> l;
}

// The texel of coordinate `u` on a level `n` texels across, clamped to it.
fn texel_index(u: f32, n: u32) -> u32 {
    return u32(clamp(floor(u * f32(n)), 0.0, f32(n - 1u)));
}

// The first table entry of level `l`: the coarser levels' entries come before it.
fn level_base(l: u32) -> u32 {
    return vp.bases[l / 4u][l % 4u];
}

// The table entry of the page holding texel (tx, ty) of level `l` of face `f`.
fn entry_of(f: u32, l: u32, tx: u32, ty: u32) -> u32 {
    let n = pages_across(l);
    return level_base(l) + f * n * n + (ty / vp.page) * n + tx / vp.page;
}

// The finest level at or coarser than `start` whose page at `uv` is resident, and its slot.
fn finest_resident(f: u32, start: u32, uv: vec2<f32>) -> Hit {
    for (var l = start; l < vp.levels; l++) {
        let n = texels_across(l);
        let s = table[entry_of(f, l, texel_index(uv.x, n), texel_index(uv.y, n))];
        if s != 0u {
            return Hit(l, s - 1u);
        }
    }
    return Hit(vp.levels - 1u, NO_SLOT);
}

// The pool atlas texel holding `uv` at the hit's level.
fn atlas_texel(h: Hit, uv: vec2<f32>) -> vec2<i32> {
    let n = texels_across(h.level);
    let tx = texel_index(uv.x, n) % vp.page;
    let ty = texel_index(uv.y, n) % vp.page;
    let ox = (h.slot % vp.atlas_cols) * vp.page;
    let oy = (h.slot / vp.atlas_cols) * vp.page;
    return vec2<i32>(i32(ox + tx), i32(oy + ty));
}

// Vertex `k` of triangle `tri` (nine floats a triangle in `tris`).
fn corner(tri: u32, k: u32) -> vec3<f32> {
    let i = tri * 9u + k * 3u;
    return vec3<f32>(tris[i], tris[i + 1u], tris[i + 2u]);
}

// How far in front of `p` (in linear depth of view `f`, towards the light) the plane of
// triangle `tri` meets `p`'s shadow ray: positive when the plane lies between `p` and the
// light, else 0 (the plane crosses the line behind `p` or behind the light).
fn plane_ahead(f: u32, tri: u32, p: vec3<f32>, depth: f32) -> f32 {
    let v0 = corner(tri, 0u);
    let n = cross(corner(tri, 1u) - v0, corner(tri, 2u) - v0);
    if vp.light.kind == LIGHT_DIRECTIONAL {
        // q = p + s · to_light on the plane; linear depth falls by s.
        let s = dot3(n, v0 - p) / dot3(n, vp.light.pos_or_dir);
        return select(0.0, s, s > 0.0 && finite(s));
    }
    // q = L + t (p − L) on the plane; linear depth is t · depth(p).
    let l = vp.light.pos_or_dir;
    let t = dot3(n, v0 - l) / dot3(n, p - l);
    if !(t > 0.0 && t < 1.0) {
        return 0.0;
    }
    return (1.0 - t) * depth;
}

// Section 4.2's combined test with the texel holding `uv` in the hit's page: lit when the
// texel holds the receiver's own triangle, else when the texel's triangle's plane lies no
// more than `bias` in front of `p` along its shadow ray (the stored depth of the paper,
// taken at `p` instead of at the texel's centre).
fn lit_at(h: Hit, uv: vec2<f32>, own: u32, f: u32, p: vec3<f32>, depth: f32, bias: f32) -> bool {
    if h.slot == NO_SLOT {
        return true;
    }
    let id = textureLoad(pool_id, atlas_texel(h, uv), 0).x;
    if id == own || id == NO_TRIANGLE {
        return true;
    }
    return plane_ahead(f, id, p, depth) <= bias;
}

// The library's `receiver_bias` at level `l` of view `f`, in world units.
fn level_bias(f: u32, l: u32, depth: f32, n: vec3<f32>, dir: vec3<f32>) -> f32 {
    let v = faces[f];
    let e = f32(texels_across(l));
    var texel = v.extent / e;
    if v.ortho == 0u {
        texel = v.extent * max(depth, v.near) / e;
    }
    let c = clamp(dot3(n, dir), MIN_COSINE, 1.0);
    let t = min(sqrt(max(1.0 - c * c, 0.0)) / c, MAX_SLOPE);
    return texel * (vp.bias + vp.slope_bias * t);
}
