//! `gpu:psm`, `gpu:lispsm` and `gpu:cascaded` against their CPU twins: the verdict on the
//! shared scenes (two runs bit-identical, the error against the reference within 10% of
//! the twin's), and for `gpu:psm` the paper's light cases the CPU tests set up — lights
//! behind the viewer (an inverted post-space light), a light parallel to the image plane
//! (post-space directional), a point light inside the view (a cube of post-space maps),
//! and casters outside the view (above it, and behind the viewer through the virtual
//! shift) — each with the same post-space case as the CPU's.

mod support;

use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec3};
use shadowlab::scene::{Material, Scene};
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;
use support::{have_gpu, verdict, verdict_sets, Set};

#[test]
fn gpu_psm_matches_psm_on_the_verdict_scenes() {
    if !have_gpu("gpu_psm_matches_psm_on_the_verdict_scenes") {
        return;
    }
    for (name, set) in verdict_sets() {
        verdict(name, &set, "gpu:psm", "psm", &[], 1);
    }
}

#[test]
fn gpu_lispsm_matches_lispsm_on_the_verdict_scenes() {
    if !have_gpu("gpu_lispsm_matches_lispsm_on_the_verdict_scenes") {
        return;
    }
    for (name, set) in verdict_sets() {
        verdict(name, &set, "gpu:lispsm", "lispsm", &[], 1);
    }
    // The warp itself (bunny's and the leaf's lights are directional; chessboard's spot
    // and room's point light take the single-map fallback), here with its own parameter
    // and PCF under a directional light on chessboard.
    let chess = chessboard_sun();
    verdict("chessboard (sun)", &chess, "gpu:lispsm", "lispsm", &[], 1);
    verdict(
        "chessboard (sun)",
        &chess,
        "gpu:lispsm",
        "lispsm",
        &["n=5", "kernel=3"],
        1,
    );
}

#[test]
fn gpu_cascaded_matches_cascaded_on_the_verdict_scenes() {
    if !have_gpu("gpu_cascaded_matches_cascaded_on_the_verdict_scenes") {
        return;
    }
    for (name, set) in verdict_sets() {
        verdict(name, &set, "gpu:cascaded", "cascaded", &[], 1);
    }
    let chess = chessboard_sun();
    let cases: [&[&str]; 3] = [
        &[],
        &["depth-bounds=camera", "stabilize=false", "kernel=0"],
        &["cascades=2", "blend=0.3", "lambda=0.5"],
    ];
    for params in cases {
        verdict(
            "chessboard (sun)",
            &chess,
            "gpu:cascaded",
            "cascaded",
            params,
            1,
        );
    }
}

/// chessboard under a directional light (its own is a spot light, which the warped and
/// split maps answer with one map).
fn chessboard_sun() -> Set {
    let sun = Light::Directional {
        to_light: vec3(0.5, 1.0, 0.3).normalize(),
    };
    support::builtin("chessboard", 128, 96, Some(sun))
}

/// The SDSM bounds reduced on the GPU are the CPU's nearest and farthest lit view depth
/// up to the last bits of a float (a fused multiply-add may round the dot product once
/// instead of twice): so the splits agree.
#[test]
fn gpu_cascaded_reduces_the_cpus_depth_bounds() {
    if !have_gpu("gpu_cascaded_reduces_the_cpus_depth_bounds") {
        return;
    }
    /// Relative difference allowed between the GPU's and the CPU's split planes.
    const SPLIT_ROUNDING: f64 = 1e-5;
    let set = chessboard_sun();
    let a = render(&set, "gpu:cascaded");
    let b = render(&set, "cascaded");
    for i in 0..=4 {
        let key = format!("split{i}");
        let (x, y) = (a.stats.counters[&key], b.stats.counters[&key]);
        assert!(
            (x - y).abs() <= SPLIT_ROUNDING * y.abs(),
            "{key}: GPU {x} vs CPU {y}"
        );
    }
}

