//! `afsm` (alias-free shadow maps) against brute force and the ray-traced reference: every
//! pixel's shadow term on small random scenes, the mismatch rate on every built-in scene
//! and every mesh of the shared data with directional, spot and point lights, the hairball's
//! semi-transparent shadows, the shadow terms of the layers behind semi-transparent
//! receivers, and independence of thread count and leaf size.

mod support;

use shadowlab::camera::Camera;
use shadowlab::compare::{compare, Metrics};
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Vec3};
use shadowlab::reference::{brute_force_occlusion, Reference};
use shadowlab::scene::{self, builtin, Material, Scene};
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::{ViewLayers, ViewSamples};
use std::collections::BTreeMap;
use support::{data, lights_for};

/// The exactness target: share of covered pixels whose shadow term may differ from the
/// reference (numerical ties only).
const MISMATCH_TARGET: f64 = 1e-4;
/// The hairball's RGB transmittance may differ from the reference by this on average.
const HAIRBALL_MAE_TARGET: f64 = 1e-3;
/// The resolution of the paper's measurements and of the exactness target.
const WIDTH: u32 = 1024;
/// See [`WIDTH`].
const HEIGHT: u32 = 768;

fn afsm(frame: &Frame, params: &[(&str, &str)]) -> Shadows {
    let mut t = techniques::create("afsm").unwrap();
    for (k, v) in params {
        t.set_param(k, v).unwrap();
    }
    t.render(frame).unwrap()
}

fn camera_for(scene: &Scene, w: u32, h: u32) -> Camera {
    let mut c = scene.camera.expect("scene has a camera");
    c.width = w;
    c.height = h;
    c.fit_depth_range(&scene.bounds);
    c
}

/// `afsm` and the reference on one frame: the metrics and the share of lit samples that
/// are in shadow (so a test knows it looked at shadows).
fn against_reference(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    reference: &Reference,
) -> (Metrics, f64) {
    let view = ViewSamples::render(scene, camera);
    let frame = Frame::new(scene, camera, light, &view);
    let truth = reference.visibility(&frame, &[vec2(0.5, 0.5)]);
    let shadows = afsm(&frame, &[]);
    let m = compare(&view, &shadows.visibility, &truth);
    let lit: Vec<usize> = (0..view.triangle.len())
        .filter(|&k| frame.receiver_lit(k))
        .collect();
    let shadowed = lit
        .iter()
        .filter(|&&k| truth.value[k].max_element() < 0.5)
        .count();
    (m, shadowed as f64 / lit.len().max(1) as f64)
}

fn check_scene(label: &str, scene: &Scene, lights: &[Light]) {
    let camera = camera_for(scene, WIDTH, HEIGHT);
    let reference = Reference::build(scene);
    for light in lights {
        let (m, shadowed) = against_reference(scene, &camera, light, &reference);
        eprintln!(
            "{label} {}: mismatch {:.6}% mae {:.2e} over {} pixels, {:.1}% of lit samples shadowed",
            light.kind(),
            m.mismatch_rate * 100.0,
            m.mean_abs_error_rgb,
            m.covered_pixels,
            shadowed * 100.0
        );
        assert!(
            m.covered_pixels > 1000,
            "{label}: the camera sees the scene"
        );
        assert!(
            m.mismatch_rate <= MISMATCH_TARGET,
            "{label} with a {} light: mismatch rate {} above {MISMATCH_TARGET}",
            light.kind(),
            m.mismatch_rate
        );
    }
}

fn check_mesh(file: &str) {
    let scene = scene::load(data(file).to_str().unwrap(), &BTreeMap::new()).unwrap();
    check_scene(file, &scene, &lights_for(&scene));
}

/// One test per mesh of the shared data, each with directional, spot and point lights.
macro_rules! mesh_tests {
    ($($name:ident => $file:expr),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                check_mesh($file);
            }
        )*
    };
}

mesh_tests! {
    mesh_bunny_matches_reference => "bunny.obj",
    mesh_teapot_matches_reference => "teapot.obj",
    mesh_dragon_matches_reference => "dragon-11k.ply",
    mesh_fence_matches_reference => "fence/fence.obj",
    mesh_chessboard_matches_reference => "chessboard/chessboard.obj",
    mesh_bike_matches_reference => "bike/bike.obj",
    mesh_engine_matches_reference => "gltf/2CylinderEngine.glb",
    mesh_box_matches_reference => "gltf/BoxTextured.glb",
}

