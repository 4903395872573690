//! The automatic light of a scene that has none: a directional light chosen per scene so
//! that its shadows fall on receivers the camera sees.
//!
//! A fixed direction suits some meshes and not others: from nearly overhead, a railing's
//! shadow falls behind the railing and a radiator's under it, so a comparison there
//! measures little. Instead a few candidate directions are tried, each with a cheap
//! ray-traced estimate at [`ESTIMATE_WIDTH`] × [`ESTIMATE_HEIGHT`] pixels of the camera's
//! view: the share of covered pixels that face the light yet are occluded (cast shadow). The
//! direction with the largest cast-shadow share wins, among those that light at least
//! [`MIN_LIT_FACING`] of the covered pixels (so the visible side of the mesh is not in its
//! own attached shadow). Candidates are taken in a fixed order and ties keep the first, so
//! the choice is a function of the scene and the camera alone.
//!
//! The candidates are [`ELEVATIONS_DEG`] above the horizon at [`AZIMUTHS`] azimuths from
//! the camera's right, through behind the camera, to its left: grazing enough that shadows
//! are long and their edges cross the ground and the mesh, high enough that they stay on
//! the ground plane the auto-framing adds (four times the mesh's footprint). Lights from
//! beyond the mesh are not tried: they would leave the side the camera sees unlit.

use super::Scene;
use crate::camera::Camera;
use crate::frame::Frame;
use crate::light::Light;
use crate::math::{vec3, Vec3};
use crate::reference::Reference;
use crate::view::ViewSamples;

/// Width in pixels of the low-resolution view the candidates are judged in.
pub const ESTIMATE_WIDTH: u32 = 96;
/// Height in pixels of that view.
pub const ESTIMATE_HEIGHT: u32 = 72;
/// Elevations of the candidate directions above the horizon, in degrees.
pub const ELEVATIONS_DEG: [f32; 3] = [30.0, 40.0, 55.0];
/// Candidate azimuths per elevation, evenly spaced over the half circle on the camera's
/// side, from its right to its left.
pub const AZIMUTHS: u32 = 5;
/// A candidate must face at least this share of the covered pixels (their viewed side
/// towards the light), else the visible side of the mesh would be mostly self-shadowed.
pub const MIN_LIT_FACING: f32 = 0.5;

/// What a candidate light does in the estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The candidate.
    pub light: Light,
    /// Share of covered pixels whose viewed side faces the light.
    pub facing: f32,
    /// Share of covered pixels that face the light and are occluded from it.
    pub cast: f32,
}

/// The candidate directions (unit vectors towards the light), in the order they are tried.
pub fn candidates(camera: &Camera) -> Vec<Vec3> {
    let f = camera.forward();
    let mut back = vec3(-f.x, 0.0, -f.z);
    if back.length_squared() < 1e-8 {
        back = Vec3::Z;
    }
    let back = back.normalize();
    let right = Vec3::Y.cross(back).normalize();
    let mut out = Vec::new();
    for e in ELEVATIONS_DEG {
        let (se, ce) = e.to_radians().sin_cos();
        for i in 0..AZIMUTHS {
            let a = i as f32 * std::f32::consts::PI / (AZIMUTHS - 1) as f32;
            let (sa, ca) = a.sin_cos();
            out.push((right * (ce * ca) + back * (ce * sa) + Vec3::Y * se).normalize());
        }
    }
    out
}

/// The estimate of every candidate for `scene` seen by `camera`.
pub fn estimates(scene: &Scene, camera: &Camera) -> Vec<Estimate> {
    let mut cam = *camera;
    cam.width = ESTIMATE_WIDTH;
    cam.height = ESTIMATE_HEIGHT;
    cam.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(scene, &cam);
    let covered: Vec<usize> = (0..view.triangle.len())
        .filter(|&k| view.covered(k))
        .collect();
    let reference = Reference::build(scene);
    candidates(camera)
        .into_iter()
        .map(|d| {
            let light = Light::Directional { to_light: d };
            let frame = Frame::new(scene, &cam, &light, &view);
            let vis = reference.visibility(&frame, &[]);
            let (mut facing, mut cast) = (0usize, 0usize);
            for &k in &covered {
                if frame.receiver_lit(k) {
                    facing += 1;
                    if vis.value[k].max_element() < 0.5 {
                        cast += 1;
                    }
                }
            }
            let n = covered.len().max(1) as f32;
            Estimate {
                light,
                facing: facing as f32 / n,
                cast: cast as f32 / n,
            }
        })
        .collect()
}

