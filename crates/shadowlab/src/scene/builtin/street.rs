//! The `street` scene of the perspective shadow map paper's Figure 9 (Stamminger &
//! Drettakis 2002): a long street of buildings, lamp posts and cars to the horizon, the
//! sun perpendicular to the view. The paper's cars and aeroplanes move; here everything
//! stands still (a still frame is what the techniques are compared on), and the camera
//! path (`--frames N`) is a sideways dolly across the street, looking down it: the view's
//! receivers shift under maps fitted to them, where a uniform or perspective map's texels
//! swim and its shadow edges shimmer while the true shadows stand still.

use super::params::Params;
use super::rng::Rng;
use super::shapes::{add_box, add_cylinder, add_plane};
use super::{camera, sky_direction};
use crate::camera::{CameraKey, CameraPath};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::scene::{Material, Scene};

/// The longest street `street` makes (metres).
pub const MAX_STREET_LENGTH: f32 = 20_000.0;
/// The sideways dolly of the camera path: the eye and the point looked at both move this
/// far (metres, along +X) from the first key to the last, centred on the still camera.
const DOLLY_METRES: f32 = 2.0;
/// Distance between lamp posts along each side of the street (metres).
const LAMP_SPACING: f32 = 25.0;

pub(super) fn build(p: &Params) -> Result<Scene> {
    let length = p.real("length", 1500.0, 50.0, MAX_STREET_LENGTH)?;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let mut rng = Rng::new(seed, 0);
    let mut s = Scene::new("street");
    let asphalt = s.add_material(Material::opaque("road", vec3(0.35, 0.35, 0.37)));
    let pavement = s.add_material(Material::opaque("pavement", vec3(0.70, 0.68, 0.64)));
    let facade = [
        s.add_material(Material::opaque("brick", vec3(0.66, 0.40, 0.32))),
        s.add_material(Material::opaque("stucco", vec3(0.85, 0.80, 0.68))),
        s.add_material(Material::opaque("concrete", vec3(0.62, 0.63, 0.64))),
    ];
    let metal = s.add_material(Material::opaque("lamp posts", vec3(0.20, 0.22, 0.24)));
    let car_colours = [
        s.add_material(Material::opaque("red car", vec3(0.70, 0.12, 0.10))),
        s.add_material(Material::opaque("blue car", vec3(0.15, 0.25, 0.65))),
        s.add_material(Material::opaque("white car", vec3(0.85, 0.85, 0.85))),
    ];
    let (road_half, walk) = (6.0f32, 4.0f32);
    let (z0, z1) = (20.0f32, -length);
    let mid = (z0 + z1) * 0.5;
    let half_len = (z0 - z1) * 0.5;
    // Road, two raised pavements, and the ground beyond the buildings.
    add_plane(&mut s, vec3(0.0, 0.0, mid), road_half, half_len, asphalt);
    for side in [-1.0f32, 1.0] {
        let x = side * (road_half + walk * 0.5);
        add_box(
            &mut s,
            vec3(x - walk * 0.5, 0.0, z1),
            vec3(x + walk * 0.5, 0.15, z0),
            pavement,
        );
        let gx = side * (road_half + walk + 200.0);
        add_plane(&mut s, vec3(gx, 0.0, mid), 200.0, half_len, pavement);
    }
    // Buildings of random widths and heights along both sides.
    for side in [-1.0f32, 1.0] {
        let mut z = z0;
        while z > z1 {
            let w = rng.range(10.0, 28.0).min(z - z1);
            // The sunny side's buildings are lower, so their shadows end on the road in a
            // ragged edge (and the gaps between them let the sun through) rather than
            // covering the whole street.
            let h = if side > 0.0 {
                rng.range(5.0, 18.0)
            } else {
                rng.range(8.0, 40.0)
            };
            let depth = rng.range(12.0, 20.0);
            let gap = if rng.unit() < 0.4 {
                rng.range(5.0, 15.0)
            } else {
                0.0
            };
            let x_in = side * (road_half + walk);
            let x_out = side * (road_half + walk + depth);
            let m = facade[(rng.next_u64() % 3) as usize];
            add_box(
                &mut s,
                vec3(x_in.min(x_out), 0.0, z - w),
                vec3(x_in.max(x_out), h, z),
                m,
            );
            z -= w + gap;
        }
    }
    // Lamp posts on both pavements, their arms over the road.
    let mut z = z0 - 5.0;
    while z > z1 {
        for side in [-1.0f32, 1.0] {
            let x = side * (road_half + 0.6);
            add_cylinder(
                &mut s,
                vec3(x, 0.15, z),
                vec3(x, 6.0, z),
                0.09,
                8,
                false,
                metal,
            );
            add_cylinder(
                &mut s,
                vec3(x, 6.0, z),
                vec3(x - side * 1.5, 6.2, z),
                0.05,
                6,
                false,
                metal,
            );
            let lx = x - side * 1.5;
            add_box(
                &mut s,
                vec3(lx - 0.3, 5.95, z - 0.15),
                vec3(lx + 0.3, 6.2, z + 0.15),
                metal,
            );
        }
        z -= LAMP_SPACING;
    }
    // Parked and driving cars: a body and a cabin each.
    let mut z = z0 - 40.0;
    while z > z1 {
        let lane = if rng.unit() < 0.5 { -3.0 } else { 3.0 };
        let m = car_colours[(rng.next_u64() % 3) as usize];
        add_box(
            &mut s,
            vec3(lane - 0.9, 0.25, z - 2.2),
            vec3(lane + 0.9, 1.0, z + 2.2),
            m,
        );
        add_box(
            &mut s,
            vec3(lane - 0.8, 1.0, z - 1.1),
            vec3(lane + 0.8, 1.5, z + 1.0),
            m,
        );
        z -= rng.range(15.0, 60.0);
    }
    // Light from the right, perpendicular to the view down the street (−Z).
    s.light = Some(Light::Directional {
        to_light: sky_direction(50.0, 90.0),
    });
    let (eye, target) = (vec3(-2.0, 1.7, 15.0), vec3(-1.5, 1.2, -100.0));
    s.camera = Some(camera(eye, target, 60.0));
    let step = Vec3::X * (DOLLY_METRES * 0.5);
    s.camera_path = Some(CameraPath::stretched(vec![
        CameraKey {
            eye: eye - step,
            target: target - step,
        },
        CameraKey {
            eye: eye + step,
            target: target + step,
        },
    ]));
    Ok(s)
}
