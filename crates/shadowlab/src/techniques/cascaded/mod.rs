//! `cascaded`: cascaded shadow maps for directional lights (Engel, "Cascaded Shadow Maps",
//! ShaderX⁵ 2006; Dimitrov, "Cascaded Shadow Maps", NVIDIA 2007; Zhang et al.'s
//! parallel-split shadow maps).
//!
//! The idea: split the view depth range into `N` slices with the practical split scheme
//! ([`splits`]) and give each slice its own orthographic shadow map fitted to it in light
//! space ([`fit`]), so near slices get small maps with fine texels and far ones large maps
//! with coarse texels — the texel density falls with the distance as the image's does. A
//! receiver reads the cascade of its view depth, with PCF inside it, and blends into the
//! next cascade across a band at the slice's far end so the change of resolution does not
//! show as a seam.
//!
//! Memory: unless `cascade-resolution` is set, each cascade is `⌊resolution/√N⌋²`, so all
//! cascades together hold (at most) the texels of one `resolution²` map: four cascades of
//! 1024² against one 2048² map. Depth bounds: the camera's near and far planes, or
//! (`depth-bounds=sdsm`, sample distribution shadow maps, Lauritzen et al. 2011) the
//! nearest and farthest view depth of the receivers this frame shows that the light can
//! reach, read from the camera pass.
//!
//! Orthographic cameras: the slices are boxes (the view's rectangle between two depths)
//! and the stabilized window is the sphere about a box's centre through its corners; the
//! splits stay the practical scheme's, although an orthographic view's texel demand does
//! not fall with depth, so its logarithmic share buys nothing there (`lambda=0`, uniform
//! splits, is the better setting for such views).
//!
//! Invariants: every cascade's depth range holds every caster between its slice and the
//! light; with `stabilize`, each cascade's window is the same size for every camera
//! orientation and moves by whole texels of a world-fixed light basis; biases are `sm`'s,
//! in texels of the cascade that is read. Departures: spot and point lights have no
//! cascades (their frusta are not sliced by engines either): they fall back to one
//! `resolution²` map (a cube of six for point lights) with the same PCF and biases, and the
//! counter `single_map_fallback` says so. SDSM here takes only the depth bounds (not the
//! paper's tight light-space rectangles per partition). Known artifacts: the usual
//! shadow-map acne and peter-panning at the bias trade-off; the blend band shows softer
//! shadow edges; SDSM bounds change with the view, which undoes stabilization's texel
//! snapping when the visible depth range changes.

pub mod fit;
pub mod splits;

use super::shadow_map::{
    check_light_map_size, check_resolution, lookup_nearest, lookup_pcf, receiver_bias,
    render_depth_map, ShadowMap, DEFAULT_CONSTANT_BIAS, DEFAULT_PCF_KERNEL, DEFAULT_RESOLUTION,
    DEFAULT_SLOPE_BIAS,
};
use super::{
    find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique, Shadows,
    Stats, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::Result;
use crate::light::{Light, LightView};
use crate::math::Vec3;
use crate::raster::DepthBuffer;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Default number of cascades: engines' usual four.
pub const DEFAULT_CASCADES: usize = 4;
/// The most cascades accepted.
pub const MAX_CASCADES: usize = 8;
/// Default λ of the practical split scheme: mostly logarithmic (the density the image
/// needs), with a uniform share so the nearest cascade is not spent on a sliver.
pub const DEFAULT_LAMBDA: f32 = 0.75;
/// Default blend band: the last tenth of each slice blends into the next cascade.
pub const DEFAULT_BLEND: f32 = 0.1;

/// Where the cascades' depth range comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthBounds {
    /// The camera's near and far planes.
    Camera,
    /// The nearest and farthest lit receiver of the camera pass (SDSM).
    Sdsm,
}

