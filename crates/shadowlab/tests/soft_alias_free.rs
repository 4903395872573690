//! `afsm-soft` (exact soft shadows from the alias-free structure) against brute force and
//! the soft reference: every pixel of small random scenes under rectangle, disk, sphere,
//! sized-spot and distant lights with several light-sample counts equals the brute-force
//! fraction of light samples seen (every light sample's ray against every triangle, the
//! ray formed as the reference forms it), and every pixel of `penumbra` and `room-soft`
//! equals the soft reference; the counters add up, the results do not depend on the
//! thread count, and bad sample counts are refused.

use shadowlab::area_light::{light_samples, AreaLight};
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Vec3};
use shadowlab::reference::{brute_force_occlusion, Reference};
use shadowlab::scene::{self, Material, Scene};
use shadowlab::soft_reference::{shadow_ray, soft_visibility};
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;

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

fn soft(frame: &Frame) -> Shadows {
    techniques::create("afsm-soft")
        .unwrap()
        .render(frame)
        .unwrap()
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

/// An area light of kind `trial % 5` placed at random (some inside the cloud of
/// triangles, so casters lie on every side of it), and the punctual stand-in hard
/// techniques see (a spot's for the sized spot).
fn random_light(rng: &mut Lcg, trial: usize) -> (AreaLight, Light) {
    let above = vec3(rng.next() - 0.5, 2.0 + rng.next(), rng.next() - 0.5);
    let area = match trial % 5 {
        0 => AreaLight::Rect {
            centre: if trial.is_multiple_of(2) {
                above
            } else {
                rng.v() * 0.3
            },
            edge_u: vec3(0.5 + rng.next(), 0.2 * rng.next(), 0.0),
            edge_v: vec3(0.1 * rng.next(), 0.0, 0.3 + rng.next()),
        },
        1 => AreaLight::Disk {
            centre: above,
            normal: vec3(rng.next() - 0.5, -1.0, rng.next() - 0.5).normalize(),
            radius: 0.2 + 0.8 * rng.next(),
        },
        2 => AreaLight::Sphere {
            centre: if trial.is_multiple_of(2) {
                above
            } else {
                rng.v() * 0.4
            },
            radius: 0.1 + 0.5 * rng.next(),
        },
        3 => AreaLight::Distant {
            to_light: vec3(rng.next() - 0.5, 1.0, rng.next() - 0.5).normalize(),
            angle_deg: 2.0 + 20.0 * rng.next(),
        },
        _ => {
            let spot = Light::Spot {
                position: above,
                target: rng.v() * 0.5,
                fov_deg: 50.0 + 60.0 * rng.next(),
            };
            return (
                AreaLight::sized(&spot, 0.2 + 0.6 * rng.next()).unwrap(),
                spot,
            );
        }
    };
    (area, area.punctual())
}

/// The fraction of light samples seen, every light sample's ray against every triangle,
/// summed in sample order as the reference sums.
fn brute_force(frame: &Frame, area: &AreaLight, n: u32) -> Vec<Vec3> {
    let view = frame.view;
    let uvs = light_samples(n);
    (0..view.triangle.len())
        .map(|k| {
            if !view.covered(k) {
                return Vec3::ONE;
            }
            let sp = view.surface_point(k);
            let in_cone = AreaLight::in_cone(frame.light, sp.p);
            let mut rgb = Vec3::ZERO;
            for &uv in &uvs {
                rgb += match shadow_ray(area, &sp, view.normal[k], uv) {
                    Some((o, dir, len)) if in_cone => {
                        brute_force_occlusion(frame.scene, o, dir, len, view.triangle[k])
                    }
                    _ => Vec3::ZERO,
                };
            }
            rgb / n as f32
        })
        .collect()
}

#[test]
fn matches_brute_force_on_every_pixel_of_small_random_scenes() {
    let mut rng = Lcg(23);
    let (mut checked, mut penumbra) = (0usize, 0usize);
    for trial in 0..20 {
        let scene = random_scene(&mut rng, 30 + 20 * (trial % 3), trial % 4 == 3);
        let dir = vec3(rng.next() - 0.5, 0.4 + rng.next(), rng.next() - 0.5).normalize();
        let mut camera = Camera::look_at(dir * 6.0, Vec3::ZERO, 50.0, 48, 36);
        camera.fit_depth_range(&scene.bounds);
        let (area, light) = random_light(&mut rng, trial);
        let n = [256, 16, 100, 64, 7][trial % 5];
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view).with_area(Some(&area), n);
        let expected = brute_force(&frame, &area, n);
        let got = soft(&frame).visibility.value;
        for k in (0..expected.len()).filter(|&k| view.covered(k)) {
            checked += 1;
            assert_eq!(
                got[k],
                expected[k],
                "trial {trial} ({} light, {n} samples): pixel {k} differs from brute force",
                area.kind()
            );
            let l = expected[k].max_element();
            penumbra += usize::from(l > 0.0 && l < 1.0);
        }
    }
    assert!(checked > 15_000, "{checked} pixels checked");
    assert!(penumbra > 3_000, "{penumbra} pixels in penumbrae");
}

