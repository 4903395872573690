// The light as every technique sees it (the library's `Light::shadow_ray`,
// `illuminates` and `cone_contains`), with the spot light's axis and cosine formed once on
// the CPU so both sides use the same bits.

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_POINT: u32 = 2u;

struct LightU {
    // Directional: the unit vector towards the light; else the light's position.
    pos_or_dir: vec3<f32>,
    kind: u32,
    // Spot: the unit axis from the light towards its target.
    axis: vec3<f32>,
    // Spot: the cosine of half the cone's opening angle.
    cos_half: f32,
    // +infinity, the reach of a directional light's shadow ray.
    far: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

struct ShadowRay {
    dir: vec3<f32>,
    t_max: f32,
}

fn shadow_ray(light: LightU, p: vec3<f32>) -> ShadowRay {
    if light.kind == LIGHT_DIRECTIONAL {
        return ShadowRay(light.pos_or_dir, light.far);
    }
    let d = light.pos_or_dir - p;
    let len = sqrt(dot3(d, d));
    return ShadowRay(d / len, len);
}

fn cone_contains(light: LightU, l: vec3<f32>) -> bool {
    if light.kind != LIGHT_SPOT {
        return true;
    }
    return dot3(-l, light.axis) >= light.cos_half;
}

fn illuminates(light: LightU, p: vec3<f32>, n: vec3<f32>) -> bool {
    let r = shadow_ray(light, p);
    let dist = r.t_max;
    if dist != dist || dist <= 0.0 || dot3(n, r.dir) <= 0.0 {
        return false;
    }
    return cone_contains(light, r.dir);
}
