//! The library's entry points for other renderers: a caller's G-buffer, point queries,
//! indexed meshes, geometry that moves between frames, and several lights in one frame.

mod support;

use shadowlab::camera::Camera;
use shadowlab::gbuffer::GBuffer;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Mat4, Vec3};
use shadowlab::multi_light::PerLight;
use shadowlab::points::{visibility_of_points, Points, FREE_POINT, POINT_TECHNIQUES};
use shadowlab::reference::Reference;
use shadowlab::scene::mesh::IndexedMesh;
use shadowlab::scene::{self, Material, Scene};
use shadowlab::techniques::{self, Frame, ShadowTechnique, ALL};
use shadowlab::view::ViewSamples;

/// A technique with the parameters that make it a function of its inputs alone: `asm`
/// without its wall-clock time budget (its tile count otherwise follows the machine's
/// speed).
fn deterministic(name: &str) -> Box<dyn ShadowTechnique> {
    let mut t = techniques::create(name).unwrap();
    if name == "asm" {
        t.set_param("time-budget-ms", "none").unwrap();
    }
    t
}

fn chessboard(w: u32, h: u32) -> (Scene, Camera, Light) {
    let s = scene::load("chessboard", &Default::default()).unwrap();
    let mut c = s.camera.unwrap();
    (c.width, c.height) = (w, h);
    c.fit_depth_range(&s.bounds);
    let l = s.light.unwrap().normalized();
    (s, c, l)
}

fn coverage(view: &ViewSamples) -> Vec<bool> {
    (0..view.triangle.len()).map(|k| view.covered(k)).collect()
}

/// SplitMix64: a fixed, seedable sequence for the random points.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[test]
fn gbuffer_of_the_camera_pass_gives_bit_identical_visibility_for_every_technique() {
    let (scene, camera, light) = chessboard(160, 120);
    let own = ViewSamples::render(&scene, &camera);
    let cov = coverage(&own);
    let handed = ViewSamples::from_gbuffer(&scene, &camera, &GBuffer::of_view(&own, &cov)).unwrap();
    for name in ALL {
        let a = deterministic(name)
            .render(&Frame::new(&scene, &camera, &light, &own))
            .unwrap();
        let b = deterministic(name)
            .render(&Frame::new(&scene, &camera, &light, &handed))
            .unwrap();
        let what = format!("entry-points-gbuffer-{name}");
        support::assert_same_visibility(&what, &a.visibility, &b.visibility);
    }
}

#[test]
fn a_minimal_gbuffer_gets_the_camera_pass_ids_and_derivatives() {
    let (scene, camera, light) = chessboard(160, 120);
    let own = ViewSamples::render(&scene, &camera);
    let cov = coverage(&own);
    let g = GBuffer::new(160, 120, &own.position, &own.normal, &cov);
    let derived = ViewSamples::from_gbuffer(&scene, &camera, &g).unwrap();
    let covered = own.covered_count();
    let same_id = (0..cov.len())
        .filter(|&k| cov[k] && own.triangle[k] == derived.triangle[k])
        .count();
    // Ids differ only where the pixel's position lies on two surfaces (coplanar
    // neighbours sharing the edge the ray passes through, overlapping faces 1e-4 apart)
    // or where the ray through the position grazes a silhouette the raster's coverage
    // rule gave to the surface behind: 38 of 16,960 pixels here.
    assert!(same_id * 1000 >= covered * 995, "{same_id} of {covered}");
    assert_eq!(own.dpdx, derived.dpdx);
    assert_eq!(own.dpdy, derived.dpdy);
    assert_eq!(own.depth, derived.depth);
    // The derived error bounds are at least the camera pass's own.
    for k in (0..cov.len()).filter(|&k| cov[k] && own.triangle[k] == derived.triangle[k]) {
        assert!(
            derived.position_error[k].cmpge(own.position_error[k]).all(),
            "pixel {k}"
        );
    }
    // Exact techniques agree with the reference on the derived frame too.
    let frame = Frame::new(&scene, &camera, &light, &derived);
    let truth = deterministic("raytrace").render(&frame).unwrap().visibility;
    let afsm = deterministic("afsm").render(&frame).unwrap().visibility;
    assert_eq!(truth, afsm);
}