fn render(set: &Set, name: &str) -> Shadows {
    shadowlab_gpu::register();
    let frame = Frame::new(&set.0, &set.1, &set.2, &set.3);
    techniques::create(name).unwrap().render(&frame).unwrap()
}

fn add_quad(s: &mut Scene, corner: Vec3, a: Vec3, b: Vec3, m: u32) {
    let (p0, p1, p2, p3) = (corner, corner + a, corner + a + b, corner + b);
    s.push([p0, p1, p2], m);
    s.push([p0, p2, p3], m);
}

fn add_box(s: &mut Scene, min: Vec3, max: Vec3, m: u32) {
    let d = max - min;
    let (x, y, z) = (
        vec3(d.x, 0.0, 0.0),
        vec3(0.0, d.y, 0.0),
        vec3(0.0, 0.0, d.z),
    );
    add_quad(s, min, y, x, m);
    add_quad(s, min + z, x, y, m);
    add_quad(s, min, z, y, m);
    add_quad(s, min + x, y, z, m);
    add_quad(s, min, x, z, m);
    add_quad(s, min + y, z, x, m);
}

/// The library's psm test ground: a 40 × 40 ground of 8 × 8 quads (several cross the
/// camera plane) with boxes, a pole and a floating plate.
fn ground_scene() -> Scene {
    let mut s = Scene::new("psm-cases");
    let g = s.add_material(Material::opaque("ground", Vec3::splat(0.7)));
    let m = s.add_material(Material::opaque("boxes", vec3(0.7, 0.5, 0.4)));
    let step = 5.0;
    for j in 0..8 {
        for i in 0..8 {
            let c = vec3(-20.0 + i as f32 * step, 0.0, -20.0 + j as f32 * step);
            add_quad(&mut s, c, vec3(0.0, 0.0, step), vec3(step, 0.0, 0.0), g);
        }
    }
    add_box(&mut s, vec3(-3.0, 0.0, -2.0), vec3(-1.5, 2.5, -0.5), m);
    add_box(&mut s, vec3(1.0, 0.0, -4.0), vec3(2.2, 1.5, -2.8), m);
    add_box(&mut s, vec3(0.0, 0.0, 2.0), vec3(1.0, 1.0, 3.0), m);
    add_box(&mut s, vec3(3.5, 0.0, 1.0), vec3(3.7, 3.0, 1.2), m);
    add_box(&mut s, vec3(-1.0, 1.8, 0.5), vec3(0.5, 1.9, 2.0), m);
    add_box(&mut s, vec3(-7.0, 0.0, -7.5), vec3(6.0, 2.0, -7.0), m);
    add_box(&mut s, vec3(-5.0, 1.2, 3.5), vec3(-2.0, 1.4, 5.0), m);
    add_box(&mut s, vec3(4.0, 0.0, -1.0), vec3(5.5, 2.2, 0.5), m);
    s
}

/// `scene` seen from `eye` towards `target` at 160 × 120 under `light`.
fn case(scene: Scene, eye: Vec3, target: Vec3, light: Light) -> Set {
    let mut c = Camera::look_at(eye, target, 45.0, 160, 120);
    c.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(&scene, &c);
    (scene, c, light, view)
}

/// The verdict of `gpu:psm` on a case, and the GPU's counters equal to the CPU's for
/// the post-space light's case, the number of maps and whether the camera was shifted.
fn check_case(name: &str, set: &Set) -> Shadows {
    verdict(name, set, "gpu:psm", "psm", &["resolution=1024"], 1);
    let (mut a, mut b) = (
        techniques::create("gpu:psm").unwrap(),
        techniques::create("psm").unwrap(),
    );
    for t in [&mut a, &mut b] {
        t.set_param("resolution", "1024").unwrap();
    }
    let frame = Frame::new(&set.0, &set.1, &set.2, &set.3);
    let (g, c) = (a.render(&frame).unwrap(), b.render(&frame).unwrap());
    for key in ["inverted", "post_directional", "maps"] {
        assert_eq!(
            g.stats.counters[key], c.stats.counters[key],
            "{name}: {key}"
        );
    }
    assert_eq!(
        g.stats.counters["virtual_shift"] > 0.0,
        c.stats.counters["virtual_shift"] > 0.0,
        "{name}: virtual shift"
    );
    g
}

