//! Shadow techniques: the interface every algorithm implements, the frame they read and
//! the result they return.
//!
//! A technique gets a [`Frame`] — scene, camera, light and the shared camera pass — and
//! returns [`Shadows`]: a per-pixel RGB transmittance towards the light (1 = lit) and
//! [`Stats`]. Techniques are `&mut self` so progressive ones keep state between frames.
//! All of them share [`Light::illuminates`]: a pixel whose viewed side faces away from
//! the light, or lies outside a spot light's cone, is unlit (0) in every technique and in
//! the reference alike.

pub mod adaptive;
pub mod alias_free;
pub mod cascaded;
pub mod convolution;
pub mod filtering;
pub mod lispsm;
pub mod moments;
pub mod perspective;
pub mod raytrace;
pub mod shadow_map;
pub mod subpixel;
pub mod variance;

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::Vec3;
use crate::scene::Scene;
use crate::view::{ViewLayers, ViewSamples};
use std::collections::BTreeMap;
use std::path::Path;

/// Everything a technique may read to shade one frame.
#[derive(Clone, Copy)]
pub struct Frame<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The camera of this frame.
    pub camera: &'a Camera,
    /// The light.
    pub light: &'a Light,
    /// The camera pass.
    pub view: &'a ViewSamples,
    /// Frame number within a sequence (0 for a still).
    pub index: usize,
    /// Where to write intermediate images, when asked for.
    pub dump_dir: Option<&'a Path>,
    /// The surfaces behind semi-transparent nearest surfaces, when the caller wants them
    /// shaded too (see [`ViewLayers`]); techniques that support them return their shadow
    /// terms in [`Shadows::layers`].
    pub layers: Option<&'a ViewLayers>,
}

impl<'a> Frame<'a> {
    /// A still frame.
    pub fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        light: &'a Light,
        view: &'a ViewSamples,
    ) -> Self {
        Frame {
            scene,
            camera,
            light,
            view,
            index: 0,
            dump_dir: None,
            layers: None,
        }
    }

    /// The same frame, with the layers behind its semi-transparent surfaces to shade.
    pub fn with_layers(self, layers: &'a ViewLayers) -> Self {
        Frame {
            layers: Some(layers),
            ..self
        }
    }

    /// True when pixel `k` shows a surface that the light can reach if nothing is in the
    /// way (see [`Light::illuminates`]).
    #[inline]
    pub fn receiver_lit(&self, k: usize) -> bool {
        self.view.covered(k)
            && self
                .light
                .illuminates(self.view.position[k], self.view.normal[k])
    }

    /// True when layer sample `i` of [`Frame::layers`] faces the light (see
    /// [`Light::illuminates`]).
    #[inline]
    pub fn layer_lit(&self, layers: &ViewLayers, i: usize) -> bool {
        self.light.illuminates(layers.position[i], layers.normal[i])
    }
}

/// Per-pixel RGB transmittance towards the light, row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Visibility {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Transmittance per pixel in `[0, 1]³` (1 = lit); uncovered pixels hold 1.
    pub value: Vec<Vec3>,
}

impl Visibility {
    /// A visibility of `width × height` pixels, all lit.
    pub fn lit(width: u32, height: u32) -> Self {
        Visibility {
            width,
            height,
            value: vec![Vec3::ONE; width as usize * height as usize],
        }
    }
}

/// What a technique measured about its own work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Wall time of each stage in milliseconds, in the order the stages ran.
    pub stages_ms: Vec<(String, f64)>,
    /// Bytes held by the technique's own structures (maps, trees, tables).
    pub memory_bytes: u64,
    /// Named counters (nodes visited, texels, evaluations, …).
    pub counters: BTreeMap<String, f64>,
}

impl Stats {
    /// Runs `f` as the stage `name`, recording its wall time.
    pub fn stage<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = std::time::Instant::now();
        let r = f();
        self.stages_ms
            .push((name.to_string(), t0.elapsed().as_secs_f64() * 1e3));
        r
    }

    /// Sets a counter.
    pub fn count(&mut self, name: &str, value: f64) {
        self.counters.insert(name.to_string(), value);
    }
}