/// A built-in scene at a small size.
fn builtin(name: &str, w: u32, h: u32) -> (Scene, Camera) {
    let scene = scene::load(name, &Default::default()).unwrap();
    let mut camera = scene.camera.unwrap();
    camera.width = w;
    camera.height = h;
    camera.fit_depth_range(&scene.bounds);
    (scene, camera)
}

/// `afsm-soft` and the soft reference (one primary ray a pixel) on a built-in scene
/// with `n` light samples: equal on every pixel. Returns the technique's shadows.
fn equals_reference(name: &str, w: u32, h: u32, n: u32) -> Shadows {
    let (scene, camera) = builtin(name, w, h);
    let area = scene.area_light.expect("a soft scene has an area light");
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view).with_area(Some(&area), n);
    let reference = Reference::build(&scene);
    let truth = soft_visibility(&reference, &frame, &area, n, &[vec2(0.5, 0.5)]);
    let shadows = soft(&frame);
    let mut penumbra = 0;
    for k in (0..truth.visibility.value.len()).filter(|&k| view.covered(k)) {
        assert_eq!(
            shadows.visibility.value[k], truth.visibility.value[k],
            "{name}, {n} light samples: pixel {k} differs from the reference"
        );
        let l = truth.visibility.value[k].max_element();
        penumbra += usize::from(l > 0.0 && l < 1.0);
    }
    assert!(penumbra > 200, "{name}: {penumbra} penumbra pixels");
    shadows
}

#[test]
fn penumbra_equals_the_reference_on_every_pixel() {
    let shadows = equals_reference("penumbra", 320, 240, 256);
    let c = &shadows.stats.counters;
    // The pairs add up, and the bitmasks leave few light samples to the ray.
    let sum = c["pairs_missed"] + c["pairs_hidden"] + c["pairs_masked"] + c["pairs_grazing"];
    assert_eq!(c["pairs"], sum, "{c:?}");
    assert!(c["pairs_masked"] > 1000.0, "{c:?}");
    assert!(
        c["ray_tests"] < 0.05 * 256.0 * c["pairs"],
        "the ray decides at most a twentieth of the light samples: {c:?}"
    );
}

#[test]
fn soft_room_and_chessboard_equal_the_reference_on_every_pixel() {
    equals_reference("room-soft", 160, 120, 64);
    equals_reference("chessboard-soft", 160, 120, 64);
}

#[test]
fn identical_for_any_thread_count_and_leaf_size() {
    let (scene, camera) = builtin("penumbra", 160, 120);
    let area = scene.area_light.unwrap();
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view).with_area(Some(&area), 64);
    let base = soft(&frame);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| soft(&frame));
    assert_eq!(base.visibility.value, one.visibility.value);
    assert_eq!(base.stats.counters, one.stats.counters);
    let mut t = techniques::create("afsm-soft").unwrap();
    t.set_param("leaf-size", "5").unwrap();
    assert_eq!(
        t.render(&frame).unwrap().visibility.value,
        base.visibility.value
    );
}

#[test]
fn a_punctual_light_gives_the_hard_technique_and_too_many_samples_are_refused() {
    let (scene, camera) = builtin("penumbra", 64, 48);
    let light = scene.light.unwrap();
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let hard = techniques::create("afsm").unwrap().render(&frame).unwrap();
    assert_eq!(soft(&frame).visibility.value, hard.visibility.value);
    let area = scene.area_light.unwrap();
    let frame = frame.with_area(Some(&area), 4096);
    let e = techniques::create("afsm-soft")
        .unwrap()
        .render(&frame)
        .unwrap_err();
    assert!(e.to_string().contains("4096"), "{e}");
}
