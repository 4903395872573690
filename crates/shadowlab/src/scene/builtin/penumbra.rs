//! Soft-shadow set-ups under area lights: `penumbra`, the classic contact-hardening scene
//! (a thin pole standing on a ground plane, a box and a sphere floating at increasing
//! heights, under a rectangular light: the penumbra widens with the distance between
//! caster and receiver, as in Fernando's percentage-closer soft shadows paper), and the
//! soft versions of `room` (a ceiling panel where its spot light was) and `chessboard`
//! (its spot light given a disk, keeping the cone).
//!
//! The light of each is an area light ([`crate::area_light`]); its punctual stand-in (the
//! light hard techniques use) is the light at its centre.

use super::params::Params;
use super::shapes::{add_box, add_cylinder, add_plane, add_sphere};
use super::{camera, chessboard, room};
use crate::area_light::AreaLight;
use crate::error::Result;
use crate::light::Light;
use crate::math::vec3;
use crate::scene::{Material, Scene};

/// The `penumbra` light: a 1.2 × 0.8 rectangle 6 units above the ground, facing down.
pub const PENUMBRA_LIGHT: AreaLight = AreaLight::Rect {
    centre: vec3(-1.0, 6.0, -1.5),
    edge_u: vec3(1.2, 0.0, 0.0),
    edge_v: vec3(0.0, 0.0, 0.8),
};

/// The soft room's ceiling panel: 0.6 m square, just below the ceiling where the spot
/// light of `room` hangs.
pub const ROOM_PANEL: f32 = 0.6;

/// The soft chessboard's disk light radius (the board is 70 units wide and the light about
/// 85 away): penumbrae from hard at the pieces' feet to a few squares wide at their tops.
pub const CHESS_LIGHT_RADIUS: f32 = 4.0;

pub(super) fn build(_: &Params) -> Result<Scene> {
    let mut s = Scene::new("penumbra");
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
    let pole = s.add_material(Material::opaque("pole", vec3(0.55, 0.40, 0.30)));
    let boxm = s.add_material(Material::opaque("box", vec3(0.30, 0.45, 0.70)));
    let ball = s.add_material(Material::opaque("sphere", vec3(0.75, 0.30, 0.25)));
    add_plane(&mut s, vec3(0.0, 0.0, 0.0), 6.0, 6.0, ground);
    // The pole touches the ground: its shadow is hard at the foot, soft at the top.
    add_cylinder(
        &mut s,
        vec3(-2.0, 0.0, 0.5),
        vec3(-2.0, 2.5, 0.5),
        0.08,
        12,
        true,
        pole,
    );
    // A box 0.7 above the ground and a sphere 2.2 above it: wider penumbrae in turn.
    add_box(&mut s, vec3(-0.3, 0.7, 0.0), vec3(0.5, 1.1, 0.8), boxm);
    add_sphere(&mut s, vec3(1.6, 2.6, 0.4), 0.45, 24, 32, ball);
    s.area_light = Some(PENUMBRA_LIGHT);
    s.light = Some(PENUMBRA_LIGHT.punctual());
    s.camera = Some(camera(vec3(0.5, 7.0, 9.0), vec3(0.0, 0.3, 1.5), 45.0));
    Ok(s)
}

/// `room-soft`: the room under a square ceiling panel.
pub(super) fn build_room(p: &Params) -> Result<Scene> {
    let mut s = room::build(p)?;
    let Some(Light::Spot { position, .. } | Light::Point { position }) = s.light else {
        unreachable!("the room has a spot or point light");
    };
    let panel = AreaLight::Rect {
        centre: position,
        edge_u: vec3(ROOM_PANEL, 0.0, 0.0),
        edge_v: vec3(0.0, 0.0, ROOM_PANEL),
    };
    s.area_light = Some(panel);
    Ok(s)
}

/// `chessboard-soft`: the chess set under its spot light given a disk.
pub(super) fn build_chess(p: &Params) -> Result<Scene> {
    let mut s = chessboard::build(p)?;
    let light = s.light.expect("the chessboard has a light");
    s.area_light = Some(AreaLight::sized(&light, CHESS_LIGHT_RADIUS)?);
    Ok(s)
}
