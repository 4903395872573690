// gpu:raytrace, stage `trace`: one shadow ray per covered pixel of the camera pass,
// through the library's wide BVH (flattened: eight child records a node), exactly as the
// CPU reference forms and tests it. Composed after shaders/common/{ray_offset, light,
// watertight, alpha_mask, triangles}.wgsl.

struct Params {
    light: LightU,
    // Pixels in the view.
    count: u32,
    // Threads along x of the dispatch (its rows are this wide).
    row: u32,
    // 1 when some material lets light through (products in index order are needed).
    transparency: u32,
    // 1 when some material is alpha-masked (texture coordinates are read).
    masks: u32,
}

// One child of a wide BVH node: its box (widened outwards, scene units) and what it is.
// `kind`: 0 empty, 1 inner node (`index` = node), 2 + 4·count a leaf of `count`
// primitives starting at `index` in the primitive list.
struct Child {
    lo: vec3<f32>,
    kind: u32,
    hi: vec3<f32>,
    index: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> tris: array<f32>;
@group(0) @binding(2) var<storage, read> children: array<Child>;
@group(0) @binding(3) var<storage, read> prims: array<u32>;
@group(0) @binding(4) var<storage, read> tri_material: array<u32>;
@group(0) @binding(5) var<storage, read> materials: array<MaterialU>;
@group(0) @binding(6) var<storage, read> uvs: array<f32>;
@group(0) @binding(7) var<storage, read> texels: array<u32>;
@group(0) @binding(8) var<storage, read> view: array<f32>;
@group(0) @binding(9) var<storage, read_write> out: array<f32>;

// Floats a view sample holds: position, its error bound, normal, triangle id (as bits).
const VIEW_STRIDE: u32 = 10u;
// No triangle: the library's NO_TRIANGLE.
const NO_TRIANGLE: u32 = 0xffffffffu;
// Node groups the traversal can hold: the library's wide trees are at most 31 deep, and
// each level leaves at most seven siblings waiting.
const STACK: u32 = 224u;
// The far end of each box's interval is stretched by this much (pbrt's 1 + 2γ₃ and
// then some), so rounding in the slab test can only visit more boxes, never fewer.
const SLAB_STRETCH: f32 = 1.000001;
// Direction components smaller than this are treated as this (with their sign), so the
// slab test never multiplies zero by infinity; it can only visit more boxes.
const TINY_DIR: f32 = 1e-30;

// The lowest triangle index above `after` that the segment o + t·dir, t in (0, t_max),
// meets (skipping `own`), or NO_TRIANGLE; with `any` the first met in traversal order.
fn first_hit(o: vec3<f32>, dir: vec3<f32>, t_max: f32, own: u32, after: i32, any: bool) -> u32 {
    let sh = shear_of(dir);
    let tiny = select(vec3<f32>(-TINY_DIR), vec3<f32>(TINY_DIR), dir >= vec3<f32>(0.0));
    let safe = select(dir, tiny, abs(dir) < vec3<f32>(TINY_DIR));
    let inv = 1.0 / safe;
    var best = NO_TRIANGLE;
    var stack: array<u32, STACK>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let node = stack[top];
        for (var c = 0u; c < 8u; c++) {
            let ch = children[node * 8u + c];
            if ch.kind == 0u {
                continue;
            }
            let t0 = (ch.lo - o) * inv;
            let t1 = (ch.hi - o) * inv;
            let tmin = min(t0, t1);
            let tmax = max(t0, t1);
            let near = max(max(tmin.x, tmin.y), tmin.z);
            let far = min(min(tmax.x, tmax.y), tmax.z) * SLAB_STRETCH;
            if !(near <= far && far >= 0.0 && near <= t_max) {
                continue;
            }
            if ch.kind == 1u {
                if top < STACK {
                    stack[top] = ch.index;
                    top += 1u;
                }
                continue;
            }
            let count = ch.kind >> 2u;
            for (var k = 0u; k < count; k++) {
                let tri = prims[ch.index + k];
                if tri == own || i32(tri) <= after || tri >= best {
                    continue;
                }
                let h = intersect_sheared(o, sh, 0.0, t_max, vertex(tri, 0u), vertex(tri, 1u), vertex(tri, 2u));
                if h.ok && !cut_out(params.masks, tri, h.b) {
                    best = tri;
                    if any {
                        return best;
                    }
                }
            }
        }
    }
    return best;
}

// Semi-transparent casters gathered by one traversal: the GATHER lowest triangle indices
// above `after` met along the segment, in increasing order, or `opaque` when an opaque
// caster is met (the answer is then 0 whatever else lies on the segment). Every further
// GATHER casters cost one more traversal, and one invocation's loops may turn only 65535
// times on llvmpipe: at 16 a shadow ray through hairball's hairs outran that count.
const GATHER: u32 = 64u;

struct Gathered {
    opaque: bool,
    count: u32,
    tri: array<u32, GATHER>,
}