/// The result of one technique on one frame.
#[derive(Clone, Debug)]
pub struct Shadows {
    /// The shadow term.
    pub visibility: Visibility,
    /// Timings, memory and counters.
    pub stats: Stats,
    /// The shadow term of every layer sample of [`Frame::layers`], in its order; `None`
    /// when the frame has no layers or the technique shades only the nearest surface.
    pub layers: Option<Vec<Vec3>>,
}

impl Shadows {
    /// The result of a technique that shades the nearest surface of each pixel only.
    pub fn new(visibility: Visibility, stats: Stats) -> Self {
        Shadows {
            visibility,
            stats,
            layers: None,
        }
    }
}

/// A shadow algorithm.
pub trait ShadowTechnique: Send {
    /// The technique's name as the command line spells it (`sm`, `afsm`, …).
    fn name(&self) -> &'static str;
    /// Every parameter in effect, defaults included.
    fn params(&self) -> BTreeMap<String, serde_json::Value>;
    /// Sets one parameter from its text form; unknown keys and bad values are errors
    /// that list what is accepted.
    fn set_param(&mut self, key: &str, value: &str) -> Result<()>;
    /// Computes the shadow term of a frame.
    fn render(&mut self, frame: &Frame) -> Result<Shadows>;
    /// For a progressive technique (one that refines its result over the frames of a still
    /// view): `Some(true)` once another frame of the same view would change nothing,
    /// `Some(false)` while it is still refining. `None` for techniques that are done in one
    /// frame.
    fn converged(&self) -> Option<bool> {
        None
    }
}

/// Every technique name, in the order reports list them.
pub const ALL: &[&str] = &[
    "raytrace", "sm", "pcf", "psm", "asm", "afsm", "subpixel", "csm", "vsm", "evsm", "msm",
    "cascaded", "lispsm",
];

/// A technique by name, with default parameters.
pub fn create(name: &str) -> Result<Box<dyn ShadowTechnique>> {
    Ok(match name {
        "raytrace" => Box::new(raytrace::RayTrace::default()),
        "sm" => Box::new(shadow_map::ShadowMap::standard()),
        "pcf" => Box::new(shadow_map::ShadowMap::pcf()),
        "psm" => Box::new(perspective::Perspective::default()),
        "asm" => Box::new(adaptive::Adaptive::default()),
        "afsm" => Box::new(alias_free::AliasFree::default()),
        "subpixel" => Box::new(subpixel::Subpixel::default()),
        "csm" | "convolution" => Box::new(convolution::Convolution::default()),
        "vsm" => Box::new(variance::Variance::default()),
        "evsm" => Box::new(moments::evsm::ExponentialVariance::default()),
        "msm" => Box::new(moments::msm::MomentShadowMap::default()),
        "cascaded" => Box::new(cascaded::Cascaded::default()),
        "lispsm" => Box::new(lispsm::LightSpacePerspective::default()),
        _ => {
            return Err(Error::param(format!(
                "unknown technique {name:?}: known techniques are {}",
                ALL.join(", ")
            )))
        }
    })
}

/// The error for an unknown parameter key of `technique`, listing the known keys.
pub fn unknown_param(technique: &str, key: &str, known: &[&str]) -> Error {
    Error::param(format!(
        "technique {technique} has no parameter {key:?}: its parameters are {}",
        known.join(", ")
    ))
}

/// Parses `value` for `technique.key`, naming both on failure.
pub fn parse_value<T: std::str::FromStr>(technique: &str, key: &str, value: &str) -> Result<T> {
    value.trim().parse::<T>().map_err(|_| {
        Error::param(format!(
            "parameter {technique}.{key} = {value:?} is not a valid {}",
            std::any::type_name::<T>()
        ))
    })
}

/// Checks `value` lies in `lo..=hi` for `technique.key`.
pub fn check_range<T: PartialOrd + std::fmt::Display + Copy>(
    technique: &str,
    key: &str,
    value: T,
    lo: T,
    hi: T,
) -> Result<T> {
    if value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(Error::param(format!(
            "parameter {technique}.{key} = {value} is outside its range {lo}..={hi}"
        )))
    }
}