/// The `cascaded` technique.
#[derive(Clone, Debug)]
pub struct Cascaded {
    /// Side of the one map whose memory the cascades share.
    pub resolution: u32,
    /// Number of cascades.
    pub cascades: usize,
    /// Side of each cascade's map; 0 (`auto`) for the share of `resolution²`.
    pub cascade_resolution: u32,
    /// λ of the practical split scheme.
    pub lambda: f32,
    /// Texel-snapped, rotation-invariant windows.
    pub stabilize: bool,
    /// Share of each slice's depth range, at its far end, blended into the next cascade.
    pub blend: f32,
    /// Depth range the slices split.
    pub depth_bounds: DepthBounds,
    /// Constant bias in texels (as `sm`'s).
    pub bias: f32,
    /// Slope-scaled bias in texels per unit of tan θ (as `sm`'s).
    pub slope_bias: f32,
    /// PCF kernel side (0 for unfiltered look-ups).
    pub kernel: u32,
}

impl Default for Cascaded {
    fn default() -> Self {
        Cascaded {
            resolution: DEFAULT_RESOLUTION,
            cascades: DEFAULT_CASCADES,
            cascade_resolution: 0,
            lambda: DEFAULT_LAMBDA,
            stabilize: true,
            blend: DEFAULT_BLEND,
            depth_bounds: DepthBounds::Sdsm,
            bias: DEFAULT_CONSTANT_BIAS,
            slope_bias: DEFAULT_SLOPE_BIAS,
            kernel: DEFAULT_PCF_KERNEL,
        }
    }
}

/// The parameter table, in key order.
const TABLE: &[ParamSpec] = &[
    BIAS,
    ParamSpec::real(
        "blend",
        0.0,
        0.5,
        "share of a cascade's depth range over which it fades into the next (0: hard seams)",
    ),
    ParamSpec::int(
        "cascade-resolution",
        1,
        crate::raster::MAX_RASTER_SIDE as i64,
        "side of each cascade's map, or auto to share resolution² among the cascades",
    ),
    ParamSpec::int(
        "cascades",
        1,
        MAX_CASCADES as i64,
        "number of view-depth slices, each with its own map",
    ),
    ParamSpec::choice(
        "depth-bounds",
        &["camera", "sdsm"],
        "depth range the slices split: the camera's near..far, or the lit receivers' (sdsm)",
    ),
    ParamSpec::int(
        "kernel",
        0,
        15,
        "PCF kernel side in texels, 0 for one nearest-texel test",
    ),
    ParamSpec::real(
        "lambda",
        0.0,
        1.0,
        "split scheme: 0 uniform, 1 logarithmic, between them the practical blend",
    ),
    RESOLUTION,
    SLOPE_BIAS,
    ParamSpec::flag(
        "stabilize",
        "texel-snapped, rotation-invariant windows, so shadows do not shimmer in motion",
    ),
];

/// One cascade: its view depth interval, light view and map.
pub struct Cascade {
    /// View depths `[d0, d1)` the cascade covers.
    pub slice: (f32, f32),
    /// The light view.
    pub view: LightView,
    /// The depth map.
    pub map: DepthBuffer,
}

impl Cascaded {
    /// The side of each cascade's map.
    pub fn resolved_cascade_resolution(&self) -> u32 {
        if self.cascade_resolution > 0 {
            self.cascade_resolution
        } else {
            ((self.resolution as f64 / (self.cascades as f64).sqrt()).floor() as u32).max(1)
        }
    }

    /// The view depth interval the slices split this frame.
    pub fn depth_interval(&self, frame: &Frame) -> (f32, f32) {
        let cam = frame.camera;
        let camera = (cam.near, cam.far);
        if self.depth_bounds == DepthBounds::Camera {
            return camera;
        }
        let f = cam.forward();
        let view = frame.view;
        let lit = (0..view.position.len())
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&k| frame.receiver_lit(k))
            .map(|k| {
                let z = (view.position[k] - cam.eye).dot(f);
                (z, z)
            })
            .reduce(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        sdsm_interval(frame, lit)
    }

    /// The cascades of a frame lit by a directional light towards `to_light`.
    pub fn build(&self, frame: &Frame, to_light: Vec3, stats: &mut Stats) -> Vec<Cascade> {
        let views = self.views(frame, to_light, self.depth_interval(frame), stats);
        let res = self.resolved_cascade_resolution();
        stats.stage("shadow_map", || {
            views
                .into_iter()
                .map(|(d0, d1, view)| Cascade {
                    slice: (d0, d1),
                    map: render_depth_map(frame.scene, &view, res),
                    view,
                })
                .collect()
        })
    }

