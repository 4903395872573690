//! Convolution shadow maps (`csm`), variance shadow maps (`vsm`) and the shared texture
//! filtering, checked against the analytic step function, brute-force filtering and the
//! ray-traced reference.

use shadowlab::camera::Camera;
use shadowlab::compare::compare;
use shadowlab::light::{Light, LightView};
use shadowlab::math::{vec2, vec3, Vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::scene::{Material, Scene};
use shadowlab::techniques::convolution::Expansion;
use shadowlab::techniques::filtering::{
    blur, level_of_detail, light_footprint, Channel, Filter, Footprint, MipChain, Texture,
};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;

/// Heaviside step of `t = z − d`: lit (1) when the map depth is behind the receiver.
fn heaviside(t: f32) -> f32 {
    if t > 0.0 {
        1.0
    } else {
        0.0
    }
}

/// Statistics of the reconstructed step over `t ∈ [−1, 1]`: mean absolute error, the
/// 10–90% transition width, the overshoot above 1, and the largest error with
/// `|t| ∈ [1/M, 1 − 1/M]` (ringing away from the step).
fn step_stats(e: &Expansion) -> (f32, f32, f32, f32) {
    let n = 20_000;
    let ts: Vec<f32> = (0..=n).map(|i| -1.0 + 2.0 * i as f32 / n as f32).collect();
    let g: Vec<f32> = ts.iter().map(|&t| e.step(t)).collect();
    let l1 = ts
        .iter()
        .zip(&g)
        .map(|(&t, &v)| (v - heaviside(t)).abs())
        .sum::<f32>()
        / ts.len() as f32;
    let first = |level: f32| {
        ts.iter()
            .zip(&g)
            .find(|(&t, &v)| t > -0.5 && v >= level)
            .map(|(&t, _)| t)
            .unwrap()
    };
    let width = first(0.9) - first(0.1);
    let overshoot = g.iter().copied().fold(0.0f32, f32::max) - 1.0;
    let m = e.m as f32;
    let ring = ts
        .iter()
        .zip(&g)
        .filter(|(&t, _)| t.abs() >= 1.0 / m && t.abs() <= 1.0 - 1.0 / m)
        .map(|(&t, &v)| (v - heaviside(t)).abs())
        .fold(0.0f32, f32::max);
    (l1, width, overshoot, ring)
}

#[test]
fn truncated_expansion_reconstructs_the_step_as_in_figure_3() {
    let mut last_l1 = f32::INFINITY;
    for m in [4u32, 8, 16] {
        let plain = Expansion { m, alpha: 0.0 };
        let (l1, width, overshoot, ring) = step_stats(&plain);
        // Figure 3(a): the step steepens as 1/M, with the Gibbs overshoot of about 9%
        // that does not shrink with M, and ringing that stays near 5% around the step.
        assert!(width <= 0.46 / m as f32, "M={m}: transition width {width}");
        assert!(
            (0.08..=0.095).contains(&overshoot),
            "M={m}: overshoot {overshoot}"
        );
        assert!(ring <= 0.056, "M={m}: ringing {ring}");
        let bound = match m {
            4 => 0.14,
            8 => 0.08,
            _ => 0.046,
        };
        assert!(l1 < last_l1 && l1 <= bound, "M={m}: mean error {l1}");
        last_l1 = l1;
        // Figure 3(b): attenuation suppresses the ringing and flattens the step.
        let damped = Expansion { m, alpha: 1.0 };
        let (_, dwidth, dovershoot, dring) = step_stats(&damped);
        assert!(
            dovershoot < overshoot * 0.25,
            "M={m}: attenuated overshoot {dovershoot}"
        );
        assert!(dring < ring, "M={m}: attenuated ringing {dring} vs {ring}");
        assert!(dwidth > width, "M={m}: attenuation must flatten the step");
        // Figure 3(c): after the offset, a surface that is its own occluder is lit.
        let e = Expansion { m, alpha: 0.5 };
        let off = e.auto_offset();
        assert!(
            e.step(off) >= 1.0,
            "M={m}: step at offset {off} is {}",
            e.step(off)
        );
        assert!(
            off <= 0.6 / m as f32,
            "M={m}: offset {off} does not shrink with M"
        );
    }
}

/// A pseudo-random depth map in `[0, span]` (a small xorshift: deterministic, no crate).
fn random_depths(w: u32, h: u32, span: f32) -> Vec<f32> {
    let mut s = 0x9e37_79b9_u32;
    (0..w * h)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s >> 8) as f32 / (1u32 << 24) as f32 * span
        })
        .collect()
}

