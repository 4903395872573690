//! One frame as every technique sees it, and what a technique hands back: the shared
//! types of the data flow between the camera pass and the techniques, the reference and
//! the comparison.
//!
//! A technique gets a [`Frame`] — scene, camera, light and the shared camera pass — and
//! returns a [`Visibility`] (a per-pixel RGB transmittance towards the light, 1 = lit)
//! with [`Stats`]. Intermediate images a technique can show (its shadow map, tree, tiles)
//! go to the frame's [`DumpSink`]: a folder of PNGs on the command line, memory in tests.

use crate::area_light::AreaLight;
use crate::camera::Camera;
use crate::error::Result;
use crate::light::Light;
use crate::math::Vec3;
use crate::picture::{self, GreyImage, RgbImage};
use crate::raster::DepthBuffer;
use crate::scene::Scene;
use crate::view::{ViewLayers, ViewSamples};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Everything a technique may read to shade one frame.
#[derive(Clone, Copy)]
pub struct Frame<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The camera of this frame.
    pub camera: &'a Camera,
    /// The light: the punctual one, or an area light's punctual stand-in (its centre),
    /// which hard techniques use.
    pub light: &'a Light,
    /// The area light, when the light has an area: the soft-shadow reference and the
    /// soft techniques read it (see [`crate::area_light`]).
    pub area: Option<&'a AreaLight>,
    /// Light samples per point under an area light (see
    /// [`crate::area_light::light_samples`]).
    pub light_samples: u32,
    /// The camera pass.
    pub view: &'a ViewSamples,
    /// Frame number within a sequence (0 for a still).
    pub index: usize,
    /// Where intermediate images go, when asked for (see [`DumpSink`]).
    pub dump: Option<&'a dyn DumpSink>,
    /// The surfaces behind semi-transparent nearest surfaces, when the caller wants them
    /// shaded too (see [`ViewLayers`]); techniques that support them return their shadow
    /// terms in `Shadows::layers`.
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
            area: None,
            light_samples: crate::area_light::DEFAULT_LIGHT_SAMPLES,
            view,
            index: 0,
            dump: None,
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

    /// The same frame under the area light `area` (whose stand-in `light` already is),
    /// with `samples` light samples per point.
    pub fn with_area(self, area: Option<&'a AreaLight>, samples: u32) -> Self {
        Frame {
            area,
            light_samples: samples,
            ..self
        }
    }

    /// The same frame, writing its intermediate images to `sink`.
    pub fn with_dump(self, sink: &'a dyn DumpSink) -> Self {
        Frame {
            dump: Some(sink),
            ..self
        }
    }

    /// True when intermediate images are asked for: build them only then.
    #[inline]
    pub fn dumping(&self) -> bool {
        self.dump.is_some()
    }

    /// Hands the intermediate image `name` (a file name such as `sm-map0.png`) to the dump
    /// sink; `make` runs only when there is one.
    pub fn dump_image(&self, name: &str, make: impl FnOnce() -> RgbImage) -> Result<()> {
        match self.dump {
            Some(sink) => sink.image(name, &make()),
            None => Ok(()),
        }
    }

    /// Hands the grey image `name` to the dump sink; `make` runs only when there is one.
    pub fn dump_grey(&self, name: &str, make: impl FnOnce() -> GreyImage) -> Result<()> {
        match self.dump {
            Some(sink) => sink.grey(name, &make()),
            None => Ok(()),
        }
    }

    /// Hands the text `name` to the dump sink; `make` runs only when there is one.
    pub fn dump_text(&self, name: &str, make: impl FnOnce() -> String) -> Result<()> {
        match self.dump {
            Some(sink) => sink.text(name, &make()),
            None => Ok(()),
        }
    }

    /// Dumps a depth map as a grey picture (see [`picture::depth_image`]).
    pub fn dump_depth(&self, name: &str, map: &DepthBuffer) -> Result<()> {
        self.dump_image(name, || {
            picture::depth_image(map.width, map.height, &map.depth)
        })
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

    /// Pixel `k`'s shadow term when no look-up is needed: `None` when the light can reach
    /// its surface (the technique decides), else 0 for a surface the light cannot reach and
    /// 1 for a pixel that shows no surface.
    #[inline]
    pub fn unreached(&self, k: usize) -> Option<Vec3> {
        if self.receiver_lit(k) {
            None
        } else if self.view.covered(k) {
            Some(Vec3::ZERO)
        } else {
            Some(Vec3::ONE)
        }
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

    /// The luminance of pixel `k`'s transmittance (see [`luminance`]).
    #[inline]
    pub fn luminance(&self, k: usize) -> f32 {
        luminance(self.value[k])
    }
}

/// Rec. 709 luminance of an RGB transmittance.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Where a technique's intermediate images go.
pub trait DumpSink: Sync {
    /// Takes the image `name` (a file name such as `sm-map0.png`).
    fn image(&self, name: &str, image: &RgbImage) -> Result<()>;
    /// Takes the grey image `name` (masks).
    fn grey(&self, name: &str, image: &GreyImage) -> Result<()>;
    /// Takes the text `name` (a description of the images, such as `psm-post-space.json`).
    fn text(&self, name: &str, text: &str) -> Result<()>;
}

/// A dump sink writing each image as a PNG into a folder.
#[derive(Clone, Debug)]
pub struct DumpDir(pub PathBuf);

impl DumpDir {
    /// A sink writing into `dir`, which must exist.
    pub fn new(dir: &Path) -> Self {
        DumpDir(dir.to_path_buf())
    }
}

impl DumpSink for DumpDir {
    fn image(&self, name: &str, image: &RgbImage) -> Result<()> {
        picture::save_png(image, &self.0.join(name))
    }

    fn grey(&self, name: &str, image: &GreyImage) -> Result<()> {
        picture::save_grey_png(image, &self.0.join(name))
    }

    fn text(&self, name: &str, text: &str) -> Result<()> {
        picture::save_text(text, &self.0.join(name))
    }
}

/// One item a technique dumped.
#[derive(Clone, Debug, PartialEq)]
pub enum Dumped {
    /// A colour image.
    Image(RgbImage),
    /// A grey image.
    Grey(GreyImage),
    /// A text.
    Text(String),
}

/// A dump sink keeping what it is given in memory, in the order it came (for tests and
/// programs that show the images without files).
#[derive(Debug, Default)]
pub struct DumpMemory(Mutex<Vec<(String, Dumped)>>);

impl DumpMemory {
    /// What was received so far, by name, in order; the sink is empty afterwards.
    pub fn take(&self) -> Vec<(String, Dumped)> {
        std::mem::take(&mut *self.lock())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(String, Dumped)>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl DumpSink for DumpMemory {
    fn image(&self, name: &str, image: &RgbImage) -> Result<()> {
        self.lock()
            .push((name.to_string(), Dumped::Image(image.clone())));
        Ok(())
    }

    fn grey(&self, name: &str, image: &GreyImage) -> Result<()> {
        self.lock()
            .push((name.to_string(), Dumped::Grey(image.clone())));
        Ok(())
    }

    fn text(&self, name: &str, text: &str) -> Result<()> {
        self.lock()
            .push((name.to_string(), Dumped::Text(text.to_string())));
        Ok(())
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
    /// The device a GPU technique ran on, as one line (adapter name, backend, device type,
    /// driver; a software adapter marked `CPU-emulated`); `None` on the CPU.
    pub device: Option<String>,
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
