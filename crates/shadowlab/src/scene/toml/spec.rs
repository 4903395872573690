//! The TOML scene file's structure: what each table and key may hold, deserialized with
//! unknown keys refused, and the parse error placed by line and column.

use serde::Deserialize;

/// Three numbers, exactly: a longer or shorter array is an error, not truncated.
#[derive(Clone, Copy)]
pub(super) struct V3(pub(super) [f32; 3]);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let v = Vec::<f32>::deserialize(d)?;
        match v[..] {
            [x, y, z] => Ok(V3([x, y, z])),
            _ => Err(serde::de::Error::custom(format!(
                "expected 3 numbers [x, y, z], found {}",
                v.len()
            ))),
        }
    }
}

impl From<V3> for [f32; 3] {
    fn from(v: V3) -> Self {
        v.0
    }
}

/// The whole file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    pub(super) camera: Option<CameraSpec>,
    pub(super) light: Option<LightSpec>,
    #[serde(default)]
    pub(super) mesh: Vec<MeshSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub(super) eye: V3,
    pub(super) target: V3,
    pub(super) up: Option<V3>,
    pub(super) fov_y_deg: Option<f32>,
    pub(super) projection: Option<ProjectionKind>,
    pub(super) xmag: Option<f32>,
    pub(super) ymag: Option<f32>,
    pub(super) width: Option<u32>,
    pub(super) height: Option<u32>,
    pub(super) near: Option<f32>,
    pub(super) far: Option<f32>,
    pub(super) path: Option<Vec<KeySpec>>,
    pub(super) pace: Option<u32>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum ProjectionKind {
    Perspective,
    Orthographic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct KeySpec {
    pub(super) eye: V3,
    pub(super) target: V3,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum LightKind {
    Directional,
    Spot,
    Point,
    Rect,
    Disk,
    Sphere,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LightSpec {
    pub(super) kind: LightKind,
    pub(super) direction: Option<V3>,
    pub(super) to_light: Option<V3>,
    pub(super) position: Option<V3>,
    pub(super) target: Option<V3>,
    pub(super) fov_deg: Option<f32>,
    pub(super) size: Option<f32>,
    pub(super) centre: Option<V3>,
    pub(super) edge_u: Option<V3>,
    pub(super) edge_v: Option<V3>,
    pub(super) normal: Option<V3>,
    pub(super) radius: Option<f32>,
}

#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum Scale {
    Uniform(f32),
    PerAxis(V3),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MeshSpec {
    pub(super) name: Option<String>,
    pub(super) file: Option<String>,
    pub(super) generator: Option<String>,
    pub(super) params: Option<toml::Table>,
    pub(super) translate: Option<V3>,
    pub(super) rotate_deg: Option<V3>,
    pub(super) rotate_axis: Option<V3>,
    pub(super) rotate_angle_deg: Option<f32>,
    pub(super) scale: Option<Scale>,
    pub(super) color: Option<V3>,
    pub(super) transmittance: Option<V3>,
    pub(super) opacity: Option<f32>,
    pub(super) up: Option<String>,
    pub(super) obj_kd_alpha: Option<bool>,
}

/// The scene file `text`, or the parse error with its line and column.
pub(super) fn parse(text: &str) -> std::result::Result<SceneFile, String> {
    ::toml::from_str(text).map_err(|e| {
        let at = e.span().map(|s| {
            let before = &text[..s.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!("line {line}, column {col}: ")
        });
        format!("{}{}", at.unwrap_or_default(), e.message().trim())
    })
}
