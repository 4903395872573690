//! What the library's integration tests share: the meshes it carries, a fresh folder per
//! test, a scene loaded from a path, the three test lights (one of each kind) placed from a
//! scene's bounds, and a bit-for-bit comparison of shadow terms that leaves an error image
//! behind when it fails.

// Each test file uses the part it needs.
#![allow(dead_code)]

use shadowlab::frame::Visibility;
use shadowlab::light::Light;
use shadowlab::math::vec3;
use shadowlab::scene::Scene;
use std::path::{Path, PathBuf};

/// A file under `crates/shadowlab/assets`.
pub fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/assets")).join(name)
}

/// A fresh, empty folder for one test, named after the test file, this process and
/// `test`.
pub fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "shadowlab-{}-{}-{test}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The scene at `path`, with no scene parameters.
pub fn load(path: &Path) -> shadowlab::Result<Scene> {
    shadowlab::auto_light::load(path.to_str().unwrap(), &Default::default())
}

/// Directional, spot and point lights placed from the scene's bounds: the spot shines from
/// above at an angle, the point light hangs low over the scene's centre so that its
/// samples spread over several cube faces.
pub fn lights_for(scene: &Scene) -> Vec<Light> {
    let b = scene.bounds;
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

/// Where comparisons that fail leave their error images: `target/test-failures/`.
pub fn failures_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("the target folder")
        .join("test-failures");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The error image of two shadow terms: black where they agree, red where `a` is lighter,
/// blue where it is darker, brighter for larger differences (√ of the largest channel
/// difference; any difference at all shows).
pub fn error_image(a: &Visibility, b: &Visibility) -> image::RgbImage {
    image::RgbImage::from_fn(a.width, a.height, |x, y| {
        let k = (y * a.width + x) as usize;
        let d = a.value[k] - b.value[k];
        let big = [d.x, d.y, d.z]
            .into_iter()
            .fold(0.0f32, |m, v| if v.abs() > m.abs() { v } else { m });
        let v =
            if a.value[k].to_array().map(f32::to_bits) == b.value[k].to_array().map(f32::to_bits) {
                0
            } else {
                (big.abs().sqrt().min(1.0) * 255.0).max(32.0) as u8
            };
        if big > 0.0 {
            image::Rgb([v, 0, 0])
        } else {
            image::Rgb([0, 0, v])
        }
    })
}

/// Asserts two shadow terms are equal bit for bit; when they are not, writes their error
/// image into [`failures_dir`] as `<what>.png` and names it in the failure.
pub fn assert_same_visibility(what: &str, a: &Visibility, b: &Visibility) {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "{what}: the shadow terms differ in size"
    );
    let bits = |v: &Visibility, k: usize| v.value[k].to_array().map(f32::to_bits);
    let differ: Vec<usize> = (0..a.value.len())
        .filter(|&k| bits(a, k) != bits(b, k))
        .collect();
    if differ.is_empty() {
        return;
    }
    let name: String = what
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let path = failures_dir().join(format!("{name}.png"));
    let written = error_image(a, b).save(&path);
    eprintln!("{what}: error image in {}", path.display());
    let k = differ[0];
    panic!(
        "{what}: {} of {} pixels differ (the first, pixel {k}: {:?} against {:?}); error image: {}{}",
        differ.len(),
        a.value.len(),
        a.value[k],
        b.value[k],
        path.display(),
        written.err().map(|e| format!(" (not written: {e})")).unwrap_or_default()
    );
}
