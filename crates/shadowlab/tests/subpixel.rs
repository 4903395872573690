//! `subpixel` against brute force (every sub-sample of every facet against every triangle)
//! and against the supersampled ray-traced reference with the same sample positions.
//!
//! Run with `cargo test --release -p shadowlab --test subpixel`.

use shadowlab::camera::Camera;
use shadowlab::compare::{compare, luminance};
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::sampling::{centre_index, pattern, PatternKind};
use shadowlab::scene::builtin::{add_box, add_plane, add_sphere};
use shadowlab::scene::{Material, Scene};
use shadowlab::techniques::{self, Frame, Shadows, Visibility};
use shadowlab::view::ViewSamples;

/// Largest share of ground pixels allowed to differ from the brute-force facet answer by
/// more than [`SLACK_SAMPLES`] samples. The half-plane masks are exact (the table's uncertain
/// samples are tested one by one), so what remains is geometry the facet evaluation treats
/// differently: under the point light, facets on the seam between two cube faces see the
/// blockers of one face only (10 pixels along x = −5 here); under the directional light at
/// 128 samples, 3 pixels differ by 3 to 5 samples.
const BRUTE_FORCE_OUTLIER_SHARE: f64 = 0.001;
/// Samples per pixel an ordinary pixel may differ from brute force by (a sample that lies on
/// a shadow edge to within rounding may go either way).
const SLACK_SAMPLES: f32 = 2.0;
/// The spec's quality target: mean absolute error on planar receivers at 32 samples.
const PLANAR_MAE_TARGET: f64 = 0.005;

fn render(name: &str, params: &[(&str, &str)], frame: &Frame) -> Shadows {
    let mut t = techniques::create(name).unwrap();
    for (k, v) in params {
        t.set_param(k, v).unwrap();
    }
    t.render(frame).unwrap()
}

/// Floating blockers over a ground plane: a sphere, a tilted slab and a cage of thin bars.
/// Nothing touches the ground, so every ground facet keeps all its samples valid.
fn blocker_scene(light: Light) -> Scene {
    let mut s = Scene::new("floating blockers");
    let ground = s.add_material(Material::opaque("ground", vec3(0.7, 0.7, 0.7)));
    let stuff = s.add_material(Material::opaque("stuff", vec3(0.8, 0.5, 0.3)));
    add_plane(&mut s, Vec3::ZERO, 12.0, 12.0, ground);
    add_sphere(&mut s, vec3(-1.5, 1.6, 0.5), 0.9, 12, 24, stuff);
    add_box(&mut s, vec3(0.6, 1.2, -1.2), vec3(2.2, 1.35, 0.4), stuff);
    for i in 0..7 {
        let x = -2.4 + i as f32 * 0.37;
        add_box(
            &mut s,
            vec3(x, 2.6, -2.0),
            vec3(x + 0.035, 2.64, 2.0),
            stuff,
        );
    }
    s.light = Some(light);
    s.camera = Some(Camera::look_at(
        vec3(2.0, 7.5, 8.0),
        vec3(0.0, 0.0, 0.0),
        45.0,
        200,
        150,
    ));
    s
}

struct Setup {
    scene: Scene,
    camera: Camera,
    light: Light,
}

impl Setup {
    fn new(scene: Scene) -> Self {
        let mut camera = scene.camera.unwrap();
        camera.fit_depth_range(&scene.bounds);
        let light = scene.light.unwrap();
        Setup {
            scene,
            camera,
            light,
        }
    }

    fn builtin(name: &str, width: u32, height: u32) -> Self {
        let mut scene = shadowlab::scene::load(name, &Default::default()).unwrap();
        let cam = scene.camera.as_mut().unwrap();
        cam.width = width;
        cam.height = height;
        Setup::new(scene)
    }
}

/// The facet's answer by brute force: each sample's point on the pixel's tangent plane,
/// tested against every triangle but the pixel's own (through the reference's BVH, which
/// `reference.rs` checks against a loop over all triangles).
fn brute_force_facets(frame: &Frame, samples: &[Vec2]) -> Vec<f32> {
    use rayon::prelude::*;
    let view = frame.view;
    let cam = frame.camera;
    let scene = frame.scene;
    let bvh = Reference::build(scene);
    let offset = scene.bounds.diagonal() * 1e-5;
    (0..view.triangle.len())
        .into_par_iter()
        .map(|k| {
            if !view.covered(k) {
                return 1.0;
            }
            if !frame.receiver_lit(k) {
                return 0.0;
            }
            let (x, y) = (
                (k as u32 % view.width) as f32,
                (k as u32 / view.width) as f32,
            );
            let (p, n) = (view.position[k], view.normal[k]);
            let mut lit = 0;
            for s in samples {
                let d = cam.ray_direction(x + s.x, y + s.y);
                let t = n.dot(p - cam.eye) / n.dot(d);
                let q = cam.eye + d * t + n * offset;
                let (dir, t_max) = frame.light.shadow_ray(q);
                if bvh.occlusion(q, dir, t_max, view.triangle[k]) == Vec3::ONE {
                    lit += 1;
                }
            }
            lit as f32 / samples.len() as f32
        })
        .collect()
}

