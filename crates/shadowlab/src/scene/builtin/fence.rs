//! The `fence` and `fence-far` scenes of the convolution shadow map paper's Figures 9 and
//! 10 (Annen et al. 2007): a wrought-iron fence in front of boxes and a wall, with fine
//! scrollwork shadows and high depth complexity; `fence-far` sees it from five times as
//! far on a bounded yard (minified on screen and in the light's map), with a camera path
//! pulling back.

use super::params::Params;
use super::shapes::{add_box, add_cylinder, add_plane, add_scene, add_sphere};
use super::{asset, camera, sky_direction};
use crate::camera::{CameraKey, CameraPath};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Mat4};
use crate::scene::{Material, Scene};

/// The wrought-iron fence (19,368 triangles, centimetres, Y up, 180 cm wide, 1 m tall).
const FENCE_OBJ: &str = include_str!("../../../assets/fence/fence.obj");
/// The fence's materials.
const FENCE_MTL: &str = include_str!("../../../assets/fence/fence.mtl");
/// The largest camera distance factor of the fence scenes.
const MAX_FENCE_DISTANCE: f32 = 100.0;
/// The camera distance factor of `fence-far`: far enough that the fence's scrollwork is
/// well below a pixel (the minification the convolution shadow map paper filters).
const FENCE_FAR_DISTANCE: f32 = 5.0;
/// Half extents (x, z) of `fence-far`'s ground, in centimetres: the yard in front of the
/// wall, from its back (z = −100) to 2 m in front of the fence, wide and deep enough to fill
/// the frame below the wall at distance factor 1.
const FENCE_YARD_HALF: (f32, f32) = (350.0, 150.0);
/// Centre (z) of `fence-far`'s ground.
const FENCE_YARD_CENTER_Z: f32 = 50.0;
/// The camera distances (factors) of the fence scenes' pull-away camera path.
const FENCE_PATH_DISTANCES: [f32; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];

pub(super) fn build(p: &Params, far: bool) -> Result<Scene> {
    let default = if far { FENCE_FAR_DISTANCE } else { 1.0 };
    let distance = p.real("distance", default, 0.05, MAX_FENCE_DISTANCE)?;
    let mesh = asset("fence.obj", FENCE_OBJ, Some(FENCE_MTL))?;
    let mut s = Scene::new("fence");
    // Feet on the ground, centred on x = 0, in the plane z = 0.
    let c = mesh.bounds.center();
    add_scene(
        &mut s,
        &mesh,
        Mat4::from_translation(vec3(-c.x, -mesh.bounds.min.y, -c.z)),
    );
    let ground = s.add_material(Material::opaque("ground", vec3(0.55, 0.62, 0.45)));
    let wall = s.add_material(Material::opaque("wall", vec3(0.80, 0.74, 0.66)));
    let crate_ = s.add_material(Material::opaque("boxes", vec3(0.70, 0.52, 0.32)));
    let stone = s.add_material(Material::opaque("stone", vec3(0.62, 0.64, 0.68)));
    if far {
        // A bounded yard instead of the 100 m ground: the light's map is fitted to the visible
        // receivers, so with the ground to the horizon in view its texels would be 5 cm and
        // the fence's scrollwork would be magnified in light space however far the camera
        // is. Round the wall, fence and boxes only, the map's texels are a few millimetres and
        // the scrollwork is minified in light space as on screen (many texels per pixel). The
        // yard ends at the wall, so the wall's long shadow under the low sun falls off it and
        // the shadows in view span the fence's depths, not the wall's.
        add_plane(
            &mut s,
            vec3(0.0, 0.0, FENCE_YARD_CENTER_Z),
            FENCE_YARD_HALF.0,
            FENCE_YARD_HALF.1,
            ground,
        );
    } else {
        add_plane(&mut s, vec3(0.0, 0.0, -2000.0), 10_000.0, 10_000.0, ground);
    }
    // A wall behind, boxes and a low column between it and the fence.
    add_box(
        &mut s,
        vec3(-300.0, 0.0, -100.0),
        vec3(300.0, 260.0, -80.0),
        wall,
    );
    add_box(
        &mut s,
        vec3(-85.0, 0.0, -65.0),
        vec3(-35.0, 45.0, -30.0),
        crate_,
    );
    add_box(
        &mut s,
        vec3(-15.0, 0.0, -60.0),
        vec3(35.0, 25.0, -35.0),
        crate_,
    );
    add_box(
        &mut s,
        vec3(45.0, 0.0, -55.0),
        vec3(90.0, 55.0, -30.0),
        crate_,
    );
    add_cylinder(
        &mut s,
        vec3(-130.0, 0.0, -60.0),
        vec3(-130.0, 90.0, -60.0),
        18.0,
        24,
        true,
        stone,
    );
    add_sphere(&mut s, vec3(135.0, 25.0, -55.0), 25.0, 16, 24, stone);
    s.light = Some(Light::Directional {
        to_light: sky_direction(24.0, -30.0),
    });
    let mut cam = camera(vec3(70.0, 110.0, 270.0), vec3(0.0, 45.0, -40.0), 45.0);
    let base = cam;
    cam.scale_distance(distance);
    s.camera = Some(cam);
    let keys = FENCE_PATH_DISTANCES
        .iter()
        .map(|&f| {
            let mut c = base;
            c.scale_distance(f);
            CameraKey {
                eye: c.eye,
                target: c.target,
            }
        })
        .collect();
    s.camera_path = Some(CameraPath::stretched(keys));
    Ok(s)
}
