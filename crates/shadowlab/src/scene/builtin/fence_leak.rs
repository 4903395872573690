//! The `fence-leak` scene: a picket fence in front of objects standing at
//! staggered depths behind it, built to make variance shadow maps leak (the convolution
//! shadow map paper's Figure 9 set-up).
//!
//! A low sun shines through the fence; the pickets' shadows fall across the ground and
//! across boxes and columns placed at several distances behind the fence and of several
//! heights. Under one filter footprint the light's map then holds three depths — a picket,
//! the top of an object and the ground behind it — which is exactly where the two-moment
//! Chebyshev bound of `vsm` lets light through (the ground in a picket's shadow right behind
//! an object lights up). Units are centimetres, as in `fence`.

use super::params::Params;
use super::shapes::{add_box, add_cylinder, add_plane};
use super::{camera, sky_direction};
use crate::error::Result;
use crate::light::Light;
use crate::math::vec3;
use crate::scene::{Material, Scene};

/// Number of pickets.
const PICKETS: usize = 24;
/// Picket width and the gap between pickets, in centimetres.
const PICKET: (f32, f32) = (6.0, 6.0);
/// Picket height.
const PICKET_HEIGHT: f32 = 110.0;
/// The objects behind the fence: `(x, z, half width, height)`, at staggered depths.
const OBJECTS: [(f32, f32, f32, f32); 7] = [
    (-110.0, -25.0, 14.0, 30.0),
    (-70.0, -55.0, 12.0, 55.0),
    (-30.0, -90.0, 16.0, 20.0),
    (10.0, -35.0, 10.0, 70.0),
    (50.0, -70.0, 14.0, 40.0),
    (90.0, -110.0, 18.0, 60.0),
    (125.0, -45.0, 10.0, 25.0),
];

/// Generates the scene (it has no parameters).
pub(super) fn build(_p: &Params) -> Result<Scene> {
    let mut s = Scene::new("fence-leak");
    let ground = s.add_material(Material::opaque("ground", vec3(0.55, 0.62, 0.45)));
    let wood = s.add_material(Material::opaque("pickets", vec3(0.55, 0.40, 0.28)));
    let boxes = s.add_material(Material::opaque("boxes", vec3(0.72, 0.70, 0.66)));
    add_plane(&mut s, vec3(0.0, 0.0, -60.0), 260.0, 220.0, ground);
    let span = PICKETS as f32 * (PICKET.0 + PICKET.1);
    for i in 0..PICKETS {
        let x = -0.5 * span + i as f32 * (PICKET.0 + PICKET.1);
        add_box(
            &mut s,
            vec3(x, 0.0, -1.5),
            vec3(x + PICKET.0, PICKET_HEIGHT, 1.5),
            wood,
        );
    }
    // Two rails holding the pickets.
    for y in [25.0, 85.0] {
        add_box(
            &mut s,
            vec3(-0.5 * span, y, 1.5),
            vec3(0.5 * span, y + 6.0, 4.0),
            wood,
        );
    }
    for (i, &(x, z, hw, h)) in OBJECTS.iter().enumerate() {
        if i % 3 == 1 {
            add_cylinder(&mut s, vec3(x, 0.0, z), vec3(x, h, z), hw, 20, true, boxes);
        } else {
            add_box(
                &mut s,
                vec3(x - hw, 0.0, z - hw),
                vec3(x + hw, h, z + hw),
                boxes,
            );
        }
    }
    // A low sun in front of the fence, so the pickets' shadows run back across the objects.
    s.light = Some(Light::Directional {
        to_light: sky_direction(30.0, 20.0),
    });
    s.camera = Some(camera(
        vec3(-60.0, 190.0, -330.0),
        vec3(10.0, 10.0, -60.0),
        45.0,
    ));
    Ok(s)
}
