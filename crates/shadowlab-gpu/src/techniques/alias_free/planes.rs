//! The light's image planes, formed on the CPU exactly as the library's `afsm` forms them:
//! an orthographic plane along a directional light (centred on the scene), a spot light's
//! own perspective plane followed by the six faces of a cube (for samples behind the
//! spot's plane), or a point light's six cube faces.

use bytemuck::{Pod, Zeroable};
use shadowlab::light::{pick_up, Light, CUBE_FACES};
use shadowlab::math::Vec3;
use shadowlab::scene::Scene;

/// `Proj` of `grid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct ProjU {
    o: [f32; 3],
    persp: u32,
    s: [f32; 3],
    pad0: u32,
    t: [f32; 3],
    pad1: u32,
    w: [f32; 3],
    pad2: u32,
}

impl ProjU {
    fn new(o: Vec3, persp: bool, s: Vec3, t: Vec3, w: Vec3) -> Self {
        ProjU {
            o: o.to_array(),
            persp: u32::from(persp),
            s: s.to_array(),
            pad0: 0,
            t: t.to_array(),
            pad1: 0,
            w: w.to_array(),
            pad2: 0,
        }
    }
}

/// The planes of `light`, and the scales of the culling tolerance: the scene's diagonal
/// (orthographic) and the farthest scene corner from the light (perspective).
pub(super) struct Planes {
    pub(super) projs: Vec<ProjU>,
    pub(super) ortho_scale: f32,
    pub(super) far_corner: f32,
}

fn cube(l: Vec3) -> impl Iterator<Item = ProjU> {
    CUBE_FACES
        .into_iter()
        .map(move |(dir, up)| ProjU::new(l, true, dir.cross(up), up, dir))
}

/// The planes of `light` over `scene`.
pub(super) fn planes(light: &Light, scene: &Scene) -> Planes {
    let bounds = scene.bounds;
    let far_from = |l: Vec3| {
        bounds
            .corners()
            .iter()
            .map(|c| (*c - l).length())
            .fold(0.0f32, f32::max)
    };
    let (projs, far_corner) = match *light {
        Light::Directional { to_light } => {
            let w = -to_light.normalize();
            let s = w.cross(pick_up(w)).normalize();
            let t = s.cross(w);
            (vec![ProjU::new(bounds.center(), false, s, t, w)], 0.0)
        }
        Light::Spot {
            position, target, ..
        } => {
            let f = (target - position).normalize();
            let s = f.cross(pick_up(f)).normalize();
            let t = s.cross(f);
            let mut v = vec![ProjU::new(position, true, s, t, f)];
            v.extend(cube(position));
            (v, far_from(position))
        }
        Light::Point { position } => (cube(position).collect(), far_from(position)),
    };
    Planes {
        projs,
        ortho_scale: bounds.diagonal().max(f32::MIN_POSITIVE),
        far_corner,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_projection_record_has_the_wgsl_size() {
        assert_eq!(std::mem::size_of::<ProjU>(), 64);
    }
}
