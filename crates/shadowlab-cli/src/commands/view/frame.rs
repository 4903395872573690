//! One frame of the viewer, drawn as `render` draws it: the camera pass with the camera's
//! depth range fitted to the scene, the technique on that frame, then the shading of its
//! shadow term — each stage timed. The technique's intermediate images are collected when
//! their overlay is shown.

use anyhow::{Context, Result};
use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::frame::{DumpMemory, Dumped, Frame};
use shadowlab::light::Light;
use shadowlab::picture::RgbImage;
use shadowlab::scene::Scene;
use shadowlab::shade;
use shadowlab::techniques::{ShadowTechnique, Shadows};
use shadowlab::view::{ViewLayers, ViewSamples};
use std::time::Instant;

/// A drawn frame.
pub struct Drawn {
    /// The camera, its depth range fitted.
    pub camera: Camera,
    /// The camera pass.
    pub view: ViewSamples,
    /// The surfaces behind semi-transparent ones, when shaded.
    pub layers: Option<ViewLayers>,
    /// The technique's result (`None` when it stayed on the device).
    pub shadows: Option<Shadows>,
    /// The shaded image (`None` when shaded on the device).
    pub image: Option<RgbImage>,
    /// Milliseconds of each stage: the camera pass, the technique's own stages, shading.
    pub stages_ms: Vec<(String, f64)>,
    /// The technique's images, when asked for (grey ones as colour).
    pub dumps: Vec<(String, RgbImage)>,
    /// The technique's counters (its GPU stage times `gpu_STAGE_ms` among them).
    pub counters: std::collections::BTreeMap<String, f64>,
    /// True when the camera pass was the GPU's own: its samples stayed on the device and
    /// `view` holds no per-pixel data.
    pub gpu_camera_pass: bool,
}

/// The camera pass of a frame: the camera with its depth range fitted, the samples, the
/// layers behind semi-transparent surfaces (with `layers`), and its stage time. The pass
/// of `previous` is kept when its camera is the same; else it renders into its buffers.
pub type CameraPass = (Camera, ViewSamples, Option<ViewLayers>, Vec<(String, f64)>);

/// The camera pass of `camera` (see [`CameraPass`]).
pub fn camera_pass(
    scene: &Scene,
    camera: &Camera,
    layers: bool,
    previous: Option<Drawn>,
) -> Result<CameraPass> {
    let mut camera = *camera;
    camera.fit_depth_range(&scene.bounds);
    camera.validate()?;
    let mut stages_ms = Vec::new();
    let (kept, spare) = match previous {
        Some(p) if p.camera == camera && p.layers.is_some() == layers && !p.gpu_camera_pass => {
            (Some(p), None)
        }
        // A moved camera renders into the last pass's buffers.
        Some(p) => (None, Some(p.view)),
        None => (None, None),
    };
    let (view, layer_samples) = match kept {
        Some(p) => {
            stages_ms.push(("camera pass (kept)".to_string(), 0.0));
            (p.view, p.layers)
        }
        None => {
            let t0 = Instant::now();
            let view = match spare {
                Some(mut v) => {
                    v.render_into(scene, &camera)?;
                    v
                }
                None => ViewSamples::try_render(scene, &camera)?,
            };
            let l = if layers {
                Some(ViewLayers::render(scene, &camera, &view)?)
            } else {
                None
            };
            stages_ms.push(("camera pass".to_string(), ms(t0)));
            (view, l)
        }
    };
    Ok((camera, view, layer_samples, stages_ms))
}

/// Draws the frame of `camera` and `light` with `technique`: the light, its area light
/// when it has one and the light samples a pixel under it, as `render` hands them to the
/// technique; `layers` shades the surfaces behind semi-transparent ones too, `dump`
/// keeps the technique's images. The camera pass of `previous` is kept when its camera
/// is the same (the light or the technique changed): it depends on nothing else.
pub fn draw(
    scene: &Scene,
    camera: &Camera,
    (light, area, light_samples): (&Light, Option<&AreaLight>, u32),
    layers: bool,
    technique: &mut dyn ShadowTechnique,
    dump: bool,
    previous: Option<Drawn>,
) -> Result<Drawn> {
    let (camera, view, layer_samples, mut stages_ms) =
        camera_pass(scene, camera, layers, previous)?;
    let sink = DumpMemory::default();
    let mut frame = Frame::new(scene, &camera, light, &view).with_area(area, light_samples);
    if let Some(l) = &layer_samples {
        frame = frame.with_layers(l);
    }
    if dump {
        frame = frame.with_dump(&sink);
    }
    let t1 = Instant::now();
    let shadows = technique
        .render(&frame)
        .with_context(|| format!("technique {}", technique.name()))?;
    let technique_ms = ms(t1);
    if shadows.stats.stages_ms.is_empty() {
        stages_ms.push((technique.name().to_string(), technique_ms));
    } else {
        stages_ms.extend(shadows.stats.stages_ms.iter().cloned());
    }
    let t2 = Instant::now();
    let image = match (&layer_samples, &shadows.layers) {
        (Some(l), Some(lv)) => shade::shade_layers(scene, &view, l, light, &shadows.visibility, lv),
        _ => shade::shade(scene, &view, light, &shadows.visibility),
    };
    stages_ms.push(("shade".to_string(), ms(t2)));
    let dumps = sink
        .take()
        .into_iter()
        .filter_map(|(name, d)| match d {
            Dumped::Image(i) => Some((name, i)),
            Dumped::Grey(g) => Some((name, image::DynamicImage::ImageLuma8(g).to_rgb8())),
            Dumped::Text(_) => None,
        })
        .collect();
    Ok(Drawn {
        camera,
        view,
        layers: layer_samples,
        counters: shadows.stats.counters.clone(),
        shadows: Some(shadows),
        image: Some(image),
        stages_ms,
        dumps,
        gpu_camera_pass: false,
    })
}

/// Milliseconds since `t0`.
pub fn ms(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}