/// Pixels on the ground plane, away from every other surface in the image (their whole
/// 3×3 neighbourhood sees the ground), so that all sub-samples lie on the plane.
fn ground_interior(scene: &Scene, view: &ViewSamples, materials: &[&str]) -> Vec<usize> {
    let (w, h) = (view.width as i64, view.height as i64);
    let on = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= w || y >= h {
            return false;
        }
        let k = (y * w + x) as usize;
        view.covered(k)
            && materials.contains(&scene.material_of(view.triangle[k] as usize).name.as_str())
    };
    (0..w * h)
        .filter(|&k| {
            let (x, y) = (k % w, k / w);
            (-1..=1).all(|dy| (-1..=1).all(|dx| on(x + dx, y + dy)))
        })
        .map(|k| k as usize)
        .collect()
}

fn mae_over(a: &Visibility, b: &Visibility, pixels: &[usize]) -> f64 {
    pixels
        .iter()
        .map(|&k| (luminance(a.value[k]) - luminance(b.value[k])).abs() as f64)
        .sum::<f64>()
        / pixels.len().max(1) as f64
}

fn check_against_brute_force(light: Light, n: u32, kind: &str) {
    let setup = Setup::new(blocker_scene(light));
    let view = ViewSamples::render(&setup.scene, &setup.camera);
    let frame = Frame::new(&setup.scene, &setup.camera, &setup.light, &view);
    let ns = n.to_string();
    let shadows = render("subpixel", &[("samples", &ns), ("pattern", kind)], &frame);
    let samples = pattern(kind.parse().unwrap(), n).unwrap();
    let brute = brute_force_facets(&frame, &samples);
    let pixels = ground_interior(&setup.scene, &view, &["ground"]);
    assert!(
        pixels.len() > 5000,
        "too few ground pixels: {}",
        pixels.len()
    );
    let slack = SLACK_SAMPLES / n as f32 + 1e-6;
    let mut outliers = 0;
    let mut partial = 0;
    let mut sum = 0.0f64;
    for &k in &pixels {
        let d = (shadows.visibility.value[k].x - brute[k]).abs();
        sum += d as f64;
        outliers += (d > slack) as usize;
        partial += (brute[k] > 0.0 && brute[k] < 1.0) as usize;
    }
    let share = outliers as f64 / pixels.len() as f64;
    let mean = sum / pixels.len() as f64;
    eprintln!(
        "{} {kind} {n}: {} ground pixels, {partial} partly shadowed, {outliers} outliers, mean |diff| {mean:.6}, counters {:?}",
        light.kind(),
        pixels.len(),
        shadows.stats.counters
    );
    assert!(
        partial > 100,
        "the scene should put shadow edges on the ground ({partial})"
    );
    assert!(
        share <= BRUTE_FORCE_OUTLIER_SHARE,
        "{outliers} of {} pixels differ by more than {slack}",
        pixels.len()
    );
    assert!(mean < 5e-4, "mean difference {mean}");
}

#[test]
fn matches_brute_force_facets_under_a_directional_light() {
    check_against_brute_force(
        Light::Directional {
            to_light: vec3(-0.5, 1.0, 0.35).normalize(),
        },
        32,
        "grid",
    );
    check_against_brute_force(
        Light::Directional {
            to_light: vec3(0.3, 1.0, -0.6).normalize(),
        },
        128,
        "rotated-grid",
    );
}

#[test]
fn matches_brute_force_facets_under_spot_and_point_lights() {
    check_against_brute_force(
        Light::Spot {
            position: vec3(-4.0, 9.0, 3.0),
            target: vec3(0.0, 0.0, 0.0),
            fov_deg: 80.0,
        },
        16,
        "grid",
    );
    check_against_brute_force(
        Light::Point {
            position: vec3(1.0, 6.0, -2.0),
        },
        64,
        "rotated-grid",
    );
}

#[test]
fn output_does_not_depend_on_thread_count() {
    let setup = Setup::new(blocker_scene(Light::Point {
        position: vec3(1.0, 6.0, -2.0),
    }));
    let view = ViewSamples::render(&setup.scene, &setup.camera);
    let frame = Frame::new(&setup.scene, &setup.camera, &setup.light, &view);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render("subpixel", &[("samples", "32")], &frame))
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.visibility, b.visibility);
    assert_eq!(a.stats.counters, b.stats.counters);
}

