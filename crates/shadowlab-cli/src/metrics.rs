//! The records the commands write, as typed structs: `metrics.json` of `compare`
//! ([`Metrics`]), which the report is drawn from, and the `--stats` file of `render`
//! ([`RenderStats`]). Field names, types and presence are docs/CLI.md's: a field listed
//! there as always present is a plain field (`null` where it has no value), one present
//! only with some flags is skipped when absent. Fields serialize in the order declared.
//!
//! Numbers are stored as JSON holds them (`f64`), so a record reads back exactly as it
//! was written.

use crate::config::Setup;
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use shadowlab::area_light::AreaLight;
use shadowlab::camera::{Camera, Projection};
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::scene::UpAxis;
use std::collections::BTreeMap;

/// A technique's parameters in effect, by key (values as the technique reports them).
pub type Params = BTreeMap<String, serde_json::Value>;

/// Wall time per stage in milliseconds, in the order the stages ran (a JSON object).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageTimes(pub Vec<(String, f64)>);

impl Serialize for StageTimes {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for StageTimes {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // The workspace's serde_json keeps an object's keys in order (`preserve_order`).
        let stages = serde_json::Map::<String, serde_json::Value>::deserialize(d)?;
        let time = |(k, v): (String, serde_json::Value)| match v.as_f64() {
            Some(ms) => Ok((k, ms)),
            None => Err(serde::de::Error::custom(format!(
                "stage {k:?} is not a number"
            ))),
        };
        stages
            .into_iter()
            .map(time)
            .collect::<Result<_, _>>()
            .map(StageTimes)
    }
}

/// What a technique measured about its own frame: the fields `results[]` and the stats
/// file share.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Figures {
    /// The technique's own frame time (the camera pass excluded).
    pub time_ms: f64,
    /// Time per stage.
    pub stages_ms: StageTimes,
    /// Bytes held by the technique's own structures.
    pub memory_bytes: u64,
    /// The technique's counters.
    pub counters: BTreeMap<String, f64>,
    /// The GPU adapter a `gpu:` technique ran on (name, backend, type, driver; a software
    /// adapter's times marked CPU-emulated); absent on the CPU.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<String>,
}

impl Figures {
    /// The figures of a result that took `time_ms`.
    pub fn of(stats: &shadowlab::frame::Stats, time_ms: f64) -> Self {
        Figures {
            time_ms,
            stages_ms: StageTimes(stats.stages_ms.clone()),
            memory_bytes: stats.memory_bytes,
            counters: stats.counters.clone(),
            device: stats.device.clone(),
        }
    }
}

/// One frame of a sequence: its index, the technique's time and memory in it, and in
/// `compare` its verdict against that frame's own reference.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct FrameFigures {
    /// Frame index along the camera path.
    pub frame: usize,
    /// The technique's time in that frame.
    pub time_ms: f64,
    /// The technique's memory in that frame.
    pub memory_bytes: u64,
    /// In `compare`, the frame measured against its own reference.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<FrameVerdict>,
}

/// One frame of a sequence measured against the reference traced for that frame.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct FrameVerdict {
    /// Share of covered pixels whose shadow term differs from the reference by ≥ 0.5.
    pub mismatch_rate: f64,
    /// Mean absolute luminance error over covered pixels.
    pub mean_abs_error: f64,
    /// Mean |Δ(technique) − Δ(reference)| of the shadow term from the frame before over
    /// the pixels visible in both (`shadowlab::temporal`); null in the first frame and
    /// when no pixel is visible in both.
    pub temporal_error: Option<f64>,
    /// Pixels visible in this frame and the one before; null in the first frame.
    pub reprojected_pixels: Option<usize>,
}

/// A point or direction in world units.
pub type Xyz = [f64; 3];

