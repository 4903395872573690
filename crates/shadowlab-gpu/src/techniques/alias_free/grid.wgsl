// gpu:afsm, what every stage shares: the frame's parameters, the light planes' records
// and the light-space grid's conventions. Composed after shaders/common/{ray_offset,
// light}.wgsl.

struct AfsmParams {
    light: LightU,
    // Samples of the frame (the camera pass's pixels, or the sub-pixel samples).
    n_samples: u32,
    // Pixels of the frame.
    n_pixels: u32,
    // 1 when sample i is pixel i (one sample a pixel, the camera pass's own).
    identity: u32,
    // Light planes: 1 (directional), 7 (spot: its own plane, then a cube for samples
    // behind it) or 6 (point: the cube's faces).
    n_planes: u32,
    // The first triangle of this batch and how many it holds.
    tri_first: u32,
    tri_count: u32,
    // A chunk of a cell's list holds at most this many samples.
    leaf: u32,
    // Cells the frame's grid may hold.
    cell_cap: u32,
    // Samples a cell should hold on average.
    cell_target: f32,
    // 1 when some material is alpha-masked.
    masks: u32,
    // Scale of the culling tolerance on an orthographic plane (the scene's diagonal).
    ortho_scale: f32,
    // The farthest scene corner from a point or spot light.
    far_corner: f32,
}

// A light plane's projection (formed on the CPU as the library's `afsm` forms it):
// orthographic `(u, v, depth) = ((p - o)·s, (p - o)·t, (p - o)·w)`, or perspective from
// the light at `o`: `(x, y, z) = ((p - o)·s, (p - o)·t, (p - o)·w)`, `(u, v) = (x, y) / z`.
struct Proj {
    o: vec3<f32>,
    persp: u32,
    s: vec3<f32>,
    _p0: u32,
    t: vec3<f32>,
    _p1: u32,
    w: vec3<f32>,
    _p2: u32,
}

// Each plane's record in `planes`, PLANE_STRIDE words from PLANE_STRIDE · plane: filled
// by the transform (atomics on order-preserving encodings) and by the plan.
const PLANE_STRIDE: u32 = 16u;
const PL_COUNT: u32 = 0u;
const PL_LO_U: u32 = 1u;
const PL_LO_V: u32 = 2u;
const PL_HI_U: u32 = 3u;
const PL_HI_V: u32 = 4u;
const PL_ZMAX: u32 = 5u;
// The largest |(u, v, 1)| of a perspective plane's samples (positive float bits).
const PL_DMAX: u32 = 6u;
// The farthest sample from the light (positive float bits; plane 0's slot holds the
// largest over every plane after the plan).
const PL_FAR: u32 = 7u;
const PL_GX: u32 = 8u;
const PL_GY: u32 = 9u;
const PL_CELL_BASE: u32 = 10u;
const PL_SAT_BASE: u32 = 11u;
// The grid's origin and cells per unit along u and v (float bits).
const PL_ORG_U: u32 = 12u;
const PL_ORG_V: u32 = 13u;
const PL_INV_U: u32 = 14u;
const PL_INV_V: u32 = 15u;
// After the planes: the grid's total cells.
const PL_TOTAL_CELLS: u32 = 7u * PLANE_STRIDE;

// Threads a row of a two-dimensional dispatch: 32768 workgroups of 64.
const ROW: u32 = 2097152u;
// The sample state of a pixel that shows no surface, and of one the light cannot reach.
const UNCOVERED: u32 = 0xfffffffeu;
const UNLIT: u32 = 0xffffffffu;
// The largest grid side.
const MAX_SIDE: u32 = 4096u;

fn linear_id(gid: vec3<u32>) -> u32 {
    return gid.y * ROW + gid.x;
}

// An order-preserving map of floats to unsigned integers (for atomicMin/atomicMax).
fn enc(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    if (b & 0x80000000u) != 0u {
        return ~b;
    }
    return b | 0x80000000u;
}

fn dec(u: u32) -> f32 {
    if (u & 0x80000000u) != 0u {
        return bitcast<f32>(u & 0x7fffffffu);
    }
    return bitcast<f32>(~u);
}

// True for a finite float.
fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// The cell column (or row) of coordinate `x` on a side of `g` cells from `org`, `inv`
// cells a unit: monotone in `x`, so a rectangle's end cells bracket every sample inside.
fn cell_of(x: f32, org: f32, inv: f32, g: u32) -> u32 {
    let f = (x - org) * inv;
    if !(f > 0.0) {
        return 0u;
    }
    if f >= f32(g) {
        return g - 1u;
    }
    return min(u32(f), g - 1u);
}