/// Receiver pixels split by what their sub-samples see: `on` when every sub-sample's primary
/// ray (the reference's, through the same positions) hits a receiver triangle, `mixed` when
/// some hit another surface (an object standing on or in front of the receiver) or nothing.
/// Only the centre sample decides which pixels are receiver pixels at all.
struct ReceiverPixels {
    on: Vec<usize>,
    mixed: Vec<usize>,
}

fn receiver_pixels(
    scene: &Scene,
    camera: &Camera,
    view: &ViewSamples,
    samples: &[Vec2],
    receiver: &[&str],
) -> ReceiverPixels {
    use rayon::prelude::*;
    let bvh = Reference::build(scene);
    let rays = camera.rays();
    let is_receiver = |t: u32| receiver.contains(&scene.material_of(t as usize).name.as_str());
    let w = view.width as usize;
    let class: Vec<Option<bool>> = (0..view.triangle.len())
        .into_par_iter()
        .map(|k| {
            if !view.covered(k) || !is_receiver(view.triangle[k]) {
                return None;
            }
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            Some(samples.iter().all(|s| {
                bvh.closest_hit(camera.eye, rays.direction(x + s.x, y + s.y))
                    .is_some_and(|h| is_receiver(h.triangle))
            }))
        })
        .collect();
    let pick = |want: bool| {
        (0..class.len())
            .filter(|&k| class[k] == Some(want))
            .collect::<Vec<_>>()
    };
    ReceiverPixels {
        on: pick(true),
        mixed: pick(false),
    }
}

/// The quality target on a planar receiver of a built-in scene: 32 samples against the
/// reference with the same 32 positions. On the pixels whose sub-samples all land on the
/// receiver (where the facet is the surface, contact shadows next to the objects included)
/// the error is at most [`PLANAR_MAE_TARGET`] and below that of one exact sample per pixel;
/// on every receiver pixel, including those whose sub-samples see the objects standing on
/// it (which one facet per pixel cannot represent), it is still below the one-sample error.
fn check_planar_receiver(name: &str, receiver: &[&str]) {
    let setup = Setup::builtin(name, 256, 192);
    let view = ViewSamples::render(&setup.scene, &setup.camera);
    let frame = Frame::new(&setup.scene, &setup.camera, &setup.light, &view);
    let samples = pattern(PatternKind::Grid, 32).unwrap();
    let reference = Reference::build(&setup.scene).visibility(&frame, &samples);
    let ours = render("subpixel", &[("samples", "32")], &frame);
    let ReceiverPixels { on, mixed } =
        receiver_pixels(&setup.scene, &setup.camera, &view, &samples, receiver);
    let all: Vec<usize> = {
        let mut v = [on.as_slice(), mixed.as_slice()].concat();
        v.sort_unstable();
        v
    };
    assert!(
        on.len() > 2000,
        "{name}: {} pixels wholly on {receiver:?}",
        on.len()
    );
    // Shadow edges must cross the measured pixels, or the comparison proves nothing.
    let partial = on
        .iter()
        .filter(|&&k| (0.01..0.99).contains(&reference.value[k].x))
        .count();
    assert!(
        partial > 100,
        "{name}: {partial} partly shadowed pixels on the receiver"
    );
    // One exact sample per pixel: `afsm` when it runs, else the ray-traced centre sample
    // (the answer `afsm` is built to give).
    let (one_name, one) = match techniques::create("afsm").unwrap().render(&frame) {
        Ok(s) => ("afsm", s.visibility),
        Err(_) => ("raytrace", render("raytrace", &[], &frame).visibility),
    };
    let mae_on = mae_over(&ours.visibility, &reference, &on);
    let mae_all = mae_over(&ours.visibility, &reference, &all);
    let one_on = mae_over(&one, &reference, &on);
    let one_all = mae_over(&one, &reference, &all);
    eprintln!(
        "{name}: all sub-samples on the receiver: MAE {mae_on:.5} ({} px, {partial} partly shadowed; {one_name} {one_on:.5}); every receiver pixel: MAE {mae_all:.5} ({} px; {one_name} {one_all:.5}); mixed pixels only: {:.5} ({} px; {one_name} {:.5}); counters {:?}",
        on.len(),
        all.len(),
        mae_over(&ours.visibility, &reference, &mixed),
        mixed.len(),
        mae_over(&one, &reference, &mixed),
        ours.stats.counters
    );
    assert!(
        mae_on <= PLANAR_MAE_TARGET,
        "{name}: MAE {mae_on} on {receiver:?} above {PLANAR_MAE_TARGET}"
    );
    assert!(
        mae_on < one_on,
        "{name}: MAE {mae_on} on {receiver:?} not below {one_name}'s {one_on}"
    );
    assert!(
        mae_all < one_all,
        "{name}: MAE {mae_all} over every receiver pixel not below {one_name}'s {one_all}"
    );
}