fn xyz(v: Vec3) -> Xyz {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// The resolved camera in world units (CLI.md's provenance section).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CameraRecord {
    /// Where the camera is.
    pub eye: Xyz,
    /// What it looks at.
    pub target: Xyz,
    /// Its up direction.
    pub up: Xyz,
    /// `perspective` or `orthographic`.
    #[serde(default = "perspective")]
    pub projection: String,
    /// Vertical field of view in degrees (a perspective camera's).
    pub fov_y_deg: f64,
    /// An orthographic camera's half width and half height in world units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub xmag: Option<f64>,
    /// See `xmag`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ymag: Option<f64>,
    /// Near end of the depth range fitted to the scene.
    pub near: f64,
    /// Far end of the depth range.
    pub far: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

fn perspective() -> String {
    "perspective".to_string()
}

/// An orthographic camera's `(xmag, ymag)`.
fn ortho_extent(c: &Camera) -> Option<(f64, f64)> {
    match c.projection {
        Projection::Orthographic { xmag, ymag } => Some((xmag as f64, ymag as f64)),
        Projection::Perspective => None,
    }
}

impl From<&Camera> for CameraRecord {
    fn from(c: &Camera) -> Self {
        CameraRecord {
            eye: xyz(c.eye),
            target: xyz(c.target),
            up: xyz(c.up),
            projection: c.projection.name().to_string(),
            fov_y_deg: c.fov_y_deg as f64,
            xmag: ortho_extent(c).map(|e| e.0),
            ymag: ortho_extent(c).map(|e| e.1),
            near: c.near as f64,
            far: c.far as f64,
            width: c.width,
            height: c.height,
        }
    }
}

/// The resolved light in world units, tagged by `kind`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum LightRecord {
    /// A light at infinity.
    Directional {
        /// Unit vector from the scene towards the light.
        to_light: Xyz,
    },
    /// A light at a point, shining every way.
    Point {
        /// Where it is.
        position: Xyz,
    },
    /// A light at a point, shining in a cone.
    Spot {
        /// Where it is.
        position: Xyz,
        /// What it points at.
        target: Xyz,
        /// Full cone angle in degrees.
        fov_deg: f64,
    },
}

impl From<&Light> for LightRecord {
    fn from(l: &Light) -> Self {
        match *l {
            Light::Directional { to_light } => LightRecord::Directional {
                to_light: xyz(to_light),
            },
            Light::Point { position } => LightRecord::Point {
                position: xyz(position),
            },
            Light::Spot {
                position,
                target,
                fov_deg,
            } => LightRecord::Spot {
                position: xyz(position),
                target: xyz(target),
                fov_deg: fov_deg as f64,
            },
        }
    }
}

/// An area light and the light samples per pixel the reference took.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AreaRecord {
    /// The light, tagged by `kind` (`rect`, `disk`, `sphere`, `distant`).
    #[serde(flatten)]
    pub light: AreaLight,
    /// Light samples per pixel (`--light-samples`).
    pub light_samples: u32,
}

impl AreaRecord {
    /// The area light of a run, if it has one.
    pub fn of(setup: &Setup) -> Option<AreaRecord> {
        setup.area.map(|light| AreaRecord {
            light,
            light_samples: setup.light_samples,
        })
    }
}

/// The scene a record was computed from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneRecord {
    /// The scene's name.
    pub scene: String,
    /// The `--scene` argument as given.
    pub scene_source: String,
    /// The `--scene-param` values.
    pub scene_params: BTreeMap<String, String>,
    /// The mesh file's up axis (`--up`): `x`, `y`, `z`, `-x`, `-y` or `-z`.
    #[serde(default)]
    pub up: UpAxis,
    /// Whether OBJ `map_Kd` alpha cut materials out (`--obj-kd-alpha`; false before it).
    #[serde(default)]
    pub obj_kd_alpha: bool,
    /// Triangles rendered (after instancing and any added ground plane).
    pub triangles: usize,
    /// What the loader skipped or approximated, one sentence per kind.
    pub warnings: Vec<String>,
}

impl From<&Setup> for SceneRecord {
    fn from(setup: &Setup) -> Self {
        SceneRecord {
            scene: setup.scene.name.clone(),
            scene_source: setup.source.clone(),
            scene_params: setup.params.clone(),
            up: setup.up,
            obj_kd_alpha: setup.obj_kd_alpha,
            triangles: setup.scene.len(),
            warnings: setup.scene.warnings.clone(),
        }
    }
}

