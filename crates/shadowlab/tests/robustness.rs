//! Robustness: geometry that breaks naive code, limits refused with clear errors before
//! anything large is allocated, and bit-for-bit determinism across runs and thread counts.
//!
//! Every valid case runs every technique in [`techniques::ALL`] and checks its output for
//! shape, NaN and range, for the shared illumination test (0 wherever the light cannot
//! reach the viewed side) and for agreement with the ray-traced reference.

mod support;

use shadowlab::camera::{Camera, MAX_IMAGE_SIDE};
use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Vec3};
use shadowlab::raster::MAX_RASTER_SIDE;
use shadowlab::reference::Reference;
use shadowlab::scene::{self, Material, Scene, MAX_TRIANGLES};
use shadowlab::techniques::{self, Frame, Visibility};
use shadowlab::view::ViewSamples;
use shadowlab::Error;
use std::collections::BTreeMap;
use support::{assert_same_visibility, data};

/// Largest mismatch against the reference accepted from the map-based techniques on these
/// small frames: a few pixels along shadow edges at 160×120 are about 1%; a technique that
/// mishandles the case flips whole regions, tens of percent.
const MAX_MISMATCH: f64 = 0.03;

/// Largest mismatch accepted from the filtered techniques (`csm`, `vsm`): they approximate
/// the depth test and leak light where a receiver lies close behind its caster (the
/// convolution series' ringing, variance light bleeding), a band along every contact.
const MAX_FILTERED_MISMATCH: f64 = 0.1;

/// Techniques whose depth test is filtered, judged against [`MAX_FILTERED_MISMATCH`].
const FILTERED: &[&str] = &["csm", "vsm"];

/// Techniques that compute exact visibility at the pixel centre: no mismatch at all.
const EXACT: &[&str] = &["raytrace", "afsm"];

/// Image size of the frames tested here.
const W: u32 = 160;
/// Image height of the frames tested here.
const H: u32 = 120;

/// A technique with the settings used here: `asm` without its wall-clock time budget, so
/// its result depends on the frame alone.
fn technique(name: &str) -> Box<dyn techniques::ShadowTechnique> {
    let mut t = techniques::create(name).unwrap();
    if name == "asm" {
        t.set_param("time-budget-ms", "none").unwrap();
    }
    t
}

fn quad(s: &mut Scene, c: Vec3, a: Vec3, b: Vec3, m: u32) {
    let (p0, p1, p2, p3) = (c - a - b, c + a - b, c + a + b, c - a + b);
    s.push([p0, p1, p2], m);
    s.push([p0, p2, p3], m);
}

/// The six faces of the box `lo..hi`.
fn cuboid(s: &mut Scene, lo: Vec3, hi: Vec3, m: u32) {
    let c = (lo + hi) * 0.5;
    let h = (hi - lo) * 0.5;
    let (x, y, z) = (
        vec3(h.x, 0.0, 0.0),
        vec3(0.0, h.y, 0.0),
        vec3(0.0, 0.0, h.z),
    );
    for (d, a, b) in [(x, y, z), (y, z, x), (z, x, y)] {
        quad(s, c + d, a, b, m);
        quad(s, c - d, b, a, m);
    }
}

/// A ground of half-size `ground`, a block and a tilted plate floating over it, all times
/// `scale`.
fn blocks(scale: f32, ground: f32) -> Scene {
    let mut s = Scene::new("blocks");
    let m = s.add_material(Material::default());
    quad(
        &mut s,
        Vec3::ZERO,
        vec3(ground, 0.0, 0.0),
        vec3(0.0, 0.0, ground),
        m,
    );
    cuboid(&mut s, vec3(-0.8, 0.5, -0.6), vec3(0.2, 1.3, 0.4), m);
    s.push(
        [
            vec3(0.6, 0.8, 0.2),
            vec3(1.6, 1.1, 0.4),
            vec3(1.0, 0.9, 1.4),
        ],
        m,
    );
    for v in [&mut s.v0, &mut s.v1, &mut s.v2] {
        for p in v.iter_mut() {
            *p *= scale;
        }
    }
    s.recompute_bounds();
    s.validate().unwrap();
    s
}

fn camera(eye: Vec3, target: Vec3, scene: &Scene) -> Camera {
    let mut c = Camera::look_at(eye, target, 50.0, W, H);
    c.fit_depth_range(&scene.bounds);
    c.validate().unwrap();
    c
}

fn sun() -> Light {
    Light::Directional {
        to_light: vec3(-0.4, 1.0, 0.3).normalize(),
    }
}