#[test]
fn gpu_psm_handles_lights_behind_the_viewer() {
    if !have_gpu("gpu_psm_handles_lights_behind_the_viewer") {
        return;
    }
    let (eye, target) = (vec3(0.0, 6.0, 14.0), Vec3::ZERO);
    let directional = Light::Directional {
        to_light: vec3(0.6, 1.0, 0.9).normalize(),
    };
    let g = check_case(
        "directional behind",
        &case(ground_scene(), eye, target, directional),
    );
    assert_eq!(g.stats.counters["inverted"], 1.0);
    let point = Light::Point {
        position: vec3(-8.0, 6.0, 40.0),
    };
    let g = check_case("point behind", &case(ground_scene(), eye, target, point));
    assert_eq!(g.stats.counters["inverted"], 1.0);
}

#[test]
fn gpu_psm_handles_the_other_post_space_lights() {
    if !have_gpu("gpu_psm_handles_the_other_post_space_lights") {
        return;
    }
    let (eye, target) = (vec3(0.0, 6.0, 14.0), Vec3::ZERO);
    let front = Light::Directional {
        to_light: vec3(0.3, 1.0, -0.9).normalize(),
    };
    check_case(
        "directional front",
        &case(ground_scene(), eye, target, front),
    );
    let inside = Light::Point {
        position: vec3(-0.5, 3.5, -0.2),
    };
    let g = check_case(
        "point inside the view",
        &case(ground_scene(), eye, target, inside),
    );
    assert!(g.stats.counters["maps"] > 1.0, "expected a cube of maps");
    let spot = Light::Spot {
        position: vec3(-4.0, 9.0, 4.0),
        target: vec3(0.0, 0.0, -1.0),
        fov_deg: 70.0,
    };
    check_case("spot", &case(ground_scene(), eye, target, spot));
}

#[test]
fn gpu_psm_shadows_from_casters_outside_the_view() {
    if !have_gpu("gpu_psm_shadows_from_casters_outside_the_view") {
        return;
    }
    // A roof above the view frustum.
    let mut s = ground_scene();
    let m = s.add_material(Material::opaque("roof", Vec3::splat(0.5)));
    let first = s.len();
    add_box(&mut s, vec3(-2.0, 7.0, 2.0), vec3(2.0, 7.2, 6.0), m);
    let light = Light::Directional {
        to_light: vec3(0.1, 1.0, -0.3).normalize(),
    };
    let set = case(s, vec3(0.0, 2.0, 12.0), vec3(0.0, 1.0, 0.0), light);
    assert!(
        set.3
            .triangle
            .iter()
            .all(|&t| (t as usize) < first || t == u32::MAX),
        "the roof must be outside the view"
    );
    check_case("caster above the view", &set);
    // A wall behind the viewer, reached through the virtual camera's shift.
    let mut s = ground_scene();
    let m = s.add_material(Material::opaque("wall", Vec3::splat(0.5)));
    let first = s.len();
    add_box(&mut s, vec3(-1.5, 0.0, 12.0), vec3(1.5, 6.0, 12.3), m);
    let light = Light::Directional {
        to_light: vec3(0.0, 0.6, 1.0).normalize(),
    };
    let set = case(s, vec3(0.0, 3.0, 8.0), vec3(0.0, 0.0, -4.0), light);
    assert!(
        set.3
            .triangle
            .iter()
            .all(|&t| (t as usize) < first || t == u32::MAX),
        "the wall must be behind the viewer"
    );
    let g = check_case("caster behind the viewer", &set);
    assert!(g.stats.counters["virtual_shift"] > 0.0);
    assert_eq!(g.stats.counters["inverted"], 1.0);
}