fn blur_commutes_with_reconstruction<T: Channel>(tolerance: impl Fn(&Expansion) -> f32) {
    let (w, h) = (48u32, 40u32);
    let z = random_depths(w, h, 0.8);
    for (m, n) in [(4u32, 3u32), (8, 5), (16, 7)] {
        let e = Expansion { m, alpha: 0.5 };
        let basis = Texture::<T>::from_fn(w, h, e.channels(), |x, y, o| {
            e.basis(z[(y * w + x) as usize], o);
            for v in o.iter_mut() {
                *v = T::encode_signed(*v);
            }
        });
        let blurred_basis = blur(&basis, n);
        for d in [0.1f32, 0.45, 0.7] {
            // The shadow test per texel for a receiver plane at depth d, then blurred.
            let test = Texture::<f32>::from_fn(w, h, 1, |x, y, o| {
                let b: Vec<f32> = basis
                    .texel(x, y)
                    .iter()
                    .map(|v| T::decode_signed(v.to_f32()))
                    .collect();
                o[0] = e.reconstruct(d, &b);
            });
            let blurred_test = blur(&test, n);
            let tol = tolerance(&e);
            for y in 0..h {
                for x in 0..w {
                    let b: Vec<f32> = blurred_basis
                        .texel(x, y)
                        .iter()
                        .map(|v| T::decode_signed(v.to_f32()))
                        .collect();
                    let a = e.reconstruct(d, &b);
                    let r = blurred_test.texel(x, y)[0];
                    assert!(
                        (a - r).abs() <= tol,
                        "M={m} blur {n} d={d} at ({x},{y}): {a} vs {r} (tolerance {tol})"
                    );
                }
            }
        }
    }
}

#[test]
fn blurring_the_basis_equals_blurring_the_shadow_test() {
    // f32: equal up to rounding.
    blur_commutes_with_reconstruction::<f32>(|_| 2e-5);
    // 8-bit: the blurred basis is rounded twice more (two passes) than the basis the test
    // was computed from, half a code (1/255 in [-1, 1]) each, on every channel.
    blur_commutes_with_reconstruction::<u8>(|e| {
        let per_channel = 2.0 * 0.5 / 127.5;
        (1..=e.m)
            .map(|k| 2.0 * e.attenuation(k) / Expansion::c(k) * 2.0 * per_channel)
            .sum::<f32>()
            + 1e-5
    });
}