#[test]
fn every_shared_mesh_is_covered_by_a_test() {
    // A new mesh in the shared data must get its line in `mesh_tests!`.
    let tested = [
        "bunny.obj",
        "teapot.obj",
        "dragon-11k.ply",
        "fence/fence.obj",
        "chessboard/chessboard.obj",
        "bike/bike.obj",
        "gltf/2CylinderEngine.glb",
        "gltf/BoxTextured.glb",
        // Two quads and cameras only: checked for loading elsewhere, too small to shadow.
        "gltf/Cameras.gltf",
        // Its orthographic camera's afsm-against-reference test is in tests/orthographic.rs.
        "gltf/orthographic.gltf",
    ];
    let mut found = Vec::new();
    for dir in ["", "fence", "chessboard", "bike", "gltf"] {
        for e in std::fs::read_dir(data(dir)).unwrap() {
            let p = e.unwrap().path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ["obj", "ply", "gltf", "glb"].contains(&ext) {
                let rel = p
                    .strip_prefix(data(""))
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                found.push(rel);
            }
        }
    }
    for f in found {
        assert!(
            tested.contains(&f.as_str()),
            "shared mesh {f} has no afsm test"
        );
    }
}

#[test]
fn builtin_scenes_match_reference_with_every_light_kind() {
    for (name, _) in builtin::list() {
        // The full hairball is checked with its own light below; a smaller ball of the
        // same hairs is enough for the three light kinds.
        let params: BTreeMap<String, String> = match name {
            "hairball" => [("hairs".to_string(), "300".to_string())].into(),
            _ => BTreeMap::new(),
        };
        let scene = scene::load(name, &params).unwrap();
        let mut lights = lights_for(&scene);
        lights.extend(scene.light);
        check_scene(name, &scene, &lights);
    }
}

