//! The receivers' look-up of `psm` (Stamminger & Drettakis 2002, Section 3: "handled as
//! point lights with their shadow map depth test reversed" for inverted lights): each
//! visible receiver is taken into post-perspective space, to its map (the cube face of its
//! direction from `q`, if there is a cube) and compared with the stored depth.
//!
//! The depth offset is applied in shadow map space, as the paper does, in units of the
//! map's own texel: `texel' · (bias + slope_bias · tan θ')` with `texel'` the post-space
//! texel size at the receiver and `θ'` the post-space angle between the receiver's plane
//! and the light.

use super::post_space::PostLight;
use super::Setup;
use crate::frame::Frame;
use crate::light::cube_face;
use crate::math::Vec3;
use crate::techniques::shadow_map::receiver_bias;
use rayon::prelude::*;

/// Per-pixel shadow test against the post-perspective maps.
pub(super) fn lookup(
    frame: &Frame,
    setup: &Setup,
    lit: &[bool],
    res: u32,
    bias: f32,
    slope: f32,
) -> Vec<Vec3> {
    let view = frame.view;
    let pfw = setup.post.post_from_world;
    let planes = setup.post_planes;
    let sign = if setup.post.light == PostLight::Inverted {
        -1.0f32
    } else {
        1.0
    };
    let kind = setup.post.light;
    let (fres, ires) = (res as f32, res as i64 - 1);
    let shadow = |p: Vec3, nw: Vec3| -> f32 {
        let h = p.extend(1.0);
        let inv_wp = 1.0 / setup.w_row.dot(h);
        // The post-space position is needed only towards a post-space point light.
        let pp = if kind == PostLight::Directional {
            Vec3::ZERO
        } else {
            (pfw * h).truncate() * inv_wp
        };
        let map = match setup.cube {
            None => &setup.maps[0],
            Some(faces) => match faces[cube_face(pp - setup.q)] {
                usize::MAX => return 1.0,
                i => &setup.maps[i],
            },
        };
        let (c, depth) = map.transform(h, inv_wp);
        let inv_cw = 1.0 / c.w;
        let (u, v) = (c.x * inv_cw * 0.5 + 0.5, 0.5 - c.y * inv_cw * 0.5);
        // The receiver's plane and the light direction in post-perspective space.
        let np = (planes * nw.extend(-nw.dot(p)))
            .truncate()
            .normalize_or_zero();
        let l = match kind {
            PostLight::Directional => setup.dir,
            PostLight::Point => (setup.q - pp).normalize_or_zero(),
            PostLight::Inverted => (pp - setup.q).normalize_or_zero(),
        };
        let offset = receiver_bias(map.texel_size(depth), np, l, bias, slope);
        let x = ((u * fres).floor() as i64).clamp(0, ires) as usize;
        let y = ((v * fres).floor() as i64).clamp(0, ires) as usize;
        if sign * depth - offset > map.depth[y * res as usize + x] {
            0.0
        } else {
            1.0
        }
    };
    const CHUNK: usize = 4096;
    let mut value = vec![Vec3::ONE; lit.len()];
    value
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let base = c * CHUNK;
            let range = base..base + out.len();
            let (lit, pos, nrm) = (
                &lit[range.clone()],
                &view.position[range.clone()],
                &view.normal[range],
            );
            for (i, o) in out.iter_mut().enumerate() {
                *o = if lit[i] {
                    Vec3::splat(shadow(pos[i], nrm[i]))
                } else if view.covered(base + i) {
                    Vec3::ZERO
                } else {
                    Vec3::ONE
                };
            }
        });
    value
}
