//! Small scenes and light views for the unit tests of adaptive shadow maps.

use super::tree::Face;
use crate::light::{light_views, Light};
use crate::math::vec3;
use crate::scene::{Material, Scene};
use crate::techniques::shadow_map::DIRECTIONAL_PAD;

/// A ground quad under a few tilted triangles at different heights.
pub(super) fn small_scene() -> Scene {
    let mut tris = vec![
        [
            vec3(-4.0, 0.0, -4.0),
            vec3(4.0, 0.0, 4.0),
            vec3(4.0, 0.0, -4.0),
        ],
        [
            vec3(-4.0, 0.0, -4.0),
            vec3(-4.0, 0.0, 4.0),
            vec3(4.0, 0.0, 4.0),
        ],
    ];
    for i in 0..12 {
        let a = i as f32 * 0.7;
        let c = vec3(2.0 * a.cos(), 0.5 + 0.15 * i as f32, 2.0 * a.sin());
        tris.push([c, c + vec3(0.9, 0.2, 0.1), c + vec3(0.2, -0.1, 0.8)]);
    }
    Scene::from_triangles(tris, Material::default()).unwrap()
}

/// The first light view of `light` over `scene` as a face of `res²` root texels with
/// `tile²` tiles of `cells²` cells, its culling lists made and no root yet.
pub(super) fn face(scene: &Scene, light: &Light, res: u32, tile: u32, cells: u32) -> Face {
    let lv = light_views(light, &scene.bounds, &scene.bounds, DIRECTIONAL_PAD)[0];
    Face::new(scene, lv, res, res / (tile / cells))
}