fn gather(o: vec3<f32>, dir: vec3<f32>, t_max: f32, own: u32, after: i32) -> Gathered {
    let sh = shear_of(dir);
    let tiny = select(vec3<f32>(-TINY_DIR), vec3<f32>(TINY_DIR), dir >= vec3<f32>(0.0));
    let safe = select(dir, tiny, abs(dir) < vec3<f32>(TINY_DIR));
    let inv = 1.0 / safe;
    var g: Gathered;
    g.opaque = false;
    g.count = 0u;
    var stack: array<u32, STACK>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let node = stack[top];
        for (var c = 0u; c < 8u; c++) {
            let ch = children[node * 8u + c];
            if ch.kind == 0u {
                continue;
            }
            let t0 = (ch.lo - o) * inv;
            let t1 = (ch.hi - o) * inv;
            let tmin = min(t0, t1);
            let tmax = max(t0, t1);
            let near = max(max(tmin.x, tmin.y), tmin.z);
            let far = min(min(tmax.x, tmax.y), tmax.z) * SLAB_STRETCH;
            if !(near <= far && far >= 0.0 && near <= t_max) {
                continue;
            }
            if ch.kind == 1u {
                if top < STACK {
                    stack[top] = ch.index;
                    top += 1u;
                }
                continue;
            }
            let count = ch.kind >> 2u;
            for (var k = 0u; k < count; k++) {
                let tri = prims[ch.index + k];
                if tri == own || i32(tri) <= after {
                    continue;
                }
                // Full, and above every index kept: not among the lowest.
                if g.count == GATHER && tri >= g.tri[GATHER - 1u] {
                    continue;
                }
                let h = intersect_sheared(o, sh, 0.0, t_max, vertex(tri, 0u), vertex(tri, 1u), vertex(tri, 2u));
                if !h.ok || cut_out(params.masks, tri, h.b) {
                    continue;
                }
                if materials[tri_material[tri]].opaque != 0u {
                    g.opaque = true;
                    return g;
                }
                // Insert in order (a triangle is met once: it lies in one leaf).
                var i = min(g.count, GATHER - 1u);
                while i > 0u && g.tri[i - 1u] > tri {
                    g.tri[i] = g.tri[i - 1u];
                    i -= 1u;
                }
                g.tri[i] = tri;
                g.count = min(g.count + 1u, GATHER);
            }
        }
    }
    return g;
}

// The library's `Reference::occlusion`: 0 behind any opaque caster, else the product of
// the transmittances met, taken in triangle-index order (each traversal gathers the next
// GATHER indices), so the bits do not depend on the traversal order.
fn occlusion(o: vec3<f32>, dir: vec3<f32>, t_max: f32, own: u32) -> vec3<f32> {
    if params.transparency == 0u {
        if first_hit(o, dir, t_max, own, -1, true) == NO_TRIANGLE {
            return vec3<f32>(1.0);
        }
        return vec3<f32>(0.0);
    }
    var t = vec3<f32>(1.0);
    var after = -1;
    loop {
        let g = gather(o, dir, t_max, own, after);
        if g.opaque {
            return vec3<f32>(0.0);
        }
        for (var i = 0u; i < g.count; i++) {
            t *= materials[tri_material[g.tri[i]]].transmittance;
        }
        if g.count < GATHER {
            break;
        }
        after = i32(g.tri[GATHER - 1u]);
    }
    return t;
}

// The library's `Reference::transmittance` from a surface point.
fn transmittance(p: vec3<f32>, err: vec3<f32>, n: vec3<f32>, own: u32) -> vec3<f32> {
    if !illuminates(params.light, p, n) {
        return vec3<f32>(0.0);
    }
    let l = shadow_ray(params.light, p).dir;
    let o = offset_origin(p, err, n, l);
    let r = shadow_ray(params.light, o);
    return occlusion(o, r.dir, r.t_max, own);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let own = bitcast<u32>(view[b + 9u]);
    var v = vec3<f32>(1.0);
    if own != NO_TRIANGLE {
        let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
        let err = vec3<f32>(view[b + 3u], view[b + 4u], view[b + 5u]);
        let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
        v = transmittance(p, err, n, own);
    }
    out[k * 3u] = v.x;
    out[k * 3u + 1u] = v.y;
    out[k * 3u + 2u] = v.z;
}

// ---- spp > 1: primary rays re-traced through sub-pixel positions ----

