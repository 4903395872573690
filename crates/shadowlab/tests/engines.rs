//! The techniques engines ship (`cascaded`, `lispsm`, `evsm`, `msm`) measured against the
//! ray-traced reference on the same camera pass as the papers' techniques.

use shadowlab::compare::{compare, Metrics};
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::{self, Frame, Visibility};
use shadowlab::view::ViewSamples;

/// A built-in scene's frame at `w × h` and its one-ray-per-pixel reference.
struct Setup {
    scene: shadowlab::scene::Scene,
    camera: shadowlab::camera::Camera,
    light: shadowlab::light::Light,
    view: ViewSamples,
}

impl Setup {
    fn new(name: &str, w: u32, h: u32) -> Self {
        let scene = shadowlab::scene::load(name, &Default::default()).unwrap();
        let mut camera = scene.camera.unwrap();
        (camera.width, camera.height) = (w, h);
        camera.fit_depth_range(&scene.bounds);
        let light = scene.light.unwrap();
        let view = ViewSamples::render(&scene, &camera);
        Setup {
            scene,
            camera,
            light,
            view,
        }
    }

    fn frame(&self) -> Frame<'_> {
        Frame::new(&self.scene, &self.camera, &self.light, &self.view)
    }

    fn reference(&self, spp: u32) -> Visibility {
        let samples = if spp <= 1 {
            vec![vec2(0.5, 0.5)]
        } else {
            pattern(PatternKind::Grid, spp).unwrap()
        };
        Reference::build(&self.scene).visibility(&self.frame(), &samples)
    }

    fn run(&self, name: &str, params: &[(&str, &str)]) -> Visibility {
        let mut t = techniques::create(name).unwrap();
        for (k, v) in params {
            t.set_param(k, v).unwrap();
        }
        t.render(&self.frame()).unwrap().visibility
    }

    fn metrics(&self, name: &str, params: &[(&str, &str)], reference: &Visibility) -> Metrics {
        compare(&self.view, &self.run(name, params), reference)
    }
}

#[test]
fn cascaded_on_the_street_has_at_most_a_quarter_of_sm_mismatch() {
    let s = Setup::new("street", 1024, 768);
    let r = s.reference(1);
    let sm = s.metrics("sm", &[("resolution", "2048")], &r);
    let cascaded = s.metrics("cascaded", &[("resolution", "2048"), ("cascades", "4")], &r);
    eprintln!(
        "street: sm {:.4}% cascaded {:.4}%",
        sm.mismatch_rate * 100.0,
        cascaded.mismatch_rate * 100.0
    );
    assert!(
        cascaded.mismatch_rate <= 0.25 * sm.mismatch_rate,
        "cascaded {} vs sm {}",
        cascaded.mismatch_rate,
        sm.mismatch_rate
    );
}

#[test]
fn vsm_leaks_on_the_leak_scene_and_evsm_msm_do_less() {
    let s = Setup::new("fence-leak", 512, 384);
    // Filtered techniques against a 16-sample reference (its own error against the exact
    // area average is that of a 4×4 grid: at most 1/16 per edge-crossing pixel).
    let r = s.reference(16);
    let leak = |v: &Visibility| {
        // The mean light let through where the reference is fully shadowed (VSM's leaks
        // are partial: a faint light inside the shadow, not a flipped pixel).
        let (mut n, mut sum) = (0usize, 0f64);
        for k in 0..v.value.len() {
            if s.view.covered(k) && s.frame().receiver_lit(k) && r.value[k].x <= 0.0 {
                n += 1;
                sum += v.value[k].x as f64;
            }
        }
        sum / n.max(1) as f64
    };
    let vsm = s.run("vsm", &[]);
    let evsm = s.run("evsm", &[]);
    let msm = s.run("msm", &[]);
    let csm = s.run("csm", &[]);
    let err = |v: &Visibility| compare(&s.view, v, &r).mean_abs_error;
    eprintln!(
        "fence-leak leak share: vsm {:.4} evsm {:.4} msm {:.4} csm {:.4}; mean error vsm {:.4} evsm {:.4} msm {:.4} csm {:.4}",
        leak(&vsm), leak(&evsm), leak(&msm), leak(&csm), err(&vsm), err(&evsm), err(&msm), err(&csm)
    );
    assert!(
        leak(&vsm) > 0.001,
        "vsm does not leak visibly: {}",
        leak(&vsm)
    );
    assert!(leak(&evsm) < leak(&vsm) && leak(&msm) < leak(&vsm));
    assert!(
        err(&evsm) < err(&vsm),
        "evsm {} vs vsm {}",
        err(&evsm),
        err(&vsm)
    );
    assert!(
        err(&msm) < err(&vsm),
        "msm {} vs vsm {}",
        err(&msm),
        err(&vsm)
    );
}

#[test]
fn msm_at_16_bits_is_within_a_thousandth_of_its_f32_version() {
    for scene in ["fence-leak", "chessboard"] {
        let s = Setup::new(scene, 512, 384);
        let r = s.reference(1);
        let q16 = s.metrics("msm", &[("bits", "16")], &r).mean_abs_error;
        let q32 = s.metrics("msm", &[("bits", "32")], &r).mean_abs_error;
        eprintln!("{scene}: msm 16-bit {q16:.5}, f32 {q32:.5}");
        assert!((q16 - q32).abs() <= 1e-3, "{scene}: {q16} vs {q32}");
    }
}

#[test]
fn lispsm_with_a_huge_n_matches_a_uniform_map_and_n_opt_beats_it() {
    let s = Setup::new("street", 512, 384);
    let r = s.reference(1);
    let opt = s.metrics("lispsm", &[("resolution", "1024")], &r);
    let uniform = s.metrics("lispsm", &[("resolution", "1024"), ("n", "1e9")], &r);
    let sm = s.metrics("sm", &[("resolution", "1024")], &r);
    eprintln!(
        "street: lispsm n_opt {:.4}%, n = 1e9 {:.4}%, sm {:.4}%",
        opt.mismatch_rate * 100.0,
        uniform.mismatch_rate * 100.0,
        sm.mismatch_rate * 100.0
    );
    assert!(opt.mismatch_rate < uniform.mismatch_rate);
    assert!(opt.mismatch_rate < sm.mismatch_rate);
}

#[test]
fn engine_techniques_fall_back_or_run_for_every_light_kind_and_are_thread_independent() {
    let s = Setup::new("chessboard", 256, 192);
    for name in ["cascaded", "lispsm", "evsm", "msm"] {
        let a = s.run(name, &[("resolution", "512")]);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| s.run(name, &[("resolution", "512")]));
        assert_eq!(a, b, "{name} depends on the thread count");
        assert!(a
            .value
            .iter()
            .all(|v| v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0));
    }
}
