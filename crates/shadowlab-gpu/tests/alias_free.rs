//! `gpu:afsm` against the CPU reference, `gpu:raytrace` and brute force: the same shadow
//! ray and the same watertight test decide every sample, so every covered pixel equals
//! the reference's but for floating-point ties — with every light kind, through alpha
//! masks and semi-transparent casters, at one and at eight samples a pixel — and two runs
//! give the same bits, the second on the first's buffers as well as on new ones.

mod support;

use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec3};
use shadowlab::reference::{brute_force_occlusion, Reference};
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::scene::{Material, Scene};
use shadowlab::techniques::{Frame, ShadowTechnique, Shadows};
use support::{builtin, framed, have_gpu, Set};

/// The share of covered pixels that may differ from the reference: floating-point ties (a
/// driver fusing a multiply and an add moves a hit by an ulp). At these sizes it allows no
/// pixel at all.
const TIE_SHARE: f64 = 1e-5;

/// Semi-transparent shadows are a product taken in log space, each caster's transmittance
/// quantized to 2^-20 in log2 (see the module doc): a partly lit pixel may differ from the
/// reference's index-order product by this much (a few casters' quantization and exp2's
/// rounding), far below anything the mismatch rate counts.
const PRODUCT_TOLERANCE: f32 = 1e-5;

fn afsm(samples: u32) -> Box<dyn ShadowTechnique> {
    shadowlab_gpu::register();
    let mut t = shadowlab::techniques::create("gpu:afsm").unwrap();
    t.set_param("samples", &samples.to_string()).unwrap();
    t
}

