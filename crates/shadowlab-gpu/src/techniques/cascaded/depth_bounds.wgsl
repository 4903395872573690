// gpu:cascaded, stage `depth_bounds` (sample distribution shadow maps, Lauritzen et al.
// 2011): the nearest and farthest view depth of the camera pass's samples that the light
// reaches, reduced on the GPU. Each thread takes one pixel's view depth (along the
// camera's forward axis from its eye, the library's formula); a workgroup reduces its
// threads' depths in shared memory, then one thread per workgroup folds them into the two
// global bounds. Depths are reduced as order-preserving integer keys with integer atomics
// (min and max are exact and order-independent), so the result does not depend on the
// order threads run. Composed after shaders/common/{ray_offset, light, order_key}.wgsl.

struct Params {
    light: LightU,
    // The camera's eye and unit forward axis (w unused).
    eye: vec4<f32>,
    forward: vec4<f32>,
    count: u32,
    row: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> view: array<f32>;
// [0]: the nearest depth's key (atomic min), [1]: the farthest's (atomic max).
@group(0) @binding(2) var<storage, read_write> bounds: array<atomic<u32>, 2>;

const VIEW_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
// Keys of +inf and -inf: what a workgroup without a lit receiver contributes.
const KEY_POS_INF: u32 = 0xff800000u;
const KEY_NEG_INF: u32 = 0x007fffffu;

var<workgroup> lo: atomic<u32>;
var<workgroup> hi: atomic<u32>;

@compute @workgroup_size(64)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
) {
    if li == 0u {
        atomicStore(&lo, KEY_POS_INF);
        atomicStore(&hi, KEY_NEG_INF);
    }
    workgroupBarrier();
    let k = gid.y * params.row + gid.x;
    if k < params.count {
        let b = k * VIEW_STRIDE;
        let tri = bitcast<u32>(view[b + 9u]);
        if tri != NO_TRIANGLE {
            let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
            let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
            if illuminates(params.light, p, n) {
                let z = dot3(p - params.eye.xyz, params.forward.xyz);
                let key = order_key(z);
                atomicMin(&lo, key);
                atomicMax(&hi, key);
            }
        }
    }
    workgroupBarrier();
    if li == 0u {
        atomicMin(&bounds[0], atomicLoad(&lo));
        atomicMax(&bounds[1], atomicLoad(&hi));
    }
}
