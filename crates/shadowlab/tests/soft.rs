//! Soft shadows under area lights: the reference converges as an estimator should (its
//! measured variance halves when its light samples double; references at 256 and 4096
//! samples agree within their stated standard errors), and the TOML scene format reads
//! area lights and refuses keys that do not apply.

use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::frame::{luminance, Frame};
use shadowlab::reference::Reference;
use shadowlab::scene::Scene;
use shadowlab::soft_reference::{soft_visibility, SoftReference};
use shadowlab::view::ViewSamples;

/// The `penumbra` scene at a small size.
fn penumbra(w: u32, h: u32) -> (Scene, Camera) {
    let scene = shadowlab::scene::load("penumbra", &Default::default()).unwrap();
    let mut camera = scene.camera.unwrap();
    camera.width = w;
    camera.height = h;
    camera.fit_depth_range(&scene.bounds);
    (scene, camera)
}

fn soft(scene: &Scene, camera: &Camera, view: &ViewSamples, n: u32) -> SoftReference {
    let area = scene.area_light.expect("penumbra has an area light");
    let light = scene.light.unwrap();
    let frame = Frame::new(scene, camera, &light, view).with_area(Some(&area), n);
    let r = Reference::build(scene);
    soft_visibility(&r, &frame, &area, n, &[shadowlab::math::vec2(0.5, 0.5)])
}

#[test]
fn doubling_the_light_samples_halves_the_measured_variance() {
    let (scene, camera) = penumbra(96, 72);
    let view = ViewSamples::render(&scene, &camera);
    let light = scene.light.unwrap();
    let frame = Frame::new(&scene, &camera, &light, &view);
    let mut last = None;
    for n in [128, 256, 512] {
        let var = soft(&scene, &camera, &view, n).mean_variance(&frame);
        assert!(var > 0.0, "the penumbra scene has penumbrae");
        if let Some(prev) = last {
            let ratio = var / prev;
            assert!(
                (0.45..=0.55).contains(&ratio),
                "{n} samples: variance {var} is {ratio} of the previous"
            );
        }
        last = Some(var);
    }
}

#[test]
fn references_at_256_and_4096_samples_agree_within_their_standard_errors() {
    let (scene, camera) = penumbra(64, 48);
    let view = ViewSamples::render(&scene, &camera);
    let light = scene.light.unwrap();
    let frame = Frame::new(&scene, &camera, &light, &view);
    let a = soft(&scene, &camera, &view, 256);
    let b = soft(&scene, &camera, &view, 4096);
    let (mut diff, mut stated, mut outside, mut covered) = (0.0, 0.0, 0, 0);
    for k in 0..a.std_error.len() {
        if !view.covered(k) {
            continue;
        }
        covered += 1;
        let d = (luminance(a.visibility.value[k]) - luminance(b.visibility.value[k])).abs() as f64;
        let se = ((a.std_error[k] as f64).powi(2) + (b.std_error[k] as f64).powi(2)).sqrt();
        diff += d;
        stated += se;
        // Three standard errors, and a pixel of zero stated error must agree exactly
        // (up to the float rounding of the mean).
        if d > 3.0 * se + 1e-5 {
            outside += 1;
        }
    }
    assert!(
        diff <= stated,
        "mean difference {} exceeds the mean stated error {}",
        diff / covered as f64,
        stated / covered as f64
    );
    assert!(
        outside * 100 <= covered,
        "{outside} of {covered} pixels differ by more than three standard errors"
    );
    assert!(a.mean_std_error(&frame) > b.mean_std_error(&frame));
}