fn render(name: &str, frame: &Frame, samples: u32) -> Shadows {
    afsm(samples)
        .render(frame)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Covered pixels whose shadow terms differ by more than `tol` in some channel.
fn beyond(set: &Set, a: &[Vec3], b: &[Vec3], tol: f32) -> (usize, usize) {
    let view = &set.3;
    let covered = (0..a.len()).filter(|&k| view.covered(k)).count();
    let diff = (0..a.len())
        .filter(|&k| view.covered(k) && (a[k] - b[k]).abs().max_element() > tol)
        .count();
    (diff, covered)
}

/// Renders `set` with gpu:afsm at `samples` twice, the second time with the same technique
/// (on the first's buffers, cleared), and the CPU reference at as many samples a pixel;
/// asserts the runs are bit-identical and that at most [`TIE_SHARE`] of the
/// covered pixels differ from the reference (by more than [`PRODUCT_TOLERANCE`] when the
/// scene has semi-transparent casters, else at all). With one sample, `gpu:raytrace` is
/// held to the same.
fn check(name: &str, set: &Set, samples: u32) {
    let (s, c, l, view) = set;
    let frame = Frame::new(s, c, l, view);
    let mut t = afsm(samples);
    let a = t.render(&frame).unwrap_or_else(|e| panic!("{name}: {e}"));
    let b = t.render(&frame).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(
        a.visibility.value, b.visibility.value,
        "{name}: two runs differ"
    );
    let positions = pattern(PatternKind::Grid, samples).unwrap();
    let truth = Reference::build(s).visibility(&frame, &positions);
    let tol = if s.has_transparency() {
        PRODUCT_TOLERANCE
    } else {
        0.0
    };
    let (diff, covered) = beyond(set, &a.visibility.value, &truth.value, tol);
    let allowed = (covered as f64 * TIE_SHARE).floor() as usize;
    eprintln!("{name} at {samples} samples: {diff} of {covered} covered pixels differ");
    assert!(covered > 1000, "{name}: only {covered} covered pixels");
    assert!(
        diff <= allowed,
        "{name} at {samples} samples: {diff} of {covered} covered pixels differ from the reference (at most {allowed})"
    );
    let m = compare(view, &a.visibility, &truth);
    assert!(
        m.mismatch_rate <= TIE_SHARE,
        "{name}: mismatch rate {}",
        m.mismatch_rate
    );
    let shadowed = (0..view.triangle.len())
        .filter(|&k| frame.receiver_lit(k) && a.visibility.value[k].min_element() < 1.0)
        .count();
    assert!(
        shadowed > 50,
        "{name}: only {shadowed} shadowed lit pixels: the test shows nothing"
    );
    if samples == 1 {
        let mut rt = shadowlab::techniques::create("gpu:raytrace").unwrap();
        let r = rt.render(&frame).unwrap();
        let (diff, _) = beyond(set, &a.visibility.value, &r.visibility.value, tol);
        assert!(
            diff <= allowed,
            "{name}: {diff} covered pixels differ from gpu:raytrace"
        );
    }
    assert!(a.stats.device.is_some(), "{name}: no adapter recorded");
    assert!(
        a.stats.counters["ray_tests"] > 0.0,
        "{name}: no sample took the exact test"
    );
}

/// The test lights of a scene's bounds: directional, spot and point.
fn lights(s: &Scene) -> Vec<Light> {
    let b = s.bounds;
    let c = b.center();
    let size = (b.max - b.min).max_element();
    vec![
        Light::Directional {
            to_light: vec3(-0.4, 1.0, 0.3).normalize(),
        },
        Light::Spot {
            position: c + vec3(0.4, 1.2, 0.6) * size,
            target: c,
            fov_deg: 60.0,
        },
        Light::Point {
            position: vec3(c.x + 0.05 * size, b.max.y + 0.02 * size, c.z + 0.1 * size),
        },
    ]
}

fn room_with_point_light(w: u32, h: u32) -> Set {
    let room = shadowlab::scene::load("room", &Default::default()).unwrap();
    let b = room.bounds;
    let c = b.center();
    let point = Light::Point {
        position: vec3(c.x, b.min.y + 0.8 * (b.max.y - b.min.y), c.z),
    };
    framed(room, w, h, Some(point))
}

#[test]
fn equals_the_reference_on_bunny_chessboard_and_room() {
    if !have_gpu("equals_the_reference_on_bunny_chessboard_and_room") {
        return;
    }
    check("bunny", &builtin("bunny", 128, 96, None), 1);
    check("chessboard", &builtin("chessboard", 128, 96, None), 1);
    check("room (point light)", &room_with_point_light(128, 96), 1);
}

#[test]
fn equals_the_reference_with_every_light_kind() {
    if !have_gpu("equals_the_reference_with_every_light_kind") {
        return;
    }
    for name in ["bunny", "chessboard"] {
        let s = shadowlab::scene::load(name, &Default::default()).unwrap();
        for l in lights(&s) {
            let set = framed(s.clone(), 96, 72, Some(l));
            check(&format!("{name} ({} light)", l.kind()), &set, 1);
        }
    }
}

/// A frame drawn on the last frame's buffers (the same sizes: the same view, the light
/// moved) gives the bits a new technique gives: nothing of the last frame's grid, counters
/// or sums is left in them.
#[test]
fn a_frame_on_the_last_frames_buffers_equals_one_on_new_buffers() {
    if !have_gpu("a_frame_on_the_last_frames_buffers_equals_one_on_new_buffers") {
        return;
    }
    let (s, c, l, view) = builtin("chessboard", 96, 72, None);
    let Light::Spot {
        position,
        target,
        fov_deg,
    } = l
    else {
        panic!("chessboard's light is a spot light");
    };
    let moved = Light::Spot {
        position: position + (target - position) * 0.2 + vec3(3.0, 0.0, 0.0),
        target,
        fov_deg,
    };
    let first = Frame::new(&s, &c, &l, &view);
    let second = Frame::new(&s, &c, &moved, &view);
    let mut t = afsm(1);
    let a = t.render(&first).unwrap();
    let b = t.render(&second).unwrap();
    let fresh = render("chessboard, the light moved", &second, 1);
    assert_ne!(
        a.visibility.value, b.visibility.value,
        "the light's move shows nothing"
    );
    assert_eq!(
        b.visibility.value, fresh.visibility.value,
        "the frame on the last frame's buffers differs from one on new buffers"
    );
    // The grid is the same (how much work the dark-chunk culling saves depends on the
    // threads' timing, so those counters are not compared).
    for k in ["samples", "cells", "light_planes", "work_items"] {
        assert_eq!(b.stats.counters[k], fresh.stats.counters[k], "{k}");
    }
}

#[test]
fn equals_the_reference_through_alpha_masks_and_semi_transparent_casters() {
    if !have_gpu("equals_the_reference_through_alpha_masks_and_semi_transparent_casters") {
        return;
    }
    check("leaf (alpha mask)", &support::leaf(), 1);
    // The hairball's hairs at a tenth of their number (its full 2.88M triangles take
    // minutes on a software adapter): semi-transparent casters over one another.
    let params = [("hairs".to_string(), "300".to_string())].into();
    let ball = shadowlab::scene::load("hairball", &params).unwrap();
    assert!(ball.has_transparency());
    check("hairball (opacity)", &framed(ball, 96, 72, None), 1);
}

#[test]
fn equals_the_supersampled_reference_at_8_samples() {
    if !have_gpu("equals_the_supersampled_reference_at_8_samples") {
        return;
    }
    check("bunny", &builtin("bunny", 64, 48, None), 8);
    check("room (point light)", &room_with_point_light(64, 48), 8);
    check("leaf (alpha mask)", &support::leaf(), 8);
}

/// A scene of `n` random triangles over a ground quad, a third of them semi-transparent
/// when `glass`, seen from above.
fn random_scene(seed: u64, n: usize, glass: bool) -> Scene {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut s = Scene::new("random");
    let opaque = s.add_material(Material::default());
    let filter = s.add_material(Material {
        name: "glass".into(),
        color: Vec3::ONE,
        transmittance: vec3(0.9, 0.5, 0.25),
        alpha_mask: None,
    });
    for i in 0..n {
        let c = vec3(next() * 2.0 - 1.0, next() * 0.8 + 0.1, next() * 2.0 - 1.0);
        let mut v = || c + vec3(next() - 0.5, next() - 0.5, next() - 0.5) * 0.5;
        let t = [v(), v(), v()];
        s.push(t, if glass && i % 3 == 0 { filter } else { opaque });
    }
    s.recompute_bounds();
    s.place_camera(true);
    s
}

#[test]
fn equals_brute_force_on_random_scenes() {
    if !have_gpu("equals_brute_force_on_random_scenes") {
        return;
    }
    for seed in 0..4u64 {
        let s = random_scene(seed, 150, seed % 2 == 1);
        for l in lights(&s) {
            let set = framed(s.clone(), 64, 48, Some(l));
            let (s, c, l, view) = &set;
            let frame = Frame::new(s, c, l, view);
            let got = render("random", &frame, 1).visibility.value;
            // Every lit sample's shadow ray against every triangle.
            let brute: Vec<Vec3> = (0..view.triangle.len())
                .map(|k| match frame.unreached(k) {
                    Some(v) => v,
                    None => {
                        let sp = view.surface_point(k);
                        let (towards, _) = l.shadow_ray(sp.p);
                        let o = sp.offset_origin(view.normal[k], towards);
                        let (dir, t_max) = l.shadow_ray(o);
                        brute_force_occlusion(s, o, dir, t_max, view.triangle[k])
                    }
                })
                .collect();
            let tol = if s.has_transparency() {
                PRODUCT_TOLERANCE
            } else {
                0.0
            };
            let (diff, covered) = beyond(&set, &got, &brute, tol);
            let shadowed = brute.iter().filter(|v| v.min_element() < 1.0).count();
            assert!(
                covered > 500 && shadowed > 50,
                "seed {seed}: the scene shows too little"
            );
            assert_eq!(
                diff,
                0,
                "seed {seed}, {} light: {diff} of {covered} covered pixels differ from brute force",
                l.kind()
            );
        }
    }
}
