//! The built-in test scenes: the papers' set-ups (random triangles and the hair ball of the
//! alias-free shadow map paper, the chess set and street of the perspective shadow map paper,
//! the fence of the convolution shadow map paper, the room walkthrough of the adaptive shadow
//! map paper) and a few stress scenes (thin bars, a bumpy receiver).
//!
//! Every scene comes with its own camera (1024×768), light and name; generation is
//! deterministic (a seeded SplitMix64 generator, parallel work collected in order). The meshes
//! the scenes use are compiled into the library from `assets/` (see `assets/README.md` for
//! their sources and licences), so nothing outside the library is read at run time.
//!
//! Parameters arrive as text (`--scene-param K=V`); an unknown key is an error that lists the
//! scene's known keys, and every value is range-checked against a named limit.
//!
//! One module a scene family, each saying where it departs from its paper's description
//! and why: `bunny` (`bunny`, `bunny-closeup`), `random_triangles`, `chessboard`,
//! `hairball`, `fence` (`fence`, `fence-far`), `fence_leak`, `cage`, `bumpy`, `room`,
//! `street`, `penumbra` (`penumbra`, `room-soft`, `chessboard-soft`: area lights). Beside them: `params` (the checked parameters), `rng` (the seeded generator)
//! and [`shapes`], the geometry generators ([`add_quad`], [`add_plane`], [`add_box`],
//! [`add_sphere`], [`add_cylinder`], [`add_scene`], …), public so that other scene
//! builders (the TOML format's generators among them) can use them.

mod bumpy;
mod bunny;
mod cage;
mod chessboard;
mod fence;
mod fence_leak;
mod hairball;
mod params;
mod penumbra;
mod random_triangles;
mod rng;
mod room;
pub mod shapes;
mod street;

pub use bumpy::MAX_BUMPY_RESOLUTION;
pub use cage::MAX_CAGE_BARS;
pub use chessboard::CHESS_MIN_ALBEDO;
pub use hairball::{HAIR_SEGMENTS, HAIR_SIDES, HAIR_TRANSMITTANCE, MAX_HAIRS, TRIANGLES_PER_HAIR};
pub use random_triangles::{MAX_RANDOM_TRIANGLES, RANDOM_TRIANGLES_TOTAL_AREA};
pub use room::ROOM_LIGHT_FOV_DEG;
pub use shapes::{add_box, add_cylinder, add_plane, add_quad, add_scene, add_sphere};
pub use street::MAX_STREET_LENGTH;

use super::{obj, Scene};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::math::{vec3, Vec3};
use params::Params;
use std::collections::BTreeMap;

/// The image size every built-in camera uses.
const WIDTH: u32 = 1024;
/// The image height every built-in camera uses.
const HEIGHT: u32 = 768;

/// The scenes, in the order `shadowlab scenes` lists them: (name, one-line description).
const SCENES: &[(&str, &str)] = &[
    (
        "bunny",
        "Stanford bunny on a ground plane, oblique directional light (the default scene)",
    ),
    (
        "bunny-closeup",
        "the bunny scene with the camera close to the edge of the ear's shadow",
    ),
    (
        "random-triangles",
        "random triangles above a ground plane, total area constant for any count (alias-free shadow maps, Table 1)",
    ),
    (
        "chessboard",
        "chess set with its 32 pieces under a spot light, seen from a player's seat (perspective shadow maps, Fig. 1)",
    ),
    (
        "hairball",
        "ball of curly hairs, 576 triangles each, 10% opaque, over a ground plane (alias-free shadow maps, Fig. 1)",
    ),
    (
        "fence",
        "wrought-iron fence in front of boxes and a wall: fine scrollwork shadows, high depth complexity (convolution shadow maps, Fig. 9)",
    ),
    (
        "fence-far",
        "the fence, boxes and wall on a bounded yard seen from five times as far (minified on screen and in the light's map), with a camera path pulling back (convolution shadow maps, Fig. 10)",
    ),
    (
        "fence-leak",
        "picket fence in front of boxes and columns at staggered depths under a low sun: three depths under one filter, where variance shadow maps leak (convolution shadow maps, Fig. 9)",
    ),
    ("cage", "a cage of thin bars over a plane: thin shadows that alias"),
    (
        "bumpy",
        "densely tessellated bumpy height field with a few casters above it",
    ),
    (
        "room",
        "room with the bunny, a teapot on a table, boxes, a sphere and a rod sculpture; 122° light on the ceiling and a walkthrough (adaptive shadow maps)",
    ),
    (
        "penumbra",
        "a pole, a box and a sphere at increasing heights over a plane under a rectangular area light: contact-hardening soft shadows",
    ),
    (
        "room-soft",
        "the room under a 0.6 m square ceiling panel where its spot light hangs (soft shadows)",
    ),
    (
        "chessboard-soft",
        "the chess set under its spot light given a disk of radius 4 (soft shadows, the cone kept)",
    ),
    (
        "street",
        "long street of buildings, lamp posts and cars to the horizon, sun perpendicular to the view, with a camera path dollying sideways across it (perspective shadow maps, Fig. 9)",
    ),
];

