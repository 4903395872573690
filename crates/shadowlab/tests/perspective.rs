//! Perspective shadow maps (`psm`): every light case of the paper's Sections 3.1–3.2 gives
//! the ray-traced answer away from shadow edges, casters outside the view frustum (above
//! it, and behind the viewer) still cast, and on the paper's scenes with the light
//! perpendicular to the view `psm` halves the mismatch of a uniform map of the same size.

use shadowlab::camera::Camera;
use shadowlab::compare::{compare, luminance, MISMATCH_THRESHOLD};
use shadowlab::frame::Dumped;
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{self, Material, Scene};
use shadowlab::techniques::perspective::{Perspective, PostLight};
use shadowlab::techniques::{self, Frame, Shadows, Visibility};
use shadowlab::view::ViewSamples;

/// Pixels within this many pixels (Chebyshev distance) of a reference shadow edge are left
/// out of the "away from edges" mismatch: at an edge a map-based answer may flip by up to
/// a texel's footprint.
const EDGE_RADIUS: i32 = 3;
/// Largest mismatch away from shadow edges the spec allows for each light case.
const MAX_MISMATCH_AWAY_FROM_EDGES: f64 = 0.01;
/// Shadow map side for the light-case scenes (400×300 images).
const CASE_RESOLUTION: &str = "1024";
/// Smallest share of light-reachable pixels the reference must find shadowed for a case
/// scene to test anything.
const MIN_SHADOWED_SHARE: f64 = 0.03;

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

/// A 40 × 40 ground (8 × 8 quads, so several of its triangles cross the camera plane) with
/// boxes, a thin pole and a floating plate on it; nothing is taller than 3.
fn ground_scene() -> Scene {
    let mut s = Scene::new("psm-cases");
    let g = s.add_material(Material::opaque("ground", Vec3::splat(0.7)));
    let m = s.add_material(Material::opaque("boxes", vec3(0.7, 0.5, 0.4)));
    let n = 8;
    let step = 40.0 / n as f32;
    for j in 0..n {
        for i in 0..n {
            let c = vec3(-20.0 + i as f32 * step, 0.0, -20.0 + j as f32 * step);
            add_quad(&mut s, c, vec3(0.0, 0.0, step), vec3(step, 0.0, 0.0), g);
        }
    }
    add_box(&mut s, vec3(-3.0, 0.0, -2.0), vec3(-1.5, 2.5, -0.5), m);
    add_box(&mut s, vec3(1.0, 0.0, -4.0), vec3(2.2, 1.5, -2.8), m);
    add_box(&mut s, vec3(0.0, 0.0, 2.0), vec3(1.0, 1.0, 3.0), m);
    add_box(&mut s, vec3(3.5, 0.0, 1.0), vec3(3.7, 3.0, 1.2), m);
    add_box(&mut s, vec3(-1.0, 1.8, 0.5), vec3(0.5, 1.9, 2.0), m);
    // A low wall across the back and a bench-like slab at the front.
    add_box(&mut s, vec3(-7.0, 0.0, -7.5), vec3(6.0, 2.0, -7.0), m);
    add_box(&mut s, vec3(-5.0, 1.2, 3.5), vec3(-2.0, 1.4, 5.0), m);
    add_box(&mut s, vec3(4.0, 0.0, -1.0), vec3(5.5, 2.2, 0.5), m);
    s
}

fn camera(eye: Vec3, target: Vec3, scene: &Scene) -> Camera {
    let mut c = Camera::look_at(eye, target, 45.0, 400, 300);
    c.fit_depth_range(&scene.bounds);
    c
}

/// What one frame gave.
struct Outcome {
    shadows: Shadows,
    /// Mismatch over pixels away from reference shadow edges.
    away: f64,
    /// Plain mismatch over all covered pixels.
    plain: f64,
    /// Share of light-reachable pixels the reference finds shadowed.
    shadowed: f64,
    /// Pixels counted in `away`.
    counted: usize,
}