    /// Each cascade's view depth slice and light view, over the view depth interval
    /// `(near, far)`, before any map is drawn (the GPU twin draws them itself); the split
    /// planes are counted in `stats`.
    pub fn views(
        &self,
        frame: &Frame,
        to_light: Vec3,
        (near, far): (f32, f32),
        stats: &mut Stats,
    ) -> Vec<(f32, f32, LightView)> {
        let planes = splits::practical_splits(near, far, self.cascades, self.lambda);
        let res = self.resolved_cascade_resolution();
        let basis = fit::light_basis(to_light, &frame.scene.bounds);
        let views: Vec<(f32, f32, LightView)> = planes
            .windows(2)
            .map(|w| {
                let s = (w[0], w[1]);
                let win = fit::fit_window(
                    frame.camera,
                    &basis,
                    &frame.scene.bounds,
                    s,
                    res,
                    self.stabilize,
                );
                (
                    s.0,
                    s.1,
                    fit::cascade_view(frame.camera, &basis, &frame.scene.bounds, s, &win),
                )
            })
            .collect();
        for (i, p) in planes.iter().enumerate() {
            stats.count(&format!("split{i}"), *p as f64);
        }
        views
    }

    /// The lit fraction of receiver `k` read from cascade `c`.
    fn read(&self, frame: &Frame, c: &Cascade, k: usize, slope: f32) -> f32 {
        let view = frame.view;
        let p = view.position[k];
        let s = c.view.project(p);
        let (l, _) = frame.light.shadow_ray(p);
        let d = s.depth
            - receiver_bias(
                c.view.texel_size(c.map.width, s.depth),
                view.normal[k],
                l,
                self.bias,
                slope,
            );
        if !(s.u.is_finite() && s.v.is_finite() && d.is_finite()) {
            return 1.0;
        }
        if self.kernel == 0 {
            lookup_nearest(&c.map, s.u, s.v, d)
        } else {
            lookup_pcf(&c.map, s.u, s.v, d, self.kernel)
        }
    }

    /// The shadow term of every pixel from the cascades, and each pixel's cascade (255 where
    /// none was read).
    fn lookup(&self, frame: &Frame, cascades: &[Cascade]) -> (Vec<Vec3>, Vec<u8>) {
        let view = frame.view;
        let cam = frame.camera;
        let f = cam.forward();
        let slope = crate::techniques::shadow_map::pcf_slope_bias(self.slope_bias, self.kernel);
        let bounds: Vec<f32> = std::iter::once(cascades[0].slice.0)
            .chain(cascades.iter().map(|c| c.slice.1))
            .collect();
        let blend = self.blend;
        (0..view.position.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| {
                if let Some(v) = frame.unreached(k) {
                    return (v, u8::MAX);
                }
                let z = (view.position[k] - cam.eye).dot(f);
                let i = splits::cascade_of(&bounds, z);
                let mut lit = self.read(frame, &cascades[i], k, slope);
                let (d0, d1) = cascades[i].slice;
                let band = blend * (d1 - d0);
                if i + 1 < cascades.len() && band > 0.0 && z > d1 - band {
                    let t = ((z - (d1 - band)) / band).min(1.0);
                    lit += t * (self.read(frame, &cascades[i + 1], k, slope) - lit);
                }
                (Vec3::splat(lit), i as u8)
            })
            .unzip()
    }

    fn fallback(&self, frame: &Frame) -> Result<Shadows> {
        let mut sm = if self.kernel > 0 {
            ShadowMap::pcf()
        } else {
            ShadowMap::standard()
        };
        sm.resolution = self.resolution;
        sm.bias = self.bias;
        sm.slope_bias = self.slope_bias;
        if self.kernel > 0 {
            sm.kernel = self.kernel;
        }
        let mut s = sm.render(frame)?;
        s.stats.count("single_map_fallback", 1.0);
        Ok(s)
    }
}

/// SDSM's view depth interval from the nearest and farthest view depth `(lo, hi)` of the
/// lit receivers: padded a little so the extreme receivers are inside their slices, and
/// the camera's near..far when there are none (`lo`, `hi` not finite, or `hi <= lo`).
pub fn sdsm_interval(frame: &Frame, (lo, hi): (f32, f32)) -> (f32, f32) {
    let cam = frame.camera;
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return (cam.near, cam.far);
    }
    let pad = (hi - lo) * fit::DEPTH_PAD;
    ((lo - pad).max(cam.near), hi + pad)
}