// The library's `RayGenerator` and the sub-pixel grid.
struct CameraU {
    rays: RaysU,
    // Sub-pixel positions per pixel.
    spp: u32,
    // The library's gamma(7) and gamma(16), the error-bound factors of a hit point.
    gamma7: f32,
    gamma16: f32,
    // This round's first sub-pixel position and how many it traces (see `supersample`).
    first: u32,
    round: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(10) var<storage, read> subpixel: array<vec2<f32>>;
@group(0) @binding(11) var<uniform> cam: CameraU;
// Per pixel, the sum so far of its sub-pixel rays' shadow terms (xyz) and their number (w).
@group(0) @binding(12) var<storage, read_write> accum: array<vec4<f32>>;

struct Closest {
    tri: u32,
    t: f32,
    b: vec3<f32>,
}

// The library's `Reference::closest_hit`: the nearest kept hit for t > 0, the lower index
// on equal distance.
fn closest_hit(o: vec3<f32>, dir: vec3<f32>) -> Closest {
    let sh = shear_of(dir);
    let tiny = select(vec3<f32>(-TINY_DIR), vec3<f32>(TINY_DIR), dir >= vec3<f32>(0.0));
    let safe = select(dir, tiny, abs(dir) < vec3<f32>(TINY_DIR));
    let inv = 1.0 / safe;
    var best = Closest(NO_TRIANGLE, params.light.far, vec3<f32>(0.0));
    var stack: array<u32, STACK>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let node = stack[top];
        for (var c = 0u; c < 8u; c++) {
            let ch = children[node * 8u + c];
            if ch.kind == 0u {
                continue;
            }
            let t0 = (ch.lo - o) * inv;
            let t1 = (ch.hi - o) * inv;
            let tmin = min(t0, t1);
            let tmax = max(t0, t1);
            let near = max(max(tmin.x, tmin.y), tmin.z);
            let far = min(min(tmax.x, tmax.y), tmax.z) * SLAB_STRETCH;
            if !(near <= far && far >= 0.0 && near <= best.t) {
                continue;
            }
            if ch.kind == 1u {
                if top < STACK {
                    stack[top] = ch.index;
                    top += 1u;
                }
                continue;
            }
            let count = ch.kind >> 2u;
            for (var k = 0u; k < count; k++) {
                let tri = prims[ch.index + k];
                let h = intersect_sheared(o, sh, 0.0, params.light.far, vertex(tri, 0u), vertex(tri, 1u), vertex(tri, 2u));
                if h.ok && !cut_out(params.masks, tri, h.b) && (h.t < best.t || (h.t == best.t && tri < best.tri)) {
                    best = Closest(tri, h.t, h.b);
                }
            }
        }
    }
    return best;
}

// glam's `cross`, component for component.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// The library's `facing_normal`: the unit face normal (glam's `normalize_or_zero`) turned
// against `d`.
fn facing_normal(tri: u32, d: vec3<f32>) -> vec3<f32> {
    let v0 = vertex(tri, 0u);
    let c = cross3(vertex(tri, 1u) - v0, vertex(tri, 2u) - v0);
    let rcp = 1.0 / sqrt(dot3(c, c));
    var n = vec3<f32>(0.0);
    if rcp < params.light.far && rcp > 0.0 {
        n = c * rcp;
    }
    if dot3(n, d) > 0.0 {
        return -n;
    }
    return n;
}

// One round of the sub-pixel rays of every pixel: positions first..first + round of the
// grid, added to the pixel's sum; the last round writes the mean (or, where no ray hit,
// the camera pass sample's own term). The host runs as many rounds as it takes, one
// position a round: Mesa's llvmpipe ends every loop of an invocation once its loops
// together have turned 65535 times, which all of a pixel's rays through hairball's
// semi-transparent hairs exceed.
@compute @workgroup_size(64)
fn supersample(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let own = bitcast<u32>(view[b + 9u]);
    let done = cam.first + cam.round >= cam.spp;
    var v = vec3<f32>(1.0);
    if own != NO_TRIANGLE {
        let px = f32(k % cam.rays.width);
        let py = f32(k / cam.rays.width);
        // The sum of the shadow terms of the sub-pixel rays that hit (xyz) and their
        // number (w), over the rounds so far: one sum in sample order, as one loop would
        // take it.
        var acc = vec4<f32>(0.0);
        if cam.first > 0u {
            acc = accum[k];
        }
        for (var i = cam.first; i < min(cam.first + cam.round, cam.spp); i++) {
            let s = subpixel[i];
            let ray = camera_ray(cam.rays, px + s.x, py + s.y);
            let hit = closest_hit(ray.o, ray.d);
            if hit.tri == NO_TRIANGLE {
                continue;
            }
            let sp = surface_point(vertex(hit.tri, 0u), vertex(hit.tri, 1u), vertex(hit.tri, 2u), hit.b, cam.gamma7, cam.gamma16);
            acc = vec4<f32>(acc.xyz + transmittance(sp.p, sp.err, facing_normal(hit.tri, ray.d), hit.tri), acc.w + 1.0);
        }
        if !done {
            accum[k] = acc;
            return;
        }
        if acc.w == 0.0 {
            let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
            let err = vec3<f32>(view[b + 3u], view[b + 4u], view[b + 5u]);
            let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
            v = transmittance(p, err, n, own);
        } else {
            v = acc.xyz / acc.w;
        }
    }
    if !done {
        return;
    }
    out[k * 3u] = v.x;
    out[k * 3u + 1u] = v.y;
    out[k * 3u + 2u] = v.z;
}
