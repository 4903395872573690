// gpu:asm, stage `analysis`: the paper's resolution analysis (Fernando et al. 2001,
// Sections 3.1 and 4.1) as page requests. Each lit receiver projects its pixel's footprint
// (the camera pass's screen-space derivatives) into its light view and finds the mip level
// whose texels are `oversampling` times finer than the footprint across; it reads the
// finest resident page covering it, stamps that page's slot with the frame's clock (the
// LRU's use), and when that page is coarser than wanted and the 2×2 texels around the
// receiver disagree on its shadow test (it straddles a shadow boundary), requests the page
// one level finer. Each page's flag counts the receivers that request it (the paper's
// benefit: mismatched pixels that straddle a boundary), and the first to raise it appends
// the page's entry to the list; `tally` then reads each listed page's count. The list's
// order depends on the threads', the counts do not: the driver sorts before allocating. Composed after shaders/common/{ray_offset,
// light}.wgsl and pages.wgsl.

@group(0) @binding(0) var<uniform> vp: VirtualU;
@group(0) @binding(1) var<storage, read> faces: array<FaceV>;
@group(0) @binding(2) var<storage, read> view: array<f32>;
// dpdx then dpdy of each pixel, six floats.
@group(0) @binding(3) var<storage, read> footprints: array<f32>;
@group(0) @binding(4) var<storage, read> table: array<u32>;
@group(0) @binding(5) var pool_id: texture_2d<u32>;
// Nine floats a triangle.
@group(0) @binding(6) var<storage, read> tris: array<f32>;
@group(0) @binding(7) var<storage, read_write> flags: array<atomic<u32>>;
// [0]: the number of requests; then the requested entries.
@group(0) @binding(8) var<storage, read_write> requests: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> slot_used: array<atomic<u32>>;

// The finest level whose texel density reaches `wanted` texels across the view.
fn wanted_level(wanted: f32) -> u32 {
    let x = floor(log2(f32(vp.side) / wanted));
    return u32(clamp(x, 0.0, f32(vp.levels - 1u)));
}

// True when the 2×2 texels of level `l` whose centres surround `uv` disagree on the test.
fn straddles(f: u32, l: u32, uv: vec2<f32>, own: u32, p: vec3<f32>, depth: f32, bias: f32) -> bool {
    let n = texels_across(l);
    let last = f32(n - 1u);
    let x0 = clamp(floor(uv.x * f32(n) - 0.5), 0.0, last);
    let y0 = clamp(floor(uv.y * f32(n) - 0.5), 0.0, last);
    let x1 = min(x0 + 1.0, last);
    let y1 = min(y0 + 1.0, last);
    let inv = 1.0 / f32(n);
    let c00 = vec2<f32>(x0 + 0.5, y0 + 0.5) * inv;
    let c10 = vec2<f32>(x1 + 0.5, y0 + 0.5) * inv;
    let c01 = vec2<f32>(x0 + 0.5, y1 + 0.5) * inv;
    let c11 = vec2<f32>(x1 + 0.5, y1 + 0.5) * inv;
    let a = lit_at(finest_resident(f, l, c00), c00, own, f, p, depth, bias);
    return a != lit_at(finest_resident(f, l, c10), c10, own, f, p, depth, bias)
        || a != lit_at(finest_resident(f, l, c01), c01, own, f, p, depth, bias)
        || a != lit_at(finest_resident(f, l, c11), c11, own, f, p, depth, bias);
}

fn request(e: u32) {
    if atomicAdd(&flags[e], 1u) == 0u {
        let i = atomicAdd(&requests[0], 1u);
        atomicStore(&requests[1u + i], e);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * vp.row + gid.x;
    if k >= vp.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let own = bitcast<u32>(view[b + 9u]);
    if own == NO_TRIANGLE {
        return;
    }
    let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
    let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
    if !illuminates(vp.light, p, n) {
        return;
    }
    let f = face_of(p);
    let uv = uv_in(f, p);
    let depth = linear_depth(f, p);
    if !(finite(uv.x) && finite(uv.y) && finite(depth)) {
        return;
    }
    let h = finest_resident(f, 0u, uv);
    if h.slot == NO_SLOT {
        return;
    }
    atomicMax(&slot_used[h.slot], vp.now);
    // The footprint's area in view coordinates.
    let q = k * 6u;
    let dx = vec3<f32>(footprints[q], footprints[q + 1u], footprints[q + 2u]);
    let dy = vec3<f32>(footprints[q + 3u], footprints[q + 4u], footprints[q + 5u]);
    let ax = uv_in(f, p + dx) - uv;
    let ay = uv_in(f, p + dy) - uv;
    let area = abs(ax.x * ay.y - ay.x * ax.y);
    if !(area > 0.0 && finite(area)) {
        // No footprint where the neighbouring rays miss the plane.
        return;
    }
    let w = wanted_level(vp.oversampling / sqrt(area));
    if h.level <= w {
        return;
    }
    let dir = shadow_ray(vp.light, p).dir;
    let bias = level_bias(f, h.level, depth, n, dir);
    if straddles(f, h.level, uv, own, p, depth, bias) {
        let l = h.level - 1u;
        let m = texels_across(l);
        request(entry_of(f, l, texel_index(uv.x, m), texel_index(uv.y, m)));
    }
}

// Each listed request's benefit, once `main` has finished.
@group(0) @binding(10) var<storage, read_write> benefits: array<u32>;

@compute @workgroup_size(64)
fn tally(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * vp.row + gid.x;
    if i >= atomicLoad(&requests[0]) {
        return;
    }
    benefits[i] = atomicLoad(&flags[atomicLoad(&requests[1u + i])]);
}
