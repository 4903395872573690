//! The `bunny` and `bunny-closeup` scenes: the Stanford bunny on a ground plane under an
//! oblique sun, the default scene of every comparison; the close-up puts the camera at the
//! edge of the shadow of an ear, where a shadow map's texels show.

use super::params::Params;
use super::shapes::add_plane;
use super::{asset, camera, sky_direction, BUNNY_OBJ};
use crate::error::Result;
use crate::light::Light;
use crate::math::vec3;
use crate::scene::{Material, Scene};

pub(super) const BUNNY_PARAMS: &[&str] = &["closeup"];

/// Elevation of the bunny scene's sun: low enough for a shadow about as long as the bunny
/// is tall, high enough that the shadow stays whole on screen.
const BUNNY_LIGHT_ELEVATION_DEG: f32 = 35.0;
/// Azimuth of the bunny scene's sun: from the camera's left, so the shadow falls to the
/// right of the bunny, beside it on screen rather than hidden behind it.
const BUNNY_LIGHT_AZIMUTH_DEG: f32 = -75.0;

pub(super) fn build(p: &Params, closeup_scene: bool) -> Result<Scene> {
    let closeup = p.flag("closeup", closeup_scene)?;
    let mesh = asset("bunny.obj", BUNNY_OBJ, None)?;
    let mut s = Scene::new("bunny");
    let fur = s.add_material(Material::opaque("bunny", vec3(0.78, 0.72, 0.62)));
    let ground = s.add_material(Material::opaque("ground", vec3(0.72, 0.74, 0.70)));
    let floor_y = mesh.bounds.min.y;
    for i in 0..mesh.len() {
        s.push(mesh.triangle(i), fur);
    }
    add_plane(&mut s, vec3(0.0, floor_y, 0.0), 60.0, 60.0, ground);
    let to_light = sky_direction(BUNNY_LIGHT_ELEVATION_DEG, BUNNY_LIGHT_AZIMUTH_DEG);
    s.light = Some(Light::Directional { to_light });
    s.camera = Some(if closeup {
        // The shadow of the bunny's highest point (an ear tip) on the ground: the camera
        // looks at it from a little above, close enough that the shadow edge fills the view.
        let top = (0..mesh.len())
            .flat_map(|i| mesh.triangle(i))
            .fold(mesh.bounds.min, |a, b| if b.y > a.y { b } else { a });
        let on_ground = top - to_light * ((top.y - floor_y) / to_light.y);
        camera(on_ground + vec3(1.2, 2.2, 3.0), on_ground, 40.0)
    } else {
        camera(vec3(14.0, 13.0, 26.0), vec3(7.0, 2.0, -1.5), 45.0)
    });
    Ok(s)
}