/// `metrics.json`: what `compare` measured, and everything the report shows.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Metrics {
    /// The scene.
    #[serde(flatten)]
    pub scene: SceneRecord,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Pixels whose centre a surface covers; the denominator of every rate.
    pub covered_pixels: usize,
    /// With `--layers`, the samples behind semi-transparent surfaces.
    pub layer_samples: Option<usize>,
    /// The camera pass, shared by every technique.
    pub camera_pass_ms: f64,
    /// Frames rendered.
    pub frames: usize,
    /// Worker threads.
    pub threads: usize,
    /// The version that computed the result.
    pub shadowlab_version: String,
    /// The resolved camera.
    pub camera: CameraRecord,
    /// The resolved light.
    pub light: LightRecord,
    /// The reference with the most samples per pixel of those the verdicts use.
    pub reference: ReferenceSummary,
    /// Every reference traced, the most samples first.
    pub references: Vec<ReferenceImage>,
    /// Under an area light: the light and its samples per pixel (`light` is then the
    /// punctual stand-in at its centre that hard techniques use).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area_light: Option<AreaRecord>,
    /// One element per technique (and per `--sweep` value).
    pub results: Vec<RunResult>,
    /// With `--dump`, the folder of intermediate images.
    pub dump: Option<String>,
}

/// `metrics.json`'s `reference`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceSummary {
    /// Always `raytrace`.
    pub technique: String,
    /// Its primary rays per pixel.
    pub samples_per_pixel: u32,
    /// The sub-pixel pattern (`--reference-pattern`).
    pub pattern: String,
    /// BVH build plus trace.
    pub time_ms: f64,
    /// The BVH build.
    pub bvh_build_ms: f64,
    /// The trace (of every reference).
    pub trace_ms: f64,
    /// Its shaded image in the report folder.
    pub image: String,
    /// Share of covered pixels whose shadow term is below 0.5.
    pub shadowed_share: f64,
}

/// One element of `metrics.json`'s `references`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceImage {
    /// Its primary rays per pixel.
    pub samples_per_pixel: u32,
    /// Its trace time.
    pub trace_ms: f64,
    /// Its shaded image.
    pub image: String,
    /// Share of covered pixels whose shadow term is below 0.5.
    pub shadowed_share: f64,
    /// Under an area light: its mean per-pixel standard error over covered pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_std_error: Option<f64>,
    /// Under an area light: its standard-error image (brightness ∝ √error, as the error
    /// images).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_error_image: Option<String>,
}

/// One technique run of `compare`: `metrics.json`'s `results[]`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunResult {
    /// The technique's name.
    pub technique: String,
    /// Its label in the report (with the swept value).
    pub label: String,
    /// Every parameter in effect, defaults included.
    pub params: Params,
    /// Time, stages, memory and counters of the last frame.
    #[serde(flatten)]
    pub figures: Figures,
    /// Share of covered pixels whose shadow term differs from the reference by ≥ 0.5.
    pub mismatch_rate: f64,
    /// Mean absolute luminance error over covered pixels.
    pub mean_abs_error: f64,
    /// Mean absolute error of the RGB channels, averaged over them.
    pub mean_abs_error_rgb: f64,
    /// Samples per pixel of the reference this verdict is measured against.
    pub reference_spp: u32,
    /// Under an area light: that reference's mean per-pixel standard error over covered
    /// pixels (an upper bound on its own noise; see `shadowlab::soft_reference`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_std_error: Option<f64>,
    /// Frames the technique rendered.
    pub frames_run: usize,
    /// For a progressive technique, whether it had converged.
    pub converged: Option<bool>,
    /// With `--layers`, for a technique that shades layers: the layer samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_samples: Option<usize>,
    /// The mismatch rate over the layer samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_mismatch_rate: Option<f64>,
    /// The RGB mean error over the layer samples.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_mean_abs_error_rgb: Option<f64>,
    /// The shaded image in the report folder.
    pub image: String,
    /// The error image in the report folder.
    pub error_image: String,
    /// With `--frames N > 1`: one element per frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<Vec<FrameFigures>>,
    /// With `--frames N > 1`: the GIF of every frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<String>,
    /// With `--frames N > 1`: the mean of the per-frame temporal errors (absent when no
    /// pixel is visible in two consecutive frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temporal_error: Option<f64>,
    /// With `--frames N > 1`: the GIF of the reference and the technique side by side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walkthrough: Option<String>,
    /// With `--sweep`: the swept parameter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<Sweep>,
    /// The image region with the largest error (none when there is no error).
    pub worst_region: Option<WorstRegion>,
}

/// The swept parameter of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sweep {
    /// Its name.
    pub key: String,
    /// Its value in this run.
    pub value: String,
}

/// The image region where a technique is furthest from the reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WorstRegion {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Its mean absolute luminance error.
    pub mean_abs_error: f64,
    /// The crop image (reference, technique, error side by side).
    pub crop: String,
}