#[test]
fn mip_level_selection_matches_the_footprint() {
    // Level i of the chain holds the constant i, so a tri-linear sample returns λ itself.
    let base = Texture::<f32>::from_fn(256, 256, 1, |_, _, o| o[0] = 0.0);
    let mut chain = MipChain::build(base);
    for (i, l) in chain.levels.iter_mut().enumerate() {
        l.data.fill(i as f32);
    }
    let mut out = [0.0f32];
    for texels in [0.5f32, 1.0, 2.0, 3.0, 8.0, 40.0, 128.0] {
        let fp = Footprint {
            dx: Vec2::new(texels / 256.0, 0.0),
            dy: Vec2::new(0.0, texels * 0.5 / 256.0),
        };
        chain.sample(0.3, 0.6, &fp, Filter::Trilinear, 1, &mut out);
        let want = texels.log2().max(0.0);
        assert!(
            (out[0] - want).abs() < 1e-4,
            "footprint {texels} texels: level {} want {want}",
            out[0]
        );
        // Anisotropic: two probes along the long axis, each with half the footprint.
        let lod = chain.sample(0.3, 0.6, &fp, Filter::Anisotropic, 16, &mut out);
        if texels > 1.0 {
            assert_eq!(lod.probes, 2);
            assert!((out[0] - (texels / 2.0).log2().max(0.0)).abs() < 1e-4);
        }
    }

    // In a real frame: a ground plane under a light straight above, so map texels are
    // squares on the ground; the footprint from the camera pass's derivatives must match
    // the brute-force one, from the rays through the next pixel centres.
    let scene = Scene::from_triangles(ground(30.0), Material::default()).unwrap();
    let mut camera = Camera::look_at(vec3(0.0, 3.0, 12.0), vec3(0.0, 0.0, 2.0), 45.0, 160, 120);
    camera.fit_depth_range(&scene.bounds);
    let view = ViewSamples::render(&scene, &camera);
    let lv = LightView::directional(Vec3::Y, &view.receiver_bounds(), &scene.bounds, 0.0);
    let side = 1024;
    let hit = |x: f32, y: f32| {
        let d = camera.ray_direction(x, y);
        let t = -camera.eye.y / d.y;
        let p = camera.eye + d * t;
        let s = lv.project(p);
        Vec2::new(s.u, s.v)
    };
    let mut checked = 0;
    for (px, py) in [(80u32, 40u32), (20, 60), (140, 90), (80, 110)] {
        let k = (py * 160 + px) as usize;
        assert!(view.covered(k));
        let fp = light_footprint(&lv, view.position[k], view.dpdx[k], view.dpdy[k]);
        let (cx, cy) = (px as f32 + 0.5, py as f32 + 0.5);
        // The camera pass's derivatives are the steps to the next pixel's centre.
        let brute = Footprint {
            dx: hit(cx + 1.0, cy) - hit(cx, cy),
            dy: hit(cx, cy + 1.0) - hit(cx, cy),
        };
        let a = level_of_detail(&fp, side, Filter::Trilinear, 1).lambda;
        let b = level_of_detail(&brute, side, Filter::Trilinear, 1).lambda;
        assert!(
            (a - b).abs() < 0.02,
            "pixel ({px},{py}): λ {a} vs brute force {b}"
        );
        checked += 1;
    }
    assert_eq!(checked, 4);
}

/// Thin bars (top faces only) at height `y`, `count` of them across `[-g, g]`, along z or x.
fn bars(tris: &mut Vec<[Vec3; 3]>, g: f32, y: f32, count: u32, width: f32, along_x: bool) {
    let pitch = 2.0 * g / count as f32;
    for i in 0..count {
        let a = -g + (i as f32 + 0.5) * pitch - width * 0.5;
        let b = a + width;
        let q = if along_x {
            [vec3(-g, y, a), vec3(g, y, a), vec3(g, y, b), vec3(-g, y, b)]
        } else {
            [vec3(a, y, -g), vec3(a, y, g), vec3(b, y, g), vec3(b, y, -g)]
        };
        tris.push([q[0], q[1], q[2]]);
        tris.push([q[0], q[2], q[3]]);
    }
}

fn ground(g: f32) -> Vec<[Vec3; 3]> {
    vec![
        [vec3(-g, 0.0, -g), vec3(-g, 0.0, g), vec3(g, 0.0, g)],
        [vec3(-g, 0.0, -g), vec3(g, 0.0, g), vec3(g, 0.0, -g)],
    ]
}

struct Run {
    mae: f64,
    memory: u64,
    minified_share: f64,
    counters: std::collections::BTreeMap<String, f64>,
}

/// Renders `technique` with `params` on `scene` and measures it against a 64-sample
/// reference.
fn measure(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    runs: &[(&str, &[(&str, &str)])],
) -> Vec<Run> {
    measure_spp(scene, camera, light, 64, runs)
}

