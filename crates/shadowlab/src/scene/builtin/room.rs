//! The `room` scene of the adaptive shadow map paper's walkthrough (Fernando et al. 2001):
//! a room with the bunny, a teapot on a table, boxes, a sphere and a rod sculpture, lit
//! from the ceiling, with a key-framed walkthrough.
//!
//! The paper's 122° is the field of view of the *light* ("a point light with a 122° field
//! of view ... placed on the room ceiling"), so the light is a 122° spot light hanging
//! from the ceiling and the camera has an ordinary 60°; `light=point` makes it an
//! omnidirectional point light at the same place. The paper's robot and sculpture are
//! replaced by a teapot on a table and a lattice of thin rods; its bunny is the
//! low-resolution one (3,674 triangles, not 20,000).

use super::params::Params;
use super::shapes::{add_box, add_cylinder, add_mesh_as, add_plane, add_quad, add_sphere};
use super::{asset, camera, BUNNY_OBJ};
use crate::camera::{CameraKey, CameraPath};
use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::{vec3, Mat4, Vec3};
use crate::scene::{Material, Scene};

/// The teapot (992 triangles, 32 units wide).
const TEAPOT_OBJ: &str = include_str!("../../../assets/teapot.obj");
/// The room light's field of view: the adaptive shadow map paper's "point light with a 122°
/// field of view ... placed on the room ceiling".
pub const ROOM_LIGHT_FOV_DEG: f32 = 122.0;
/// The room's half width and depth, and its height (metres).
const ROOM: (f32, f32) = (4.0, 3.0);
/// The frames the room's walkthrough takes from its first key to its last.
pub const ROOM_WALK_FRAMES: u32 = 120;

