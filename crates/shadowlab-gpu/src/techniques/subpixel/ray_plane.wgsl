// gpu:subpixel, the library's `ray_plane.rs`: the camera's primary rays as affine
// functions of the image position, the facet and blocker-plane parts whose products are
// a blocker plane's half-plane on the screen, and the tangent plane's Jacobian. Composed
// after subpixel/bindings.wgsl.

struct Ray {
    o: vec3<f32>,
    d: vec3<f32>,
}

fn ray_at(x: f32, y: f32) -> Ray {
    if fr.parallel == 1u {
        return Ray(fr.o0 + fr.ox * x + fr.oy * y, fr.d0);
    }
    return Ray(fr.o0, fr.d0 + fr.dx * x + fr.dy * y);
}

fn pixel_widths(stretch: f32, depth: f32) -> f32 {
    if fr.parallel == 1u {
        return stretch * length(fr.ox);
    }
    return stretch * length(fr.dx) * max(depth, 0.0);
}

// `RayPlane::plane` of the plane m·(X − q) = 0.
fn plane_part(m: vec3<f32>, q: vec3<f32>) -> vec4<f32> {
    if fr.parallel == 1u {
        return vec4<f32>(dot3(m, fr.d0), dot3(m, fr.ox), dot3(m, fr.oy), dot3(m, fr.o0 - q));
    }
    return vec4<f32>(dot3(m, fr.o0 - q), dot3(m, fr.dx), dot3(m, fr.dy), dot3(m, fr.d0));
}

// `RayPlane::facet` of the tangent plane through p with normal n at pixel corner (x, y).
fn facet_part(n: vec3<f32>, p: vec3<f32>, x: f32, y: f32) -> vec4<f32> {
    let r = ray_at(x, y);
    if fr.parallel == 1u {
        return vec4<f32>(dot3(n, fr.ox), dot3(n, fr.oy), dot3(n, r.o - p), -dot3(n, r.d));
    }
    return vec4<f32>(-dot3(n, fr.dx), -dot3(n, fr.dy), -dot3(n, r.d), -dot3(n, p - r.o));
}

struct Jacobian {
    ok: bool,
    jx: vec3<f32>,
    jy: vec3<f32>,
    r: f32,
}

// `RayPlane::tangent_jacobian`.
fn tangent_jacobian(n: vec3<f32>, p: vec3<f32>, x: f32, y: f32) -> Jacobian {
    let ray = ray_at(x, y);
    let dc = ray.d;
    let gc = dot3(n, dc);
    if fr.parallel == 1u {
        let jx = fr.ox - dc * (dot3(n, fr.ox) / gc);
        let jy = fr.oy - dc * (dot3(n, fr.oy) / gc);
        let ok = finite(jx.x) && finite(jx.y) && finite(jx.z) && finite(jy.x) && finite(jy.y) && finite(jy.z);
        return Jacobian(ok, jx, jy, 0.0);
    }
    let gx = dot3(n, fr.dx);
    let gy = dot3(n, fr.dy);
    let r = 0.5 * (abs(gx) + abs(gy)) / abs(gc);
    if r != r {
        return Jacobian(false, vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    }
    let s = dot3(n, p - ray.o) / (gc * gc);
    let jx = (fr.dx * gc - dc * gx) * s;
    let jy = (fr.dy * gc - dc * gy) * s;
    return Jacobian(true, jx, jy, r);
}
