// The GPU camera pass, stage `samples`: each pixel's view sample formed from the triangle
// the G-buffer (`gbuffer.wgsl`) saw there, as the library's camera pass forms it
// (`view.rs`, `sample`): the ray through the pixel's centre (`RayGenerator::ray`) met with
// the triangle's plane (`math::intersect_plane`), the point from its barycentrics with its
// floating-point error bound (`SurfacePoint::from_barycentrics`), the face normal turned
// against the ray. A pixel whose ray runs along the plane, or whose point is not finite,
// is uncovered, as on the CPU. Written in the layout every technique reads
// (`upload::view_floats`: position, error bound, normal, triangle id's bits), with the
// count of covered pixels and the bounds of their positions reduced alongside by integer
// atomics on order-preserving keys, within each workgroup and then once a workgroup into
// the summary (a global atomic a pixel would queue millions of threads on seven words):
// minimum, maximum and sum do not depend on the order
// the pixels ran in, so the summary is the same bits every run. The G-buffer discarded
// the fragments alpha masks cut out already. Composed after
// shaders/common/{ray_offset, camera_rays, order_key}.wgsl.

struct SamplesU {
    rays: RaysU,
    height: u32,
    // The library's gamma(7) and gamma(16), the error-bound factors of a surface point.
    gamma7: f32,
    gamma16: f32,
    // Invocations per row of the dispatch grid.
    row: u32,
}

@group(0) @binding(0) var<uniform> cam: SamplesU;
@group(0) @binding(1) var ids: texture_2d<u32>;
@group(0) @binding(2) var<storage, read> tris: array<f32>;
@group(0) @binding(3) var<storage, read_write> view: array<f32>;
// Covered pixels, then the order-preserving keys of the positions' minimum (x, y, z) and
// maximum (x, y, z).
@group(0) @binding(4) var<storage, read_write> summary: array<atomic<u32>, 7>;

const NO_TRIANGLE: u32 = 0xffffffffu;
const VIEW_STRIDE: u32 = 10u;

// Vertex `k` of triangle `tri` (nine f32 a triangle).
fn corner(tri: u32, k: u32) -> vec3<f32> {
    let i = tri * 9u + k * 3u;
    return vec3<f32>(tris[i], tris[i + 1u], tris[i + 2u]);
}

// glam's `cross`, term for term.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

fn write_uncovered(k: u32) {
    for (var i = 0u; i < 9u; i++) {
        view[k * VIEW_STRIDE + i] = 0.0;
    }
    view[k * VIEW_STRIDE + 9u] = bitcast<f32>(NO_TRIANGLE);
}

fn finite3(v: vec3<f32>) -> bool {
    // NaN fails every comparison; infinities exceed the largest float.
    return all(abs(v) <= vec3<f32>(3.4028235e38));
}

// This workgroup's share of the summary, added to `summary` once by its first threads: a
// global atomic per pixel would queue two million threads on seven words.
var<workgroup> local: array<atomic<u32>, 7>;

// Pixel `k`'s sample written to `view`; its position when covered.
fn form(k: u32) -> Sample {
    let none = Sample(false, vec3<f32>(0.0));
    let width = cam.rays.width;
    if k >= width * cam.height {
        return none;
    }
    let x = k % width;
    let y = k / width;
    let tri = textureLoad(ids, vec2<u32>(x, y), 0).x;
    if tri == NO_TRIANGLE {
        write_uncovered(k);
        return none;
    }
    let ray = camera_ray(cam.rays, f32(x) + 0.5, f32(y) + 0.5);
    let o = ray.o;
    let d = ray.d;
    // intersect_plane: barycentrics of the ray's meeting with the triangle's plane.
    let v0 = corner(tri, 0u);
    let v1 = corner(tri, 1u);
    let v2 = corner(tri, 2u);
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = cross3(d, e2);
    let det = dot3(e1, p);
    if det == 0.0 || !(abs(det) <= 3.4028235e38) {
        write_uncovered(k);
        return none;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let b1 = dot3(s, p) * inv;
    let q = cross3(s, e1);
    let b2 = dot3(d, q) * inv;
    let b0 = 1.0 - b1 - b2;
    let sp = surface_point(v0, v1, v2, vec3<f32>(b0, b1, b2), cam.gamma7, cam.gamma16);
    let point = sp.p;
    let err = sp.err;
    // The face normal, turned against the ray (glam's normalize_or_zero).
    let c = cross3(e1, e2);
    let len2 = dot3(c, c);
    var n = vec3<f32>(0.0);
    if len2 > 0.0 && len2 <= 3.4028235e38 {
        n = c * (1.0 / sqrt(len2));
    }
    if dot3(n, d) > 0.0 {
        n = -n;
    }
    if !finite3(point) || all(n == vec3<f32>(0.0)) {
        write_uncovered(k);
        return none;
    }
    let base = k * VIEW_STRIDE;
    view[base] = point.x;
    view[base + 1u] = point.y;
    view[base + 2u] = point.z;
    view[base + 3u] = err.x;
    view[base + 4u] = err.y;
    view[base + 5u] = err.z;
    view[base + 6u] = n.x;
    view[base + 7u] = n.y;
    view[base + 8u] = n.z;
    view[base + 9u] = bitcast<f32>(tri);
    return Sample(true, point);
}

struct Sample {
    covered: bool,
    point: vec3<f32>,
}

// Pixels one thread forms: its workgroup's 64 threads take 64 × PER_THREAD consecutive
// pixels, neighbouring threads neighbouring pixels, and reduce them in registers first, so
// the workgroup's barriers and shared atomics are paid once per 1024 pixels.
const PER_THREAD: u32 = 16u;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    // The count from zero, the minima from the largest key, the maxima from the smallest.
    if li < 7u {
        atomicStore(&local[li], select(0u, 0xffffffffu, li >= 1u && li <= 3u));
    }
    var count = 0u;
    var lo = vec3<u32>(0xffffffffu);
    var hi = vec3<u32>(0u);
    let first = (gid.y * cam.row + gid.x - li) * PER_THREAD + li;
    for (var j = 0u; j < PER_THREAD; j++) {
        let sample = form(first + j * 64u);
        if sample.covered {
            count += 1u;
            let key = vec3<u32>(order_key(sample.point.x), order_key(sample.point.y), order_key(sample.point.z));
            lo = min(lo, key);
            hi = max(hi, key);
        }
    }
    workgroupBarrier();
    if count > 0u {
        atomicAdd(&local[0], count);
        for (var i = 0u; i < 3u; i++) {
            atomicMin(&local[1u + i], lo[i]);
            atomicMax(&local[4u + i], hi[i]);
        }
    }
    workgroupBarrier();
    if li < 7u {
        let v = atomicLoad(&local[li]);
        if li == 0u {
            if v > 0u {
                atomicAdd(&summary[0], v);
            }
        } else if li <= 3u {
            atomicMin(&summary[li], v);
        } else {
            atomicMax(&summary[li], v);
        }
    }
}