/// Colours of the cascades in the `--dump` overlay.
const CASCADE_COLOURS: [[f32; 3]; MAX_CASCADES] = [
    [1.0, 0.3, 0.3],
    [0.3, 1.0, 0.3],
    [0.3, 0.4, 1.0],
    [1.0, 1.0, 0.3],
    [1.0, 0.3, 1.0],
    [0.3, 1.0, 1.0],
    [1.0, 0.6, 0.2],
    [0.7, 0.7, 0.7],
];

fn dump(frame: &Frame, cascades: &[Cascade], which: &[u8], vis: &[Vec3]) -> Result<()> {
    for (i, c) in cascades.iter().enumerate() {
        frame.dump_depth(&format!("cascaded-map{i}.png"), &c.map)?;
    }
    let (w, h) = (frame.view.width, frame.view.height);
    let img = crate::picture::RgbImage::from_fn(w, h, |x, y| {
        let k = (y * w + x) as usize;
        let base = match which[k] {
            u8::MAX => [0.15; 3],
            i => CASCADE_COLOURS[i as usize % MAX_CASCADES],
        };
        let s = 0.35 + 0.65 * vis[k].x;
        image::Rgb(base.map(|c| (c * s * 255.0) as u8))
    });
    frame.dump_image("cascaded-overlay.png", || img)
}

impl ShadowTechnique for Cascaded {
    fn name(&self) -> &'static str {
        "cascaded"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("cascades".to_string(), self.cascades.into()),
            (
                "cascade-resolution".to_string(),
                self.resolved_cascade_resolution().into(),
            ),
            ("lambda".to_string(), param_value(self.lambda)),
            ("stabilize".to_string(), self.stabilize.into()),
            ("blend".to_string(), param_value(self.blend)),
            (
                "depth-bounds".to_string(),
                match self.depth_bounds {
                    DepthBounds::Camera => "camera",
                    DepthBounds::Sdsm => "sdsm",
                }
                .into(),
            ),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
            ("kernel".to_string(), self.kernel.into()),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        TABLE.to_vec()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "cascaded";
        let spec = find_param(t, TABLE, key)?;
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "cascades" => self.cascades = spec.usize(t, value)?,
            "cascade-resolution" => {
                // `auto`: the share of `resolution²`; a number is checked like any map side.
                self.cascade_resolution = if value.trim() == "auto" {
                    0
                } else {
                    spec.u32(t, value)?
                };
            }
            "lambda" => self.lambda = spec.f32(t, value)?,
            "stabilize" => {
                // The words of a switch are accepted beside the table's true and false.
                self.stabilize = match value.trim() {
                    "on" | "yes" | "1" => true,
                    "off" | "no" | "0" => false,
                    _ => spec.bool(t, value)?,
                }
            }
            "blend" => self.blend = spec.f32(t, value)?,
            "depth-bounds" => {
                self.depth_bounds = match spec.word(t, value)? {
                    "camera" => DepthBounds::Camera,
                    _ => DepthBounds::Sdsm,
                }
            }
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            "kernel" => self.kernel = spec.u32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        check_resolution("cascaded", self.resolution)?;
        let Light::Directional { to_light } = *frame.light else {
            return self.fallback(frame);
        };
        let res = check_resolution("cascaded", self.resolved_cascade_resolution())?;
        check_light_map_size("cascaded", self.cascades, res)?;
        let mut stats = Stats::default();
        let cascades = self.build(frame, to_light, &mut stats);
        let (value, which) = stats.stage("lookup", || self.lookup(frame, &cascades));
        stats.memory_bytes = cascades.iter().map(|c| c.map.depth.len() as u64 * 4).sum();
        stats.count("cascades", cascades.len() as f64);
        stats.count("cascade_resolution", res as f64);
        stats.count(
            "map_texels",
            cascades.iter().map(|c| c.map.depth.len() as f64).sum(),
        );
        if frame.dumping() {
            dump(frame, &cascades, &which, &value)?;
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}
