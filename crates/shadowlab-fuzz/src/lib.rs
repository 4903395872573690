//! Fuzz harnesses: each takes arbitrary bytes and drives one entry point of shadowlab the
//! way a user's file or a script would, asserting only what must hold for *any* input —
//! no panic, no hang, no unbounded allocation, and results that are finite and in range.
//!
//! The coverage-guided targets in `fuzz/` (cargo fuzz, libFuzzer) call these functions;
//! the test suite replays the kept corpus and every crash case through them.

#![forbid(unsafe_code)]

use shadowlab::auto_light;
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{Material, Scene};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::{ViewLayers, ViewSamples};
use std::path::PathBuf;

/// The file kinds the loader harness feeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// PLY, ASCII or binary.
    Ply,
    /// glTF 2.0, JSON or binary (chosen by the GLB magic).
    Gltf,
    /// The TOML scene format.
    Toml,
}

fn scratch_path(ext: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowlab-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    dir.join(format!("input.{ext}"))
}

/// Writes `data` as a file of `format` and loads it through [`auto_light::load`], exactly as
/// the command line does. A loaded scene must be valid and finite.
pub fn load(format: Format, data: &[u8]) {
    let ext = match format {
        Format::Obj => "obj",
        Format::Ply => "ply",
        Format::Gltf if data.starts_with(b"glTF") => "glb",
        Format::Gltf => "gltf",
        Format::Toml => "toml",
    };
    let path = scratch_path(ext);
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(s) = auto_light::load(
        path.to_str().expect("temp paths are UTF-8"),
        &Default::default(),
    ) {
        s.validate()
            .expect("auto_light::load returns validated scenes");
        assert!(s.bounds.min.is_finite() && s.bounds.max.is_finite());
    }
}

/// Reads bytes as a stream of small numbers.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((b, rest)) => {
                self.0 = rest;
                *b
            }
            None => 0,
        }
    }
    /// A coordinate in about [-4, 4], with rare special values that break naive code.
    fn coord(&mut self) -> f32 {
        let hi = self.byte();
        let lo = self.byte();
        match hi {
            255 => f32::NAN,
            254 => f32::INFINITY,
            253 => 1e30,
            252 => 0.0,
            _ => (i16::from_le_bytes([lo, hi]) as f32) / 8192.0,
        }
    }
    fn vec(&mut self) -> Vec3 {
        vec3(self.coord(), self.coord(), self.coord())
    }
}

/// A tiny random scene, camera and light from `data`, run through every technique at a
/// small resolution. Invalid set-ups must be refused with an error; valid ones must give
/// a shadow term in `[0, 1]` for every technique, and the reference must agree with
/// itself.
pub fn pipeline(data: &[u8]) {
    let mut b = Bytes(data);
    let n = 1 + b.byte() as usize % 12;
    let mut s = Scene::new("fuzz");
    let opaque = s.add_material(Material::default());
    let glass = s.add_material(Material {
        name: "glass".into(),
        color: Vec3::ONE,
        transmittance: vec3(0.5, 0.7, 0.9),
        alpha_mask: None,
    });
    // Always a floor, so there is something to receive shadows.
    s.push(
        [
            vec3(-4.0, -1.0, -4.0),
            vec3(-4.0, -1.0, 4.0),
            vec3(4.0, -1.0, 4.0),
        ],
        opaque,
    );
    s.push(
        [
            vec3(-4.0, -1.0, -4.0),
            vec3(4.0, -1.0, 4.0),
            vec3(4.0, -1.0, -4.0),
        ],
        opaque,
    );
    for _ in 0..n {
        let m = if b.byte() % 4 == 0 { glass } else { opaque };
        let t = [b.vec(), b.vec(), b.vec()];
        s.push(t, m);
    }
    let w = 4 + b.byte() as u32 % 40;
    let h = 4 + b.byte() as u32 % 30;
    let mut camera = Camera::look_at(b.vec() * 3.0, b.vec(), 10.0 + b.byte() as f32 * 0.6, w, h);
    let light = match b.byte() % 3 {
        0 => Light::Directional { to_light: b.vec() },
        1 => Light::Point {
            position: b.vec() * 2.0,
        },
        _ => Light::Spot {
            position: b.vec() * 2.0,
            target: b.vec(),
            fov_deg: 1.0 + b.byte() as f32 * 0.7,
        },
    };
    let technique = techniques::ALL[b.byte() as usize % techniques::ALL.len()];
    if s.validate().is_err() || light.validate().is_err() {
        return;
    }
    let light = light.normalized();
    camera.fit_depth_range(&s.bounds);
    if camera.validate().is_err() {
        return;
    }
    let view = ViewSamples::render(&s, &camera);
    let layers = ViewLayers::render(&s, &camera, &view).expect("a tiny scene has few layers");
    let frame = Frame::new(&s, &camera, &light, &view).with_layers(&layers);
    let mut t = techniques::create(technique).expect("every listed technique exists");
    // Small maps keep each run fast; the parameter is optional for techniques without it.
    let _ = t.set_param("resolution", "64");
    let out = t
        .render(&frame)
        .unwrap_or_else(|e| panic!("{technique} failed on a valid scene: {e}"));
    assert_eq!(out.visibility.value.len(), (w * h) as usize);
    for v in &out.visibility.value {
        assert!(
            v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
            "{technique}: visibility {v} out of range"
        );
    }
    if let Some(l) = &out.layers {
        assert_eq!(l.len(), layers.len());
        for v in l {
            assert!(
                v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
                "{technique}: layer visibility {v} out of range"
            );
        }
    }
    let r = Reference::build(&s).visibility(&frame, &[shadowlab::math::vec2(0.5, 0.5)]);
    for (k, v) in r.value.iter().enumerate() {
        assert!(
            v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
            "reference pixel {k}: {v}"
        );
    }
}
