//! The `chessboard` scene of the perspective shadow map paper's Figure 1 (Stamminger &
//! Drettakis 2002): a chess set with its 32 pieces under a spot light, seen from a
//! player's seat.
//!
//! The file's near-black materials are lifted to [`CHESS_MIN_ALBEDO`] so that shadows
//! show in the shaded image; visibility is unaffected.

use super::params::Params;
use super::shapes::{add_plane, add_scene};
use super::{asset, camera};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Mat4, Vec3};
use crate::scene::{Material, Scene};

/// The chess set (125,810 triangles, centimetres, Y up, board from y = 0).
const CHESSBOARD_OBJ: &str = include_str!("../../../assets/chessboard/chessboard.obj");
/// The chess set's materials.
const CHESSBOARD_MTL: &str = include_str!("../../../assets/chessboard/chessboard.mtl");

/// The darkest albedo a chess-set material keeps: the file's black pieces and squares
/// (albedo ≈ 0.01) would hide every shadow falling on them, so darker colours are lifted to
/// this (the shading only; visibility does not depend on colour).
pub const CHESS_MIN_ALBEDO: f32 = 0.06;

pub(super) fn build(_p: &Params) -> Result<Scene> {
    let mut mesh = asset("chessboard.obj", CHESSBOARD_OBJ, Some(CHESSBOARD_MTL))?;
    for m in &mut mesh.materials {
        m.color = m.color.max(Vec3::splat(CHESS_MIN_ALBEDO));
    }
    let mut s = Scene::new("chessboard");
    add_scene(&mut s, &mesh, Mat4::IDENTITY);
    let table = s.add_material(Material::opaque("table", vec3(0.55, 0.42, 0.30)));
    add_plane(
        &mut s,
        vec3(0.0, mesh.bounds.min.y - 0.01, 0.0),
        70.0,
        55.0,
        table,
    );
    s.light = Some(Light::Spot {
        position: vec3(-35.0, 75.0, -20.0),
        target: vec3(0.0, 0.0, 0.0),
        fov_deg: 60.0,
    });
    s.camera = Some(camera(vec3(0.0, 38.0, 46.0), vec3(0.0, 1.0, -1.0), 45.0));
    Ok(s)
}
