// The library's camera rays and surface points, as the GPU camera pass and the
// supersampled reference form them: `RayGenerator::ray` from the generator's parts
// (`RaysU`, filled by upload.rs `RaysU::of`), and `SurfacePoint::from_barycentrics`, a
// point on a triangle with its floating-point error bound.

struct RaysU {
    eye: vec3<f32>,
    // 1 for parallel (orthographic) rays.
    parallel: u32,
    forward: vec3<f32>,
    inv_width: f32,
    // The image's right and upper half-extents: at unit depth, or in world units when
    // parallel.
    right: vec3<f32>,
    inv_height: f32,
    up: vec3<f32>,
    // Image width in pixels.
    width: u32,
}

struct CameraRay {
    o: vec3<f32>,
    d: vec3<f32>,
}

// `RayGenerator::ray` through image position (x, y).
fn camera_ray(r: RaysU, x: f32, y: f32) -> CameraRay {
    let nx = x * r.inv_width * 2.0 - 1.0;
    let ny = 1.0 - y * r.inv_height * 2.0;
    if r.parallel != 0u {
        return CameraRay(r.eye + (r.right * nx + r.up * ny), r.forward);
    }
    return CameraRay(r.eye, r.forward + r.right * nx + r.up * ny);
}

struct SurfacePoint {
    p: vec3<f32>,
    err: vec3<f32>,
}

// `SurfacePoint::from_barycentrics` of the triangle (v0, v1, v2) at b, with the library's
// gamma(7) and gamma(16).
fn surface_point(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, b: vec3<f32>, gamma7: f32, gamma16: f32) -> SurfacePoint {
    let w0 = v0 * b.x;
    let w1 = v1 * b.y;
    let w2 = v2 * b.z;
    let mag = abs(w0) + abs(w1) + abs(w2);
    let vmag = max(max(abs(v0), abs(v1)), abs(v2));
    return SurfacePoint(w0 + w1 + w2, mag * gamma7 + vmag * gamma16);
}
