//! Orthographic cameras end to end: the glTF fixture loads as one, the primary hits of its
//! parallel rays equal a brute-force intersection, `afsm` equals the reference on every
//! pixel, every technique renders with one against the reference, and the scene formats
//! refuse bad extents.

mod support;

use shadowlab::camera::{Camera, Projection};
use shadowlab::compare::{compare, Metrics};
use shadowlab::light::Light;
use shadowlab::math::{vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{self, gltf, Scene};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;
use support::{data, scratch};

/// The fixture's camera at a test's image size (the aspect kept: xmag/ymag = 4/3).
fn fixture(w: u32, h: u32) -> (Scene, Camera) {
    let scene = gltf::load(&data("gltf/orthographic.gltf")).unwrap();
    let mut c = scene.camera.unwrap();
    (c.width, c.height) = (w, h);
    (scene, c)
}

/// A built-in scene's camera made orthographic, framing what it framed at its target.
fn orthographic_builtin(name: &str, w: u32, h: u32) -> (Scene, Camera) {
    let scene = scene::load(name, &BTreeMap::new()).unwrap();
    let mut c = scene.camera.unwrap();
    (c.width, c.height) = (w, h);
    let (xmag, ymag) = c.orthographic_extent_at_target();
    c.projection = Projection::Orthographic { xmag, ymag };
    c.fit_depth_range(&scene.bounds);
    (scene, c)
}

fn light_of(scene: &Scene) -> Light {
    scene
        .light
        .unwrap_or(Light::Directional {
            to_light: Vec3::new(0.3, 1.0, 0.2),
        })
        .normalized()
}

/// A technique's shadow term against the one-sample reference.
fn against_reference(
    scene: &Scene,
    camera: &Camera,
    technique: &str,
    reference: &Reference,
) -> Metrics {
    let light = light_of(scene);
    let view = ViewSamples::render(scene, camera);
    let frame = Frame::new(scene, camera, &light, &view);
    let truth = reference.visibility(&frame, &[vec2(0.5, 0.5)]);
    let shadows = techniques::create(technique)
        .unwrap()
        .render(&frame)
        .unwrap_or_else(|e| panic!("{technique}: {e}"));
    compare(&view, &shadows.visibility, &truth)
}

#[test]
fn the_gltf_fixture_loads_as_an_orthographic_camera() {
    let scene = gltf::load(&data("gltf/orthographic.gltf")).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let c = scene.camera.unwrap();
    assert_eq!(
        c.projection,
        Projection::Orthographic {
            xmag: 2.4,
            ymag: 1.8
        }
    );
    assert_eq!((c.width, c.height), (1024, 768));
    assert_eq!((c.near, c.far), (0.5, 12.0));
    // The node at (0, 3, 4) looks at the origin.
    assert!((c.eye - Vec3::new(0.0, 3.0, 4.0)).length() < 1e-5);
    assert!((c.forward() - Vec3::new(0.0, -0.6, -0.8)).length() < 1e-5);
}

/// The primary ray of pixel `(x, y)` built from the camera's basis and extent alone.
fn parallel_ray(c: &Camera, x: u32, y: u32) -> (Vec3, Vec3) {
    let Projection::Orthographic { xmag, ymag } = c.projection else {
        panic!("not orthographic")
    };
    let (r, u, f) = c.basis();
    let sx = (x as f32 + 0.5) / c.width as f32 * 2.0 - 1.0;
    let sy = 1.0 - (y as f32 + 0.5) / c.height as f32 * 2.0;
    (c.eye + r * (sx * xmag) + u * (sy * ymag), f)
}

/// The nearest triangle along a ray by testing every triangle (Möller–Trumbore in f64):
/// `(triangle, t, smallest barycentric, gap to the next hit's t)`.
fn brute_force_hit(scene: &Scene, o: Vec3, d: Vec3) -> Option<(u32, f64, f64, f64)> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let mut hits: Vec<(f64, u32, f64)> = Vec::new();
    for i in 0..scene.len() {
        let v = scene.triangle(i).map(|p| p.as_dvec3());
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-14 {
            continue;
        }
        let s = o - v[0];
        let b1 = s.dot(p) / det;
        let q = s.cross(e1);
        let b2 = d.dot(q) / det;
        let t = e2.dot(q) / det;
        let b0 = 1.0 - b1 - b2;
        if b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 && t > 0.0 {
            hits.push((t, i as u32, b0.min(b1).min(b2)));
        }
    }
    hits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let gap = hits.get(1).map_or(f64::INFINITY, |n| n.0 - hits[0].0);
    hits.first().map(|&(t, i, m)| (i, t, m, gap))
}

