//! `gpu:subpixel` against the library's `subpixel` on the verdict scenes at the paper's 32
//! samples a pixel, judged against the reference at the same sub-pixel positions (a grid
//! of as many samples, as the library's own tests judge `subpixel`); the same bits on two
//! runs; and few pixels apart from the CPU twin.

mod support;

use support::{have_gpu, verdict, verdict_sets};

/// The share of covered pixels whose shadow terms may differ from the CPU twin's by more
/// than one sample's share: the depth map is the hardware rasterizer's (the non-silhouette
/// pixels' test and the hidden-silhouette test see its rounding, as `gpu:sm` does), and a
/// GPU may fuse a facet's or a half-plane's products, which can move a sample lying on a
/// shadow edge, or a caster standing on the receiver across a crease test, to the other
/// side. Measured on lavapipe: 0 pixels on every verdict scene, at 32 and at 128 samples;
/// the allowance is for other adapters' rounding. (Before the work was cut into short
/// invocations, chessboard had 107 such pixels at 32 samples and 216 at 128: the ground
/// plane's pairs and a busy facet's last blockers were lost to llvmpipe's loop count.)
const DIFFER_SHARE: f64 = 0.002;

fn check(samples: u32, only: Option<&str>) {
    for (name, set) in verdict_sets() {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let p = format!("samples={samples}");
        let v = verdict(name, &set, "gpu:subpixel", "subpixel", &[&p], samples);
        let one = 1.0 / samples as f32 + 1e-6;
        let view = &set.3;
        let mut differ = 0;
        let mut covered = 0;
        for k in 0..v.gpu.len() {
            if view.covered(k) {
                covered += 1;
                if (v.gpu[k] - v.cpu[k]).abs().max_element() > one {
                    differ += 1;
                }
            }
        }
        eprintln!(
            "{name} at {samples}: errors gpu {:.5}, cpu {:.5}; {differ} of {covered} pixels apart by more than a sample",
            v.errors.0, v.errors.1
        );
        let allowed = (covered as f64 * DIFFER_SHARE).ceil() as usize;
        assert!(
            differ <= allowed,
            "{name}: gpu:subpixel differs from subpixel on {differ} of {covered} covered pixels (at most {allowed})"
        );
    }
}

#[test]
fn gpu_subpixel_matches_its_cpu_twin_at_32_samples() {
    if !have_gpu("gpu_subpixel_matches_its_cpu_twin_at_32_samples") {
        return;
    }
    check(32, None);
}

/// At 128 samples every word of the 128-bit masks is in use; chessboard's pieces stand on
/// a board over a table plane larger than the light's map, whose pairs need the blocks of
/// rows, and its facets over the finely tessellated pieces need the chunked evaluation.
#[test]
fn gpu_subpixel_matches_its_cpu_twin_at_128_samples_on_chessboard() {
    if !have_gpu("gpu_subpixel_matches_its_cpu_twin_at_128_samples_on_chessboard") {
        return;
    }
    check(128, Some("chessboard"));
}
