//! The built-in scenes: each generates, validates, frames something and shows shadows in the
//! ray-traced reference; parameters are checked; the papers' set-ups hold (constant total
//! area of the random triangles, 576 triangles per hair).

use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::scene::{self, builtin, Scene};
use shadowlab::techniques::Frame;
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;
use std::time::Instant;

/// Reduced image width for the coverage and shadow checks (same view, fewer pixels).
const TEST_WIDTH: u32 = 256;
/// Reduced image height (keeps the built-in 4:3 aspect).
const TEST_HEIGHT: u32 = 192;
/// A reference value at or above this in every channel counts as lit; below it in every
/// channel, as shadowed.
const LIT_THRESHOLD: f32 = 0.99;

fn params(kv: &[(&str, &str)]) -> BTreeMap<String, String> {
    kv.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// Small parameters so each scene renders quickly in the shadow check.
fn small_params(name: &str) -> BTreeMap<String, String> {
    match name {
        "random-triangles" => params(&[("count", "2000")]),
        "hairball" => params(&[("hairs", "200")]),
        "bumpy" => params(&[("resolution", "128")]),
        _ => BTreeMap::new(),
    }
}

struct Shares {
    covered: f64,
    lit: f64,
    shadowed: f64,
}

/// Renders `scene` at the test size and measures the share of covered pixels, and of
/// covered pixels the light reaches that the reference finds lit or shadowed.
fn shares(scene: &Scene) -> Shares {
    let mut camera = scene.camera.expect("scene has a camera");
    camera.width = TEST_WIDTH;
    camera.height = TEST_HEIGHT;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.expect("scene has a light");
    let view = ViewSamples::render(scene, &camera);
    let frame = Frame::new(scene, &camera, &light, &view);
    let reference = Reference::build(scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    let n = (TEST_WIDTH * TEST_HEIGHT) as usize;
    let (mut covered, mut lit, mut shadowed) = (0usize, 0usize, 0usize);
    for k in 0..n {
        if !view.covered(k) {
            continue;
        }
        covered += 1;
        if !frame.receiver_lit(k) {
            continue;
        }
        let v = reference.value[k];
        if v.min_element() >= LIT_THRESHOLD {
            lit += 1;
        } else if v.max_element() < LIT_THRESHOLD {
            shadowed += 1;
        }
    }
    Shares {
        covered: covered as f64 / n as f64,
        lit: lit as f64 / covered.max(1) as f64,
        shadowed: shadowed as f64 / covered.max(1) as f64,
    }
}

#[test]
fn every_scene_generates_frames_and_shows_shadows() {
    let list = builtin::list();
    assert_eq!(list[0].0, "bunny", "the default scene is listed first");
    for (name, description) in list {
        assert!(!description.is_empty(), "{name} has a description");
        let scene =
            scene::load(name, &small_params(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        scene.validate().unwrap();
        assert_eq!(scene.name, name);
        let camera = scene
            .camera
            .unwrap_or_else(|| panic!("{name} has no camera"));
        camera.validate().unwrap();
        assert_eq!(
            (camera.width, camera.height),
            (1024, 768),
            "{name} camera size"
        );
        scene
            .light
            .unwrap_or_else(|| panic!("{name} has no light"))
            .validate()
            .unwrap();
        let s = shares(&scene);
        eprintln!(
            "{name:18} {:>9} triangles  covered {:5.1}%  lit {:5.1}%  shadowed {:5.1}%",
            scene.len(),
            s.covered * 100.0,
            s.lit * 100.0,
            s.shadowed * 100.0
        );
        // A minified scene is small on screen by design: fence-far sees its bounded yard
        // from five times the fence scene's distance.
        let least = if name == "fence-far" { 0.05 } else { 0.20 };
        assert!(
            s.covered > least,
            "{name}: the camera sees only {:.1}% of the image",
            s.covered * 100.0
        );
        assert!(
            s.lit > 0.01,
            "{name}: only {:.2}% of covered pixels are lit",
            s.lit * 100.0
        );
        assert!(
            s.shadowed > 0.01,
            "{name}: only {:.2}% of covered pixels are shadowed",
            s.shadowed * 100.0
        );
    }
}

#[test]
fn generation_is_deterministic_and_seeded() {
    let a = scene::load("random-triangles", &params(&[("count", "500")])).unwrap();
    let b = scene::load("random-triangles", &params(&[("count", "500")])).unwrap();
    let c = scene::load(
        "random-triangles",
        &params(&[("count", "500"), ("seed", "7")]),
    )
    .unwrap();
    assert_eq!(a.v0, b.v0);
    assert_eq!(a.v2, b.v2);
    assert_ne!(a.v0, c.v0, "another seed gives other triangles");
}

/// Total area of the triangles whose material is called `material`, in f64.
fn area_of(scene: &Scene, material: &str) -> f64 {
    (0..scene.len())
        .filter(|&i| scene.material_of(i).name == material)
        .map(|i| {
            let [a, b, c] = scene.triangle(i).map(|p| p.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

#[test]
fn random_triangles_keep_total_area_constant() {
    let mut areas = Vec::new();
    for count in ["1", "10", "1000", "100000"] {
        let s = scene::load("random-triangles", &params(&[("count", count)])).unwrap();
        assert_eq!(
            s.len(),
            count.parse::<usize>().unwrap() + 2,
            "count triangles plus the ground"
        );
        let low = (0..s.len())
            .flat_map(|i| s.triangle(i))
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        assert!(
            low >= -1e-6,
            "nothing below the ground (lowest vertex {low})"
        );
        areas.push((count, area_of(&s, "triangles")));
    }
    let first = areas[0].1;
    for (count, a) in &areas {
        assert!(
            (a / first - 1.0).abs() < 0.01,
            "count {count}: total area {a} vs {first}"
        );
    }
    assert!(
        (first - builtin::RANDOM_TRIANGLES_TOTAL_AREA as f64).abs() < 0.01 * first,
        "total area {first} is the named constant"
    );
}

#[test]
fn a_million_random_triangles_generate() {
    // Its speed is `bench`'s business; this checks the count and that every vertex is
    // finite and inside the scene's bounds.
    let p = params(&[("count", "1000000")]);
    let t = Instant::now();
    let s = builtin::generate("random-triangles", &p).unwrap();
    eprintln!(
        "random-triangles count=1000000: {} triangles in {:.3} s",
        s.len(),
        t.elapsed().as_secs_f64()
    );
    assert_eq!(s.len(), 1_000_002);
    s.validate().unwrap();
    for v in s.v0.iter().chain(&s.v1).chain(&s.v2) {
        assert!(v.is_finite() && s.bounds.min.cmple(*v).all() && v.cmple(s.bounds.max).all());
    }
}

#[test]
fn unknown_scene_parameter_is_an_error_naming_it() {
    for name in ["bunny", "random-triangles", "chessboard"] {
        let e = scene::load(name, &params(&[("bogus-key", "1")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bogus-key"), "{name}: {e}");
    }
    let e = scene::load("random-triangles", &params(&[("colour", "red")]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("colour") && e.contains("count") && e.contains("seed"),
        "{e}"
    );
}

#[test]
fn out_of_range_and_malformed_values_are_errors() {
    for (k, v) in [
        ("count", "0"),
        ("count", "100000000"),
        ("count", "ten"),
        ("count", "-5"),
    ] {
        let e = scene::load("random-triangles", &params(&[(k, v)]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("count"), "{k}={v}: {e}");
    }
    let e = scene::load("bunny", &params(&[("closeup", "maybe")]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("closeup"), "{e}");
    let e = scene::load("no-such-scene", &BTreeMap::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no-such-scene") && e.contains("bunny"), "{e}");
}

#[test]
fn bunny_closeup_looks_at_a_shadow_edge() {
    let base = scene::load("bunny", &BTreeMap::new()).unwrap();
    let close = scene::load("bunny", &params(&[("closeup", "true")])).unwrap();
    let variant = scene::load("bunny-closeup", &BTreeMap::new()).unwrap();
    assert_eq!(close.camera, variant.camera);
    let (cb, cc) = (base.camera.unwrap(), close.camera.unwrap());
    assert!((cc.eye - cc.target).length() < 0.5 * (cb.eye - cb.target).length());
    // The view looks at the ground only, across the boundary: part lit, part shadowed.
    let s = shares(&close);
    assert!(
        s.covered > 0.99,
        "the close-up sees {:.3} of the image covered",
        s.covered
    );
    assert!(
        s.lit > 0.02 && s.shadowed > 0.02,
        "lit {:.3} shadowed {:.3}",
        s.lit,
        s.shadowed
    );
}

#[test]
fn chessboard_keeps_its_pieces_and_materials() {
    let s = scene::load("chessboard", &BTreeMap::new()).unwrap();
    assert_eq!(s.len(), 125_810 + 2, "the chess set and a table top");
    assert!(s.materials.iter().any(|m| m.name == "white"));
    assert!(matches!(
        s.light,
        Some(shadowlab::light::Light::Spot { .. })
    ));
    let size = s.bounds.max - s.bounds.min;
    assert!(
        size.max_element() > 30.0 && size.y < 10.0,
        "centimetres, Y up: {size:?}"
    );
}

#[test]
fn every_scene_rejects_an_unknown_parameter_by_name() {
    for (name, _) in builtin::list() {
        let e = scene::load(name, &params(&[("no-such-key", "1")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no-such-key") && e.contains(name), "{name}: {e}");
    }
}

#[test]
fn hairball_has_576_triangles_per_hair() {
    assert_eq!(builtin::TRIANGLES_PER_HAIR, 576);
    let s = scene::load("hairball", &BTreeMap::new()).unwrap();
    assert_eq!(
        s.len(),
        5000 * 576 + 2,
        "5000 hairs and a two-triangle ground"
    );
    let hair = s.materials.iter().find(|m| m.name == "hair").unwrap();
    assert_eq!(
        hair.transmittance,
        shadowlab::math::Vec3::splat(0.9),
        "10% opacity"
    );
    assert!(s.has_transparency());
    let small = scene::load("hairball", &params(&[("hairs", "10")])).unwrap();
    assert_eq!(small.len(), 10 * 576 + 2);
    // The same hairs whatever the count: the first ten of the default ball.
    assert_eq!(small.v0[..5760], s.v0[..5760]);
    for bad in ["0", "1000000", "many"] {
        assert!(
            scene::load("hairball", &params(&[("hairs", bad)])).is_err(),
            "hairs={bad}"
        );
    }
}

#[test]
fn walkthrough_and_pull_back_paths() {
    use shadowlab::light::Light;
    let room = scene::load("room", &BTreeMap::new()).unwrap();
    match room.light.unwrap() {
        Light::Spot {
            position, fov_deg, ..
        } => {
            assert_eq!(fov_deg, builtin::ROOM_LIGHT_FOV_DEG);
            assert!(
                position.y > room.bounds.max.y - 0.1,
                "the light hangs from the ceiling"
            );
        }
        other => panic!("room light {other:?}"),
    }
    let path = room.camera_path.expect("room has a walkthrough");
    assert!(path.keys.len() >= 4);
    for k in &path.keys {
        assert!(
            room.bounds.min.cmplt(k.eye).all() && k.eye.cmplt(room.bounds.max).all(),
            "inside the room"
        );
    }
    let point = scene::load("room", &params(&[("light", "point")])).unwrap();
    assert!(matches!(point.light, Some(Light::Point { .. })));
    assert!(scene::load("room", &params(&[("light", "laser")])).is_err());

    let near = scene::load("fence", &BTreeMap::new()).unwrap();
    let far = scene::load("fence-far", &BTreeMap::new()).unwrap();
    let dist = |s: &Scene| {
        let c = s.camera.unwrap();
        (c.eye - c.target).length()
    };
    assert!(dist(&far) > 4.0 * dist(&near), "fence-far is far");
    let keys = far.camera_path.unwrap().keys;
    for w in keys.windows(2) {
        assert!(
            (w[1].eye - w[1].target).length() > (w[0].eye - w[0].target).length(),
            "pulls away"
        );
    }
    let twice = scene::load("fence", &params(&[("distance", "2")])).unwrap();
    assert!((dist(&twice) / dist(&near) - 2.0).abs() < 1e-3);
}

#[test]
fn street_light_is_perpendicular_to_the_view() {
    let s = scene::load("street", &BTreeMap::new()).unwrap();
    let (camera, light) = (s.camera.unwrap(), s.light.unwrap());
    let shadowlab::light::Light::Directional { to_light } = light else {
        panic!("street light {light:?}");
    };
    assert!(
        to_light.dot(camera.forward()).abs() < 0.02,
        "light {to_light} view {}",
        camera.forward()
    );
    assert!(s.bounds.max.z - s.bounds.min.z > 1000.0, "a long street");
}
