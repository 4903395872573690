//! `gpu:sm` and `gpu:pcf` against their CPU twins on the library's scenes: the same light
//! views, bias and kernel, the map drawn by the hardware rasterizer; the same bits on two
//! runs.

mod support;

use shadowlab::compare::compare;
use shadowlab::math::Vec3;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::{self, Frame};
use support::{builtin, have_gpu, Set, ERROR_ABS, ERROR_FACTOR};

/// The share of covered pixels on which a GPU map may differ from its CPU twin: the
/// hardware rasterizer rounds coverage and depth differently from the library's on a few
/// edge texels.
const DIFFER_SHARE: f64 = 5e-4;

/// A PCF pixel differs when its shadow terms are this far apart: the hardware's bilinear
/// weights are quantized (8 bits of sub-texel position on many adapters, so a tap's weight
/// is off by at most 1/256 and the kernel's mean likewise).
const PCF_DIFFERENCE: f32 = 1.0 / 64.0;

fn check(name: &str, set: &Set, technique: &str) {
    shadowlab_gpu::register();
    let (s, c, l, view) = (&set.0, &set.1, &set.2, &set.3);
    let frame = Frame::new(s, c, l, view);
    let gpu_name = format!("gpu:{technique}");
    let a = techniques::create(&gpu_name)
        .unwrap()
        .render(&frame)
        .unwrap();
    let b = techniques::create(&gpu_name)
        .unwrap()
        .render(&frame)
        .unwrap();
    assert_eq!(
        a.visibility.value, b.visibility.value,
        "{name} {gpu_name}: two runs differ"
    );
    let cpu = techniques::create(technique)
        .unwrap()
        .render(&frame)
        .unwrap();
    let tol = if technique == "pcf" {
        PCF_DIFFERENCE
    } else {
        0.0
    };
    let mut differ = 0;
    let mut covered = 0;
    for k in 0..view.triangle.len() {
        if view.covered(k) {
            covered += 1;
            let d: Vec3 = a.visibility.value[k] - cpu.visibility.value[k];
            if d.abs().max_element() > tol {
                differ += 1;
            }
        }
    }
    let allowed = (covered as f64 * DIFFER_SHARE).ceil() as usize;
    assert!(
        differ <= allowed,
        "{name}: {gpu_name} differs from {technique} on {differ} of {covered} covered pixels (at most {allowed})"
    );
    let spp = if technique == "pcf" { 16 } else { 1 };
    let reference =
        Reference::build(s).visibility(&frame, &pattern(PatternKind::Grid, spp).unwrap());
    let eg = compare(view, &a.visibility, &reference).mean_abs_error;
    let ec = compare(view, &cpu.visibility, &reference).mean_abs_error;
    assert!(
        (eg - ec).abs() <= (ERROR_FACTOR * ec).max(ERROR_ABS),
        "{name}: {gpu_name}'s error {eg} against the reference is not within 10% of {technique}'s {ec}"
    );
    let shadowed = a.visibility.value.iter().filter(|v| v.x < 0.5).count();
    assert!(
        shadowed > 50,
        "{name}: only {shadowed} shadowed pixels: the test shows nothing"
    );
}

#[test]
fn gpu_sm_and_pcf_match_their_cpu_twins() {
    if !have_gpu("gpu_sm_and_pcf_match_their_cpu_twins") {
        return;
    }
    let sets = [
        ("bunny", builtin("bunny", 128, 96, None)),
        ("chessboard", builtin("chessboard", 128, 96, None)),
        ("room (point light)", support::room_point()),
        ("leaf (alpha mask)", support::leaf()),
    ];
    for (name, set) in &sets {
        check(name, set, "sm");
        check(name, set, "pcf");
    }
}