#[test]
fn gbuffer_errors_name_the_field_or_pixel() {
    let (scene, camera, _) = chessboard(32, 24);
    let own = ViewSamples::render(&scene, &camera);
    let cov = coverage(&own);
    let k = cov.iter().position(|&c| c).unwrap();
    let msg = |g: &GBuffer| {
        ViewSamples::from_gbuffer(&scene, &camera, g)
            .unwrap_err()
            .to_string()
    };
    let short = &own.position[1..];
    let m = msg(&GBuffer::new(32, 24, short, &own.normal, &cov));
    assert!(m.contains("G-buffer position has 767 entries"), "{m}");
    let mut p = own.position.clone();
    p[k] = Vec3::NAN;
    let m = msg(&GBuffer::new(32, 24, &p, &own.normal, &cov));
    let at = format!("G-buffer pixel ({}, {})", k % 32, k / 32);
    assert_eq!(m, format!("{at}: position is not finite"));
    let mut n = own.normal.clone();
    n[k] = Vec3::ZERO;
    let m = msg(&GBuffer::new(32, 24, &own.position, &n, &cov));
    assert_eq!(m, format!("{at}: normal is zero or not finite"));
    let mut ids = own.triangle.clone();
    ids[k] = scene.len() as u32;
    let g = GBuffer {
        triangle: Some(&ids),
        ..GBuffer::new(32, 24, &own.position, &own.normal, &cov)
    };
    assert!(msg(&g).starts_with(&format!("{at}: triangle {} is not in scene", scene.len())));
    let m = msg(&GBuffer::new(16, 24, &own.position, &own.normal, &cov));
    assert!(m.contains("does not match the camera's 32 × 24"), "{m}");
}

/// `n` random points on the chessboard's triangles (uniform over triangles, then over
/// each triangle), each with its triangle, its exact error bound and its face normal
/// turned to a random side.
fn random_surface_points(scene: &Scene, n: usize) -> (Vec<Vec3>, Vec<Vec3>, Vec<u32>, Vec<Vec3>) {
    let mut rng = Rng(20);
    let (mut p, mut nrm, mut ids, mut err) = (vec![], vec![], vec![], vec![]);
    while p.len() < n {
        let t = (rng.next() % scene.len() as u64) as usize;
        let v = scene.triangle(t);
        let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        if normal == Vec3::ZERO {
            continue;
        }
        let (mut a, mut b) = (rng.unit(), rng.unit());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let sp = shadowlab::math::SurfacePoint::from_barycentrics(v, [1.0 - a - b, a, b]);
        p.push(sp.p);
        err.push(sp.error);
        nrm.push(if rng.next() & 1 == 0 { normal } else { -normal });
        ids.push(t as u32);
    }
    (p, nrm, ids, err)
}

