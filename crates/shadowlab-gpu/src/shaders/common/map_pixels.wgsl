// The map look-ups' entry point (gpu:sm, gpu:pcf, gpu:psm, gpu:lispsm, gpu:cascaded): one
// thread per pixel of the camera pass; a covered pixel the light reaches takes the stage's
// `shadow_term(p, n)`, one it does not reach is dark, and an empty pixel is lit, written
// as RGB. Composed after light.wgsl (`illuminates`). The stage declares `params` (with
// `light`, `count` and `row`), the camera pass's samples `view` and the output `out`.

// Floats a pixel of the uploaded camera pass (upload.rs `VIEW_STRIDE`): position, its
// error bound, normal, triangle.
const VIEW_STRIDE: u32 = 10u;
// The triangle index of an empty pixel.
const NO_TRIANGLE: u32 = 0xffffffffu;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.y * params.row + gid.x;
    if k >= params.count {
        return;
    }
    let b = k * VIEW_STRIDE;
    let tri = bitcast<u32>(view[b + 9u]);
    var s = 1.0;
    if tri != NO_TRIANGLE {
        let p = vec3<f32>(view[b], view[b + 1u], view[b + 2u]);
        let n = vec3<f32>(view[b + 6u], view[b + 7u], view[b + 8u]);
        if illuminates(params.light, p, n) {
            s = shadow_term(p, n);
        } else {
            s = 0.0;
        }
    }
    out[k * 3u] = s;
    out[k * 3u + 1u] = s;
    out[k * 3u + 2u] = s;
}