/// The `--stats` file of `render`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RenderStats {
    /// Time, stages, memory and counters of the last frame.
    #[serde(flatten)]
    pub figures: Figures,
    /// The technique as given.
    pub technique: String,
    /// Every parameter in effect.
    pub params: Params,
    /// The scene.
    #[serde(flatten)]
    pub scene: SceneRecord,
    /// The version.
    pub shadowlab_version: String,
    /// The resolved camera of the last frame.
    pub camera: CameraRecord,
    /// The resolved light.
    pub light: LightRecord,
    /// Under an area light: the light and its samples per pixel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area_light: Option<AreaRecord>,
    /// The camera pass of the last frame.
    pub camera_pass_ms: f64,
    /// Pixels whose centre a surface covers.
    pub covered_pixels: usize,
    /// With `--layers`: samples behind semi-transparent surfaces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layer_samples: Option<usize>,
    /// With `--layers`: time to gather them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers_ms: Option<f64>,
    /// With `--layers`: whether the technique shaded them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layers_shaded: Option<bool>,
    /// With `--frames N > 1`: per frame figures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frames: Option<Vec<FrameFigures>>,
    /// Frames the technique rendered.
    pub frames_run: usize,
    /// For a progressive technique, whether it had converged.
    pub converged: Option<bool>,
}

/// The version that computed a record.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn stage_times_keep_their_order_both_ways() {
        let s = StageTimes(vec![("raster".into(), 2.0), ("bsp".into(), 1.5)]);
        let text = serde_json::to_string(&s).unwrap();
        assert_eq!(text, r#"{"raster":2.0,"bsp":1.5}"#);
        assert_eq!(serde_json::from_str::<StageTimes>(&text).unwrap(), s);
    }

    #[test]
    fn lights_are_tagged_by_kind_and_numbers_are_the_f32_values() {
        let l = Light::Spot {
            position: Vec3::new(0.1, 2.0, 3.0),
            target: Vec3::ZERO,
            fov_deg: 40.0,
        };
        let v = serde_json::to_value(LightRecord::from(&l)).unwrap();
        assert_eq!(
            v,
            json!({"kind": "spot", "position": [0.1f32, 2.0, 3.0], "target": [0.0, 0.0, 0.0], "fov_deg": 40.0})
        );
        let back: LightRecord = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(serde_json::to_value(back).unwrap(), v);
    }

    #[test]
    fn a_result_reads_back_as_written_with_optional_fields_absent() {
        let r = RunResult {
            technique: "sm".into(),
            label: "sm.resolution=512".into(),
            params: BTreeMap::from([("resolution".into(), json!(512))]),
            figures: Figures {
                time_ms: 1.25,
                stages_ms: StageTimes(vec![("shadow_map".into(), 1.0), ("lookup".into(), 0.25)]),
                memory_bytes: 1 << 20,
                counters: BTreeMap::from([("texels".into(), 262144.0)]),
                device: None,
            },
            mismatch_rate: 0.01,
            mean_abs_error: 0.002,
            mean_abs_error_rgb: 0.002,
            reference_spp: 1,
            reference_std_error: None,
            frames_run: 1,
            converged: None,
            layer_samples: None,
            layer_mismatch_rate: None,
            layer_mean_abs_error_rgb: None,
            image: "sm.resolution_512.png".into(),
            error_image: "sm.resolution_512-error.png".into(),
            frames: None,
            animation: None,
            temporal_error: None,
            walkthrough: None,
            sweep: Some(Sweep {
                key: "resolution".into(),
                value: "512".into(),
            }),
            worst_region: None,
        };
        let v = serde_json::to_value(&r).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        assert_eq!(
            keys,
            [
                "technique",
                "label",
                "params",
                "time_ms",
                "stages_ms",
                "memory_bytes",
                "counters",
                "mismatch_rate",
                "mean_abs_error",
                "mean_abs_error_rgb",
                "reference_spp",
                "frames_run",
                "converged",
                "image",
                "error_image",
                "sweep",
                "worst_region"
            ]
        );
        assert!(v["converged"].is_null() && v["worst_region"].is_null());
        let back: RunResult = serde_json::from_value(v.clone()).unwrap();
        assert_eq!(serde_json::to_value(back).unwrap(), v);
    }
}