/// Renders `technique` and the reference on one frame.
fn run(
    scene: &Scene,
    cam: &Camera,
    light: &Light,
    technique: &str,
    params: &[(&str, &str)],
) -> Outcome {
    let view = ViewSamples::render(scene, cam);
    let frame = Frame::new(scene, cam, light, &view);
    let reference = Reference::build(scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    let mut t = techniques::create(technique).unwrap();
    for (k, v) in params {
        t.set_param(k, v).unwrap();
    }
    let shadows = t.render(&frame).unwrap();
    let plain = compare(&view, &shadows.visibility, &reference).mismatch_rate;
    let (away, counted) =
        mismatch_away_from_edges(&view, &shadows.visibility, &reference, EDGE_RADIUS);
    let reachable: Vec<usize> = (0..view.triangle.len())
        .filter(|&k| frame.receiver_lit(k))
        .collect();
    let dark = reachable
        .iter()
        .filter(|&&k| luminance(reference.value[k]) < MISMATCH_THRESHOLD)
        .count();
    Outcome {
        shadows,
        away,
        plain,
        shadowed: dark as f64 / reachable.len().max(1) as f64,
        counted,
    }
}

/// Mismatch over covered pixels farther than `radius` pixels from every covered pixel whose
/// reference answer (lit or shadowed) differs from theirs.
fn mismatch_away_from_edges(
    view: &ViewSamples,
    vis: &Visibility,
    reference: &Visibility,
    radius: i32,
) -> (f64, usize) {
    let (w, h) = (view.width as i32, view.height as i32);
    let lit = |k: usize| luminance(reference.value[k]) >= MISMATCH_THRESHOLD;
    let (mut counted, mut wrong) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            if !view.covered(k) {
                continue;
            }
            let mut edge = false;
            'scan: for dy in -radius..=radius {
                for dx in -radius..=radius {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx < 0 || yy < 0 || xx >= w || yy >= h {
                        continue;
                    }
                    let j = (yy * w + xx) as usize;
                    if view.covered(j) && lit(j) != lit(k) {
                        edge = true;
                        break 'scan;
                    }
                }
            }
            if edge {
                continue;
            }
            counted += 1;
            let d = (luminance(vis.value[k]) - luminance(reference.value[k])).abs();
            if d >= MISMATCH_THRESHOLD {
                wrong += 1;
            }
        }
    }
    (wrong as f64 / counted.max(1) as f64, counted)
}

fn counter(s: &Shadows, name: &str) -> f64 {
    *s.stats
        .counters
        .get(name)
        .unwrap_or_else(|| panic!("psm reports no counter {name}"))
}

fn post_light(s: &Shadows) -> PostLight {
    match (
        counter(s, "inverted") as u8,
        counter(s, "post_directional") as u8,
    ) {
        (0, 0) => PostLight::Point,
        (1, 0) => PostLight::Inverted,
        (0, 1) => PostLight::Directional,
        other => panic!("inconsistent light case counters {other:?}"),
    }
}

/// Runs one light case and checks its post-perspective case and its answer.
fn check_case(
    name: &str,
    scene: &Scene,
    cam: &Camera,
    light: Light,
    expected: PostLight,
) -> Outcome {
    let o = run(
        scene,
        cam,
        &light,
        "psm",
        &[("resolution", CASE_RESOLUTION)],
    );
    eprintln!(
        "{name}: case {:?}, mismatch {:.4}% plain, {:.4}% away from edges ({} px), reference shadowed {:.1}%, shift {:.3}",
        post_light(&o.shadows),
        o.plain * 100.0,
        o.away * 100.0,
        o.counted,
        o.shadowed * 100.0,
        counter(&o.shadows, "virtual_shift")
    );
    assert_eq!(
        post_light(&o.shadows),
        expected,
        "{name}: wrong post-perspective light case"
    );
    assert!(
        o.shadowed >= MIN_SHADOWED_SHARE,
        "{name}: the scene shows too little shadow to test ({:.3})",
        o.shadowed
    );
    assert!(
        o.counted > 20_000,
        "{name}: too few pixels away from edges ({})",
        o.counted
    );
    assert!(
        o.away < MAX_MISMATCH_AWAY_FROM_EDGES,
        "{name}: mismatch away from shadow edges {:.4}% (plain {:.4}%)",
        o.away * 100.0,
        o.plain * 100.0
    );
    o
}

fn ground_camera(scene: &Scene) -> Camera {
    camera(vec3(0.0, 6.0, 14.0), vec3(0.0, 0.0, 0.0), scene)
}

#[test]
fn directional_light_from_the_front_is_a_point_light() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let to_light = vec3(0.3, 1.0, -0.9).normalize();
    assert!(
        to_light.dot(cam.forward()) > 0.1,
        "the light must face the viewer"
    );
    check_case(
        "directional front",
        &s,
        &cam,
        Light::Directional { to_light },
        PostLight::Point,
    );
}

