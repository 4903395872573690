// gpu:vsm / evsm / msm / csm, stage `blur` (Annen et al. 2007, Section 4.1: "a separable
// Gaussian filter kernel on the textures"): one pass of the library's separable binomial
// blur, horizontal or vertical, clamp-to-edge, its sums taken in the library's tap order
// and written back in the storage format before the other pass reads them, as two passes
// between render targets would be. Composed after filtering/filtered.wgsl.

struct BlurU {
    res: u32,
    taps: u32,
    // 1 for the horizontal pass, 0 for the vertical.
    horizontal: u32,
    format: u32,
}

@group(0) @binding(0) var<uniform> blur: BlurU;
@group(0) @binding(1) var<storage, read> weights: array<f32>;
@group(0) @binding(2) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> dst: array<vec4<f32>>;
// Unused here; declared so the shared file's parameters resolve.
var<private> tech: TechU;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = blur.res;
    if gid.x >= n || gid.y >= n {
        return;
    }
    let r = i32(blur.taps / 2u);
    let last = i32(n) - 1;
    var acc = vec4<f32>(0.0);
    for (var j = 0; j < i32(blur.taps); j++) {
        var x = i32(gid.x);
        var y = i32(gid.y);
        if blur.horizontal == 1u {
            x = clamp(x + j - r, 0, last);
        } else {
            y = clamp(y + j - r, 0, last);
        }
        acc += weights[j] * src[u32(y) * n + u32(x)];
    }
    dst[gid.y * n + gid.x] = store(acc, blur.format);
}