/// The automatic light for `scene` seen by `camera` (see the module doc).
pub fn choose(scene: &Scene, camera: &Camera) -> Light {
    let fallback = Light::Directional {
        to_light: vec3(-0.4, 1.0, 0.3).normalize(),
    };
    if scene.is_empty() || !scene.bounds.min.is_finite() || !scene.bounds.max.is_finite() {
        return fallback;
    }
    let est = estimates(scene, camera);
    let best = |ok: &dyn Fn(&Estimate) -> bool| {
        est.iter()
            .filter(|e| ok(e))
            .fold(None::<&Estimate>, |b, e| match b {
                Some(b) if b.cast >= e.cast => Some(b),
                _ => Some(e),
            })
            .map(|e| e.light)
    };
    best(&|e| e.facing >= MIN_LIT_FACING)
        .or_else(|| best(&|_| true))
        .unwrap_or(fallback)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    /// A box standing on a wide ground, seen from the auto-framing's direction.
    fn box_on_ground() -> (Scene, Camera) {
        let mut s = Scene::new("box");
        let m = s.add_material(Material::default());
        let (a, b) = (vec3(-1.0, 0.0, -1.0), vec3(1.0, 2.0, 1.0));
        let c = |x: f32, y: f32, z: f32| vec3(x, y, z);
        let faces = [
            [
                c(a.x, a.y, b.z),
                c(b.x, a.y, b.z),
                c(b.x, b.y, b.z),
                c(a.x, b.y, b.z),
            ],
            [
                c(b.x, a.y, a.z),
                c(a.x, a.y, a.z),
                c(a.x, b.y, a.z),
                c(b.x, b.y, a.z),
            ],
            [
                c(a.x, a.y, a.z),
                c(a.x, a.y, b.z),
                c(a.x, b.y, b.z),
                c(a.x, b.y, a.z),
            ],
            [
                c(b.x, a.y, b.z),
                c(b.x, a.y, a.z),
                c(b.x, b.y, a.z),
                c(b.x, b.y, b.z),
            ],
            [
                c(a.x, b.y, b.z),
                c(b.x, b.y, b.z),
                c(b.x, b.y, a.z),
                c(a.x, b.y, a.z),
            ],
        ];
        for q in faces {
            s.push([q[0], q[1], q[2]], m);
            s.push([q[0], q[2], q[3]], m);
        }
        s.auto_frame(true);
        let cam = s.camera.expect("auto-framed");
        (s, cam)
    }

    #[test]
    fn the_chosen_light_casts_visible_shadow_and_lights_the_visible_side() {
        let (s, cam) = box_on_ground();
        let est = estimates(&s, &cam);
        let light = choose(&s, &cam);
        let chosen = est.iter().find(|e| e.light == light).expect("a candidate");
        assert!(chosen.facing >= MIN_LIT_FACING, "{chosen:?}");
        assert!(chosen.cast >= 0.05, "{chosen:?}");
        for e in est.iter().filter(|e| e.facing >= MIN_LIT_FACING) {
            assert!(e.cast <= chosen.cast);
        }
        // An overhead light hides the box's shadow under the box.
        let top = Light::Directional { to_light: Vec3::Y };
        let mut c = cam;
        c.fit_depth_range(&s.bounds);
        let view = ViewSamples::render(&s, &c);
        let frame = Frame::new(&s, &c, &top, &view);
        let vis = Reference::build(&s).visibility(&frame, &[]);
        let shadowed = (0..view.triangle.len())
            .filter(|&k| frame.receiver_lit(k) && vis.value[k].max_element() < 0.5)
            .count();
        assert!((shadowed as f32) < chosen.cast * view.covered_count() as f32);
    }

    #[test]
    fn the_choice_is_repeatable() {
        let (s, cam) = box_on_ground();
        assert_eq!(choose(&s, &cam), choose(&s, &cam));
    }
}
