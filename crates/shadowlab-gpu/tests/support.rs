//! What the GPU crate's tests share: the device or a reason to skip, the library's scenes
//! at test sizes, and counts of differing pixels.

#![allow(dead_code)]

use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::scene::Scene;
use shadowlab::view::ViewSamples;

/// True when a GPU adapter is there. Without one, under `CI=true` the test fails (CI
/// installs lavapipe, so a missing adapter is a broken set-up); elsewhere it is skipped
/// with the reason printed.
pub fn have_gpu(test: &str) -> bool {
    match shadowlab_gpu::device::shared() {
        Ok(_) => true,
        Err(e) if std::env::var("CI").as_deref() == Ok("true") => {
            panic!("{test}: no GPU adapter under CI: {e}")
        }
        Err(e) => {
            eprintln!("{test}: skipped: {e}");
            false
        }
    }
}

/// A scene, its camera, its light and the camera pass.
pub type Set = (Scene, Camera, Light, ViewSamples);

/// The leaf quad of the library's `masked/leaf.gltf`: an alpha-masked caster.
pub fn leaf() -> Set {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shadowlab/assets/masked/leaf.gltf"
    );
    let s = shadowlab::scene::load(path, &Default::default()).unwrap();
    assert!(s.has_alpha_masks());
    framed(s, 128, 96, None)
}

/// A built-in scene with its camera resized to `w × h` and its depth range fitted, its
/// light (or `light` when given), and the camera pass.
pub fn builtin(name: &str, w: u32, h: u32, light: Option<Light>) -> Set {
    let s = shadowlab::scene::load(name, &Default::default()).unwrap();
    framed(s, w, h, light)
}

/// `scene` with its camera resized to `w × h`, its light (or `light`), and the camera pass.
pub fn framed(s: Scene, w: u32, h: u32, light: Option<Light>) -> Set {
    let mut c = s.camera.unwrap();
    (c.width, c.height) = (w, h);
    c.fit_depth_range(&s.bounds);
    let l = light.or(s.light).unwrap();
    let view = ViewSamples::render(&s, &c);
    (s, c, l, view)
}

/// Covered pixels whose RGB shadow terms differ at all, and covered pixels.
pub fn differing(
    view: &ViewSamples,
    a: &[shadowlab::math::Vec3],
    b: &[shadowlab::math::Vec3],
) -> (usize, usize) {
    let mut diff = 0;
    let mut covered = 0;
    for k in 0..a.len() {
        if view.covered(k) {
            covered += 1;
            if a[k] != b[k] {
                diff += 1;
            }
        }
    }
    (diff, covered)
}

/// A verdict's error allowance: the GPU technique's mean error against the reference may
/// differ from its CPU twin's by this share of the CPU's error …
pub const ERROR_FACTOR: f64 = 0.10;
/// … or by this much absolutely, whichever is larger (for errors near zero).
pub const ERROR_ABS: f64 = 0.0002;

/// The scenes every GPU technique is judged on: bunny and chessboard under their own
/// lights, room under a point light near its ceiling, and the alpha-masked leaf.
pub fn verdict_sets() -> Vec<(&'static str, Set)> {
    vec![
        ("bunny", builtin("bunny", 128, 96, None)),
        ("chessboard", builtin("chessboard", 128, 96, None)),
        ("room (point light)", room_point()),
        ("leaf (alpha mask)", leaf()),
    ]
}

/// `room` lit by a point light at 80% of its height, over its centre.
pub fn room_point() -> Set {
    let room = shadowlab::scene::load("room", &Default::default()).unwrap();
    let b = room.bounds;
    let c = b.center();
    let point = Light::Point {
        position: shadowlab::math::vec3(c.x, b.min.y + 0.8 * (b.max.y - b.min.y), c.z),
    };
    framed(room, 128, 96, Some(point))
}

/// What a verdict found, for tests that check more.
pub struct Verdict {
    /// The GPU technique's shadow terms.
    pub gpu: Vec<shadowlab::math::Vec3>,
    /// The CPU twin's.
    pub cpu: Vec<shadowlab::math::Vec3>,
    /// Mean absolute errors against the reference: GPU, CPU.
    pub errors: (f64, f64),
}

/// How a GPU technique's mean error may stand against its CPU twin's.
#[derive(Clone, Copy, PartialEq)]
enum Bound {
    /// Within [`ERROR_FACTOR`] of the twin's, or [`ERROR_ABS`], either way.
    Within,
    /// At most the twin's plus that margin; lower is allowed.
    NoWorse,
}

