// The error-bounded ray origin (pbrt's OffsetRayOrigin), operation for operation the
// library's `SurfacePoint::offset_origin`: the origin leaves the surface along the face
// normal by the point's floating-point error bound, rounded away from the surface.

fn next_up(x: f32) -> f32 {
    if x != x || bitcast<u32>(x) == 0x7f800000u { return x; }
    if x == 0.0 { return bitcast<f32>(1u); }
    let bits = bitcast<u32>(x);
    if x > 0.0 { return bitcast<f32>(bits + 1u); }
    return bitcast<f32>(bits - 1u);
}

fn next_down(x: f32) -> f32 {
    return -next_up(-x);
}

// Dot product in the library's order: (x·x' + y·y') + z·z'.
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn offset_origin(p: vec3<f32>, err: vec3<f32>, n: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let d = dot3(abs(n), err);
    var offset = n * d;
    if dot3(w, n) < 0.0 {
        offset = -offset;
    }
    var po = p + offset;
    for (var i = 0u; i < 3u; i++) {
        if offset[i] > 0.0 {
            po[i] = next_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_down(po[i]);
        }
    }
    return po;
}