#[test]
fn point_queries_on_the_chessboard_equal_the_reference() {
    let (scene, _, light) = chessboard(8, 8);
    let (p, n, ids, err) = random_surface_points(&scene, 20_000);
    let reference = Reference::build(&scene);
    let truth: Vec<Vec3> = (0..p.len())
        .map(|k| {
            let sp = shadowlab::math::SurfacePoint {
                p: p[k],
                error: err[k],
            };
            reference.transmittance(&light, &sp, n[k], ids[k])
        })
        .collect();
    let lit = truth.iter().filter(|v| v.x == 1.0).count();
    assert!(
        lit > 2000 && lit < 18_000,
        "a mix of lit and shadowed points: {lit}"
    );
    let on_triangles = Points {
        triangle: Some(&ids),
        position_error: Some(&err),
        ..Points::new(&p, &n)
    };
    for name in ["raytrace", "afsm"] {
        let got = visibility_of_points(deterministic(name).as_mut(), &scene, &light, &on_triangles)
            .unwrap();
        assert_eq!(got, truth, "{name}");
    }
    // Map-based techniques project the points: near the reference, not equal to it. The
    // points cover every surface, the pieces' flanks and contacts included, where maps
    // alias and filters leak; measured 5.4% (sm), 7.2% (pcf), 28.8% (csm, whose smooth
    // step is half-lit at the occluder's own depth) and 5.3% (vsm) flipped.
    for (name, limit) in [("sm", 0.08), ("pcf", 0.10), ("csm", 0.40), ("vsm", 0.08)] {
        let got = visibility_of_points(deterministic(name).as_mut(), &scene, &light, &on_triangles)
            .unwrap();
        let flipped = (0..p.len())
            .filter(|&k| (got[k].x - truth[k].x).abs() >= 0.5)
            .count();
        let rate = flipped as f64 / p.len() as f64;
        assert!(rate <= limit, "{name}: {flipped} of {} flipped", p.len());
    }
}

#[test]
fn point_queries_of_the_camera_pass_samples_equal_the_frame() {
    let (scene, camera, light) = chessboard(160, 120);
    let view = ViewSamples::render(&scene, &camera);
    let ks: Vec<usize> = (0..view.triangle.len())
        .filter(|&k| view.covered(k))
        .collect();
    let pick = |v: &[Vec3]| ks.iter().map(|&k| v[k]).collect::<Vec<_>>();
    let (p, n, e) = (
        pick(&view.position),
        pick(&view.normal),
        pick(&view.position_error),
    );
    let ids: Vec<u32> = ks.iter().map(|&k| view.triangle[k]).collect();
    let q = Points {
        triangle: Some(&ids),
        position_error: Some(&e),
        ..Points::new(&p, &n)
    };
    for name in POINT_TECHNIQUES {
        let frame = deterministic(name)
            .render(&Frame::new(&scene, &camera, &light, &view))
            .unwrap()
            .visibility;
        let points =
            visibility_of_points(deterministic(name).as_mut(), &scene, &light, &q).unwrap();
        let expected: Vec<Vec3> = ks.iter().map(|&k| frame.value[k]).collect();
        let flipped = (0..p.len())
            .filter(|&k| (points[k].x - expected[k].x).abs() >= 0.5)
            .count();
        if ["csm", "vsm"].contains(name) {
            // Points have no screen-space derivatives, so these filter at the finest level
            // where the frame filtered over each pixel's footprint: measured 4 (csm) and
            // 118 (vsm) of 16,960 answers flip.
            assert!(
                flipped * 100 <= p.len(),
                "{name}: {flipped} of {} flipped",
                p.len()
            );
        } else {
            assert_eq!(points, expected, "{name}");
        }
    }
}

#[test]
fn free_points_skip_no_triangle_and_agree_between_exact_techniques() {
    let (scene, _, light) = chessboard(8, 8);
    let (mut p, n, _, _) = random_surface_points(&scene, 5_000);
    // Lift every point off its surface along its normal, so no surface is its own.
    let lift = scene.bounds.diagonal() * 1e-3;
    for (q, m) in p.iter_mut().zip(&n) {
        *q += *m * lift;
    }
    let free = Points::new(&p, &n);
    let rt =
        visibility_of_points(deterministic("raytrace").as_mut(), &scene, &light, &free).unwrap();
    let afsm = visibility_of_points(deterministic("afsm").as_mut(), &scene, &light, &free).unwrap();
    assert_eq!(rt, afsm);
    let reference = Reference::build(&scene);
    for k in 0..p.len() {
        let sp = shadowlab::math::SurfacePoint {
            p: p[k],
            error: p[k].abs() * shadowlab::math::gamma(shadowlab::points::FREE_POINT_ULPS),
        };
        assert_eq!(
            rt[k],
            reference.transmittance(&light, &sp, n[k], FREE_POINT),
            "point {k}"
        );
    }
}

