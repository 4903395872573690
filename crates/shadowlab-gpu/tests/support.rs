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
