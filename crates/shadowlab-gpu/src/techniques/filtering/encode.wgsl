// gpu:vsm / evsm / msm / csm, stage `encode` (Annen et al. 2007, Section 4.1, the basis
// images; the moment maps' moments): every texel of one light view's depth map becomes
// four of the technique's stored values (one group of its channels), through the
// technique's `encode_texel(z, variance, group)`, with `z` the linear depth normalized over
// the fitted depth range as the library's `DepthRange::normalize` does and `variance` the
// depth variance across the texel from its neighbours on the same triangle (the library's
// `texel_depth_and_variance`); rounded to the storage format. Composed after
// filtering/filtered.wgsl and the technique's encoder.

struct PlaneU {
    res: u32,
    // The light view (layer of the depth map).
    layer: u32,
    // The group of four channels written.
    group: u32,
    format: u32,
}

@group(0) @binding(0) var<uniform> plane: PlaneU;
@group(0) @binding(1) var<uniform> tech: TechU;
@group(0) @binding(2) var depth_map: texture_2d_array<u32>;
@group(0) @binding(3) var<storage, read_write> out: array<vec4<f32>>;
// The fitted depth range of each view (stage `fit`'s).
@group(0) @binding(4) var<storage, read> ranges: array<vec4<f32>>;

// The view's range: near, far, span.
var<private> range: vec4<f32>;

const NO_TRIANGLE: u32 = 0xffffffffu;
const EXPONENT_MASK: u32 = 0x7f800000u;

// The library's `DepthRange::normalize`: clamped to [0, span]; an empty texel (+inf) or NaN
// gives `span`.
fn normalize_depth(bits: u32) -> f32 {
    if (bits & EXPONENT_MASK) == EXPONENT_MASK {
        return range.z;
    }
    let d = bitcast<f32>(bits);
    return clamp((d - range.x) / (range.y - range.x), 0.0, 1.0) * range.z;
}

fn texel_at(x: i32, y: i32) -> vec2<u32> {
    return textureLoad(depth_map, vec2<i32>(x, y), i32(plane.layer), 0).xy;
}

// The depth change per texel on the texel's own triangle towards `a` (else `-` towards `b`),
// 0 where neither neighbour shares it.
fn slope(id: u32, z: f32, a: vec2<i32>, a_in: bool, b: vec2<i32>, b_in: bool) -> f32 {
    if id == NO_TRIANGLE {
        return 0.0;
    }
    if a_in {
        let t = texel_at(a.x, a.y);
        if t.y == id {
            return normalize_depth(t.x) - z;
        }
    }
    if b_in {
        let t = texel_at(b.x, b.y);
        if t.y == id {
            return -(normalize_depth(t.x) - z);
        }
    }
    return 0.0;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    // Encoders without parameters still bind them (one layout for every technique).
    _ = tech.v[0];
    range = ranges[plane.layer];
    let n = plane.res;
    if gid.x >= n || gid.y >= n {
        return;
    }
    let x = i32(gid.x);
    let y = i32(gid.y);
    let t = texel_at(x, y);
    let z = normalize_depth(t.x);
    let last = i32(n) - 1;
    let right = x < last;
    let left = x > 0;
    let down = y < last;
    let up = y > 0;
    let dx = slope(t.y, z, vec2<i32>(x + 1, y), right, vec2<i32>(x - 1, y), left);
    let dy = slope(t.y, z, vec2<i32>(x, y + 1), down, vec2<i32>(x, y - 1), up);
    let variance = 0.25 * (dx * dx + dy * dy);
    out[gid.y * n + gid.x] = store(encode_texel(z, variance, plane.group), plane.format);
}
