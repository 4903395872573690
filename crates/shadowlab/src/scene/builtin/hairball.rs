//! The `hairball` scene of the alias-free shadow map paper's Figure 1 (Aila & Laine 2004):
//! a ball of curly, semi-transparent hairs over a ground plane.
//!
//! A hair is an open tube of triangular cross-section (96 segments × 3 sides × 2 = 576
//! triangles, the paper's count); each face lets through 90% (the paper's 10% opacity),
//! so a shadow ray crossing a hair passes two faces and keeps 81%.

use super::params::Params;
use super::rng::Rng;
use super::shapes::add_plane;
use super::{camera, sky_direction};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::scene::{Material, Scene};

/// Segments along one hair.
pub const HAIR_SEGMENTS: usize = 96;
/// Sides of a hair's tube (a triangular prism, open at both ends).
pub const HAIR_SIDES: usize = 3;
/// Triangles per hair: `HAIR_SEGMENTS × HAIR_SIDES × 2` = 576, as in the alias-free shadow
/// map paper's hair ball.
pub const TRIANGLES_PER_HAIR: usize = HAIR_SEGMENTS * HAIR_SIDES * 2;
/// The most hairs `hairball` makes (20,000 hairs are 11.5 M triangles).
pub const MAX_HAIRS: u64 = 20_000;
/// Transmittance of a hair's surface: 10% opacity, as in the paper. Grey, so the RGB
/// channels agree; a ray crossing one hair passes two of its faces.
pub const HAIR_TRANSMITTANCE: f32 = 0.9;
/// Radius of the hair ball (world units).
const BALL_RADIUS: f32 = 1.0;
/// Radius of a hair's tube: thin enough that a hair is one or two pixels wide in the
/// default view, thick enough that 5,000 hairs throw a clearly grey shadow.
const HAIR_RADIUS: f32 = 0.003;

pub(super) fn build(p: &Params) -> Result<Scene> {
    use rayon::prelude::*;
    let hairs = p.int("hairs", 5_000, 1, MAX_HAIRS)? as usize;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let center = vec3(0.0, 1.6, 0.0);
    let n = hairs * TRIANGLES_PER_HAIR;
    let mut s = Scene::new("hairball");
    let hair = s.add_material(Material {
        name: "hair".into(),
        color: vec3(0.55, 0.38, 0.22),
        transmittance: Vec3::splat(HAIR_TRANSMITTANCE),
        alpha_mask: None,
    });
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
    s.v0 = vec![Vec3::ZERO; n];
    s.v1 = vec![Vec3::ZERO; n];
    s.v2 = vec![Vec3::ZERO; n];
    s.v0.par_chunks_mut(TRIANGLES_PER_HAIR)
        .zip(s.v1.par_chunks_mut(TRIANGLES_PER_HAIR))
        .zip(s.v2.par_chunks_mut(TRIANGLES_PER_HAIR))
        .enumerate()
        .for_each(|(i, ((a, b), c))| one_hair(&mut Rng::new(seed, i as u64), center, a, b, c));
    s.material = vec![hair; n];
    s.recompute_bounds();
    add_plane(&mut s, Vec3::ZERO, 8.0, 8.0, ground);
    s.light = Some(Light::Directional {
        to_light: sky_direction(55.0, -60.0),
    });
    s.camera = Some(camera(vec3(1.2, 3.4, 5.6), vec3(0.5, 0.9, -0.3), 45.0));
    Ok(s)
}

/// Writes one curly hair into `v0`, `v1`, `v2` (each `TRIANGLES_PER_HAIR` long): a tube
/// around a helix that winds about a random radial direction, from near the ball's centre
/// out to its surface.
fn one_hair(rng: &mut Rng, center: Vec3, v0: &mut [Vec3], v1: &mut [Vec3], v2: &mut [Vec3]) {
    let dir = rng.direction();
    let (u, v) = dir.any_orthonormal_pair();
    let root = rng.range(0.15, 0.45) * BALL_RADIUS;
    let tip = rng.range(0.85, 1.0) * BALL_RADIUS;
    let curl = rng.range(0.04, 0.10) * BALL_RADIUS;
    let turns = rng.range(3.0, 7.0);
    let phase = rng.range(0.0, std::f32::consts::TAU);
    let bend = vec3(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    ) * 0.15
        * BALL_RADIUS;
    let bend = bend - dir * bend.dot(dir);
    let centreline = |t: f32| {
        let a = phase + std::f32::consts::TAU * turns * t;
        center
            + dir * (root + (tip - root) * t)
            + (u * a.cos() + v * a.sin()) * curl
            + bend * (t * t)
    };
    // Rings of HAIR_SIDES points around the centreline, framed by parallel transport so the
    // tube does not twist.
    let points: Vec<Vec3> = (0..=HAIR_SEGMENTS)
        .map(|k| centreline(k as f32 / HAIR_SEGMENTS as f32))
        .collect();
    let mut normal = u;
    let mut rings = Vec::with_capacity(points.len());
    for k in 0..points.len() {
        let tangent =
            (points[(k + 1).min(HAIR_SEGMENTS)] - points[k.saturating_sub(1)]).normalize_or(dir);
        normal =
            (normal - tangent * normal.dot(tangent)).normalize_or(tangent.any_orthonormal_vector());
        let binormal = tangent.cross(normal);
        let ring: [Vec3; HAIR_SIDES] = std::array::from_fn(|j| {
            let a = std::f32::consts::TAU * j as f32 / HAIR_SIDES as f32;
            points[k] + (normal * a.cos() + binormal * a.sin()) * HAIR_RADIUS
        });
        rings.push(ring);
    }
    let mut t = 0;
    for k in 0..HAIR_SEGMENTS {
        for j in 0..HAIR_SIDES {
            let jn = (j + 1) % HAIR_SIDES;
            let (a, b, c, d) = (rings[k][j], rings[k][jn], rings[k + 1][jn], rings[k + 1][j]);
            (v0[t], v1[t], v2[t]) = (a, b, c);
            (v0[t + 1], v1[t + 1], v2[t + 1]) = (a, c, d);
            t += 2;
        }
    }
}
