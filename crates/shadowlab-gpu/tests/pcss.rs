//! `gpu:pcss` against the library's `pcss` on the verdict scenes under their punctual
//! lights (a light of no width: the narrowest kernel) and under area lights (`penumbra`'s
//! rectangle, `room-soft`'s light and the bunny's sun given a width), where the blocker
//! search and the penumbra estimate size the kernel; the same bits on two runs.

mod support;

use shadowlab::area_light::AreaLight;
use support::{builtin, have_gpu, verdict, verdict_area, verdict_sets};

/// Reference samples a pixel under punctual lights, as `gpu:pcf`'s verdict uses: PCSS
/// under a light of no width filters over a texel, as PCF does.
const SPP: u32 = 16;

/// Light samples of the soft reference, as the library's soft-shadow tests take.
const LIGHT_SAMPLES: u32 = 256;

/// The share of covered pixels whose shadow terms may differ from the CPU twin's by more
/// than [`TERM_DIFFERENCE`]: the hardware rasterizer rounds coverage and depth differently
/// from the library's on a few edge texels, and a blocker found or missed there moves a
/// whole penumbra's kernel.
const DIFFER_SHARE: f64 = 5e-4;

/// A pixel differs when its shadow terms are this far apart: the hardware's bilinear
/// weights are quantized (8 bits of sub-texel position on many adapters, so each tap's
/// weight is off by at most 1/256 and the kernel's mean likewise), and the blocker depths
/// averaged in `f32` move a penumbra's radius by rounding.
const TERM_DIFFERENCE: f32 = 1.0 / 32.0;

fn close_to_twin(scene: &str, view: &shadowlab::view::ViewSamples, v: &support::Verdict) {
    let mut differ = 0;
    let mut covered = 0;
    for k in 0..v.gpu.len() {
        if view.covered(k) {
            covered += 1;
            if (v.gpu[k] - v.cpu[k]).abs().max_element() > TERM_DIFFERENCE {
                differ += 1;
            }
        }
    }
    let allowed = (covered as f64 * DIFFER_SHARE).ceil() as usize;
    let max = (0..v.gpu.len())
        .map(|k| (v.gpu[k] - v.cpu[k]).abs().max_element())
        .fold(0.0f32, f32::max);
    eprintln!("{scene}: {differ} of {covered} pixels differ by more than {TERM_DIFFERENCE}; largest difference {max}");
    assert!(
        differ <= allowed,
        "{scene}: gpu:pcss differs from pcss on {differ} of {covered} covered pixels (at most {allowed})"
    );
}

#[test]
fn gpu_pcss_matches_its_cpu_twin_under_punctual_lights() {
    if !have_gpu("gpu_pcss_matches_its_cpu_twin_under_punctual_lights") {
        return;
    }
    for (name, set) in verdict_sets() {
        let v = verdict(name, &set, "gpu:pcss", "pcss", &[], SPP);
        eprintln!(
            "{name}: errors gpu {:.5}, cpu {:.5}",
            v.errors.0, v.errors.1
        );
        close_to_twin(name, &set.3, &v);
    }
}

#[test]
fn gpu_pcss_matches_its_cpu_twin_under_area_lights() {
    if !have_gpu("gpu_pcss_matches_its_cpu_twin_under_area_lights") {
        return;
    }
    let penumbra = builtin("penumbra", 128, 96, None);
    let room = builtin("room-soft", 128, 96, None);
    let mut bunny = builtin("bunny", 128, 96, None);
    let sun = AreaLight::sized(&bunny.2, 3.0).unwrap();
    bunny.0.area_light = Some(sun);
    for (name, set) in [
        ("penumbra", &penumbra),
        ("room-soft", &room),
        ("bunny (3° sun)", &bunny),
    ] {
        let area = set.0.area_light.expect("an area light");
        let v = verdict_area(name, set, &area, ("gpu:pcss", "pcss"), &[], LIGHT_SAMPLES);
        eprintln!(
            "{name}: errors gpu {:.5}, cpu {:.5}",
            v.errors.0, v.errors.1
        );
        close_to_twin(name, &set.3, &v);
    }
}