#[test]
fn primary_hits_equal_a_brute_force_parallel_ray_intersection() {
    for (label, (scene, camera)) in [
        ("fixture", fixture(96, 72)),
        ("bunny", orthographic_builtin("bunny", 128, 96)),
    ] {
        let reference = Reference::build(&scene);
        let view = ViewSamples::render(&scene, &camera);
        let (mut checked, mut hits, mut raster_differs) = (0, 0, 0);
        for y in 0..camera.height {
            for x in 0..camera.width {
                let (o, d) = parallel_ray(&camera, x, y);
                let (co, cd) = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                assert!((co - o).length() < 1e-4 * (1.0 + o.length()) && cd == d);
                let brute = brute_force_hit(&scene, o, d);
                let traced = reference.closest_hit(co, cd);
                let k = (y * camera.width + x) as usize;
                match brute {
                    // Numerical ties: the ray grazes an edge or meets two surfaces at
                    // almost the same depth.
                    Some((_, t, margin, gap)) if margin < 1e-4 || gap < 1e-4 * (1.0 + t) => {}
                    Some((tri, t, _, _)) => {
                        checked += 1;
                        hits += 1;
                        let h = traced.unwrap_or_else(|| panic!("{label} ({x}, {y}): no hit"));
                        assert_eq!(h.triangle, tri, "{label} ({x}, {y})");
                        assert!(
                            (h.t as f64 - t).abs() < 1e-4 * (1.0 + t),
                            "{label} ({x}, {y})"
                        );
                        // The rasterized camera pass sees the same triangle (but where its
                        // fixed-point snapping moves an edge across the pixel centre), and
                        // t is its view depth.
                        if view.triangle[k] == tri {
                            let depth = view.depth[k] as f64;
                            assert!(
                                (depth - t).abs() < 1e-3 * (1.0 + t),
                                "{label} {depth} vs {t}"
                            );
                        } else {
                            raster_differs += 1;
                        }
                    }
                    None => {
                        checked += 1;
                        assert!(traced.is_none(), "{label} ({x}, {y}): hit nothing");
                    }
                }
            }
        }
        let n = (camera.width * camera.height) as usize;
        assert!(
            checked > n * 9 / 10,
            "{label}: {checked} of {n} pixels checked"
        );
        assert!(hits > n / 4, "{label}: {hits} hits");
        assert!(
            raster_differs * 200 < hits,
            "{label}: the camera pass differs on {raster_differs} of {hits} pixels"
        );
    }
}

#[test]
fn afsm_equals_the_reference_on_every_pixel_under_orthographic_cameras() {
    for (label, (scene, camera)) in [
        ("fixture", fixture(320, 240)),
        ("bunny", orthographic_builtin("bunny", 320, 240)),
        ("chessboard", orthographic_builtin("chessboard", 320, 240)),
    ] {
        let reference = Reference::build(&scene);
        let m = against_reference(&scene, &camera, "afsm", &reference);
        eprintln!(
            "{label}: {} covered pixels, mismatch {}",
            m.covered_pixels, m.mismatch_rate
        );
        assert!(m.covered_pixels > 10_000, "{label}");
        assert_eq!(m.mismatch_rate, 0.0, "{label}");
        assert_eq!(m.mean_abs_error_rgb, 0.0, "{label}");
    }
}

#[test]
fn every_technique_renders_under_an_orthographic_camera() {
    let (scene, camera) = orthographic_builtin("bunny", 192, 144);
    let reference = Reference::build(&scene);
    let mut rates = BTreeMap::new();
    for &name in techniques::ALL {
        let m = against_reference(&scene, &camera, name, &reference);
        eprintln!("{name}: mismatch {:.4}%", m.mismatch_rate * 100.0);
        // Filtered and sampled techniques soften edges; none may be far off.
        assert!(m.mismatch_rate < 0.01, "{name}: {}", m.mismatch_rate);
        rates.insert(name, m.mismatch_rate);
    }
    assert_eq!(rates["raytrace"], 0.0);
    // psm degenerates to a uniform map fitted to the view, lispsm to the uniform map: both
    // as good as sm, no worse.
    for warped in ["psm", "lispsm"] {
        assert!(
            rates[warped] <= 2.0 * rates["sm"] + 1e-3,
            "{warped} {} against sm {}",
            rates[warped],
            rates["sm"]
        );
    }
}

#[test]
fn bad_orthographic_extents_are_refused_naming_the_culprit() {
    let dir = scratch("orthographic-bad");
    let text = std::fs::read_to_string(data("gltf/orthographic.gltf")).unwrap();
    for (from, to, says) in [
        ("\"xmag\": 2.4", "\"xmag\": 0.0", "xmag"),
        ("\"xmag\": 2.4", "\"xmag\": -2.4", "xmag"),
        ("\"ymag\": 1.8", "\"ymag\": -1.0", "ymag"),
        ("\"zfar\": 12.0", "\"zfar\": 0.25", "zfar"),
    ] {
        assert!(text.contains(from), "{from}");
        let p = dir.join("bad.gltf");
        std::fs::write(&p, text.replace(from, to)).unwrap();
        let e = gltf::load(&p).unwrap_err();
        assert!(e.is_bad_input(), "{to}: {e}");
        assert!(e.to_string().contains(says), "{to}: {e}");
    }
    let toml = |camera: &str| {
        let p = dir.join("scene.toml");
        std::fs::write(
            &p,
            format!(
                "[camera]\neye = [0.0, 2.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n{camera}\n\n[[mesh]]\ngenerator = \"box\"\n"
            ),
        )
        .unwrap();
        scene::load(p.to_str().unwrap(), &BTreeMap::new())
    };
    let ok = toml("projection = \"orthographic\"\nymag = 1.5\nwidth = 200\nheight = 100")
        .unwrap()
        .camera
        .unwrap();
    assert_eq!(
        ok.projection,
        Projection::Orthographic {
            xmag: 3.0,
            ymag: 1.5
        }
    );
    for (camera, says) in [
        ("projection = \"orthographic\"", "ymag"),
        ("projection = \"orthographic\"\nymag = -1.0", "ymag"),
        ("projection = \"orthographic\"\nymag = nan", "ymag"),
        (
            "projection = \"orthographic\"\nymag = 1.0\nxmag = 0.0",
            "xmag",
        ),
        (
            "projection = \"orthographic\"\nymag = 1.0\nfov_y_deg = 30.0",
            "fov_y_deg",
        ),
        (
            "projection = \"orthographic\"\nymag = 1.0\nnear = 2.0\nfar = 1.0",
            "near",
        ),
        ("ymag = 1.0", "ymag"),
        ("projection = \"isometric\"", "isometric"),
    ] {
        let e = toml(camera).unwrap_err();
        assert!(e.is_bad_input(), "{camera}: {e}");
        assert!(e.to_string().contains(says), "{camera}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