#[test]
fn directional_light_from_behind_is_an_inverted_point_light() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let to_light = vec3(0.6, 1.0, 0.9).normalize();
    assert!(
        to_light.dot(cam.forward()) < -0.1,
        "the light must be behind the viewer"
    );
    check_case(
        "directional behind",
        &s,
        &cam,
        Light::Directional { to_light },
        PostLight::Inverted,
    );
}

#[test]
fn directional_light_parallel_to_the_image_plane_stays_directional() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let (r, u, _) = cam.basis();
    let to_light = (u + r * 1.2).normalize();
    check_case(
        "directional parallel",
        &s,
        &cam,
        Light::Directional { to_light },
        PostLight::Directional,
    );
}

#[test]
fn point_light_in_front_of_the_viewer_stays_a_point_light() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let position = vec3(2.0, 9.0, -10.0);
    assert!((position - cam.eye).dot(cam.forward()) > 0.0);
    check_case(
        "point front",
        &s,
        &cam,
        Light::Point { position },
        PostLight::Point,
    );
}

#[test]
fn point_light_behind_the_viewer_is_inverted() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let position = vec3(-8.0, 6.0, 40.0);
    assert!((position - cam.eye).dot(cam.forward()) < 0.0);
    check_case(
        "point behind",
        &s,
        &cam,
        Light::Point { position },
        PostLight::Inverted,
    );
}

/// A wall facing the camera and a floating plate in front of it: the plate's front face is
/// both the nearest visible surface and the front of the scene's box, so the body needs no
/// virtual shift and a light on the camera plane stays on it.
fn wall_scene() -> Scene {
    let mut s = Scene::new("psm-wall");
    let g = s.add_material(Material::opaque("wall", Vec3::splat(0.7)));
    let m = s.add_material(Material::opaque("plate", vec3(0.7, 0.5, 0.4)));
    add_quad(
        &mut s,
        vec3(-12.0, -9.0, 0.0),
        vec3(24.0, 0.0, 0.0),
        vec3(0.0, 18.0, 0.0),
        g,
    );
    add_box(&mut s, vec3(-2.0, -1.0, 3.0), vec3(1.0, 1.5, 3.3), m);
    add_box(&mut s, vec3(-6.0, -5.0, 1.0), vec3(-5.0, 4.0, 1.5), m);
    s
}

#[test]
fn point_light_on_the_camera_plane_becomes_directional() {
    let s = wall_scene();
    let cam = camera(vec3(0.0, 0.0, 14.0), vec3(0.0, 0.0, 0.0), &s);
    // Off to the side and above, on the plane z = 14 through the eye.
    let light = Light::Point {
        position: vec3(5.0, 4.0, 14.0),
    };
    let o = check_case(
        "point on camera plane",
        &s,
        &cam,
        light,
        PostLight::Directional,
    );
    assert_eq!(counter(&o.shadows, "virtual_shift"), 0.0);
}

#[test]
fn spot_light_agrees_with_the_reference() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let light = Light::Spot {
        position: vec3(-4.0, 9.0, 4.0),
        target: vec3(0.0, 0.0, -1.0),
        fov_deg: 70.0,
    };
    check_case("spot", &s, &cam, light, PostLight::Point);
}

#[test]
fn caster_above_the_view_frustum_casts_its_shadow() {
    let mut s = ground_scene();
    let m = s.add_material(Material::opaque("roof", Vec3::splat(0.5)));
    let first = s.len();
    add_box(&mut s, vec3(-2.0, 7.0, 2.0), vec3(2.0, 7.2, 6.0), m);
    let cam = camera(vec3(0.0, 2.0, 12.0), vec3(0.0, 1.0, 0.0), &s);
    let light = Light::Directional {
        to_light: vec3(0.1, 1.0, -0.3).normalize(),
    };
    let view = ViewSamples::render(&s, &cam);
    assert!(
        view.triangle
            .iter()
            .all(|&t| (t as usize) < first || t == u32::MAX),
        "the roof must be outside the view"
    );
    let o = check_case("caster above the view", &s, &cam, light, PostLight::Point);
    assert!(
        o.shadowed > 0.05,
        "the roof's shadow must be on screen ({:.3})",
        o.shadowed
    );
}