pub(super) fn build(p: &Params) -> Result<Scene> {
    let light_kind = p.map.get("light").map(|v| v.trim().to_ascii_lowercase());
    let point_light = match light_kind.as_deref() {
        None | Some("spot") => false,
        Some("point") => true,
        Some(other) => {
            return Err(Error::param(format!(
                "scene room: parameter light={other:?} is neither spot nor point"
            )))
        }
    };
    let (half, height) = ROOM;
    let mut s = Scene::new("room");
    let floor = s.add_material(Material::opaque("floor", vec3(0.70, 0.62, 0.50)));
    let walls = s.add_material(Material::opaque("walls", vec3(0.82, 0.80, 0.74)));
    let white = s.add_material(Material::opaque("white", vec3(0.85, 0.85, 0.85)));
    let wood = s.add_material(Material::opaque("wood", vec3(0.55, 0.36, 0.20)));
    let red = s.add_material(Material::opaque("red", vec3(0.78, 0.25, 0.20)));
    let metal = s.add_material(Material::opaque("metal", vec3(0.45, 0.47, 0.52)));
    // Floor, ceiling and four walls.
    add_plane(&mut s, Vec3::ZERO, half, half, floor);
    add_plane(&mut s, vec3(0.0, height, 0.0), half, half, walls);
    let (x, y, z) = (
        vec3(2.0 * half, 0.0, 0.0),
        vec3(0.0, height, 0.0),
        vec3(0.0, 0.0, 2.0 * half),
    );
    add_quad(&mut s, vec3(-half, 0.0, -half), x, y, walls);
    add_quad(&mut s, vec3(-half, 0.0, half), x, y, walls);
    add_quad(&mut s, vec3(-half, 0.0, -half), z, y, walls);
    add_quad(&mut s, vec3(half, 0.0, -half), z, y, walls);
    // The bunny, about 0.8 m tall, standing on the floor.
    let bunny = asset("bunny.obj", BUNNY_OBJ, None)?;
    let k = 0.8 / (bunny.bounds.max.y - bunny.bounds.min.y);
    let to_floor = Mat4::from_translation(vec3(-1.4, -bunny.bounds.min.y * k, -1.0))
        * Mat4::from_rotation_y(0.6)
        * Mat4::from_scale(Vec3::splat(k));
    let fur = Material::opaque("bunny", vec3(0.80, 0.74, 0.64));
    add_mesh_as(&mut s, &bunny, to_floor, fur);
    // A table with the teapot on it.
    let (tx, tz, th) = (1.5f32, -1.2f32, 0.75f32);
    add_box(
        &mut s,
        vec3(tx - 0.6, th - 0.05, tz - 0.4),
        vec3(tx + 0.6, th, tz + 0.4),
        wood,
    );
    for (dx, dz) in [(-0.55, -0.35), (0.55, -0.35), (-0.55, 0.35), (0.55, 0.35)] {
        add_box(
            &mut s,
            vec3(tx + dx - 0.03, 0.0, tz + dz - 0.03),
            vec3(tx + dx + 0.03, th - 0.05, tz + dz + 0.03),
            wood,
        );
    }
    let teapot = asset("teapot.obj", TEAPOT_OBJ, None)?;
    let k = 0.4 / (teapot.bounds.max.x - teapot.bounds.min.x);
    let on_table = Mat4::from_translation(vec3(tx, th - teapot.bounds.min.y * k, tz))
        * Mat4::from_rotation_y(-0.8)
        * Mat4::from_scale(Vec3::splat(k));
    let china = Material::opaque("teapot", vec3(0.85, 0.85, 0.80));
    add_mesh_as(&mut s, &teapot, on_table, china);
    // Boxes, a sphere, and a lattice sculpture of thin rods (fine shadow detail).
    add_box(&mut s, vec3(-2.9, 0.0, 1.2), vec3(-2.1, 0.8, 2.0), red);
    add_box(
        &mut s,
        vec3(-2.75, 0.8, 1.35),
        vec3(-2.25, 1.2, 1.85),
        white,
    );
    add_sphere(&mut s, vec3(0.3, 0.45, 1.6), 0.45, 24, 32, white);
    let base = vec3(2.2, 0.0, 1.6);
    for i in 0..6 {
        let a = std::f32::consts::TAU * i as f32 / 6.0;
        let foot = base + vec3(0.35 * a.cos(), 0.0, 0.35 * a.sin());
        let head = base + vec3(0.35 * (a + 2.0).cos(), 1.6, 0.35 * (a + 2.0).sin());
        add_cylinder(&mut s, foot, head, 0.015, 6, false, metal);
    }
    for level in 1..6 {
        let y = 1.6 * level as f32 / 6.0;
        add_cylinder(
            &mut s,
            base + vec3(-0.35, y, 0.0),
            base + vec3(0.35, y, 0.0),
            0.012,
            6,
            false,
            metal,
        );
        add_cylinder(
            &mut s,
            base + vec3(0.0, y, -0.35),
            base + vec3(0.0, y, 0.35),
            0.012,
            6,
            false,
            metal,
        );
    }
    let lamp = vec3(0.3, height - 0.05, 0.2);
    s.light = Some(if point_light {
        Light::Point { position: lamp }
    } else {
        Light::Spot {
            position: lamp,
            target: vec3(0.3, 0.0, 0.2),
            fov_deg: ROOM_LIGHT_FOV_DEG,
        }
    });
    s.camera = Some(camera(vec3(3.4, 1.7, 3.5), vec3(-0.3, 0.5, -0.6), 60.0));
    // A walkthrough: along the room, up to the bunny, round to the table and the sculpture,
    // at a walking pace (a few centimetres a frame): the first frames of any sequence walk
    // slowly in from the door, the whole tour takes ROOM_WALK_FRAMES.
    let key = |eye: Vec3, target: Vec3| CameraKey { eye, target };
    s.camera_path = Some(CameraPath {
        pace: Some(ROOM_WALK_FRAMES),
        keys: vec![
            key(vec3(3.4, 1.7, 3.5), vec3(-0.3, 0.5, -0.6)),
            key(vec3(0.5, 1.4, 2.5), vec3(-1.4, 0.4, -1.0)),
            key(vec3(-0.6, 1.0, 0.0), vec3(-1.4, 0.3, -1.0)),
            key(vec3(0.2, 1.3, -0.2), vec3(1.5, 0.8, -1.2)),
            key(vec3(1.0, 1.2, 0.3), vec3(2.2, 0.6, 1.6)),
            key(vec3(-1.0, 1.8, 3.2), vec3(0.5, 0.3, -0.5)),
        ],
    });
    Ok(s)
}
