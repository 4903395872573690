//! The `bumpy` stress scene: a densely tessellated height field that shadows itself, with
//! a few casters above it whose shadows fall on its slopes.

use super::params::Params;
use super::shapes::{add_box, add_cylinder, add_sphere};
use super::{camera, sky_direction};
use crate::error::Result;
use crate::light::Light;
use crate::math::vec3;
use crate::scene::{Material, Scene};

/// The finest height-field grid `bumpy` makes (cells per side; 2048² cells are 8.4 M
/// triangles).
pub const MAX_BUMPY_RESOLUTION: u64 = 2048;
/// Half the side of the bumpy receiver.
const BUMPY_HALF: f32 = 7.0;

/// The bumpy receiver's height at `(x, z)`: a few sines of different scales, so that it
/// both shadows itself and receives the casters' shadows on slopes.
fn bump_height(x: f32, z: f32) -> f32 {
    0.30 * (0.9 * x).sin() * (0.7 * z).cos()
        + 0.12 * (2.3 * x + 0.8 * z + 1.0).sin()
        + 0.05 * (6.1 * z - 2.7 * x).sin()
        + 0.02 * (13.0 * x + 1.7).sin() * (11.0 * z).cos()
}

pub(super) fn build(p: &Params) -> Result<Scene> {
    let res = p.int("resolution", 512, 1, MAX_BUMPY_RESOLUTION)? as usize;
    let mut s = Scene::new("bumpy");
    let terrain = s.add_material(Material::opaque("terrain", vec3(0.62, 0.66, 0.52)));
    let red = s.add_material(Material::opaque("sphere", vec3(0.80, 0.30, 0.25)));
    let blue = s.add_material(Material::opaque("box", vec3(0.30, 0.45, 0.80)));
    let step = 2.0 * BUMPY_HALF / res as f32;
    let point = |i: usize, j: usize| {
        let (x, z) = (-BUMPY_HALF + i as f32 * step, -BUMPY_HALF + j as f32 * step);
        vec3(x, bump_height(x, z), z)
    };
    s.reserve(2 * res * res + 2000);
    for j in 0..res {
        for i in 0..res {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            s.push([a, b, c], terrain);
            s.push([a, c, d], terrain);
        }
    }
    add_sphere(&mut s, vec3(-1.2, 1.6, 0.6), 0.6, 24, 32, red);
    add_box(&mut s, vec3(0.8, 1.2, -1.4), vec3(1.8, 1.5, -0.4), blue);
    add_cylinder(
        &mut s,
        vec3(-0.5, 1.0, -2.0),
        vec3(1.5, 1.9, -2.2),
        0.12,
        12,
        true,
        blue,
    );
    s.light = Some(Light::Directional {
        to_light: sky_direction(30.0, -70.0),
    });
    s.camera = Some(camera(vec3(2.5, 4.5, 7.5), vec3(0.0, 0.2, -0.5), 50.0));
    Ok(s)
}