#[test]
fn point_queries_refuse_what_they_cannot_serve() {
    let (scene, _, light) = chessboard(8, 8);
    let p = [vec3(0.0, 1.0, 0.0)];
    let n = [Vec3::Y];
    for name in ALL.iter().filter(|t| !POINT_TECHNIQUES.contains(t)) {
        let e = visibility_of_points(
            deterministic(name).as_mut(),
            &scene,
            &light,
            &Points::new(&p, &n),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with(&format!("technique {name} cannot answer point queries")),
            "{e}"
        );
    }
    let mut rt = deterministic("raytrace");
    rt.set_param("spp", "4").unwrap();
    let e = visibility_of_points(rt.as_mut(), &scene, &light, &Points::new(&p, &n)).unwrap_err();
    assert!(e.to_string().contains("spp=4"), "{e}");
    let e = visibility_of_points(
        deterministic("afsm").as_mut(),
        &scene,
        &light,
        &Points::new(&p, &[]),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "0 normals given for 1 points; give one per point"
    );
    let nan = [Vec3::NAN];
    let e = visibility_of_points(
        deterministic("afsm").as_mut(),
        &scene,
        &light,
        &Points::new(&nan, &n),
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "point 0: position is not finite");
}

#[test]
fn a_two_light_frame_equals_two_one_light_frames() {
    let (scene, camera, spot) = chessboard(128, 96);
    let view = ViewSamples::render(&scene, &camera);
    let lights = [
        spot,
        Light::Directional {
            to_light: vec3(-0.5, 1.0, 0.25).normalize(),
        },
    ];
    for name in ALL {
        let base = Frame::new(&scene, &camera, &lights[0], &view);
        let params: Vec<(String, String)> = if *name == "asm" {
            vec![("time-budget-ms".into(), "none".into())]
        } else {
            vec![]
        };
        let mut both = PerLight::new(name, &params).unwrap();
        // Two frames, so progressive techniques carry each light's state forward.
        both.render(&base, &lights).unwrap();
        let two = both.render(&base, &lights).unwrap();
        assert_eq!(two.len(), 2);
        for (i, light) in lights.iter().enumerate() {
            let mut one = deterministic(name);
            let frame = Frame::new(&scene, &camera, light, &view);
            one.render(&frame).unwrap();
            let single = one.render(&frame).unwrap();
            assert_eq!(two[i].visibility, single.visibility, "{name}, light {i}");
        }
        assert_ne!(
            two[0].visibility, two[1].visibility,
            "{name}: the lights differ"
        );
    }
}

fn box_mesh(centre: Vec3, half: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for i in 0..8u32 {
        let s = |b: u32| if i & b != 0 { half } else { -half };
        p.push(centre + vec3(s(1), s(2), s(4)));
    }
    let faces = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (p, faces)
}

fn ground_and_box(offset: f32) -> Scene {
    let ground = [
        vec3(-4.0, 0.0, -4.0),
        vec3(-4.0, 0.0, 4.0),
        vec3(4.0, 0.0, 4.0),
        vec3(4.0, 0.0, -4.0),
    ];
    let quad = [[0, 1, 2], [0, 2, 3]];
    let (bp, bf) = box_mesh(vec3(offset, 1.0, 0.0), 0.5);
    let grey = Material::default();
    let red = Material::opaque("box", vec3(0.8, 0.2, 0.2));
    Scene::from_meshes(
        "ground and box",
        &[
            IndexedMesh {
                positions: &ground,
                indices: &quad,
                material: &grey,
            },
            IndexedMesh {
                positions: &bp,
                indices: &bf,
                material: &red,
            },
            // Posts at the corners keep the bounds fixed while the box moves.
            IndexedMesh {
                positions: &box_mesh(vec3(-3.5, 0.5, -3.5), 0.1).0,
                indices: &bf,
                material: &grey,
            },
            IndexedMesh {
                positions: &box_mesh(vec3(3.5, 0.5, 3.5), 0.1).0,
                indices: &bf,
                material: &grey,
            },
        ],
    )
    .unwrap()
}