#[test]
fn caster_behind_the_viewer_casts_its_shadow_through_the_virtual_shift() {
    let mut s = ground_scene();
    let m = s.add_material(Material::opaque("wall", Vec3::splat(0.5)));
    let first = s.len();
    add_box(&mut s, vec3(-1.5, 0.0, 12.0), vec3(1.5, 6.0, 12.3), m);
    let cam = camera(vec3(0.0, 3.0, 8.0), vec3(0.0, 0.0, -4.0), &s);
    let light = Light::Directional {
        to_light: vec3(0.0, 0.6, 1.0).normalize(),
    };
    let view = ViewSamples::render(&s, &cam);
    assert!(
        view.triangle
            .iter()
            .all(|&t| (t as usize) < first || t == u32::MAX),
        "the wall must be behind the viewer"
    );
    let o = check_case(
        "caster behind the viewer",
        &s,
        &cam,
        light,
        PostLight::Inverted,
    );
    assert!(
        counter(&o.shadows, "virtual_shift") > 0.0,
        "the body reaches behind the viewer"
    );
    assert!(
        o.shadowed > 0.05,
        "the wall's shadow must be on screen ({:.3})",
        o.shadowed
    );
}

#[test]
fn body_holds_the_receivers_and_lies_in_front_of_the_virtual_camera() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let light = Light::Directional {
        to_light: vec3(0.3, 1.0, 0.9).normalize(),
    };
    let view = ViewSamples::render(&s, &cam);
    let frame = Frame::new(&s, &cam, &light, &view);
    let post = Perspective::default()
        .post_space(&frame)
        .unwrap()
        .expect("receivers are lit");
    // Every vertex of the body has a finite post-perspective image (w > 0) and lies in
    // the scene's bounds.
    let pad = s.bounds.diagonal() * 1e-3;
    for v in &post.body {
        let h = post.post_from_world * v.as_vec3().extend(1.0);
        assert!(h.w > 0.0, "body vertex {v} behind the virtual camera");
        let p = v.as_vec3();
        assert!(
            p.cmpge(s.bounds.min - pad).all() && p.cmple(s.bounds.max + pad).all(),
            "{p} outside the scene"
        );
    }
    // Every lit receiver lies inside the body's bounding box.
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for v in &post.body {
        lo = lo.min(v.as_vec3());
        hi = hi.max(v.as_vec3());
    }
    for k in 0..view.triangle.len() {
        if frame.receiver_lit(k) {
            let p = view.position[k];
            assert!(
                p.cmpge(lo - pad).all() && p.cmple(hi + pad).all(),
                "receiver {p} outside the body"
            );
        }
    }
}

#[test]
fn result_does_not_depend_on_thread_count() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let light = Light::Point {
        position: vec3(-3.0, 10.0, 22.0),
    };
    let view = ViewSamples::render(&s, &cam);
    let frame = Frame::new(&s, &cam, &light, &view);
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut t = techniques::create("psm").unwrap();
            t.set_param("resolution", "512").unwrap();
            t.render(&frame).unwrap().visibility
        })
    };
    assert_eq!(render(1), render(3));
}

#[test]
fn parameters_are_checked() {
    let mut t = techniques::create("psm").unwrap();
    let e = t.set_param("kernel", "3").unwrap_err().to_string();
    assert!(e.contains("resolution") && e.contains("slope-bias"), "{e}");
    assert!(t.set_param("resolution", "0").is_err());
    assert!(t.set_param("bias", "-1").is_err());
    assert!(t.set_param("resolution", "abc").is_err());
    t.set_param("bias", "0.75").unwrap();
    assert_eq!(t.params()["bias"], serde_json::json!(0.75));
}

#[test]
fn dump_writes_the_post_perspective_map() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    let light = Light::Directional {
        to_light: vec3(0.3, 1.0, 0.9).normalize(),
    };
    let view = ViewSamples::render(&s, &cam);
    let sink = shadowlab::frame::DumpMemory::default();
    let frame = Frame::new(&s, &cam, &light, &view).with_dump(&sink);
    let mut t = techniques::create("psm").unwrap();
    t.set_param("resolution", "256").unwrap();
    t.render(&frame).unwrap();
    let dumped = sink.take();
    let find = |name: &str| {
        dumped
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, d)| d.clone())
            .unwrap_or_else(|| {
                panic!(
                    "no {name} among {:?}",
                    dumped.iter().map(|d| &d.0).collect::<Vec<_>>()
                )
            })
    };
    let Dumped::Image(img) = find("psm-post-map0.png") else {
        panic!("psm-post-map0.png is not a colour image")
    };
    assert_eq!((img.width(), img.height()), (256, 256));
    let Dumped::Text(text) = find("psm-post-space.json") else {
        panic!("psm-post-space.json is not a text")
    };
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["light"], "inverted");
}