/// [`measure`] against a reference of `spp` samples per pixel.
fn measure_spp(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    spp: u32,
    runs: &[(&str, &[(&str, &str)])],
) -> Vec<Run> {
    let view = ViewSamples::render(scene, camera);
    let frame = Frame::new(scene, camera, light, &view);
    let reference =
        Reference::build(scene).visibility(&frame, &pattern(PatternKind::Grid, spp).unwrap());
    runs.iter()
        .map(|(name, params)| {
            let mut t = techniques::create(name).unwrap();
            for (k, v) in params.iter() {
                t.set_param(k, v).unwrap();
            }
            let s = t.render(&frame).unwrap();
            let m = compare(&view, &s.visibility, &reference);
            eprintln!(
                "{} {name} {params:?}: mean abs error {:.4}, mismatch {:.4}",
                scene.name, m.mean_abs_error, m.mismatch_rate
            );
            Run {
                mae: m.mean_abs_error,
                memory: s.stats.memory_bytes,
                minified_share: s
                    .stats
                    .counters
                    .get("minified_share")
                    .copied()
                    .unwrap_or(0.0),
                counters: s.stats.counters,
            }
        })
        .collect()
}

/// A built-in scene with its camera at `width` × `height` and its light.
fn builtin(name: &str, width: u32, height: u32) -> (Scene, Camera, Light) {
    let scene = shadowlab::scene::load(name, &Default::default()).unwrap();
    let mut camera = scene.camera.unwrap();
    camera.width = width;
    camera.height = height;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.unwrap();
    (scene, camera, light)
}

/// The paper's recommended order M = 4, with the ringing attenuation that suits it.
const PAPER_M4: &[(&str, &str)] = &[("m", "4"), ("alpha", "0.5")];

#[test]
fn csm_beats_pcf_on_minified_shadows() {
    // The `fence-far` scene: the fence, boxes and wall seen from five times the fence
    // scene's distance, so each pixel covers many map texels and several scrollwork shadows,
    // which PCF's few taps alias and the mip-mapped basis averages.
    let (scene, camera, light) = builtin("fence-far", 160, 120);
    // The walkthrough pulls away: its keys get farther from the target, the first at the
    // fence scene's distance and the still camera's among them.
    let path = scene
        .camera_path
        .as_ref()
        .expect("fence-far has a camera path");
    let dist: Vec<f32> = path
        .keys
        .iter()
        .map(|k| (k.eye - k.target).length())
        .collect();
    assert!(
        dist.len() >= 3 && dist.windows(2).all(|w| w[1] > w[0] * 1.5),
        "{dist:?}"
    );
    let still = (camera.eye - camera.target).length();
    assert!(
        still > dist[0] * 4.0 && still < dist[dist.len() - 1],
        "{still} {dist:?}"
    );

    let r = measure(
        &scene,
        &camera,
        &light,
        &[
            ("pcf", &[]),
            ("csm", PAPER_M4),
            (
                "csm",
                &[("m", "4"), ("alpha", "0.5"), ("filter", "bilinear")],
            ),
        ],
    );
    // Measured: pcf 0.0306, csm 0.0207, csm without mip-mapping 0.0342 (at the defaults,
    // M = 16 and α = 0, csm has about 0.037 here: see `DEFAULT_M` for that trade-off).
    assert!(
        r[1].mae < r[0].mae * 0.9,
        "csm M=4 {} vs pcf {}",
        r[1].mae,
        r[0].mae
    );
    // Without mip-mapping csm aliases like any point-sampled map.
    assert!(
        r[2].mae > r[1].mae,
        "mip-mapping must help: {} vs {}",
        r[2].mae,
        r[1].mae
    );
    // The scrollwork is minified in light space too: every look-up spans several texels.
    assert!(r[1].minified_share > 0.99, "{}", r[1].minified_share);
}

