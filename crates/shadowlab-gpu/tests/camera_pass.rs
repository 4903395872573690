//! The GPU camera pass against the library's: the hardware G-buffer sees the same triangle
//! on nearly every covered pixel, at a position on that triangle.

mod support;

use shadowlab::raster::NO_TRIANGLE;
use shadowlab_gpu::upload::SceneBuffers;
use support::{builtin, have_gpu};

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
