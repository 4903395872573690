// The light views of the filtered maps as the fit, the blocker search and the look-up see
// them (the library's `LightView`: `project`, `texel_size`, `cube_face`, and
// `light_footprint`), and the depth range each map is normalized over, which stage `fit`
// writes and the later stages read.

struct ViewU {
    clip_from_world: mat4x4<f32>,
    light_from_world: mat4x4<f32>,
    // 1 for an orthographic view.
    ortho: u32,
    // The view's own near and far planes, and its image's extent at unit depth (or across,
    // for an orthographic view).
    near: f32,
    far: f32,
    extent: f32,
}

// The library's `DepthRange`.
struct RangeU {
    near: f32,
    far: f32,
    span: f32,
    _pad: f32,
}

const BIG: f32 = 3.0e38;

// The library's `cube_face`: the major axis of the direction from the light.
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

// The view a point is looked up in: its cube face for a point light, else the only one.
fn view_of(light: LightU, p: vec3<f32>) -> u32 {
    if light.kind == LIGHT_POINT {
        return cube_face(p - light.pos_or_dir);
    }
    return 0u;
}

// The map coordinates of `p` (`LightView::project`'s u, v).
fn project(v: ViewU, p: vec3<f32>) -> vec2<f32> {
    let c = v.clip_from_world * vec4<f32>(p, 1.0);
    let inv_w = 1.0 / c.w;
    return vec2<f32>(c.x * inv_w * 0.5 + 0.5, 0.5 - c.y * inv_w * 0.5);
}

// The linear light depth of `p` (`LightView::depth`).
fn light_depth(v: ViewU, p: vec3<f32>) -> f32 {
    return -(v.light_from_world * vec4<f32>(p, 1.0)).z;
}

// World size of one texel of an `n`-texel map at linear depth `depth`.
fn texel_size(v: ViewU, n: f32, depth: f32) -> f32 {
    if v.ortho == 1u {
        return v.extent / n;
    }
    return v.extent * max(depth, v.near) / n;
}

fn finite2(g: vec2<f32>) -> vec2<f32> {
    if abs(g.x) < BIG && abs(g.y) < BIG {
        return g;
    }
    return vec2<f32>(0.0);
}

// The library's `light_footprint` along one screen step `d`.
fn footprint_axis(v: ViewU, p: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    if v.ortho == 1u {
        let c = v.clip_from_world * vec4<f32>(d, 0.0);
        return finite2(vec2<f32>(0.5 * c.x, -0.5 * c.y));
    }
    return finite2((project(v, p + d) - project(v, p - d)) * 0.5);
}

// The `(dx, dy)` footprint of pixel `k` at `p` from the camera pass's derivatives (six
// floats a pixel in `derivs`, which the stage declares).
fn pixel_footprint(v: ViewU, k: u32, p: vec3<f32>) -> vec4<f32> {
    let b = k * 6u;
    let dx = footprint_axis(v, p, vec3<f32>(derivs[b], derivs[b + 1u], derivs[b + 2u]));
    let dy = footprint_axis(v, p, vec3<f32>(derivs[b + 3u], derivs[b + 4u], derivs[b + 5u]));
    return vec4<f32>(dx, dy);
}