#[test]
fn csm_leaks_less_than_vsm_under_depth_complexity() {
    // Two gratings crossing at different heights over the ground: where a filter region
    // holds both gratings' depths, Chebyshev's bound lets light through onto the ground
    // (light bleeding); the Fourier expansion converges to the filtered test instead.
    let g = 10.0;
    let mut tris = ground(g);
    bars(&mut tris, g, 2.0, 24, 0.3, false);
    bars(&mut tris, g, 1.0, 16, 0.4, true);
    let scene = Scene::from_triangles(tris, Material::default()).unwrap();
    let mut camera = Camera::look_at(vec3(0.0, 9.0, 12.0), vec3(0.0, 0.0, -1.0), 45.0, 160, 120);
    camera.fit_depth_range(&scene.bounds);
    let light = Light::Directional {
        to_light: vec3(0.2, 1.0, 0.15).normalize(),
    };
    let common: &[(&str, &str)] = &[("resolution", "512"), ("blur", "5")];
    let m4: &[(&str, &str)] = &[("resolution", "512"), ("blur", "5"), ("m", "4")];
    let r = measure(
        &scene,
        &camera,
        &light,
        &[
            ("vsm", common),
            ("csm", m4),
            ("csm", &[("resolution", "512"), ("blur", "5"), ("m", "16")]),
        ],
    );
    assert!(
        r[2].mae < r[0].mae,
        "csm M=16 {} vs vsm {}",
        r[2].mae,
        r[0].mae
    );
    // The paper's memory comparison: at M = 4 the 8-bit basis takes as many bytes as a
    // two-channel f32 variance map.
    assert_eq!(r[1].memory, r[0].memory);
    assert_eq!(r[2].memory, 4 * r[0].memory);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let g = 4.0;
    let mut tris = ground(g);
    bars(&mut tris, g, 1.0, 12, 0.2, false);
    let scene = Scene::from_triangles(tris, Material::default()).unwrap();
    let mut camera = Camera::look_at(vec3(0.0, 5.0, 8.0), Vec3::ZERO, 45.0, 96, 64);
    camera.fit_depth_range(&scene.bounds);
    let light = Light::Point {
        position: vec3(0.5, 3.0, 0.3),
    };
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    for name in ["csm", "vsm"] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut t = techniques::create(name).unwrap();
                t.set_param("resolution", "256").unwrap();
                t.set_param("blur", "3").unwrap();
                t.render(&frame).unwrap().visibility
            })
        };
        let one = run(1);
        assert_eq!(one, run(3), "{name}");
        // Some pixels are lit and some shadowed: the comparison is not vacuous.
        assert!(
            one.value.iter().any(|v| v.x > 0.9) && one.value.iter().any(|v| v.x < 0.1),
            "{name}"
        );
    }
}

#[test]
fn bad_parameters_are_errors_that_name_them() {
    let mut csm = techniques::create("csm").unwrap();
    for (k, v) in [
        ("m", "17"),
        ("m", "0"),
        ("blur", "4"),
        ("blur", "x"),
        ("filter", "cubic"),
        ("precision", "u16"),
        ("offset", "0.9"),
        ("max-aniso", "32"),
    ] {
        let e = csm.set_param(k, v).unwrap_err().to_string();
        assert!(e.contains(k), "{k}={v}: {e}");
    }
    let e = csm.set_param("kernel", "3").unwrap_err().to_string();
    assert!(e.contains("kernel") && e.contains("alpha"), "{e}");
    let mut vsm = techniques::create("vsm").unwrap();
    assert!(vsm.set_param("bleed-reduction", "1.5").is_err());
    for (k, v) in [
        ("blur", "7x7"),
        ("filter", "trilinear"),
        ("bleed-reduction", "0.3"),
    ] {
        vsm.set_param(k, v).unwrap();
    }
    assert_eq!(vsm.params()["blur"], 7);
    csm.set_param("offset", "auto").unwrap();
    csm.set_param("precision", "f32").unwrap();
    assert!(csm.params()["offset"].as_f64().unwrap() > 0.0);
}