/// Renders `case` with every technique, checks every output and returns the reference
/// and each technique's visibility. Panics naming the case and technique on any failure.
fn run_all(
    case: &str,
    scene: &Scene,
    cam: &Camera,
    light: &Light,
) -> (ViewSamples, Visibility, Vec<(String, Visibility)>) {
    let view = ViewSamples::render(scene, cam);
    let frame = Frame::new(scene, cam, light, &view);
    let reference = Reference::build(scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    check_output(case, "reference", &frame, &reference);
    let mut out = Vec::new();
    let mut line = format!(
        "{case}: covered {}, lit {:.3}:",
        view.covered_count(),
        lit_share(&view, &reference)
    );
    for name in techniques::ALL {
        let vis = technique(name)
            .render(&frame)
            .unwrap_or_else(|e| panic!("{case}: {name} failed: {e}"))
            .visibility;
        check_output(case, name, &frame, &vis);
        let m = compare(&view, &vis, &reference);
        let limit = if EXACT.contains(name) {
            0.0
        } else if FILTERED.contains(name) {
            MAX_FILTERED_MISMATCH
        } else {
            MAX_MISMATCH
        };
        if m.mismatch_rate > limit {
            let first: Vec<String> = (0..vis.value.len())
                .filter(|&k| {
                    view.covered(k) && (vis.value[k].x - reference.value[k].x).abs() >= 0.5
                })
                .take(3)
                .map(|k| {
                    let (x, y) = (k as u32 % view.width, k as u32 / view.width);
                    format!(
                        "({x},{y}) triangle {} {} vs reference {}",
                        view.triangle[k], vis.value[k].x, reference.value[k].x
                    )
                })
                .collect();
            fail(format!(
                "{case}: {name} mismatches {:.4} of {} covered pixels (limit {limit}), e.g. {}",
                m.mismatch_rate,
                m.covered_pixels,
                first.join(", ")
            ));
        }
        line.push_str(&format!(" {name} {:.4}", m.mismatch_rate));
        out.push((name.to_string(), vis));
    }
    eprintln!("{line}");
    (view, reference, out)
}

thread_local! {
    static FAILURES: std::cell::RefCell<Vec<String>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Records a failed expectation, so one test reports every case and technique at fault.
fn fail(msg: String) {
    FAILURES.with(|f| f.borrow_mut().push(msg));
}

/// Fails the test with every recorded failure.
fn finish() {
    let all = FAILURES.with(|f| std::mem::take(&mut *f.borrow_mut()));
    assert!(
        all.is_empty(),
        "{} failure(s):\n{}",
        all.len(),
        all.join("\n")
    );
}

/// Shape, finiteness and range of one output; lit (1) where nothing is covered and dark
/// (0) where the light cannot reach the viewed side.
fn check_output(case: &str, name: &str, frame: &Frame, vis: &Visibility) {
    let view = frame.view;
    assert_eq!(
        (vis.width, vis.height),
        (view.width, view.height),
        "{case}: {name} size"
    );
    assert_eq!(
        vis.value.len(),
        (view.width * view.height) as usize,
        "{case}: {name} length"
    );
    let (mut bad, mut uncovered, mut unreachable) = (0, 0, 0);
    let mut example = String::new();
    for (k, v) in vis.value.iter().enumerate() {
        let wrong = if !(v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0) {
            bad += 1;
            true
        } else if !view.covered(k) {
            uncovered += (*v != Vec3::ONE) as usize;
            *v != Vec3::ONE
        } else if !frame.receiver_lit(k) {
            unreachable += (*v != Vec3::ZERO) as usize;
            *v != Vec3::ZERO
        } else {
            false
        };
        if wrong && example.is_empty() {
            example = format!("pixel {k} holds {v}");
        }
    }
    if bad + uncovered + unreachable > 0 {
        fail(format!(
            "{case}: {name} has {bad} non-finite or out-of-range pixels, {uncovered} uncovered pixels not 1, \
             {unreachable} pixels the light cannot reach not 0 (e.g. {example})"
        ));
    }
}

fn lit_share(view: &ViewSamples, v: &Visibility) -> f64 {
    let lit = (0..v.value.len())
        .filter(|&k| view.covered(k) && v.value[k].x > 0.5)
        .count();
    lit as f64 / view.covered_count().max(1) as f64
}

// ---------------------------------------------------------------------------------------
// Geometry

#[test]
fn non_finite_vertices_are_refused_naming_the_triangle() {
    let good = [
        vec3(0.0, 0.0, 0.0),
        vec3(1.0, 0.0, 0.0),
        vec3(0.0, 0.0, 1.0),
    ];
    for (i, bad) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY]
        .into_iter()
        .enumerate()
    {
        let mut tris = vec![good; 5];
        tris[3 - i][i] = vec3(0.5, bad, 0.5);
        let e = Scene::from_triangles(tris, Material::default()).unwrap_err();
        assert!(matches!(e, Error::Scene { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("triangle {}", 3 - i)) && msg.contains("non-finite"),
            "{msg}"
        );
    }
    // The same through a file loader: the vertex is named.
    let dir = std::env::temp_dir().join(format!("shadowlab-robustness-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("nan.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n").unwrap();
    let e = scene::load(path.to_str().unwrap(), &BTreeMap::new()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("nan.obj") && msg.contains("vertex 3") && msg.contains("non-finite"),
        "{msg}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn degenerate_triangles_are_harmless() {
    let mut s = blocks(1.0, 4.0);
    let m = 0;
    let p = vec3(0.3, 0.7, 0.9);
    let degenerate = [
        [p, p, p],                                               // a point
        [p, p, p + vec3(0.5, 0.0, 0.0)],                         // two equal corners
        [p, p + vec3(0.3, 0.2, 0.1), p + vec3(0.6, 0.4, 0.2)],   // collinear
        [p, p + vec3(1e-7, 0.0, 0.0), p + vec3(0.0, 1e-7, 0.0)], // far below a texel
        [
            vec3(-1.5, 0.4, 1.0),
            vec3(1.5, 0.4, 1.0),
            vec3(0.0, 0.4, 1.0),
        ], // a line across the view
        [
            vec3(-1.0, 0.0, -1.0),
            vec3(1.0, 0.0, 1.0),
            vec3(0.0, 0.0, 0.0),
        ], // a line on the ground
    ];
    for t in degenerate {
        s.push(t, m);
    }
    s.validate().unwrap();
    let cam = camera(vec3(3.0, 3.5, 5.0), vec3(0.0, 0.5, 0.0), &s);
    for light in [
        sun(),
        Light::Point {
            position: vec3(0.5, 3.0, 0.8),
        },
        Light::Spot {
            position: vec3(-1.0, 4.0, 1.0),
            target: Vec3::ZERO,
            fov_deg: 80.0,
        },
    ] {
        let (view, reference, _) = run_all(
            &format!("degenerate, {} light", light.kind()),
            &s,
            &cam,
            &light,
        );
        // No degenerate triangle is ever the visible surface.
        assert!(view
            .triangle
            .iter()
            .all(|&t| (t as usize) < s.len() - 6 || t == u32::MAX));
        let share = lit_share(&view, &reference);
        assert!(
            share > 0.2 && share < 0.98,
            "the frame must show light and shadow: {share}"
        );
    }
    // A scene with nothing but degenerate casters over a ground: all lit where it faces the light.
    let mut only = Scene::new("only-degenerate");
    let m = only.add_material(Material::default());
    quad(
        &mut only,
        Vec3::ZERO,
        vec3(3.0, 0.0, 0.0),
        vec3(0.0, 0.0, 3.0),
        m,
    );
    for t in degenerate {
        only.push(t, m);
    }
    let cam = camera(vec3(2.0, 4.0, 4.0), Vec3::ZERO, &only);
    let (view, reference, _) = run_all("only degenerate casters", &only, &cam, &sun());
    assert_eq!(lit_share(&view, &reference), 1.0);
    finish();
}

#[test]
fn triangles_crossing_the_camera_plane_are_clipped() {
    // A ground and a wall reaching far behind the camera, which stands low between them.
    let mut s = blocks(1.0, 40.0);
    let m = 0;
    quad(
        &mut s,
        vec3(-2.0, 2.0, 0.0),
        vec3(0.0, 2.0, 0.0),
        vec3(0.0, 0.0, 40.0),
        m,
    );
    // One triangle with a corner on each side of the camera plane, just beside the eye.
    let eye = vec3(1.5, 0.6, 3.0);
    s.push(
        [
            eye + vec3(0.3, -0.5, 2.0),
            eye + vec3(0.3, 0.5, 2.0),
            eye + vec3(0.5, 0.0, -2.0),
        ],
        m,
    );
    let cam = camera(eye, vec3(0.0, 0.6, 0.0), &s);
    assert!(
        cam.near < 0.01 * cam.far,
        "geometry behind the eye must pull near in"
    );
    for light in [
        sun(),
        Light::Point {
            position: vec3(0.0, 3.0, 1.0),
        },
    ] {
        let (view, reference, _) = run_all(
            &format!("crossing the camera plane, {}", light.kind()),
            &s,
            &cam,
            &light,
        );
        assert!(view.covered_count() > (W * H) as usize / 2);
        let share = lit_share(&view, &reference);
        assert!(
            share > 0.2 && share < 0.95,
            "the frame must show light and shadow: {share}"
        );
    }
    finish();
}

#[test]
fn camera_inside_a_closed_room() {
    let mut s = Scene::new("closed-room");
    let m = s.add_material(Material::default());
    cuboid(&mut s, vec3(-3.0, 0.0, -3.0), vec3(3.0, 2.5, 3.0), m);
    cuboid(&mut s, vec3(-0.5, 0.0, -0.5), vec3(0.5, 1.0, 0.5), m);
    cuboid(&mut s, vec3(1.0, 0.6, -2.0), vec3(1.4, 1.8, -1.6), m);
    let eye = vec3(2.2, 1.6, 2.4);
    let cam = camera(eye, vec3(-0.5, 0.5, -1.0), &s);
    let inside = [
        Light::Point {
            position: vec3(0.3, 2.2, 0.4),
        },
        Light::Spot {
            position: vec3(-2.5, 2.3, 2.5),
            target: vec3(0.0, 0.0, -1.0),
            fov_deg: 90.0,
        },
    ];
    for light in inside {
        let (view, reference, _) = run_all(
            &format!("inside a room, {} light", light.kind()),
            &s,
            &cam,
            &light,
        );
        assert_eq!(
            view.covered_count(),
            (W * H) as usize,
            "a closed room covers the whole image"
        );
        let share = lit_share(&view, &reference);
        assert!(
            share > 0.2 && share < 0.95,
            "the frame must show light and shadow: {share}"
        );
    }
    // Sunlight cannot enter a closed room: every technique must answer dark everywhere.
    let (view, reference, all) = run_all("inside a room, directional light", &s, &cam, &sun());
    assert_eq!(lit_share(&view, &reference), 0.0);
    for (name, vis) in &all {
        if EXACT.contains(&name.as_str()) && lit_share(&view, vis) != 0.0 {
            fail(format!(
                "{name} lets sunlight into a closed room: lit {}",
                lit_share(&view, vis)
            ));
        }
    }
    finish();
}

#[test]
fn light_inside_the_view_and_inside_the_scene_bounds() {
    let s = blocks(1.0, 4.0);
    let cam = camera(vec3(3.0, 3.5, 5.0), vec3(0.0, 0.5, 0.0), &s);
    let point_in_view = vec3(0.8, 1.6, 1.2);
    // The light projects inside the image: it is seen by the camera.
    let c = cam.clip_from_world() * point_in_view.extend(1.0);
    assert!(c.w > 0.0 && c.x.abs() < c.w && c.y.abs() < c.w);
    for (case, light) in [
        (
            "point light in the view",
            Light::Point {
                position: point_in_view,
            },
        ),
        // Between the block and the ground, inside the scene's box.
        (
            "point light under the block",
            Light::Point {
                position: vec3(-0.3, 0.25, -0.1),
            },
        ),
        (
            "spot light inside the scene box",
            Light::Spot {
                position: vec3(0.5, 1.2, 1.0),
                target: vec3(-0.5, 0.0, -0.5),
                fov_deg: 100.0,
            },
        ),
    ] {
        let position = match light {
            Light::Point { position } | Light::Spot { position, .. } => position,
            Light::Directional { .. } => unreachable!(),
        };
        let inside = position.cmpge(s.bounds.min).all() && position.cmple(s.bounds.max).all();
        assert!(
            inside || case.contains("in the view"),
            "{case}: the light is outside the scene box"
        );
        let (view, reference, _) = run_all(case, &s, &cam, &light);
        let share = lit_share(&view, &reference);
        assert!(
            share > 0.05 && share < 0.95,
            "{case}: the frame must show light and shadow: {share}"
        );
    }
    finish();
}

#[test]
fn point_light_on_the_camera_lights_everything_seen() {
    let s = blocks(1.0, 4.0);
    let eye = vec3(3.0, 3.5, 5.0);
    let cam = camera(eye, vec3(0.0, 0.5, 0.0), &s);
    let light = Light::Point { position: eye };
    let (view, reference, all) = run_all("point light on the camera", &s, &cam, &light);
    // What the eye sees, the light at the eye reaches.
    assert_eq!(lit_share(&view, &reference), 1.0);
    for (name, vis) in &all {
        if lit_share(&view, vis) <= 1.0 - MAX_MISMATCH {
            fail(format!(
                "light on the camera: {name} lights only {}",
                lit_share(&view, vis)
            ));
        }
    }
    finish();
}

#[test]
fn directional_light_along_the_view_direction() {
    let s = blocks(1.0, 4.0);
    let eye = vec3(3.0, 3.5, 5.0);
    let cam = camera(eye, vec3(0.0, 0.5, 0.0), &s);
    // From behind the camera: every visible point is lit, shadows hide behind their casters.
    let behind = Light::Directional {
        to_light: -cam.forward(),
    };
    let (view, reference, _) = run_all(
        "directional light from behind the camera",
        &s,
        &cam,
        &behind,
    );
    assert!(lit_share(&view, &reference) > 0.99);
    // Against the camera: the viewed sides face away from the light, all dark.
    let against = Light::Directional {
        to_light: cam.forward(),
    };
    let (view, reference, all) =
        run_all("directional light against the camera", &s, &cam, &against);
    assert_eq!(lit_share(&view, &reference), 0.0);
    for (name, vis) in &all {
        if lit_share(&view, vis) != 0.0 {
            fail(format!(
                "light against the camera: {name} lights {}",
                lit_share(&view, vis)
            ));
        }
    }
    finish();
}

#[test]
fn near_equal_to_far_is_refused_and_never_fitted() {
    let s = blocks(1.0, 4.0);
    let mut c = Camera::look_at(vec3(3.0, 3.5, 5.0), Vec3::ZERO, 50.0, W, H);
    c.near = 2.0;
    c.far = 2.0;
    let msg = c.validate().unwrap_err().to_string();
    assert!(msg.contains("near") && msg.contains("far"), "{msg}");
    c.far = 1.0;
    assert!(c.validate().is_err());

    // Boxes in front, around, behind and flat to the camera, at every scale.
    let mut flat = Scene::new("flat");
    let m = flat.add_material(Material::default());
    quad(&mut flat, vec3(0.0, 0.0, -5.0), Vec3::X, Vec3::Y, m);
    let mut point = Scene::new("point");
    let m = point.add_material(Material::default());
    point.push([vec3(0.0, 0.0, -3.0); 3], m);
    for scale in [1e-4f32, 1.0, 1e4] {
        for (what, scene, eye, target) in [
            ("in front", &s, vec3(3.0, 3.5, 5.0), Vec3::ZERO),
            ("around", &s, vec3(0.0, 0.2, 0.0), vec3(1.0, 0.2, 0.0)),
            ("behind", &s, vec3(0.0, 1.0, 8.0), vec3(0.0, 1.0, 9.0)),
            ("flat", &flat, Vec3::ZERO, vec3(0.0, 0.0, -1.0)),
            ("a point", &point, Vec3::ZERO, vec3(0.0, 0.0, -1.0)),
            (
                "a point at the eye",
                &point,
                vec3(0.0, 0.0, -3.0),
                Vec3::ZERO,
            ),
        ] {
            let mut sc = scene.clone();
            for v in [&mut sc.v0, &mut sc.v1, &mut sc.v2] {
                v.iter_mut().for_each(|p| *p *= scale);
            }
            sc.recompute_bounds();
            let mut c = Camera::look_at(eye * scale, target * scale, 50.0, W, H);
            c.fit_depth_range(&sc.bounds);
            c.validate()
                .unwrap_or_else(|e| panic!("{what} at scale {scale}: {e}"));
            assert!(
                c.far > c.near * 1.0001,
                "{what} at scale {scale}: near {} far {}",
                c.near,
                c.far
            );
        }
    }
}

#[test]
fn nothing_in_view_gives_an_uncovered_frame() {
    let s = blocks(1.0, 4.0);
    let eye = vec3(0.0, 2.0, 6.0);
    let mut cam = Camera::look_at(eye, eye + vec3(0.0, 0.3, 1.0), 40.0, W, H);
    cam.fit_depth_range(&s.bounds);
    cam.validate().unwrap();
    let lights = [
        sun(),
        Light::Point {
            position: vec3(0.0, 3.0, 0.0),
        },
        Light::Spot {
            position: vec3(0.0, 3.0, 0.0),
            target: Vec3::ZERO,
            fov_deg: 60.0,
        },
    ];
    for light in lights {
        let (view, _, all) = run_all(
            &format!("nothing in view, {}", light.kind()),
            &s,
            &cam,
            &light,
        );
        assert_eq!(view.covered_count(), 0);
        for (name, vis) in &all {
            if !vis.value.iter().all(|v| *v == Vec3::ONE) {
                fail(format!(
                    "nothing in view, {}: {name} is not all lit",
                    light.kind()
                ));
            }
        }
    }
    finish();
}

#[test]
fn spot_light_missing_everything_leaves_all_dark() {
    let s = blocks(1.0, 4.0);
    let cam = camera(vec3(3.0, 3.5, 5.0), vec3(0.0, 0.5, 0.0), &s);
    for (case, light) in [
        (
            "spot pointing at the sky",
            Light::Spot {
                position: vec3(0.0, 3.0, 0.0),
                target: vec3(0.0, 10.0, 0.0),
                fov_deg: 60.0,
            },
        ),
        (
            "narrow spot aimed beside the scene",
            Light::Spot {
                position: vec3(0.0, 3.0, 0.0),
                target: vec3(30.0, 0.0, 0.0),
                fov_deg: 5.0,
            },
        ),
    ] {
        let (view, reference, all) = run_all(case, &s, &cam, &light);
        assert!(view.covered_count() > 1000);
        assert_eq!(lit_share(&view, &reference), 0.0, "{case}");
        for (name, vis) in &all {
            if lit_share(&view, vis) != 0.0 {
                fail(format!("{case}: {name} lights {}", lit_share(&view, vis)));
            }
        }
    }
    finish();
}

#[test]
fn results_do_not_depend_on_units() {
    let lights = |k: f32| {
        [
            sun(),
            Light::Point {
                position: vec3(0.5, 3.0, 0.8) * k,
            },
            Light::Spot {
                position: vec3(-1.0, 4.0, 1.0) * k,
                target: Vec3::ZERO,
                fov_deg: 80.0,
            },
        ]
    };
    // Scale 1 is the yardstick; a huge ground under small objects is the thin case.
    for ground in [4.0, 400.0] {
        let mut at_scale = Vec::new();
        for scale in [1.0f32, 1e-4, 1e4] {
            let s = blocks(scale, ground);
            let cam = camera(vec3(3.0, 3.5, 5.0) * scale, vec3(0.0, 0.5, 0.0) * scale, &s);
            let mut per_light = Vec::new();
            // The thin case is about the light view's fit: the directional light alone.
            for light in lights(scale)
                .into_iter()
                .take(if ground > 10.0 { 1 } else { 3 })
            {
                let case = format!("scale {scale}, ground {ground}, {} light", light.kind());
                let (view, reference, all) = run_all(&case, &s, &cam, &light);
                per_light.push((view, reference, all));
            }
            at_scale.push(per_light);
        }
        for (i, scale) in [1e-4, 1e4].into_iter().enumerate() {
            for (l, ((v1, r1, a1), (vs, rs, as_))) in
                at_scale[0].iter().zip(&at_scale[i + 1]).enumerate()
            {
                let case = format!("scale {scale} against 1, ground {ground}, light {l}");
                // The camera pass sees the same surfaces.
                let same_cover = (0..v1.triangle.len())
                    .filter(|&k| v1.triangle[k] == vs.triangle[k])
                    .count();
                assert!(
                    same_cover as f64 > 0.995 * v1.triangle.len() as f64,
                    "{case}: coverage moved"
                );
                let both =
                    |k: usize| v1.covered(k) && vs.covered(k) && v1.triangle[k] == vs.triangle[k];
                let flips = |a: &Visibility, b: &Visibility| {
                    (0..a.value.len())
                        .filter(|&k| both(k) && (a.value[k].x - b.value[k].x).abs() >= 0.5)
                        .count() as f64
                        / v1.covered_count().max(1) as f64
                };
                if flips(r1, rs) >= 0.002 {
                    let first: Vec<String> = (0..r1.value.len())
                        .filter(|&k| both(k) && (r1.value[k].x - rs.value[k].x).abs() >= 0.5)
                        .take(4)
                        .map(|k| {
                            format!(
                                "pixel {k} triangle {} at {} / {}: {} vs {}",
                                v1.triangle[k],
                                v1.position[k],
                                vs.position[k],
                                r1.value[k].x,
                                rs.value[k].x
                            )
                        })
                        .collect();
                    fail(format!(
                        "{case}: the reference changes with units on {:.4}: {}",
                        flips(r1, rs),
                        first.join("; ")
                    ));
                }
                for ((name, a), (_, b)) in a1.iter().zip(as_) {
                    let f = flips(a, b);
                    if f >= 0.01 {
                        fail(format!(
                            "{case}: {name} changes with units on {f:.4} of the pixels"
                        ));
                    }
                }
            }
        }
    }
    finish();
}

#[test]
fn reference_agrees_with_brute_force_in_any_units() {
    // Every shadow ray of the frame, traced through the BVH and against every triangle.
    for scale in [1e-4f32, 1.0, 1e4] {
        let s = blocks(scale, 4.0);
        let cam = camera(vec3(3.0, 3.5, 5.0) * scale, vec3(0.0, 0.5, 0.0) * scale, &s);
        let view = ViewSamples::render(&s, &cam);
        let reference = Reference::build(&s);
        let light = Light::Point {
            position: vec3(0.5, 3.0, 0.8) * scale,
        };
        let (mut differ, mut shadowed) = (0, 0);
        for k in (0..view.triangle.len()).filter(|&k| view.covered(k)) {
            let sp = view.surface_point(k);
            if !light.illuminates(sp.p, view.normal[k]) {
                continue;
            }
            let o = sp.offset_origin(view.normal[k], light.shadow_ray(sp.p).0);
            let (dir, t_max) = light.shadow_ray(o);
            let fast = reference.occlusion(o, dir, t_max, view.triangle[k]);
            let slow =
                shadowlab::reference::brute_force_occlusion(&s, o, dir, t_max, view.triangle[k]);
            differ += (fast != slow) as usize;
            shadowed += (slow == Vec3::ZERO) as usize;
        }
        assert!(shadowed > 300, "scale {scale}: the frame must show shadow");
        assert_eq!(
            differ, 0,
            "scale {scale}: the BVH and brute force disagree on {differ} shadow rays"
        );
    }
}

#[test]
fn every_technique_survives_a_mesh_with_its_ground() {
    // The bunny auto-framed, lit by each kind of light placed at its head.
    let s = scene::load(data("bunny.obj").to_str().unwrap(), &BTreeMap::new()).unwrap();
    let mut cam = s.camera.unwrap();
    cam.width = W;
    cam.height = H;
    cam.fit_depth_range(&s.bounds);
    let b = s.bounds;
    let top = b.center() + vec3(0.0, 0.45, 0.0) * (b.max - b.min);
    for light in [
        Light::Point { position: top },
        Light::Point { position: cam.eye },
        Light::Directional {
            to_light: -cam.forward(),
        },
    ] {
        run_all(
            &format!("bunny, {} light at {}", light.kind(), top),
            &s,
            &cam,
            &light,
        );
    }
    finish();
}

// ---------------------------------------------------------------------------------------
// Limits

#[test]
fn image_size_is_limited() {
    for (w, h) in [(MAX_IMAGE_SIDE + 1, 10), (10, u32::MAX)] {
        let c = Camera::look_at(vec3(0.0, 0.0, 5.0), Vec3::ZERO, 45.0, w, h);
        let e = c.validate().unwrap_err();
        assert!(matches!(e, Error::Limit(_)), "{e:?}");
        assert!(e.to_string().contains(&MAX_IMAGE_SIDE.to_string()), "{e}");
    }
    let c = Camera::look_at(vec3(0.0, 0.0, 5.0), Vec3::ZERO, 45.0, 0, 10);
    assert!(c.validate().unwrap_err().to_string().contains("0x10"));
}

#[test]
fn triangle_count_is_limited_before_generation() {
    let too_many = (MAX_TRIANGLES + 1).to_string();
    for (name, key, value) in [
        ("random-triangles", "count", too_many.as_str()),
        ("hairball", "hairs", "100000000"),
        ("bumpy", "resolution", "1000000000"),
    ] {
        let params = BTreeMap::from([(key.to_string(), value.to_string())]);
        let e = scene::load(name, &params).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(key), "{name}: {msg}");
    }
    // A PLY header that promises more faces than the limit with a body that has none.
    let dir = std::env::temp_dir().join(format!("shadowlab-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.ply");
    std::fs::write(
        &path,
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face {too_many}\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
        ),
    )
    .unwrap();
    let e = scene::load(path.to_str().unwrap(), &BTreeMap::new()).unwrap_err();
    assert!(e.to_string().contains("huge.ply"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn map_resolutions_are_limited_by_set_param() {
    let absurd = [
        (MAX_RASTER_SIDE as u64 + 1).to_string(),
        "1000000000".into(),
        "0".into(),
        "-5".into(),
    ];
    let mut checked = 0;
    for name in techniques::ALL {
        let mut t = techniques::create(name).unwrap();
        let keys: Vec<String> = t
            .params()
            .keys()
            .filter(|k| k.contains("resolution"))
            .cloned()
            .collect();
        for key in keys {
            for v in &absurd {
                let before = t.params();
                let e = t.set_param(&key, v).unwrap_err();
                let msg = e.to_string();
                assert!(
                    msg.contains(&key) && msg.contains(name),
                    "{name}.{key}={v}: {msg}"
                );
                // The message states the accepted range (its upper end is a number in it).
                if v != "-5" {
                    assert!(
                        msg.contains("..=") || msg.contains("outside"),
                        "{name}.{key}={v} does not name the limit: {msg}"
                    );
                }
                assert_eq!(
                    t.params(),
                    before,
                    "{name}.{key}={v} changed the parameters"
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 7, "only {checked} resolution parameters found");
}

/// A small frame to render limits on: a light of each kind.
fn small_frame_parts(light: Light) -> (Scene, Camera, Light) {
    let s = blocks(1.0, 4.0);
    let mut cam = camera(vec3(3.0, 3.5, 5.0), vec3(0.0, 0.5, 0.0), &s);
    cam.width = 32;
    cam.height = 24;
    (s, cam, light)
}

#[test]
fn technique_memory_is_limited_before_allocation() {
    // Parameters refused by set_param, each naming the parameter and its limit.
    for (name, key, value, limit) in [
        ("subpixel", "samples", "100000", "128"),
        ("csm", "m", "1000", "16"),
        ("asm", "budget-mb", "1e12", "1000000"),
        ("asm", "cells", "4096", "64"),
        ("raytrace", "spp", "1000000", "1024"),
    ] {
        let mut t = techniques::create(name).unwrap();
        let msg = t.set_param(key, value).unwrap_err().to_string();
        assert!(
            msg.contains(key) && msg.contains(limit),
            "{name}.{key}={value}: {msg}"
        );
    }
    // Accepted sizes whose maps together would take gigabytes: refused at render time, before
    // allocating (this test would otherwise take tens of GiB).
    let point = Light::Point {
        position: vec3(0.5, 3.0, 0.8),
    };
    let big = MAX_RASTER_SIDE.to_string();
    for light in [sun(), point] {
        let (s, cam, light) = small_frame_parts(light);
        let view = ViewSamples::render(&s, &cam);
        let frame = Frame::new(&s, &cam, &light, &view);
        for name in ["sm", "pcf", "psm", "subpixel", "csm", "vsm"] {
            let mut t = techniques::create(name).unwrap();
            t.set_param("resolution", &big).unwrap();
            let e = t
                .render(&frame)
                .err()
                .unwrap_or_else(|| panic!("{name} rendered {big}² maps"));
            assert!(matches!(e, Error::Limit(_)), "{name}: {e:?}");
            assert!(
                e.to_string().contains(name) && e.to_string().contains("resolution"),
                "{name}: {e}"
            );
        }
        // The adaptive shadow map's budget too small for its roots.
        let mut t = techniques::create("asm").unwrap();
        t.set_param("budget-mb", "0.01").unwrap();
        let e = t.render(&frame).unwrap_err();
        assert!(
            matches!(e, Error::Limit(_)) && e.to_string().contains("budget-mb"),
            "{e}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Determinism

type Bits = Vec<(String, Visibility)>;

/// Every technique's shadow term on `frame`, with fresh instances.
fn all_bits(frame: &Frame) -> Bits {
    techniques::ALL
        .iter()
        .map(|name| {
            let v = technique(name)
                .render(frame)
                .unwrap_or_else(|e| panic!("{name}: {e}"))
                .visibility;
            (name.to_string(), v)
        })
        .collect()
}

/// Every technique's shadow terms in `a` and `b` equal bit for bit (an error image of
/// each that is not).
fn assert_same(what: &str, a: &Bits, b: &Bits) {
    for ((name, x), (_, y)) in a.iter().zip(b) {
        assert_same_visibility(&format!("{what}: {name}"), x, y);
    }
}

fn determinism(scene: &Scene, cam: &Camera, light: &Light, threads: &[usize]) {
    let mut first: Option<(Vec<u32>, Bits)> = None;
    for &n in threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap();
        pool.install(|| {
            let view = ViewSamples::render(scene, cam);
            let frame = Frame::new(scene, cam, light, &view);
            let a = all_bits(&frame);
            let b = all_bits(&frame);
            assert_same(&format!("{}: two runs on {n} threads", scene.name), &a, &b);
            match &first {
                None => first = Some((view.triangle.clone(), a)),
                Some((ids, bits)) => {
                    assert_eq!(
                        ids, &view.triangle,
                        "{}: camera pass differs on {n} threads",
                        scene.name
                    );
                    assert_same(
                        &format!("{}: {n} threads against {}", scene.name, threads[0]),
                        bits,
                        &a,
                    );
                }
            }
        });
    }
}

fn builtin(name: &str, params: &[(&str, &str)]) -> (Scene, Camera, Light) {
    let params = params
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let s = scene::load(name, &params).unwrap();
    let mut cam = s.camera.unwrap();
    cam.width = W;
    cam.height = H;
    cam.fit_depth_range(&s.bounds);
    let light = s.light.unwrap();
    (s, cam, light)
}

#[test]
fn bunny_renders_identically_across_runs() {
    let s = scene::load(data("bunny.obj").to_str().unwrap(), &BTreeMap::new()).unwrap();
    let mut cam = s.camera.unwrap();
    cam.width = W;
    cam.height = H;
    cam.fit_depth_range(&s.bounds);
    determinism(&s, &cam, &sun(), &[2]);
}

#[test]
fn semi_transparent_hairball_is_deterministic() {
    let (s, cam, light) = builtin("hairball", &[("hairs", "20")]);
    assert!(s.has_transparency());
    determinism(&s, &cam, &light, &[1, 2, 4]);
}

#[test]
fn point_lit_room_is_deterministic() {
    let (s, cam, light) = builtin("room", &[("light", "point")]);
    assert_eq!(light.kind(), "point");
    determinism(&s, &cam, &light, &[1, 2, 4]);
}
