// gpu:asm, stage `render`: the hardware rasterizer draws each new page of the virtual map
// into its slot of the pool atlas (one viewport a page, all in one render pass; the draw's
// instance selects the page), through the page's own `clip_from_world`: the light view's,
// scaled and shifted so that the page's square of the view fills the viewport, drawing only
// the triangles of its cell's culling list. Each
// fragment writes its triangle, Section 4.2's id (the look-up takes the depth from the
// triangle's plane); the depth test keeps the nearest, on the linear depth (distance from
// the view's eye plane) over the view's far plane. Alpha-masked casters are discarded where cut. Composed after
// shaders/common/{alpha_mask, triangles}.wgsl.

struct PageU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // Linear depths are divided by this for the depth test (the view's far plane).
    depth_scale: f32,
    // 1 when some material is alpha-masked.
    masks: u32,
    // The page's first triangle in `cull` (its cell's list).
    first: u32,
    _pad0: u32,
}

@group(0) @binding(0) var<storage, read> pages: array<PageU>;
@group(0) @binding(1) var<storage, read> tris: array<f32>;
@group(0) @binding(2) var<storage, read> tri_material: array<u32>;
@group(0) @binding(3) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(4) var<storage, read> uvs: array<f32>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;
// Every cell's triangles (Section 4.3's culling lists); draw `i` of a page reads its own.
@group(0) @binding(6) var<storage, read> cull: array<u32>;

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) depth: f32,
    @location(1) bary: vec3<f32>,
    @location(2) @interpolate(flat) tri: u32,
    @location(3) @interpolate(flat) page: u32,
}

struct Texel {
    @location(0) id: u32,
    @builtin(frag_depth) test: f32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32, @builtin(instance_index) page: u32) -> Varyings {
    let pg = pages[page];
    let tri = cull[pg.first + vi / 3u];
    let k = vi % 3u;
    let p = vec4<f32>(vertex(tri, k), 1.0);
    var out: Varyings;
    out.clip = pg.clip_from_world * p;
    out.depth = -(pg.light_from_world * p).z;
    out.bary = vec3<f32>(f32(k == 0u), f32(k == 1u), f32(k == 2u));
    out.tri = tri;
    out.page = page;
    return out;
}

@fragment
fn fs(v: Varyings) -> Texel {
    let pg = pages[v.page];
    if cut_out(pg.masks, v.tri, v.bary) {
        discard;
    }
    var t: Texel;
    t.id = v.tri;
    t.test = clamp(v.depth / pg.depth_scale, 0.0, 1.0);
    return t;
}