#[test]
fn hairball_transmittance_matches_reference() {
    let scene = scene::load("hairball", &BTreeMap::new()).unwrap();
    assert!(scene.has_transparency());
    let camera = camera_for(&scene, WIDTH, HEIGHT);
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let truth = Reference::build(&scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    let shadows = afsm(&frame, &[]);
    let m = compare(&view, &shadows.visibility, &truth);
    // Partial shadows must be there: semi-transparent casters leave grey, not black.
    let grey = (0..truth.value.len())
        .filter(|&k| view.covered(k) && truth.value[k].x > 0.05 && truth.value[k].x < 0.95)
        .count();
    eprintln!(
        "hairball: mae rgb {:.2e}, mismatch {:.6}%, {grey} partly shadowed pixels",
        m.mean_abs_error_rgb,
        m.mismatch_rate * 100.0
    );
    assert!(grey > 1000, "the hairball casts semi-transparent shadows");
    assert!(
        m.mean_abs_error_rgb <= HAIRBALL_MAE_TARGET,
        "mae {}",
        m.mean_abs_error_rgb
    );
    assert!(m.mismatch_rate <= MISMATCH_TARGET);
}

#[test]
fn hairball_layers_behind_semi_transparent_receivers_match_reference() {
    let scene = scene::load("hairball", &BTreeMap::new()).unwrap();
    let camera = camera_for(&scene, 512, 384);
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let layers = ViewLayers::render(&scene, &camera, &view).unwrap();
    let frame = Frame::new(&scene, &camera, &light, &view);
    let layered = frame.with_layers(&layers);
    let reference = Reference::build(&scene);
    let truth = reference.layer_visibility(&layered, &layers);
    let with = afsm(&layered, &[]);
    let without = afsm(&frame, &[]);
    // The nearest surfaces' shadow terms do not change when layers join the BSP.
    assert_eq!(with.visibility, without.visibility);
    assert!(without.layers.is_none());
    let ours = with.layers.expect("afsm shades the layers");
    let m = shadowlab::compare::compare_samples(&ours, &truth);
    let deep = (0..view.triangle.len())
        .filter(|&k| layers.of_pixel(k).len() >= 5)
        .count();
    let grey = truth.iter().filter(|t| t.x > 0.05 && t.x < 0.95).count();
    eprintln!(
        "hairball layers: {} samples, {deep} pixels with 5+ layers, {grey} partly shadowed; mismatch {:.6}%, mae rgb {:.2e}",
        layers.len(),
        m.mismatch_rate * 100.0,
        m.mean_abs_error_rgb
    );
    assert!(layers.len() > 50_000 && deep > 1000 && grey > 1000);
    assert!(
        m.mismatch_rate <= MISMATCH_TARGET,
        "mismatch {}",
        m.mismatch_rate
    );
    assert!(
        m.mean_abs_error_rgb <= HAIRBALL_MAE_TARGET,
        "mae {}",
        m.mean_abs_error_rgb
    );
}

/// Every surface the centre ray of pixel `(x, y)` crosses behind the nearest one, front to
/// back, down to the first opaque one: the brute-force version of [`ViewLayers`].
fn layers_by_ray(scene: &Scene, camera: &Camera, x: u32, y: u32, nearest: u32) -> Vec<u32> {
    let d = camera.rays().direction(x as f32 + 0.5, y as f32 + 0.5);
    let mut hits: Vec<(f32, u32)> = (0..scene.len())
        .filter_map(|i| {
            shadowlab::math::intersect_triangle(
                camera.eye,
                d,
                0.0,
                f32::INFINITY,
                scene.triangle(i),
            )
            .map(|h| (h.t, i as u32))
        })
        .collect();
    hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut out = Vec::new();
    for (_, i) in hits.into_iter().skip_while(|&(_, i)| i != nearest).skip(1) {
        out.push(i);
        if scene.material_of(i as usize).is_opaque() {
            break;
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Brute force on small random scenes.

#[test]
fn layers_match_brute_force_on_small_random_scenes() {
    let mut rng = Lcg(23);
    let (mut pixels, mut samples, mut differ) = (0usize, 0usize, 0usize);
    let mut partial = 0usize;
    for trial in 0..9 {
        // Mostly glass, so rays cross several layers.
        let mut scene = random_scene(&mut rng, 60 + 30 * (trial % 3), true);
        for m in 1..scene.materials.len() {
            if trial % 2 == 0 {
                scene.materials[m].transmittance = vec3(0.8, 0.6, 0.7);
            }
        }
        let (camera, light) = random_view(&mut rng, trial, &scene, 80, 60);
        let view = ViewSamples::render(&scene, &camera);
        let layers = ViewLayers::render(&scene, &camera, &view).unwrap();
        let frame = Frame::new(&scene, &camera, &light, &view).with_layers(&layers);
        // The layers are the surfaces a ray through the pixel centre crosses (a pixel
        // centre exactly on an edge may be decided differently by the rasterizer's fill
        // rule and the ray test: a numerical tie).
        for k in 0..view.triangle.len() {
            if !view.covered(k) {
                continue;
            }
            let (x, y) = ((k as u32) % camera.width, (k as u32) / camera.width);
            let mut want = Vec::new();
            if !scene.material_of(view.triangle[k] as usize).is_opaque() {
                want = layers_by_ray(&scene, &camera, x, y, view.triangle[k]);
            }
            let got: Vec<u32> = layers.of_pixel(k).map(|i| layers.triangle[i]).collect();
            pixels += 1;
            if got != want {
                differ += 1;
            }
        }
        // Every layer sample's shadow term is brute force's, exactly.
        let got = afsm(&frame, &[("leaf-size", ["1", "7", "64"][trial % 3])])
            .layers
            .unwrap();
        for (i, got) in got.iter().enumerate() {
            let expected = if !frame.layer_lit(&layers, i) {
                Vec3::ZERO
            } else {
                let sp = layers.surface_point(i);
                let (l, _) = light.shadow_ray(sp.p);
                let o = sp.offset_origin(layers.normal[i], l);
                let (dir, t_max) = light.shadow_ray(o);
                brute_force_occlusion(&scene, o, dir, t_max, layers.triangle[i])
            };
            assert_eq!(*got, expected, "trial {trial}: layer sample {i}");
            samples += 1;
            if expected != Vec3::ZERO && expected != Vec3::ONE {
                partial += 1;
            }
        }
    }
    eprintln!("layers: {pixels} pixels, {differ} differ from ray casting; {samples} layer samples, {partial} partly shadowed");
    assert!(
        samples > 1500 && partial > 400,
        "{samples} layer samples, {partial} partial"
    );
    assert!(
        differ as f64 <= 1e-3 * pixels as f64,
        "{differ} of {pixels} pixels' layers differ from ray casting"
    );
}

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn v(&mut self) -> Vec3 {
        vec3(self.next(), self.next(), self.next()) * 2.0 - 1.0
    }
}

/// Random triangles in a box over a ground quad, some semi-transparent when `glass`.
fn random_scene(rng: &mut Lcg, count: usize, glass: bool) -> Scene {
    let mut s = Scene::new("random");
    let ground = s.add_material(Material::opaque("ground", Vec3::splat(0.7)));
    let opaque = s.add_material(Material::default());
    let tinted = s.add_material(Material {
        name: "glass".into(),
        color: Vec3::ONE,
        transmittance: vec3(0.9, 0.5, 0.25),
        alpha_mask: None,
    });
    let g = 3.0;
    s.push(
        [vec3(-g, -1.0, -g), vec3(-g, -1.0, g), vec3(g, -1.0, g)],
        ground,
    );
    s.push(
        [vec3(-g, -1.0, -g), vec3(g, -1.0, g), vec3(g, -1.0, -g)],
        ground,
    );
    for i in 0..count {
        let c = rng.v();
        let size = 0.1 + 0.4 * rng.next();
        let t = [c + rng.v() * size, c + rng.v() * size, c + rng.v() * size];
        s.push(t, if glass && i % 3 == 0 { tinted } else { opaque });
    }
    s
}

/// A camera looking at the random scene from above at a random angle, and a directional,
/// spot or point light (by `trial`) placed at random.
fn random_view(rng: &mut Lcg, trial: usize, scene: &Scene, w: u32, h: u32) -> (Camera, Light) {
    let dir = vec3(rng.next() - 0.5, 0.4 + rng.next(), rng.next() - 0.5).normalize();
    let mut camera = Camera::look_at(dir * 6.0, Vec3::ZERO, 50.0, w, h);
    camera.fit_depth_range(&scene.bounds);
    let light = match trial % 3 {
        0 => Light::Directional {
            to_light: vec3(rng.next() - 0.5, 1.0, rng.next() - 0.5).normalize(),
        },
        1 => Light::Spot {
            position: vec3(rng.next() - 0.5, 2.5, rng.next() - 0.5) * 2.0,
            target: rng.v() * 0.5,
            fov_deg: 40.0 + 80.0 * rng.next(),
        },
        // Inside the cloud of triangles: casters on every cube face, some crossing the
        // faces' planes.
        _ => Light::Point {
            position: rng.v() * 0.5,
        },
    };
    (camera, light)
}

/// Every sample against every triangle, the ray formed as the reference forms it.
fn brute_force(frame: &Frame) -> Vec<Vec3> {
    let view = frame.view;
    (0..view.triangle.len())
        .map(|k| {
            if !view.covered(k) {
                return Vec3::ONE;
            }
            if !frame.receiver_lit(k) {
                return Vec3::ZERO;
            }
            let sp = view.surface_point(k);
            let (l, _) = frame.light.shadow_ray(sp.p);
            let o = sp.offset_origin(view.normal[k], l);
            let (dir, t_max) = frame.light.shadow_ray(o);
            brute_force_occlusion(frame.scene, o, dir, t_max, view.triangle[k])
        })
        .collect()
}

#[test]
fn matches_brute_force_on_every_pixel_of_small_random_scenes() {
    let mut rng = Lcg(7);
    let mut checked = 0usize;
    let (mut dark, mut partial) = (0usize, 0usize);
    for trial in 0..18 {
        let scene = random_scene(&mut rng, 40 + 40 * (trial % 4), trial % 2 == 1);
        let (camera, light) = random_view(&mut rng, trial, &scene, 96, 72);
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        let expected = brute_force(&frame);
        let leaf = ["1", "5", "64"][trial % 3];
        let got = afsm(&frame, &[("leaf-size", leaf)]).visibility.value;
        for k in 0..expected.len() {
            if !view.covered(k) {
                continue;
            }
            checked += 1;
            assert_eq!(
                got[k],
                expected[k],
                "trial {trial} ({} light, leaf size {leaf}): pixel {k} differs from brute force",
                light.kind()
            );
            if frame.receiver_lit(k) && expected[k] == Vec3::ZERO {
                dark += 1;
            } else if expected[k] != Vec3::ONE && expected[k] != Vec3::ZERO {
                partial += 1;
            }
        }
    }
    assert!(checked > 50_000, "{checked} pixels checked");
    assert!(
        dark > 5_000,
        "{dark} shadowed pixels: the scenes must cast shadows"
    );
    assert!(
        partial > 1_000,
        "{partial} pixels behind semi-transparent casters only"
    );
}

#[test]
fn point_light_on_a_face_boundary_and_casters_through_its_planes() {
    // The light sits inside a box of large triangles that cross every cube face's plane;
    // a small occluder hangs over the floor.
    let mut s = Scene::new("box");
    let m = s.add_material(Material::default());
    let corners = |y: f32| {
        [
            vec3(-2.0, y, -2.0),
            vec3(2.0, y, -2.0),
            vec3(2.0, y, 2.0),
            vec3(-2.0, y, 2.0),
        ]
    };
    for y in [-1.0f32, 1.5] {
        let c = corners(y);
        s.push([c[0], c[1], c[2]], m);
        s.push([c[0], c[2], c[3]], m);
    }
    // Walls crossing the light's horizontal planes diagonally.
    s.push(
        [
            vec3(-2.0, -1.0, 1.9),
            vec3(2.0, -1.0, 1.9),
            vec3(0.0, 1.5, 1.9),
        ],
        m,
    );
    s.push(
        [
            vec3(1.9, -1.0, -2.0),
            vec3(1.9, -1.0, 2.0),
            vec3(1.9, 1.5, 0.0),
        ],
        m,
    );
    s.push(
        [
            vec3(-0.4, -0.2, -0.3),
            vec3(0.5, -0.3, -0.2),
            vec3(0.0, -0.1, 0.6),
        ],
        m,
    );
    s.push(
        [
            vec3(-1.5, 0.2, 0.1),
            vec3(1.2, 0.3, -0.4),
            vec3(0.1, 0.2, 1.2),
        ],
        m,
    );
    let light = Light::Point {
        position: vec3(0.0, 0.25, 0.0),
    };
    let mut camera = Camera::look_at(vec3(0.3, 0.6, -1.9), vec3(0.0, -0.5, 0.5), 100.0, 160, 120);
    camera.fit_depth_range(&s.bounds);
    let view = ViewSamples::render(&s, &camera);
    let frame = Frame::new(&s, &camera, &light, &view);
    let expected = brute_force(&frame);
    let shadows = afsm(&frame, &[]);
    assert!(
        shadows.stats.counters["light_planes"] >= 4.0,
        "samples spread over the cube faces"
    );
    let dark = expected.iter().filter(|v| **v == Vec3::ZERO).count();
    assert!(
        dark > 1000 && dark < expected.len() - 1000,
        "{dark} dark pixels"
    );
    for (k, e) in expected.iter().enumerate() {
        assert_eq!(shadows.visibility.value[k], *e, "pixel {k}");
    }
}

#[test]
fn identical_for_any_thread_count_and_leaf_size() {
    let scene = scene::load(
        "random-triangles",
        &[("count".to_string(), "20000".to_string())].into(),
    )
    .unwrap();
    let camera = camera_for(&scene, 320, 240);
    for light in lights_for(&scene) {
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        let run = |threads: usize, leaf: &str| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| afsm(&frame, &[("leaf-size", leaf)]))
        };
        let one = run(1, "64");
        let three = run(3, "64");
        assert_eq!(one.visibility, three.visibility, "{} light", light.kind());
        assert_eq!(
            one.stats.counters,
            three.stats.counters,
            "{} light",
            light.kind()
        );
        for leaf in ["1", "17", "1000"] {
            let other = run(2, leaf);
            assert_eq!(one.visibility, other.visibility, "leaf size {leaf}");
        }
        assert!(one.visibility.value.contains(&Vec3::ZERO));
    }
}

#[test]
fn reports_the_papers_counters_and_stages() {
    // The bunny's many small triangles overlap in light space: whole nodes go dark.
    let scene = scene::load("bunny", &BTreeMap::new()).unwrap();
    let camera = camera_for(&scene, 256, 192);
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let s = afsm(&frame, &[("leaf-size", "32")]);
    let stages: Vec<&str> = s.stats.stages_ms.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(stages, ["transform", "bsp", "raster"]);
    let c = &s.stats.counters;
    let samples = c["samples"];
    assert!(samples > 10_000.0);
    // Median splits: leaves of at most 32 samples, so between samples/32 and 2·samples/32
    // leaves, and one fewer internal node than leaves.
    let leaves = (c["bsp_nodes"] + 1.0) / 2.0;
    assert!(
        leaves >= samples / 32.0 && leaves <= 2.0 * samples / 32.0,
        "{leaves} leaves"
    );
    assert!(c["nodes_visited"] > c["bsp_nodes"]);
    assert!(c["samples_tested"] > 0.0 && c["ray_tests"] <= c["samples_tested"]);
    assert!(c["nodes_occlusion_culled"] > 0.0);
    assert!(s.stats.memory_bytes > 0);
}

#[test]
fn parameters_are_checked() {
    let mut t = techniques::create("afsm").unwrap();
    assert_eq!(t.params()["leaf-size"], 64);
    t.set_param("leaf-size", "8").unwrap();
    assert_eq!(t.params()["leaf-size"], 8);
    for bad in ["0", "-3", "many", "99999999"] {
        let e = t.set_param("leaf-size", bad).unwrap_err().to_string();
        assert!(e.contains("leaf-size"), "{e}");
    }
    let e = t.set_param("resolution", "1024").unwrap_err().to_string();
    assert!(
        e.contains("leaf-size"),
        "the error lists the known keys: {e}"
    );
}

#[test]
fn an_invalid_light_is_an_error_not_a_panic() {
    let scene = random_scene(&mut Lcg(1), 10, false);
    let mut camera = Camera::look_at(vec3(0.0, 3.0, 5.0), Vec3::ZERO, 50.0, 32, 24);
    camera.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(&scene, &camera);
    let light = Light::Spot {
        position: Vec3::ONE,
        target: Vec3::ONE,
        fov_deg: 40.0,
    };
    let frame = Frame::new(&scene, &camera, &light, &view);
    assert!(techniques::create("afsm").unwrap().render(&frame).is_err());
}

/// Stage times of `afsm` on `random-triangles` at 1024×768 (run with `--ignored
/// --nocapture` to profile; never asserts on time).
#[test]
#[ignore]
fn profile_random_triangles() {
    let count = std::env::var("AFSM_PROFILE_COUNT").unwrap_or_else(|_| "100000".into());
    let reps: usize = std::env::var("AFSM_PROFILE_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    let scene = scene::load(
        "random-triangles",
        &[("count".to_string(), count.clone())].into(),
    )
    .unwrap();
    let camera = camera_for(&scene, WIDTH, HEIGHT);
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let mut t = techniques::create("afsm").unwrap();
    for _ in 0..reps {
        let t0 = std::time::Instant::now();
        let s = t.render(&frame).unwrap();
        eprintln!(
            "{count}: {:.1} ms {:?} {:?}",
            t0.elapsed().as_secs_f64() * 1e3,
            s.stats.stages_ms,
            s.stats.counters
        );
    }
}

#[test]
fn one_technique_reused_across_frames_answers_as_a_fresh_one() {
    // afsm keeps its per-sample buffers between frames: frames of different sizes and light
    // kinds (one plane, six cube faces) must not see each other's leftovers.
    let scene = scene::load("bunny", &BTreeMap::new()).unwrap();
    let mut reused = techniques::create("afsm").unwrap();
    for (i, light) in lights_for(&scene).into_iter().cycle().take(5).enumerate() {
        let camera = camera_for(&scene, 160 + 40 * (i as u32 % 2), 120);
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        let fresh = afsm(&frame, &[]);
        let again = reused.render(&frame).unwrap();
        assert_eq!(again.visibility, fresh.visibility, "frame {i}");
        assert_eq!(again.stats.counters, fresh.stats.counters, "frame {i}");
    }
}
