// The watertight ray-triangle test (Woop, Benthin & Wald 2013), operation for operation
// the library's `intersect_sheared`, so the GPU and the CPU reference decide the same
// hits. The CPU falls back to double precision when an edge function is exactly zero in
// single precision; WGSL has no portable f64, so the fallback here forms each difference
// of products with an error-free product (fma), which has the same sign and, but for a
// double rounding, the same value.

// The axis permutation and shear of a ray direction (the library's `RayShear`).
struct Shear {
    k: vec3<u32>,
    s: vec3<f32>,
}

// A hit: `ok` false for a miss; `t` and barycentrics `b` of the three vertices.
struct TriHit {
    ok: bool,
    t: f32,
    b: vec3<f32>,
}

fn shear_of(dir: vec3<f32>) -> Shear {
    let a = abs(dir);
    // The largest component; ties go to the lower axis, as glam's max_position does.
    var kz = 0u;
    if a.y > a.x { kz = 1u; }
    if a.z > a[kz] { kz = 2u; }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if dir[kz] < 0.0 {
        let tmp = kx;
        kx = ky;
        ky = tmp;
    }
    let sz = 1.0 / dir[kz];
    let sx = dir[kx] * sz;
    let sy = dir[ky] * sz;
    return Shear(vec3<u32>(kx, ky, kz), vec3<f32>(sx, sy, sz));
}

// a·b − c·d with the rounding error of both products kept (the double-precision fallback).
fn diff_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = a * b;
    let q = c * d;
    let ep = fma(a, b, -p);
    let eq = fma(c, d, -q);
    return (p - q) + (ep - eq);
}

fn intersect_sheared(origin: vec3<f32>, sh: Shear, t_min: f32, t_max: f32,
                     v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> TriHit {
    let miss = TriHit(false, 0.0, vec3<f32>(0.0));
    let kx = sh.k.x;
    let ky = sh.k.y;
    let kz = sh.k.z;
    let a = v0 - origin;
    let b = v1 - origin;
    let c = v2 - origin;
    let ax = a[kx] - sh.s.x * a[kz];
    let ay = a[ky] - sh.s.y * a[kz];
    let bx = b[kx] - sh.s.x * b[kz];
    let by = b[ky] - sh.s.y * b[kz];
    let cx = c[kx] - sh.s.x * c[kz];
    let cy = c[ky] - sh.s.y * c[kz];
    var u = cx * by - cy * bx;
    var w = ax * cy - ay * cx;
    var x = bx * ay - by * ax;
    if u == 0.0 || w == 0.0 || x == 0.0 {
        u = diff_of_products(cx, by, cy, bx);
        w = diff_of_products(ax, cy, ay, cx);
        x = diff_of_products(bx, ay, by, ax);
    }
    if (u < 0.0 || w < 0.0 || x < 0.0) && (u > 0.0 || w > 0.0 || x > 0.0) {
        return miss;
    }
    let det = u + w + x;
    if det == 0.0 {
        return miss;
    }
    let az = sh.s.z * a[kz];
    let bz = sh.s.z * b[kz];
    let cz = sh.s.z * c[kz];
    let t_scaled = u * az + w * bz + x * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t > t_min && t < t_max) {
        return miss;
    }
    return TriHit(true, t, vec3<f32>(u * inv_det, w * inv_det, x * inv_det));
}