#[test]
fn indexed_meshes_build_the_same_scene_as_triangles() {
    let s = ground_and_box(0.0);
    assert_eq!(s.mesh_count(), 4);
    assert_eq!(s.mesh_triangles(1), 2..14);
    let (bp, bf) = box_mesh(vec3(0.0, 1.0, 0.0), 0.5);
    for (t, f) in s.mesh_triangles(1).zip(&bf) {
        assert_eq!(s.triangle(t), f.map(|i| bp[i as usize]));
        assert_eq!(s.material_of(t).name, "box");
    }
    let bad = [[0, 1, 9]];
    let e = Scene::from_meshes(
        "broken",
        &[IndexedMesh {
            positions: &bp,
            indices: &bad,
            material: &Material::default(),
        }],
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "scene broken: mesh 0: face 0 names vertex 9 but the mesh has 8 vertices"
    );
    let mut nan = bp.clone();
    nan[3].y = f32::NAN;
    let e = Scene::from_meshes(
        "nan",
        &[IndexedMesh {
            positions: &nan,
            indices: &bf,
            material: &Material::default(),
        }],
    )
    .unwrap_err();
    assert!(e.to_string().contains("non-finite"), "{e}");
}

#[test]
fn a_moving_object_rebuilds_the_state_techniques_keep_for_the_scene() {
    let mut camera = Camera::look_at(vec3(0.0, 6.0, 7.0), Vec3::ZERO, 50.0, 96, 72);
    let light = Light::Directional {
        to_light: vec3(0.2, 1.0, 0.1).normalize(),
    };
    let mut scene = ground_and_box(-2.0);
    camera.fit_depth_range(&scene.bounds);
    let moved = ground_and_box(2.0);
    assert_eq!(scene.bounds, moved.bounds, "the posts pin the bounds");
    let run = |t: &mut dyn ShadowTechnique, s: &Scene| {
        let view = ViewSamples::render(s, &camera);
        t.render(&Frame::new(s, &camera, &light, &view))
            .unwrap()
            .visibility
    };
    // A fresh technique that saw some other scene first, then the moved one.
    let mut fresh = deterministic("asm");
    run(fresh.as_mut(), &ground_and_box(0.0).tap_name("other"));
    let expected = run(fresh.as_mut(), &moved);

    // The same motion told to the scene: the tile tree is rebuilt.
    let mut told = deterministic("asm");
    run(told.as_mut(), &scene);
    let before = scene.revision;
    let (bp, bf) = box_mesh(vec3(2.0, 1.0, 0.0), 0.5);
    scene.replace_mesh(1, &bp, &bf).unwrap();
    assert!(scene.revision > before);
    assert_eq!(run(told.as_mut(), &scene), expected);

    // Control: the same edit made behind the scene's back keeps the stale tree.
    let mut untold = deterministic("asm");
    let mut sneaky = ground_and_box(-2.0);
    run(untold.as_mut(), &sneaky);
    for t in sneaky.mesh_triangles(1) {
        let shift = vec3(4.0, 0.0, 0.0);
        (sneaky.v0[t], sneaky.v1[t], sneaky.v2[t]) = (
            sneaky.v0[t] + shift,
            sneaky.v1[t] + shift,
            sneaky.v2[t] + shift,
        );
    }
    assert_ne!(
        run(untold.as_mut(), &sneaky),
        expected,
        "stale tiles change the answer"
    );

    // A rigid transform is an edit the scene is told about too.
    let r = scene.revision;
    scene.transform_triangles(
        scene.mesh_triangles(1),
        Mat4::from_translation(vec3(0.0, 0.5, 0.0)),
    );
    assert_eq!(scene.revision, r + 1);
}

trait TapName {
    fn tap_name(self, name: &str) -> Self;
}
impl TapName for Scene {
    fn tap_name(mut self, name: &str) -> Self {
        self.name = name.to_string();
        self
    }
}
