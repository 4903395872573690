//! The `cage` stress scene: a cage of thin bars over a plane, whose thin shadows alias in
//! a coarse shadow map (the case the alias-free shadow map of Aila & Laine 2004 is exact
//! on).

use super::params::Params;
use super::shapes::{add_cylinder, add_plane, add_sphere};
use super::{camera, sky_direction};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::scene::{Material, Scene};

/// The most bars `cage` makes.
pub const MAX_CAGE_BARS: u64 = 2_000;
/// Radius of a cage bar: a few pixels wide on screen in the default view, so its shadow is a
/// thin line that a coarse shadow map breaks up.
const CAGE_BAR_RADIUS: f32 = 0.012;

pub(super) fn build(p: &Params) -> Result<Scene> {
    let bars = p.int("bars", 32, 3, MAX_CAGE_BARS)? as u32;
    let mut s = Scene::new("cage");
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.74, 0.70)));
    let metal = s.add_material(Material::opaque("bars", vec3(0.35, 0.33, 0.30)));
    let bird = s.add_material(Material::opaque("ball", vec3(0.85, 0.75, 0.25)));
    add_plane(&mut s, Vec3::ZERO, 12.0, 12.0, ground);
    let (radius, height) = (1.0f32, 2.0f32);
    let top = vec3(0.0, height + 0.5, 0.0);
    let at = |k: u32, y: f32| {
        let a = std::f32::consts::TAU * k as f32 / bars as f32;
        vec3(radius * a.cos(), y, radius * a.sin())
    };
    let r = CAGE_BAR_RADIUS;
    for k in 0..bars {
        add_cylinder(&mut s, at(k, 0.0), at(k, height), r, 6, false, metal);
        // The dome: one bar from each upright to the top.
        add_cylinder(&mut s, at(k, height), top, r, 6, false, metal);
        // Rings at the foot, the middle and the top.
        for y in [0.02, height * 0.5, height] {
            add_cylinder(&mut s, at(k, y), at(k + 1, y), r, 6, false, metal);
        }
    }
    add_cylinder(
        &mut s,
        vec3(0.0, 0.0, 0.0),
        vec3(0.0, 0.6, 0.0),
        0.08,
        16,
        true,
        metal,
    );
    add_sphere(&mut s, vec3(0.0, 0.9, 0.0), 0.3, 24, 32, bird);
    s.light = Some(Light::Directional {
        to_light: sky_direction(35.0, -120.0),
    });
    s.camera = Some(camera(vec3(2.6, 3.4, 4.6), vec3(0.4, 0.7, 0.0), 45.0));
    Ok(s)
}