/// `psm` against `sm` at 1024² on a paper scene with a directional light perpendicular to
/// the view direction.
fn halves_the_mismatch_of_sm(name: &str, to_light: impl Fn(&Scene, &Camera) -> Vec3) {
    let s = scene::load(name, &Default::default()).unwrap();
    let mut cam = s.camera.unwrap();
    cam.fit_depth_range(&s.bounds);
    let to_light = to_light(&s, &cam).normalize();
    assert!(
        to_light.dot(cam.forward()).abs() < 2e-3,
        "light not perpendicular to the view"
    );
    let light = Light::Directional { to_light };
    let view = ViewSamples::render(&s, &cam);
    let frame = Frame::new(&s, &cam, &light, &view);
    let reference = Reference::build(&s).visibility(&frame, &[vec2(0.5, 0.5)]);
    let mismatch = |t: &str| {
        let mut t = techniques::create(t).unwrap();
        t.set_param("resolution", "1024").unwrap();
        compare(&view, &t.render(&frame).unwrap().visibility, &reference).mismatch_rate
    };
    let (psm, sm) = (mismatch("psm"), mismatch("sm"));
    eprintln!(
        "{name}: psm {:.4}% sm {:.4}% (ratio {:.3})",
        psm * 100.0,
        sm * 100.0,
        psm / sm
    );
    assert!(sm > 0.0);
    assert!(
        psm <= 0.5 * sm,
        "{name}: psm {psm} is not at most half of sm {sm}"
    );
}

#[test]
fn chessboard_psm_halves_sm_mismatch_with_light_perpendicular_to_view() {
    // The chess set's own light is a spot; this is the paper's ideal case (Fig. 3): the
    // direction in the plane of the view direction and the up axis, perpendicular to the view.
    halves_the_mismatch_of_sm("chessboard", |_, cam| {
        let f = cam.forward();
        Vec3::Y - f * Vec3::Y.dot(f)
    });
}

#[test]
fn street_psm_halves_sm_mismatch_with_light_perpendicular_to_view() {
    // The street's own sun comes from the right, perpendicular to the view down the street.
    halves_the_mismatch_of_sm("street", |s, _| match s.light {
        Some(Light::Directional { to_light }) => to_light,
        other => panic!("street has no sun: {other:?}"),
    });
}

#[test]
fn point_light_inside_the_view_gets_a_cube_of_post_perspective_maps() {
    let s = ground_scene();
    let cam = ground_camera(&s);
    // Low over the ground in the middle of the view: from post-perspective space it sees
    // the body over more than a single frustum can hold.
    let light = Light::Point {
        position: vec3(-0.5, 3.5, -0.2),
    };
    let o = check_case("point inside the view", &s, &cam, light, PostLight::Point);
    assert!(counter(&o.shadows, "maps") > 1.0, "expected a cube of maps");
}

#[test]
fn directional_light_almost_parallel_to_the_image_plane_keeps_precision() {
    // A light a hair off the image plane puts the post-perspective light very far away:
    // the map must stay exact in f32 (rows composed in f64 with small constants).
    let s = ground_scene();
    let cam = ground_camera(&s);
    let (r, u, f) = cam.basis();
    for tilt in [1e-3f32, -1e-4, 1e-5, -1e-6, 1e-7, -3e-8] {
        let to_light = (u + r * 1.2 + f * tilt).normalize();
        let o = run(
            &s,
            &cam,
            &Light::Directional { to_light },
            "psm",
            &[("resolution", CASE_RESOLUTION)],
        );
        eprintln!(
            "tilt {tilt}: case {:?}, mismatch {:.4}% plain, {:.4}% away from edges",
            post_light(&o.shadows),
            o.plain * 100.0,
            o.away * 100.0
        );
        assert!(o.shadowed >= MIN_SHADOWED_SHARE);
        assert!(
            o.away < MAX_MISMATCH_AWAY_FROM_EDGES,
            "tilt {tilt}: {:.4}%",
            o.away * 100.0
        );
    }
}