#[test]
fn toml_scenes_read_area_lights_and_refuse_keys_that_do_not_apply() {
    let dir = std::env::temp_dir().join(format!("shadowlab-soft-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = "[[mesh]]\ngenerator = \"plane\"\nscale = 4.0\n";
    let write = |name: &str, light: &str| {
        let p = dir.join(name);
        std::fs::write(&p, format!("[light]\n{light}\n{mesh}")).unwrap();
        shadowlab::scene::load(p.to_str().unwrap(), &Default::default())
    };
    let s = write(
        "rect.toml",
        "kind = \"rect\"\ncentre = [0, 3, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]",
    )
    .unwrap();
    assert!(matches!(s.area_light, Some(AreaLight::Rect { .. })));
    assert_eq!(s.light, Some(s.area_light.unwrap().punctual()));
    let s = write(
        "sized.toml",
        "kind = \"point\"\nposition = [0, 3, 0]\nsize = 0.5",
    )
    .unwrap();
    assert_eq!(
        s.area_light,
        Some(AreaLight::Sphere {
            centre: shadowlab::math::vec3(0.0, 3.0, 0.0),
            radius: 0.5
        })
    );
    for (name, light, needle) in [
        (
            "a.toml",
            "kind = \"disk\"\ncentre = [0, 3, 0]\nnormal = [0, -1, 0]",
            "radius",
        ),
        (
            "b.toml",
            "kind = \"sphere\"\ncentre = [0, 3, 0]\nradius = 1\nposition = [0, 1, 0]",
            "position",
        ),
        (
            "c.toml",
            "kind = \"point\"\nposition = [0, 3, 0]\nradius = 1",
            "radius",
        ),
        (
            "d.toml",
            "kind = \"point\"\nposition = [0, 3, 0]\nsize = -2",
            "size",
        ),
        (
            "e.toml",
            "kind = \"rect\"\ncentre = [0, 3, 0]\nedge_u = [1, 0, 0]\nedge_v = [2, 0, 0]",
            "parallel",
        ),
    ] {
        let e = write(name, light).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains("[light]"), "{name}: {e}");
    }
}

/// Mean absolute luminance error of technique `name` against the soft reference with
/// `n` light samples, over covered pixels, on `scene` seen by `camera` under its area light.
fn soft_error(scene: &Scene, camera: &Camera, name: &str, n: u32) -> f64 {
    let area = scene.area_light.expect("an area light");
    let light = scene.light.unwrap();
    let view = ViewSamples::render(scene, camera);
    let frame = Frame::new(scene, camera, &light, &view).with_area(Some(&area), n);
    let truth = soft(scene, camera, &view, n);
    let shadows = shadowlab::techniques::create(name)
        .unwrap()
        .render(&frame)
        .unwrap();
    shadowlab::compare::compare(&view, &shadows.visibility, &truth.visibility).mean_abs_error
}

/// `scene` (a built-in name) at `w × h` with its own camera.
fn builtin(name: &str, w: u32, h: u32) -> (Scene, Camera) {
    let scene = shadowlab::scene::load(name, &Default::default()).unwrap();
    let mut camera = scene.camera.unwrap();
    camera.width = w;
    camera.height = h;
    camera.fit_depth_range(&scene.bounds);
    (scene, camera)
}

#[test]
fn pcss_beats_fixed_kernel_pcf_under_area_lights() {
    // The bunny (a real mesh) under its sun given an angular diameter of 3°.
    let (mut bunny, camera) = builtin("bunny", 160, 120);
    bunny.area_light = Some(AreaLight::sized(&bunny.light.unwrap(), 3.0).unwrap());
    let scenes = [
        ("penumbra", builtin("penumbra", 160, 120)),
        ("room-soft", builtin("room-soft", 160, 120)),
        ("bunny", (bunny, camera)),
    ];
    for (name, (scene, camera)) in &scenes {
        let pcf = soft_error(scene, camera, "pcf", 256);
        let pcss = soft_error(scene, camera, "pcss", 256);
        eprintln!("{name}: pcf {pcf:.5}, pcss {pcss:.5}");
        assert!(pcss < pcf, "{name}: pcss {pcss} is not below pcf {pcf}");
    }
}

#[test]
fn soft_filtered_maps_follow_the_penumbra() {
    // Each soft variant is closer to the area-light reference than its hard-filtered base.
    let (scene, camera) = builtin("penumbra", 128, 96);
    for base in ["vsm", "csm"] {
        let hard = soft_error(&scene, &camera, base, 256);
        let soft = soft_error(&scene, &camera, &format!("{base}-soft"), 256);
        eprintln!("{base}: {hard:.5}, {base}-soft: {soft:.5}");
        assert!(soft < hard, "{base}-soft {soft} is not below {base} {hard}");
    }
}
