//! The GPU camera pass against the library's: the hardware G-buffer sees the same triangle
//! on nearly every covered pixel, at a position on that triangle; the pass left on the
//! device forms the library's samples from it, and the techniques run on it need nothing
//! of the samples on the CPU.

mod support;

use shadowlab::frame::Frame;
use shadowlab::raster::NO_TRIANGLE;
use shadowlab::view::ViewSamples;
use shadowlab_gpu::camera_pass;
use shadowlab_gpu::resident::DeviceView;
use shadowlab_gpu::transfer::read_back;
use shadowlab_gpu::upload::SceneBuffers;
use support::{builtin, have_gpu, leaf};

/// The share of the CPU pass's covered pixels on which the GPU's triangle may differ: the
/// hardware rasterizer rounds edges differently from the library's.
const SAME_TRIANGLE: f64 = 0.999;

#[test]
fn the_hardware_g_buffer_sees_the_cpu_pass_triangles() {
    if !have_gpu("the_hardware_g_buffer_sees_the_cpu_pass_triangles") {
        return;
    }
    let gpu = shadowlab_gpu::device::shared().unwrap();
    for name in ["bunny", "chessboard", "fence"] {
        let (s, c, _, view) = builtin(name, 320, 240, None);
        let buffers = SceneBuffers::new(&gpu, &s).unwrap();
        let g = shadowlab_gpu::camera_pass::render(&gpu, &buffers, s.len(), &c).unwrap();
        let mut covered = 0;
        let mut same = 0;
        for k in 0..view.triangle.len() {
            if view.covered(k) {
                covered += 1;
                if g.triangle[k] == view.triangle[k] {
                    same += 1;
                    // The position lies on the same plane as the CPU's, near it.
                    let d = (g.position[k] - view.position[k]).length();
                    let reach = view.dpdx[k].length() + view.dpdy[k].length() + 1e-4;
                    assert!(
                        d <= reach,
                        "{name}: pixel {k} is {d} from the CPU's position (reach {reach})"
                    );
                    assert!(
                        (g.normal[k] - view.normal[k]).length() < 1e-3,
                        "{name}: pixel {k}'s normal"
                    );
                }
            } else {
                assert!(g.triangle[k] == NO_TRIANGLE || g.triangle[k] < s.len() as u32);
            }
        }
        let share = same as f64 / covered as f64;
        assert!(covered > 1000, "{name}: {covered} covered pixels");
        assert!(
            share >= SAME_TRIANGLE,
            "{name}: the GPU pass sees the CPU pass's triangle on {same} of {covered} covered pixels ({:.4}%)",
            share * 100.0
        );
    }
}

#[test]
fn the_pass_on_the_device_forms_the_samples_as_the_library_does() {
    if !have_gpu("the_pass_on_the_device_forms_the_samples_as_the_library_does") {
        return;
    }
    let gpu = shadowlab_gpu::device::shared().unwrap();
    // An odd size too: the last workgroup's pixels run past the image.
    let sets = [
        ("bunny", builtin("bunny", 317, 239, None)),
        ("chessboard", builtin("chessboard", 320, 240, None)),
        ("leaf (alpha mask)", leaf()),
    ];
    for (name, (s, c, _, view)) in sets {
        let buffers = SceneBuffers::new(&gpu, &s).unwrap();
        let (dv, _) = camera_pass::on_device(&gpu, &buffers, s.len(), &c).unwrap();
        let g = camera_pass::read_view(&gpu, &dv, &c).unwrap();
        // The summary read back is the read-back samples' own, bit for bit.
        assert_eq!(dv.covered, g.covered_count() as u64, "{name}");
        let (a, b) = (dv.receivers, g.receiver_bounds());
        assert_eq!(
            (a.min.to_array(), a.max.to_array()),
            (b.min.to_array(), b.max.to_array()),
            "{name}: the receivers' bounds"
        );
        let (mut covered, mut same) = (0, 0);
        for k in 0..view.triangle.len() {
            if !view.covered(k) {
                continue;
            }
            covered += 1;
            if g.triangle[k] != view.triangle[k] {
                continue;
            }
            same += 1;
            // The same ray met with the same plane, the same way: the points agree within
            // their error bounds (the GPU's compiler may fuse multiply-adds), the bounds
            // themselves to 1%, the normals to rounding.
            for i in 0..3 {
                let d = (g.position[k][i] - view.position[k][i]).abs();
                let reach = g.position_error[k][i] + view.position_error[k][i];
                assert!(
                    d <= reach,
                    "{name}: pixel {k} axis {i}: {d} apart, bounds {reach}"
                );
                let (e, f) = (g.position_error[k][i], view.position_error[k][i]);
                assert!((e - f).abs() <= 0.01 * f, "{name}: pixel {k}'s bound");
            }
            assert!(
                (g.normal[k] - view.normal[k]).length() < 1e-5,
                "{name}: pixel {k}'s normal"
            );
        }
        assert!(covered > 1000, "{name}: {covered} covered pixels");
        let share = same as f64 / covered as f64;
        assert!(
            share >= SAME_TRIANGLE,
            "{name}: the GPU's samples see the CPU's triangle on {same} of {covered} covered pixels"
        );
    }
}

/// Every technique that can run on a pass left on the device gives the same bits there as
/// on those samples read back and uploaded with the library's data beside them: nothing
/// it computes reads the frame's per-pixel samples on the CPU.
#[test]
fn techniques_on_the_device_need_no_samples_on_the_cpu() {
    if !have_gpu("techniques_on_the_device_need_no_samples_on_the_cpu") {
        return;
    }
    let gpu = shadowlab_gpu::device::shared().unwrap();
    let (s, c, l, _) = builtin("chessboard", 160, 120, None);
    let buffers = SceneBuffers::new(&gpu, &s).unwrap();
    let (dv, _) = camera_pass::on_device(&gpu, &buffers, s.len(), &c).unwrap();
    let read = camera_pass::read_view(&gpu, &dv, &c).unwrap();
    let uploaded = DeviceView::upload(&gpu, &read).unwrap();
    let empty = ViewSamples::unsampled(&c);
    let terms = |t: &mut dyn shadowlab_gpu::resident::OnDevice, f: &Frame, v: &DeviceView| {
        let out = t.render_on_device(f, v).unwrap();
        read_back(&gpu, &out.visibility, u64::from(v.pixels()) * 12).unwrap()
    };
    let mut ran = 0;
    for name in shadowlab_gpu::techniques::ALL {
        let Some(mut t) = shadowlab_gpu::techniques::create_on_device(name) else {
            continue;
        };
        if t.needs_cpu_samples() {
            continue;
        }
        let on_device = terms(t.as_mut(), &Frame::new(&s, &c, &l, &empty), &dv);
        let with_cpu = terms(t.as_mut(), &Frame::new(&s, &c, &l, &read), &uploaded);
        assert!(on_device == with_cpu, "{name}: the shadow terms differ");
        ran += 1;
    }
    assert!(ran >= 5, "only {ran} techniques ran on the device's pass");
}