/// Lists the built-in scenes as (name, one-line description), the default scene first.
pub fn list() -> Vec<(&'static str, &'static str)> {
    SCENES.to_vec()
}

/// Generates the built-in scene `name` with the parameters `params` (values as text).
///
/// Fails with [`Error::Param`] for an unknown scene (listing the known ones), an unknown
/// parameter (listing the scene's known parameters) or a value out of range.
pub fn generate(name: &str, params: &BTreeMap<String, String>) -> Result<Scene> {
    let mut scene = match name {
        "bunny" => bunny::build(&Params::new(name, params, bunny::BUNNY_PARAMS)?, false)?,
        "bunny-closeup" => bunny::build(&Params::new(name, params, bunny::BUNNY_PARAMS)?, true)?,
        "random-triangles" => {
            random_triangles::build(&Params::new(name, params, &["count", "seed"])?)?
        }
        "chessboard" => chessboard::build(&Params::new(name, params, &[])?)?,
        "hairball" => hairball::build(&Params::new(name, params, &["hairs", "seed"])?)?,
        "fence" => fence::build(&Params::new(name, params, &["distance"])?, false)?,
        "fence-far" => fence::build(&Params::new(name, params, &["distance"])?, true)?,
        "fence-leak" => fence_leak::build(&Params::new(name, params, &[])?)?,
        "cage" => cage::build(&Params::new(name, params, &["bars"])?)?,
        "bumpy" => bumpy::build(&Params::new(name, params, &["resolution"])?)?,
        "room" => room::build(&Params::new(name, params, &["light"])?)?,
        "penumbra" => penumbra::build(&Params::new(name, params, &[])?)?,
        "room-soft" => penumbra::build_room(&Params::new(name, params, &["light"])?)?,
        "chessboard-soft" => penumbra::build_chess(&Params::new(name, params, &[])?)?,
        "street" => street::build(&Params::new(name, params, &["length", "seed"])?)?,
        _ => {
            let names: Vec<&str> = SCENES.iter().map(|s| s.0).collect();
            return Err(Error::param(format!(
                "unknown scene {name:?}: not a built-in scene ({}) nor a file with a known extension (.obj, .ply, .gltf, .glb, .toml)",
                names.join(", ")
            )));
        }
    };
    scene.name = name.to_string();
    if let Some(cam) = scene.camera.as_mut() {
        cam.fit_depth_range(&scene.bounds);
    }
    Ok(scene)
}

/// The Stanford bunny (3,674 triangles, about 10 units tall, feet at y = 0).
pub(super) const BUNNY_OBJ: &str = include_str!("../../../assets/bunny.obj");

/// Parses one of the compiled-in meshes.
pub(super) fn asset(name: &str, obj_text: &str, mtl: Option<&str>) -> Result<Scene> {
    obj::load_from_str(name, obj_text, mtl)
}

/// A camera of the built-in size.
pub(super) fn camera(eye: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
    Camera::look_at(eye, target, fov_y_deg, WIDTH, HEIGHT)
}

/// The unit vector towards a light at `elevation_deg` above the horizon and azimuth
/// `azimuth_deg` (0° = +Z, 90° = +X).
pub(super) fn sky_direction(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (el, az) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    vec3(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
}