#[test]
fn csm_leaks_less_than_vsm_on_the_fence() {
    // The paper's Figure 9 scene: the fence in front of boxes, a column and a wall, against a
    // 64-sample reference. Both techniques at the same map resolution and filtering (the
    // defaults: 2048², 16x anisotropic tri-linear, no blur); csm at M = 16, the order of the
    // paper's Figure 4, whose offset (about 8 cm here) keeps the fence's contact shadows
    // (csm 0.0190, vsm 0.0191). At M = 4 the offset is about 40 cm of light depth
    // and csm loses to vsm (0.031 vs 0.019): under this low sun (24°) a caster's shadow lies
    // 2.5 times its height further along the light, so the depth interval the shadows span
    // is itself 2–3 m, and the shadows the fence throws on the boxes 30–65 cm behind it fade.
    let (scene, camera, light) = builtin("fence", 256, 192);
    // The paper renders with the offset alone ("using offsetting", Section 5).
    let offset_only: &[(&str, &str)] = &[("m", "16"), ("scale", "1"), ("pivot", "0")];
    let m4: &[(&str, &str)] = &[("m", "4"), ("alpha", "0.5"), ("scale", "1"), ("pivot", "0")];
    let r = measure(
        &scene,
        &camera,
        &light,
        &[
            ("vsm", &[]),
            ("csm", offset_only),
            ("csm", &[]),
            ("csm", m4),
        ],
    );
    let (vsm, csm, scaled) = (r[0].mae, r[1].mae, r[2].mae);
    assert!(csm < vsm, "csm M=16 {csm} vs vsm {vsm}");
    // The default step, scaled by 2 about 0.1, keeps more contact shadows but sharpens the
    // scrollwork's filtered penumbrae, which here costs about as much as it gains
    // (measured 0.0192 against 0.0190 and vsm's 0.0191).
    assert!(
        scaled < 1.05 * vsm,
        "csm at its defaults {scaled} vs vsm {vsm}"
    );
    // The fitted depth range spans the receivers that may be shadowed (about 265 cm), not
    // every visible receiver (296 cm: the lit ground in front of the fence is left out) nor
    // the whole map (546 cm).
    let c = &r[1].counters;
    let range = c["depth_range"];
    let all = c["receivers_far"] - c["receivers_near"];
    assert!(
        range < 0.95 * all && range < 300.0,
        "depth range {range} of {all}"
    );
    assert!(c["shadowable_share"] < 0.5, "{c:?}");
}

/// A ground plane with a box and a tilted plate over it, seen from `eye` with a point light
/// exactly at the camera: every visible point is lit, and the cube face looking straight
/// down sees the whole ground at one light depth.
fn point_light_at_the_eye() -> (Scene, Camera, Light) {
    fn quad(s: &mut Scene, c: Vec3, a: Vec3, b: Vec3, m: u32) {
        let (p0, p1, p2, p3) = (c - a - b, c + a - b, c + a + b, c - a + b);
        s.push([p0, p1, p2], m);
        s.push([p0, p2, p3], m);
    }
    let mut s = Scene::new("blocks");
    let m = s.add_material(Material::default());
    quad(
        &mut s,
        Vec3::ZERO,
        vec3(4.0, 0.0, 0.0),
        vec3(0.0, 0.0, 4.0),
        m,
    );
    let (lo, hi) = (vec3(-0.8, 0.5, -0.6), vec3(0.2, 1.3, 0.4));
    let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
    let (x, y, z) = (
        vec3(h.x, 0.0, 0.0),
        vec3(0.0, h.y, 0.0),
        vec3(0.0, 0.0, h.z),
    );
    for (d, a, b) in [(x, y, z), (y, z, x), (z, x, y)] {
        quad(&mut s, c + d, a, b, m);
        quad(&mut s, c - d, b, a, m);
    }
    s.push(
        [
            vec3(0.6, 0.8, 0.2),
            vec3(1.6, 1.1, 0.4),
            vec3(1.0, 0.9, 1.4),
        ],
        m,
    );
    s.recompute_bounds();
    let eye = vec3(3.0, 3.5, 5.0);
    let mut cam = Camera::look_at(eye, vec3(0.0, 0.5, 0.0), 50.0, 160, 120);
    cam.fit_depth_range(&s.bounds);
    (s, cam, Light::Point { position: eye })
}

