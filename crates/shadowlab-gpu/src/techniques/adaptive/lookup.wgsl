// gpu:asm, stage `lookup`: each lit receiver reads the finest resident page of the
// virtual map covering it (falling back level by level to the always-resident coarsest)
// and applies Section 4.2's combined test there (`lit_at`): lit when the texel holds its
// own triangle, else when the texel's triangle lies no more than the bias of that level's
// texel in front of it along its shadow ray. Composed after shaders/common/{ray_offset, light}.wgsl and pages.wgsl.

@group(0) @binding(0) var<uniform> vp: VirtualU;
@group(0) @binding(1) var<storage, read> faces: array<FaceV>;
@group(0) @binding(2) var<storage, read> view: array<f32>;
@group(0) @binding(3) var<storage, read> table: array<u32>;
@group(0) @binding(4) var pool_id: texture_2d<u32>;
// Nine floats a triangle.
@group(0) @binding(5) var<storage, read> tris: array<f32>;
@group(0) @binding(6) var<storage, read_write> out: array<f32>;

fn shadow_term(p: vec3<f32>, n: vec3<f32>, own: u32) -> f32 {
    let f = face_of(p);
    let uv = uv_in(f, p);
    let depth = linear_depth(f, p);
    if !(finite(uv.x) && finite(uv.y) && finite(depth)) {
        // No texel to compare with (the CPU's answer for a non-finite look-up).
        return 1.0;
    }
    let h = finest_resident(f, 0u, uv);
    let dir = shadow_ray(vp.light, p).dir;
    let bias = level_bias(f, h.level, depth, n, dir);
    return select(0.0, 1.0, lit_at(h, uv, own, f, p, depth, bias));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * vp.row + gid.x;
    if k >= vp.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let own = bitcast<u32>(view[b + 9u]);
    var s = 1.0;
    if own != NO_TRIANGLE {
        let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
        let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
        if illuminates(vp.light, p, n) {
            s = shadow_term(p, n, own);
        } else {
            s = 0.0;
        }
    }
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}
