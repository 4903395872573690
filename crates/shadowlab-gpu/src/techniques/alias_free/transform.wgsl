// gpu:afsm, stage `transform` (Aila & Laine 2004, Section 3, "Projection of Sampling
// Points"): every lit sample's shadow ray, formed exactly as gpu:raytrace and the CPU
// reference form it, is projected to its light plane; each plane's sample count, bounds,
// depth range and reach are gathered for the plan. Composed after shaders/common/
// {ray_offset, light, watertight}.wgsl and grid.wgsl.

@group(0) @binding(0) var<uniform> params: AfsmParams;
@group(0) @binding(1) var<storage, read> samples: array<u32>;
@group(0) @binding(2) var<storage, read> projs: array<Proj>;
@group(0) @binding(3) var<storage, read_write> planes: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> s_uvz: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read_write> s_ray: array<u32>;

// Floats a sample holds: position, its error bound, normal, triangle id (as bits).
const SAMPLE_STRIDE: u32 = 10u;
const NO_TRIANGLE: u32 = 0xffffffffu;
// Per-plane fields gathered in workgroup memory: count, lo u, lo v, hi u, hi v, zmax,
// dmax, far.
const FIELDS: u32 = 8u;

var<workgroup> wg: array<atomic<u32>, 56>;

// The library's `cube_face`: the major axis of `d` and its sign.
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x >= 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

struct Placed {
    uvz: vec3<f32>,
    ok: bool,
}

// Where `p` falls on plane `pl`; `ok` false where a perspective projection is undefined.
fn project(pl: u32, p: vec3<f32>) -> Placed {
    let pr = projs[pl];
    let q = p - pr.o;
    let x = dot3(q, pr.s);
    let y = dot3(q, pr.t);
    let z = dot3(q, pr.w);
    if pr.persp == 0u {
        return Placed(vec3<f32>(x, y, z), true);
    }
    let u = x / z;
    let v = y / z;
    return Placed(vec3<f32>(u, v, z), z > 0.0 && finite(u) && finite(v));
}

fn init_field(f: u32) -> u32 {
    // lo fields start high, the others at zero.
    if f == 1u || f == 2u {
        return 0xffffffffu;
    }
    return 0u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    if li < 56u {
        atomicStore(&wg[li], init_field(li % FIELDS));
    }
    workgroupBarrier();
    let i = linear_id(gid);
    if i < params.n_samples {
        let b = i * SAMPLE_STRIDE;
        let own = samples[b + 9u];
        let p = bitcast<vec3<f32>>(vec3<u32>(samples[b], samples[b + 1u], samples[b + 2u]));
        let err = bitcast<vec3<f32>>(vec3<u32>(samples[b + 3u], samples[b + 4u], samples[b + 5u]));
        let n = bitcast<vec3<f32>>(vec3<u32>(samples[b + 6u], samples[b + 7u], samples[b + 8u]));
        var state = UNLIT;
        if own == NO_TRIANGLE {
            state = UNCOVERED;
        } else if illuminates(params.light, p, n) {
            let l = shadow_ray(params.light, p).dir;
            let o = offset_origin(p, err, n, l);
            let r = shadow_ray(params.light, o);
            let sh = shear_of(r.dir);
            let rb = i * 8u;
            s_ray[rb] = bitcast<u32>(o.x);
            s_ray[rb + 1u] = bitcast<u32>(o.y);
            s_ray[rb + 2u] = bitcast<u32>(o.z);
            s_ray[rb + 3u] = sh.k.x | (sh.k.y << 2u) | (sh.k.z << 4u);
            s_ray[rb + 4u] = bitcast<u32>(sh.s.x);
            s_ray[rb + 5u] = bitcast<u32>(sh.s.y);
            s_ray[rb + 6u] = bitcast<u32>(sh.s.z);
            s_ray[rb + 7u] = bitcast<u32>(r.t_max);
            // A point light's samples go to the cube face their direction falls on; a
            // spot light's to its own plane, or, behind it, to the face of the cube that
            // stands in for it.
            var pl = 0u;
            if params.light.kind == LIGHT_POINT {
                pl = cube_face(o - params.light.pos_or_dir);
            }
            var at = project(pl, o);
            if !at.ok && params.light.kind == LIGHT_SPOT {
                pl = 1u + cube_face(o - params.light.pos_or_dir);
                at = project(pl, o);
            }
            if !at.ok {
                // The sample sits on the light: any point of the face will do, the
                // tolerance and the exact test decide.
                at = Placed(vec3<f32>(0.0), true);
            }
            state = pl;
            s_uvz[i] = vec4<u32>(bitcast<vec3<u32>>(at.uvz), pl);
            let f = pl * FIELDS;
            atomicAdd(&wg[f], 1u);
            atomicMin(&wg[f + 1u], enc(at.uvz.x));
            atomicMin(&wg[f + 2u], enc(at.uvz.y));
            atomicMax(&wg[f + 3u], enc(at.uvz.x));
            atomicMax(&wg[f + 4u], enc(at.uvz.y));
            atomicMax(&wg[f + 5u], enc(at.uvz.z));
            if projs[pl].persp != 0u {
                let q = o - params.light.pos_or_dir;
                atomicMax(&wg[f + 7u], bitcast<u32>(sqrt(dot3(q, q))));
            }
        }
        if state >= UNCOVERED {
            s_uvz[i] = vec4<u32>(0u, 0u, 0u, state);
        }
    }
    workgroupBarrier();
    if li < 56u {
        let pl = li / FIELDS;
        let f = li % FIELDS;
        if pl < params.n_planes && atomicLoad(&wg[pl * FIELDS]) > 0u {
            let v = atomicLoad(&wg[li]);
            let g = pl * PLANE_STRIDE + f;
            if f == 0u {
                atomicAdd(&planes[g], v);
            } else if f == 1u || f == 2u {
                atomicMin(&planes[g], v);
            } else {
                atomicMax(&planes[g], v);
            }
        }
    }
}