/// What every verdict does on `frame`: `gpu` and `cpu` made with `params` (`key=value`),
/// two GPU runs the same bits, their mean errors against `truth` held to `bound`, and (with
/// `shows`) the image showing shadow (more than 50 pixels under one half), so the test
/// means something.
fn judge(
    scene: &str,
    frame: &shadowlab::techniques::Frame,
    (gpu, cpu): (&str, &str),
    params: &[&str],
    truth: &shadowlab::frame::Visibility,
    (bound, shows): (Bound, bool),
) -> Verdict {
    shadowlab_gpu::register();
    let make = |name: &str| {
        let mut t = shadowlab::techniques::create(name).unwrap();
        for p in params {
            let (k, v) = p.split_once('=').unwrap();
            t.set_param(k, v).unwrap();
        }
        t
    };
    let a = make(gpu).render(frame).unwrap();
    let b = make(gpu).render(frame).unwrap();
    assert!(
        a.visibility.value == b.visibility.value,
        "{scene}: two runs of {gpu} differ"
    );
    let cpu_shadows = make(cpu).render(frame).unwrap();
    let view = frame.view;
    let eg = shadowlab::compare::compare(view, &a.visibility, truth).mean_abs_error;
    let ec = shadowlab::compare::compare(view, &cpu_shadows.visibility, truth).mean_abs_error;
    let margin = (ERROR_FACTOR * ec).max(ERROR_ABS);
    match bound {
        Bound::Within => assert!(
            (eg - ec).abs() <= margin,
            "{scene}: {gpu}'s error {eg} against the reference is not within 10% of {cpu}'s {ec} (or {ERROR_ABS})"
        ),
        Bound::NoWorse => assert!(
            eg <= ec + margin,
            "{scene}: {gpu}'s error {eg} against the reference is above {cpu}'s {ec} by more than 10% (or {ERROR_ABS})"
        ),
    }
    if shows {
        let shadowed = a.visibility.value.iter().filter(|v| v.x < 0.5).count();
        assert!(
            shadowed > 50,
            "{scene}: {gpu} has only {shadowed} shadowed pixels: the test shows nothing"
        );
    }
    Verdict {
        gpu: a.visibility.value,
        cpu: cpu_shadows.visibility.value,
        errors: (eg, ec),
    }
}

/// The reference of `set`'s frame at a grid of `spp` samples a pixel.
fn grid_reference(set: &Set, spp: u32) -> shadowlab::frame::Visibility {
    let (s, c, l, view) = (&set.0, &set.1, &set.2, &set.3);
    let frame = shadowlab::techniques::Frame::new(s, c, l, view);
    let pattern =
        shadowlab::sampling::pattern(shadowlab::sampling::PatternKind::Grid, spp).unwrap();
    shadowlab::reference::Reference::build(s).visibility(&frame, &pattern)
}

/// Judges `gpu` (a `gpu:` name) beside `cpu` on `set`, both with `params` (`key=value`):
/// two GPU runs give the same bits; the GPU's mean error against a reference of `spp`
/// samples a pixel is within [`ERROR_FACTOR`] of the CPU's or [`ERROR_ABS`]; and the
/// image shows shadow (more than 50 pixels under one half), so the test means something.
pub fn verdict(scene: &str, set: &Set, gpu: &str, cpu: &str, params: &[&str], spp: u32) -> Verdict {
    let frame = shadowlab::techniques::Frame::new(&set.0, &set.1, &set.2, &set.3);
    let truth = grid_reference(set, spp);
    judge(
        scene,
        &frame,
        (gpu, cpu),
        params,
        &truth,
        (Bound::Within, true),
    )
}

/// Judges `gpu` beside `cpu` under `scene`'s own area light (a built-in scene with one, at
/// 128 × 96), both with `params`: two GPU runs give the same bits, and the GPU's mean
/// error against the area-light reference of `samples` light samples a point is within
/// [`ERROR_FACTOR`] of the CPU's or [`ERROR_ABS`]. Returns the errors (GPU, CPU).
pub fn soft_verdict(
    scene: &str,
    gpu: &str,
    cpu: &str,
    params: &[&str],
    samples: u32,
) -> (f64, f64) {
    let set = builtin(scene, 128, 96, None);
    let area = set.0.area_light.expect("a scene with an area light");
    area_judge(scene, &set, &area, (gpu, cpu), params, samples, false).errors
}

/// [`verdict`] with a one-sided bound, for a GPU technique built differently from its CPU
/// twin so that it may well be more accurate: two GPU runs give the same bits, the image
/// shows shadow, and the GPU's mean error against a reference of `spp` samples a pixel is
/// at most the CPU's plus [`ERROR_FACTOR`] of it (or [`ERROR_ABS`]); lower is allowed.
pub fn verdict_no_worse(
    scene: &str,
    set: &Set,
    gpu: &str,
    cpu: &str,
    params: &[&str],
    spp: u32,
) -> Verdict {
    let frame = shadowlab::techniques::Frame::new(&set.0, &set.1, &set.2, &set.3);
    let truth = grid_reference(set, spp);
    judge(
        scene,
        &frame,
        (gpu, cpu),
        params,
        &truth,
        (Bound::NoWorse, true),
    )
}

/// [`verdict`] under `area`, the area light of `set`'s scene (whose stand-in `set`'s light
/// is): both techniques see the frame with the area light, and the reference is the soft
/// one integrating `n_light` light samples a pixel.
pub fn verdict_area(
    scene: &str,
    set: &Set,
    area: &shadowlab::area_light::AreaLight,
    pair: (&str, &str),
    params: &[&str],
    n_light: u32,
) -> Verdict {
    area_judge(scene, set, area, pair, params, n_light, true)
}

/// [`judge`] under `area` against the soft reference of `n_light` light samples a pixel.
fn area_judge(
    scene: &str,
    set: &Set,
    area: &shadowlab::area_light::AreaLight,
    pair: (&str, &str),
    params: &[&str],
    n_light: u32,
    shows: bool,
) -> Verdict {
    let (s, c, l, view) = (&set.0, &set.1, &set.2, &set.3);
    let frame = shadowlab::techniques::Frame::new(s, c, l, view).with_area(Some(area), n_light);
    let reference = shadowlab::soft_reference::soft_visibility(
        &shadowlab::reference::Reference::build(s),
        &frame,
        area,
        n_light,
        &[shadowlab::math::vec2(0.5, 0.5)],
    );
    judge(
        scene,
        &frame,
        pair,
        params,
        &reference.visibility,
        (Bound::Within, shows),
    )
}