#[test]
fn cage_ground_meets_the_quality_target() {
    check_planar_receiver("cage", &["ground"]);
}

#[test]
fn bunny_ground_meets_the_quality_target() {
    check_planar_receiver("bunny", &["ground"]);
}

/// The board's squares (the table around it also passes, at about half the error of
/// `afsm`, most of it on the rim of the spot light's cone, where the shared `illuminates`
/// rule decides whole pixels by their centres).
#[test]
fn chessboard_board_meets_the_quality_target() {
    check_planar_receiver("chessboard", &["black", "white"]);
}

#[test]
fn one_sample_is_the_exact_centre_visibility() {
    let setup = Setup::new(blocker_scene(Light::Directional {
        to_light: vec3(-0.5, 1.0, 0.35).normalize(),
    }));
    let view = ViewSamples::render(&setup.scene, &setup.camera);
    let frame = Frame::new(&setup.scene, &setup.camera, &setup.light, &view);
    let ours = render("subpixel", &[("samples", "1")], &frame);
    let exact = render("raytrace", &[], &frame);
    let m = compare(&view, &ours.visibility, &exact.visibility);
    eprintln!("1 sample vs ray-traced centre: {m:?}");
    assert!(m.mismatch_rate < 1e-3, "{m:?}");
}

/// A bumpy height field under a floating slab: the concave creases cut facets, so the
/// validity mask drops samples; the counter reports how many stay.
#[test]
fn bumpy_receiver_reports_valid_samples() {
    let mut s = Scene::new("bumpy");
    let ground = s.add_material(Material::opaque("ground", vec3(0.7, 0.7, 0.7)));
    let n = 160;
    let size = 8.0;
    let height = |i: usize, j: usize| {
        let (x, z) = (
            i as f32 / n as f32 * size - size / 2.0,
            j as f32 / n as f32 * size - size / 2.0,
        );
        vec3(
            x,
            0.12 * (x * 3.1).sin() * (z * 2.7).cos() + 0.05 * (x * 7.3 + z * 5.1).sin(),
            z,
        )
    };
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (
                height(i, j),
                height(i + 1, j),
                height(i, j + 1),
                height(i + 1, j + 1),
            );
            s.push([a, c, b], ground);
            s.push([b, c, d], ground);
        }
    }
    add_box(&mut s, vec3(-1.0, 1.0, -1.0), vec3(1.0, 1.1, 1.0), ground);
    s.light = Some(Light::Directional {
        to_light: vec3(-0.6, 1.0, 0.2).normalize(),
    });
    s.camera = Some(Camera::look_at(
        vec3(1.0, 4.0, 5.0),
        vec3(0.0, 0.0, 0.0),
        40.0,
        240,
        180,
    ));
    let setup = Setup::new(s);
    let view = ViewSamples::render(&setup.scene, &setup.camera);
    let frame = Frame::new(&setup.scene, &setup.camera, &setup.light, &view);
    let ours = render("subpixel", &[("samples", "32")], &frame);
    let c = &ours.stats.counters;
    let valid = c["valid_samples_boundary_mean"];
    eprintln!("bumpy: {c:?}");
    assert!(c["boundary_pixels"] > 100.0, "{c:?}");
    assert!((1.0..32.0).contains(&valid), "valid samples {valid}");
    // The validity mask must not ruin the result: still close to the reference.
    let samples = pattern(PatternKind::Grid, 32).unwrap();
    let reference = Reference::build(&setup.scene).visibility(&frame, &samples);
    let m = compare(&view, &ours.visibility, &reference);
    eprintln!("bumpy vs reference: {m:?}");
    assert!(m.mean_abs_error < 0.02, "{m:?}");
}

#[test]
fn patterns_keep_a_centre_sample() {
    for kind in [PatternKind::Grid, PatternKind::RotatedGrid] {
        for n in [1, 4, 8, 16, 32, 64, 128] {
            let p = pattern(kind, n).unwrap();
            assert_eq!(p[centre_index(&p).unwrap()], Vec2::splat(0.5));
        }
    }
}

#[test]
fn bad_parameters_are_errors_that_name_the_culprit() {
    let mut t = techniques::create("subpixel").unwrap();
    for (k, v) in [
        ("samples", "0"),
        ("samples", "129"),
        ("samples", "many"),
        ("pattern", "hex"),
        ("resolution", "0"),
    ] {
        let e = t.set_param(k, v).unwrap_err().to_string();
        assert!(e.contains(k), "{k}={v}: {e}");
    }
    let e = t.set_param("leaf-size", "4").unwrap_err().to_string();
    assert!(e.contains("samples") && e.contains("leaf-size"), "{e}");
    assert_eq!(t.params()["samples"], 32);
}