#[test]
fn point_light_on_the_camera_keeps_flat_ground_lit_in_csm_and_vsm() {
    use shadowlab::light::cube_face;
    use shadowlab::techniques::filtering::{
        DepthRange, FilterSettings, ReceiverDepths, MIN_RANGE_RELATIVE,
    };
    use shadowlab::techniques::shadow_map::render_light_maps;
    let (scene, cam, light) = point_light_at_the_eye();
    let view = ViewSamples::render(&scene, &cam);
    let frame = Frame::new(&scene, &cam, &light, &view);
    // The downward face's receivers are all ground at one light depth; its fitted interval
    // must still be wide against the depths' rounding.
    let maps = render_light_maps(&frame, 1024);
    let settings = FilterSettings::default();
    let receivers = ReceiverDepths::of_frame(&frame, &maps.views, &maps.maps, &settings);
    let down = cube_face(vec3(0.0, -1.0, 0.0));
    assert!(receivers[down].count > 1000, "{:?}", receivers[down]);
    for ((m, v), r) in maps.maps.iter().zip(&maps.views).zip(&receivers) {
        if r.count > 0 {
            let d = DepthRange::fitted(m, v, r, 1.0);
            assert!(
                d.far - d.near >= MIN_RANGE_RELATIVE * d.far.abs() * 0.999,
                "{r:?}: {d:?}"
            );
        }
    }
    let reference = Reference::build(&scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    assert!(reference.value.iter().all(|v| v.x == 1.0));
    for name in ["csm", "vsm"] {
        let vis = techniques::create(name)
            .unwrap()
            .render(&frame)
            .unwrap()
            .visibility;
        let mm = compare(&view, &vis, &reference).mismatch_rate;
        // Nothing is shadowed: only a few pixels along the box's and plate's contacts,
        // where the filters blend the caster's depth into the receiver's, may darken.
        assert!(mm <= 0.02, "{name}: mismatch {mm} with everything lit");
    }
}

#[test]
fn csm_defaults_keep_contact_shadows_on_the_chessboard() {
    // The chess set under its spot light, 480×360, against the 16-sample reference the
    // verdicts use: every piece stands on the board, so its shadow starts at a contact
    // point, where an occluder is closer to its receiver than the smooth step's width. The
    // defaults (M = 16, the step scaled by 2 about 0.1 with the small offset that needs) keep
    // those shadows; the offset alone (scale 1, Section 3.2.2's offsetting) fades them, and
    // lost to `vsm` here. Measured: csm 0.0073, offset alone 0.0096, vsm 0.0084, pcf 0.0093.
    let (scene, camera, light) = builtin("chessboard", 480, 360);
    let offset_only: &[(&str, &str)] = &[("scale", "1"), ("pivot", "0")];
    let r = measure_spp(
        &scene,
        &camera,
        &light,
        16,
        &[
            ("vsm", &[]),
            ("pcf", &[]),
            ("csm", &[]),
            ("csm", offset_only),
        ],
    );
    let (vsm, pcf, csm, offset_only) = (r[0].mae, r[1].mae, r[2].mae, r[3].mae);
    assert!(
        csm <= vsm && csm <= pcf,
        "csm {csm} vs vsm {vsm}, pcf {pcf}"
    );
    assert!(
        csm < 0.85 * offset_only,
        "csm {csm} vs the offset alone {offset_only}"
    );
}
