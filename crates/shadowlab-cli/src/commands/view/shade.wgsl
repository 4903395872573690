// The viewer's shading and error on the GPU, over a technique's shadow term left on the
// device. Composed after shaders/common/{ray_offset, light}.wgsl.
//
// `shade`: the library's `shade::shade` per pixel: albedo · (ambient + (1 − ambient) ·
// max(0, n·l) · visibility) where the light illuminates the surface, the background where
// nothing is covered, encoded to 8-bit sRGB as `picture::to_srgb8` rounds it (the GPU's
// `pow` may differ from the CPU's in the last bit: a level in a few pixels).
//
// `measure`: the library's `compare` and `shade::error_image` against a reference shadow
// term (gpu:raytrace's): the error picture into the overlay (alpha 0 where the two agree
// or nothing is covered), and integer sums (covered pixels, mismatches, the absolute
// luminance difference in 2^-16 steps, carried into a high word) that no thread order
// changes.

struct ShadeU {
    light: LightU,
    width: u32,
    height: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> u: ShadeU;
@group(0) @binding(1) var<storage, read> view: array<f32>;
@group(0) @binding(2) var<storage, read> vis: array<f32>;
@group(0) @binding(3) var<storage, read> albedo: array<f32>;
@group(0) @binding(4) var image: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(5) var<storage, read> reference: array<f32>;
@group(0) @binding(6) var<storage, read_write> sums: array<atomic<u32>>;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
// The library's shade::AMBIENT and shade::BACKGROUND.
const AMBIENT: f32 = 0.25;
const BACKGROUND: vec3<f32> = vec3<f32>(0.18, 0.2, 0.24);
// compare::MISMATCH_THRESHOLD.
const MISMATCH: f32 = 0.5;
// The absolute difference is summed in steps of 2^-16.
const SUM_SCALE: f32 = 65536.0;

fn srgb8(c: vec3<f32>) -> vec4<f32> {
    var out = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    for (var i = 0u; i < 3u; i++) {
        let x = clamp(c[i], 0.0, 1.0);
        var s = 12.92 * x;
        if x > 0.0031308 {
            s = 1.055 * pow(x, 1.0 / 2.4) - 0.055;
        }
        out[i] = floor(s * 255.0 + 0.5) / 255.0;
    }
    return out;
}

fn vis_at(k: u32) -> vec3<f32> {
    return vec3<f32>(vis[3u * k], vis[3u * k + 1u], vis[3u * k + 2u]);
}

fn reference_at(k: u32) -> vec3<f32> {
    return vec3<f32>(reference[3u * k], reference[3u * k + 1u], reference[3u * k + 2u]);
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= u.width || id.y >= u.height {
        return;
    }
    let k = id.y * u.width + id.x;
    let b = k * VIEW_STRIDE;
    let tri = bitcast<u32>(view[b + 9u]);
    var c = BACKGROUND;
    if tri != NO_TRIANGLE {
        let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
        let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
        let a = vec3<f32>(albedo[3u * tri], albedo[3u * tri + 1u], albedo[3u * tri + 2u]);
        var direct = 0.0;
        if illuminates(u.light, p, n) {
            direct = max(dot3(n, shadow_ray(u.light, p).dir), 0.0);
        }
        c = a * (AMBIENT + (1.0 - AMBIENT) * direct * vis_at(k));
    }
    textureStore(image, vec2<i32>(id.xy), srgb8(c));
}

@compute @workgroup_size(8, 8)
fn measure(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= u.width || id.y >= u.height {
        return;
    }
    let k = id.y * u.width + id.x;
    let tri = bitcast<u32>(view[k * VIEW_STRIDE + 9u]);
    if tri == NO_TRIANGLE {
        textureStore(image, vec2<i32>(id.xy), vec4<f32>(0.0));
        return;
    }
    let d = luminance(vis_at(k)) - luminance(reference_at(k));
    // shade::error_image: √|d| on 8 bits, red where lighter, blue where darker.
    let m = floor(sqrt(abs(d)) * 255.0);
    var e = vec4<f32>(0.0, floor(m / 3.0), m, 255.0) / 255.0;
    if d > 0.0 {
        e = vec4<f32>(m, 0.0, 0.0, 255.0) / 255.0;
    }
    if m == 0.0 {
        e.a = 0.0;
    }
    textureStore(image, vec2<i32>(id.xy), e);
    atomicAdd(&sums[0], 1u);
    if abs(d) >= MISMATCH {
        atomicAdd(&sums[1], 1u);
    }
    let q = u32(abs(d) * SUM_SCALE + 0.5);
    let old = atomicAdd(&sums[2], q);
    if old > 0xffffffffu - q {
        atomicAdd(&sums[3], 1u);
    }
}
