//! The `random-triangles` scene of the alias-free shadow map paper's Table 1 (Aila &
//! Laine 2004): random triangles floating above a ground plane, their total area constant
//! for any count.
//!
//! The paper gives only "random triangles whose total area is approximately constant".
//! Here each triangle joins three random directions from a random centre (slivers
//! rejected), scaled to exactly [`RANDOM_TRIANGLES_TOTAL_AREA`] / count, and lifted when
//! it would pierce the ground (a translation, so the area is kept).

use super::params::Params;
use super::rng::Rng;
use super::shapes::add_plane;
use super::{camera, sky_direction};
use crate::error::Result;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::scene::{Material, Scene};

/// The most triangles `random-triangles` makes (its memory grows with the count).
pub const MAX_RANDOM_TRIANGLES: u64 = 10_000_000;
/// Total area of the random triangles, whatever their count (world units²; the field they
/// float in is 10 × 10): each triangle's area is this divided by the count.
pub const RANDOM_TRIANGLES_TOTAL_AREA: f32 = 50.0;
/// Half the side of the square field the triangles' centres are drawn from.
const RANDOM_FIELD_HALF: f32 = 5.0;
/// Heights the triangles' centres are drawn from.
const RANDOM_HEIGHTS: (f32, f32) = (1.0, 3.0);
/// Lowest height of any random triangle's vertex: a triangle reaching lower is lifted (which
/// keeps its area), so that none pierces the ground.
const RANDOM_MIN_HEIGHT: f32 = 0.05;

pub(super) fn build(p: &Params) -> Result<Scene> {
    let count = p.int("count", 10_000, 1, MAX_RANDOM_TRIANGLES)? as usize;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let mut s = Scene::new("random-triangles");
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
    let tri_mat = s.add_material(Material::opaque("triangles", vec3(0.85, 0.45, 0.25)));
    s.reserve(count + 2);
    add_plane(&mut s, Vec3::ZERO, 12.0, 12.0, ground);
    let area = RANDOM_TRIANGLES_TOTAL_AREA / count as f32;
    let mut rng = Rng::new(seed, 0);
    for _ in 0..count {
        let c = vec3(
            rng.range(-RANDOM_FIELD_HALF, RANDOM_FIELD_HALF),
            rng.range(RANDOM_HEIGHTS.0, RANDOM_HEIGHTS.1),
            rng.range(-RANDOM_FIELD_HALF, RANDOM_FIELD_HALF),
        );
        // Three random directions from the centre; reject slivers (area of the unit-sized
        // shape below 0.1) so every triangle is a visible caster, then scale to the area.
        let (a, b, d, unit_area) = loop {
            let (a, b, d) = (rng.direction(), rng.direction(), rng.direction());
            let ua = 0.5 * (b - a).cross(d - a).length();
            if ua > 0.1 {
                break (a, b, d, ua);
            }
        };
        let k = (area / unit_area).sqrt();
        let mut t = [c + a * k, c + b * k, c + d * k];
        let low = t[0].y.min(t[1].y).min(t[2].y);
        if low < RANDOM_MIN_HEIGHT {
            for v in &mut t {
                v.y += RANDOM_MIN_HEIGHT - low;
            }
        }
        s.push(t, tri_mat);
    }
    s.light = Some(Light::Directional {
        to_light: sky_direction(50.0, 75.0),
    });
    s.camera = Some(camera(vec3(0.0, 7.0, 12.0), vec3(0.0, 0.8, 0.0), 50.0));
    Ok(s)
}
