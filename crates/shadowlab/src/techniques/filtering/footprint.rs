//! The screen-space footprint of a pixel in the light map: the derivatives of its map
//! coordinates per pixel step, which the look-up's level of detail and anisotropy come
//! from (the GPU's `ddx/ddy` of the texture coordinates in Annen et al. 2007, Section 4.1's
//! "tri-linear and anisotropic filtering").

use crate::light::LightView;
use crate::math::{Vec2, Vec3};

/// The screen-space derivatives of a look-up's texture coordinates, in map coordinates
/// (`[0, 1]` across the map) per pixel step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// d(u, v)/dx: change per pixel step to the right.
    pub dx: Vec2,
    /// d(u, v)/dy: change per pixel step down.
    pub dy: Vec2,
}

/// The screen-space derivatives of the light-map coordinates of a surface point `p` whose
/// world position changes by `dpdx`, `dpdy` per pixel step: half the differences of the
/// projections of `p ± dpdx` and `p ± dpdy`. Non-finite projections (behind a perspective
/// eye) give a zero derivative.
pub fn light_footprint(view: &LightView, p: Vec3, dpdx: Vec3, dpdy: Vec3) -> Footprint {
    if view.orthographic {
        // The projection is affine: the difference is the linear part applied to the step
        // (one matrix-vector product per axis instead of four projections).
        let m = &view.clip_from_world;
        let lin = |d: Vec3| {
            let c = m.transform_vector3(d);
            let g = Vec2::new(0.5 * c.x, -0.5 * c.y);
            if g.is_finite() {
                g
            } else {
                Vec2::ZERO
            }
        };
        return Footprint {
            dx: lin(dpdx),
            dy: lin(dpdy),
        };
    }
    let uv = |q: Vec3| {
        let s = view.project(q);
        Vec2::new(s.u, s.v)
    };
    let diff = |d: Vec3| {
        let g = (uv(p + d) - uv(p - d)) * 0.5;
        if g.is_finite() {
            g
        } else {
            Vec2::ZERO
        }
    };
    Footprint {
        dx: diff(dpdx),
        dy: diff(dpdy),
    }
}
