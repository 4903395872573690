//! The TOML scene format: meshes from files or generators, each placed by a transform and
//! optionally given a material, plus the camera (with an optional key-framed path) and the
//! light.
//!
//! A complete example (every key shown; most are optional):
//!
//! ```toml
//! name = "bunny on a slab"         # optional; default: the file name
//!
//! [camera]                         # optional; default: framed automatically
//! eye = [0.0, 1.2, 3.0]
//! target = [0.0, 0.3, 0.0]
//! up = [0.0, 1.0, 0.0]             # default +Y
//! fov_y_deg = 45.0                 # vertical field of view, default 45
//! width = 1024                     # default 1024
//! height = 768                     # default 768
//! near = 0.05                      # near and far: default fitted to the scene
//! far = 20.0
//! path = [                         # optional key frames for walkthroughs (--frames N)
//!     { eye = [0.0, 1.2, 3.0], target = [0.0, 0.3, 0.0] },
//!     { eye = [2.0, 1.0, 2.0], target = [0.0, 0.3, 0.0] },
//! ]
//!
//! [light]                          # optional; default: directional from above
//! kind = "spot"                    # "directional", "spot" or "point"
//! position = [1.5, 3.0, 1.0]       # spot and point
//! target = [0.0, 0.0, 0.0]         # spot: the cone's axis passes through it ...
//! # direction = [-0.4, -1.0, -0.3] # ... or the direction it shines in
//! fov_deg = 60.0                   # spot: full cone angle
//! # A directional light takes `direction` (where the light travels) or `to_light`
//! # (towards the light), e.g. kind = "directional", to_light = [0.3, 1.0, 0.2].
//!
//! [[mesh]]
//! name = "slab"                    # optional; names the material
//! generator = "box"                # a unit cube centred on the origin
//! scale = [2.0, 0.1, 1.2]          # a number or [x, y, z]
//! translate = [0.0, -0.05, 0.0]
//! color = [0.6, 0.45, 0.3]         # linear RGB in [0, 1]
//!
//! [[mesh]]
//! file = "meshes/bunny.obj"        # relative to this file: .obj, .ply, .gltf or .glb
//! scale = 0.05
//! rotate_deg = [0.0, 30.0, 0.0]    # Euler angles: about X, then Y, then Z (world axes)
//! translate = [-0.3, 0.0, 0.0]
//!
//! [[mesh]]
//! generator = "sphere"             # diameter 1, centred on the origin
//! params = { segments = 48 }
//! translate = [0.6, 0.35, 0.2]
//! scale = 0.3
//! rotate_axis = [0.0, 0.0, 1.0]    # axis-angle rotation, instead of rotate_deg
//! rotate_angle_deg = 90.0
//! opacity = 0.4                    # or transmittance = [r, g, b]
//!
//! [[mesh]]
//! generator = "plane"              # a 1 × 1 square in the XZ plane, facing +Y
//! scale = 8.0
//! translate = [0.0, -0.6, 0.0]
//! ```
//!
//! Meshes:
//! - `file` loads a mesh with the loader for its extension. The file's materials are kept
//!   unless `color`, `transmittance` or `opacity` override them (each override replaces
//!   that property in all of the file's materials); a glTF file's own cameras and lights
//!   are not used — the `[camera]` and `[light]` here are.
//! - `generator` makes a shape: `plane` (or `quad`): a 1 × 1 square at y = 0 facing +Y;
//!   `box`: the unit cube `[-0.5, 0.5]³`; `sphere`: diameter 1 (`params.segments`
//!   around, half as many from pole to pole; default [`DEFAULT_SPHERE_SEGMENTS`]). Any other
//!   name is a built-in scene (`shadowlab scenes`) whose triangles and materials are
//!   used, with `params` as its parameters.
//! - The transform applies `scale`, then the rotation, then `translate`.
//!
//! Every key is checked: an unknown key, a wrong type or a value out of range is an
//! [`Error::Format`] naming this file, and the key (with TOML's line and column) or the
//! `[[mesh]]` entry (1-based) at fault; errors from a referenced file name both files.

use super::{Material, Scene};
use crate::camera::{Camera, CameraKey, CameraPath};
use crate::error::{Error, Result};
use crate::files::{Access, MAX_SCENE_TEXT_BYTES};
use crate::light::Light;
use crate::math::{vec3, Mat4, Vec3};
use glam::Quat;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Default number of segments around a generated sphere.
pub const DEFAULT_SPHERE_SEGMENTS: u32 = 32;
/// The most segments around a generated sphere (its triangle count grows with the square).
pub const MAX_SPHERE_SEGMENTS: u32 = 2048;

/// The most key frames a camera path may have.
pub const MAX_KEY_FRAMES: usize = 100_000;

/// Three numbers, exactly: a longer or shorter array is an error, not truncated.
#[derive(Clone, Copy)]
struct V3([f32; 3]);

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
struct SceneFile {
    name: Option<String>,
    camera: Option<CameraSpec>,
    light: Option<LightSpec>,
    #[serde(default)]
    mesh: Vec<MeshSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: V3,
    target: V3,
    up: Option<V3>,
    fov_y_deg: Option<f32>,
    width: Option<u32>,
    height: Option<u32>,
    near: Option<f32>,
    far: Option<f32>,
    path: Option<Vec<KeySpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeySpec {
    eye: V3,
    target: V3,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum LightKind {
    Directional,
    Spot,
    Point,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSpec {
    kind: LightKind,
    direction: Option<V3>,
    to_light: Option<V3>,
    position: Option<V3>,
    target: Option<V3>,
    fov_deg: Option<f32>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    PerAxis(V3),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSpec {
    name: Option<String>,
    file: Option<String>,
    generator: Option<String>,
    params: Option<toml::Table>,
    translate: Option<V3>,
    rotate_deg: Option<V3>,
    rotate_axis: Option<V3>,
    rotate_angle_deg: Option<f32>,
    scale: Option<Scale>,
    color: Option<V3>,
    transmittance: Option<V3>,
    opacity: Option<f32>,
}

/// Loads a TOML scene file; its mesh files must lie in its folder.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &Access::for_scene(path, false))
}

/// Loads a TOML scene file whose mesh `file` paths resolve as `access` allows.
pub fn load_with(path: &Path, access: &Access) -> Result<Scene> {
    let bytes = super::read_input(path, MAX_SCENE_TEXT_BYTES)?;
    let fmt = |what: String| Error::format(path, what);
    let text = String::from_utf8(bytes).map_err(|e| {
        fmt(format!(
            "it is not UTF-8 text (byte {} is invalid)",
            e.utf8_error().valid_up_to()
        ))
    })?;
    let file: SceneFile = ::toml::from_str(&text).map_err(|e| {
        let at = e.span().map(|s| {
            let before = &text[..s.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!("line {line}, column {col}: ")
        });
        fmt(format!("{}{}", at.unwrap_or_default(), e.message().trim()))
    })?;
    if file.mesh.is_empty() {
        return Err(fmt("the scene has no [[mesh]] entries".into()));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    let mut scene = Scene::new(name);
    for (i, spec) in file.mesh.iter().enumerate() {
        let label = format!("[[mesh]] {}", i + 1);
        let part =
            build_mesh(base, access, spec).map_err(|what| fmt(format!("{label}: {what}")))?;
        super::check_triangle_count(path, (scene.len() + part.len()) as u64)?;
        scene.append(&part);
    }
    if let Some(c) = &file.camera {
        let (camera, camera_path) =
            build_camera(c, &scene).map_err(|what| fmt(format!("[camera]: {what}")))?;
        scene.camera = Some(camera);
        scene.camera_path = camera_path;
    }
    if let Some(l) = &file.light {
        scene.light = Some(build_light(l).map_err(|what| fmt(format!("[light]: {what}")))?);
    }
    Ok(scene)
}

type Msg<T> = std::result::Result<T, String>;

fn finite3(v: impl Into<[f32; 3]>, key: &str) -> Msg<Vec3> {
    let v = Vec3::from(v.into());
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("`{key}` has a non-finite component"))
    }
}

fn unit_range3(v: V3, key: &str) -> Msg<Vec3> {
    let v = finite3(v, key)?;
    if v.min_element() < 0.0 || v.max_element() > 1.0 {
        return Err(format!("`{key}` = {v} is outside [0, 1]"));
    }
    Ok(v)
}

/// One `[[mesh]]` entry: its triangles in world space with their materials.
fn build_mesh(base: &Path, access: &Access, spec: &MeshSpec) -> Msg<Scene> {
    let mut part = match (&spec.file, &spec.generator) {
        (Some(_), Some(_)) => return Err("give either `file` or `generator`, not both".into()),
        (None, None) => return Err("give a `file` or a `generator`".into()),
        (Some(f), None) => {
            if spec.params.is_some() {
                return Err("`params` applies to generators only, not to files".into());
            }
            load_file(base, access, f)?
        }
        (None, Some(g)) => generate(g, spec.params.as_ref(), spec.name.as_deref().unwrap_or(g))?,
    };
    if part.is_empty() {
        return Err("it holds no triangles".into());
    }
    // Material overrides.
    let color = spec.color.map(|c| unit_range3(c, "color")).transpose()?;
    let transmittance = match (spec.transmittance, spec.opacity) {
        (Some(_), Some(_)) => {
            return Err("give either `transmittance` or `opacity`, not both".into())
        }
        (Some(t), None) => Some(unit_range3(t, "transmittance")?),
        (None, Some(o)) => {
            if !(0.0..=1.0).contains(&o) {
                return Err(format!("`opacity` = {o} is outside [0, 1]"));
            }
            Some(Vec3::splat(1.0 - o))
        }
        (None, None) => None,
    };
    let single = part.materials.len() == 1;
    for m in &mut part.materials {
        if let Some(c) = color {
            m.color = c;
        }
        if let Some(t) = transmittance {
            m.transmittance = t;
        }
        if let Some(n) = &spec.name {
            m.name = if single {
                n.clone()
            } else {
                format!("{n}/{}", m.name)
            };
        }
    }
    let world = transform(spec)?;
    if world != Mat4::IDENTITY {
        for k in 0..part.len() {
            part.v0[k] = world.transform_point3(part.v0[k]);
            part.v1[k] = world.transform_point3(part.v1[k]);
            part.v2[k] = world.transform_point3(part.v2[k]);
        }
        part.recompute_bounds();
    }
    Ok(part)
}

/// Loads a mesh file named relative to the scene file (inside its folder unless `access`
/// allows more); its camera and light are dropped.
fn load_file(base: &Path, access: &Access, file: &str) -> Msg<Scene> {
    let shown: String = file.chars().take(120).collect();
    let full = access
        .resolve(base, file)
        .map_err(|why| format!("the mesh file {shown:?} {why}"))?;
    let meta = std::fs::metadata(&full).map_err(|e| {
        format!(
            "the mesh file {shown:?} ({}) {}",
            full.display(),
            crate::files::io_reason(&e)
        )
    })?;
    if let Some(kind) = crate::files::special_kind(&meta.file_type()) {
        return Err(format!(
            "the mesh file {shown:?} ({}) is {kind}, not a regular file",
            full.display()
        ));
    }
    let ext = full
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let loaded = match ext.as_str() {
        "obj" => super::obj::load_with(&full, access),
        "ply" => super::ply::load(&full),
        "gltf" | "glb" => super::gltf::load_with(&full, access, 0),
        "toml" => {
            return Err(format!(
                "{file:?}: a scene file cannot include another scene file"
            ))
        }
        _ => {
            return Err(format!(
                "{file:?}: unknown mesh format (use .obj, .ply, .gltf or .glb)"
            ))
        }
    };
    let mut s = loaded.map_err(|e| format!("in the mesh file {file:?}: {e}"))?;
    s.camera = None;
    s.camera_path = None;
    s.light = None;
    Ok(s)
}

/// `scale`, then the rotation, then `translate`.
fn transform(spec: &MeshSpec) -> Msg<Mat4> {
    let scale = match &spec.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(*s),
        Some(Scale::PerAxis(v)) => Vec3::from(v.0),
    };
    if !scale.is_finite() || scale.abs().min_element() == 0.0 {
        return Err(format!(
            "`scale` = {scale} must be finite and non-zero on every axis"
        ));
    }
    let rotation = match (spec.rotate_deg, spec.rotate_axis, spec.rotate_angle_deg) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err(
                "give either `rotate_deg` or `rotate_axis` with `rotate_angle_deg`, not both"
                    .into(),
            )
        }
        (Some(e), None, None) => {
            let e = finite3(e, "rotate_deg")?;
            // About world X first, then Y, then Z.
            Quat::from_rotation_z(e.z.to_radians())
                * Quat::from_rotation_y(e.y.to_radians())
                * Quat::from_rotation_x(e.x.to_radians())
        }
        (None, Some(axis), Some(angle)) => {
            let axis = finite3(axis, "rotate_axis")?;
            if axis.length_squared() == 0.0 || !angle.is_finite() {
                return Err("`rotate_axis` must be non-zero and `rotate_angle_deg` finite".into());
            }
            Quat::from_axis_angle(axis.normalize(), angle.to_radians())
        }
        (None, Some(_), None) | (None, None, Some(_)) => {
            return Err("`rotate_axis` and `rotate_angle_deg` go together".into())
        }
        (None, None, None) => Quat::IDENTITY,
    };
    let translate = finite3(spec.translate.unwrap_or(V3([0.0; 3])), "translate")?;
    Ok(Mat4::from_scale_rotation_translation(
        scale, rotation, translate,
    ))
}

/// A generated shape, or a built-in scene's triangles.
fn generate(name: &str, params: Option<&toml::Table>, material_name: &str) -> Msg<Scene> {
    let mut text = BTreeMap::new();
    for (k, v) in params.into_iter().flatten() {
        let s = match v {
            toml::Value::String(s) => s.clone(),
            toml::Value::Integer(i) => i.to_string(),
            toml::Value::Float(f) => f.to_string(),
            toml::Value::Boolean(b) => b.to_string(),
            _ => return Err(format!("`params.{k}` must be a string, number or boolean")),
        };
        text.insert(k.clone(), s);
    }
    let own = |allowed: &[&str]| -> Msg<()> {
        match text.keys().find(|k| !allowed.contains(&k.as_str())) {
            Some(k) if allowed.is_empty() => Err(format!(
                "generator {name:?} takes no parameters, but `params.{k}` is given"
            )),
            Some(k) => Err(format!(
                "generator {name:?} has no parameter `{k}` (known: {})",
                allowed.join(", ")
            )),
            None => Ok(()),
        }
    };
    let mut s = Scene::new(name);
    let m = s.add_material(Material {
        name: material_name.into(),
        ..Material::default()
    });
    match name {
        "plane" | "quad" => {
            own(&[])?;
            let c = [
                vec3(-0.5, 0.0, -0.5),
                vec3(-0.5, 0.0, 0.5),
                vec3(0.5, 0.0, 0.5),
                vec3(0.5, 0.0, -0.5),
            ];
            // Counter-clockwise seen from +Y.
            s.push([c[0], c[1], c[2]], m);
            s.push([c[0], c[2], c[3]], m);
        }
        "box" => {
            own(&[])?;
            add_box(&mut s, m);
        }
        "sphere" => {
            own(&["segments"])?;
            let segments = match text.get("segments") {
                None => DEFAULT_SPHERE_SEGMENTS,
                Some(v) => v
                    .parse::<u32>()
                    .ok()
                    .filter(|n| (3..=MAX_SPHERE_SEGMENTS).contains(n))
                    .ok_or_else(|| format!("`params.segments` = {v} is not a whole number in 3..={MAX_SPHERE_SEGMENTS}"))?,
            };
            add_sphere(&mut s, segments, m);
        }
        _ => {
            let scenes = super::builtin::list();
            if !scenes.iter().any(|(n, _)| *n == name) {
                let names: Vec<&str> = scenes.iter().map(|(n, _)| *n).collect();
                return Err(format!(
                    "generator {name:?} is neither a shape (plane, quad, box, sphere) nor a built-in scene ({})",
                    names.join(", ")
                ));
            }
            let mut b = super::builtin::generate(name, &text)
                .map_err(|e| format!("generator {name:?}: {e}"))?;
            b.camera = None;
            b.camera_path = None;
            b.light = None;
            return Ok(b);
        }
    }
    Ok(s)
}

/// The unit cube `[-0.5, 0.5]³`, outward-facing counter-clockwise triangles.
fn add_box(s: &mut Scene, m: u32) {
    let h = 0.5;
    // Each face: its centre direction n and two in-plane axes u, v with u × v = n.
    for (n, u) in [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::X),
        (Vec3::Z, Vec3::X),
        (Vec3::NEG_Z, Vec3::Y),
    ] {
        let v = n.cross(u);
        let c = n * h;
        let (u, v) = (u * h, v * h);
        let q = [c - u - v, c + u - v, c + u + v, c - u + v];
        s.push([q[0], q[1], q[2]], m);
        s.push([q[0], q[2], q[3]], m);
    }
}

/// A UV sphere of diameter 1 with `segments` around and `segments / 2` from pole to pole.
fn add_sphere(s: &mut Scene, segments: u32, m: u32) {
    let rings = (segments / 2).max(2);
    let r = 0.5f32;
    let point = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
        vec3(
            theta.sin() * phi.cos(),
            theta.cos(),
            -theta.sin() * phi.sin(),
        ) * r
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            if i != 0 {
                s.push([a, b, d], m);
            }
            if i != rings - 1 {
                s.push([d, b, c], m);
            }
        }
    }
}

fn build_camera(c: &CameraSpec, scene: &Scene) -> Msg<(Camera, Option<CameraPath>)> {
    let eye = finite3(c.eye, "eye")?;
    let target = finite3(c.target, "target")?;
    let mut camera = Camera::look_at(
        eye,
        target,
        c.fov_y_deg.unwrap_or(45.0),
        c.width.unwrap_or(1024),
        c.height.unwrap_or(768),
    );
    if let Some(up) = c.up {
        camera.up = finite3(up, "up")?;
    }
    camera.fit_depth_range(&scene.bounds);
    match (c.near, c.far) {
        (Some(n), Some(f)) => (camera.near, camera.far) = (n, f),
        (Some(n), None) => camera.near = n,
        (None, Some(f)) => camera.far = f,
        (None, None) => {}
    }
    camera.validate().map_err(|e| e.to_string())?;
    let path = match &c.path {
        None => None,
        Some(keys) if keys.is_empty() => return Err("`path` has no key frames".into()),
        Some(keys) if keys.len() > MAX_KEY_FRAMES => {
            return Err(format!(
                "`path` has {} key frames, more than the limit of {MAX_KEY_FRAMES}",
                keys.len()
            ))
        }
        Some(keys) => {
            let mut out = Vec::with_capacity(keys.len());
            for (i, k) in keys.iter().enumerate() {
                let key = CameraKey {
                    eye: finite3(k.eye, &format!("path[{i}].eye"))?,
                    target: finite3(k.target, &format!("path[{i}].target"))?,
                };
                let mut check = camera;
                (check.eye, check.target) = (key.eye, key.target);
                check.validate().map_err(|e| format!("path[{i}]: {e}"))?;
                out.push(key);
            }
            Some(CameraPath { keys: out })
        }
    };
    Ok((camera, path))
}

fn build_light(l: &LightSpec) -> Msg<Light> {
    let kind = match l.kind {
        LightKind::Directional => "directional",
        LightKind::Spot => "spot",
        LightKind::Point => "point",
    };
    let reject = |key: &str, given: bool| -> Msg<()> {
        if given {
            Err(format!("`{key}` does not apply to a {kind} light"))
        } else {
            Ok(())
        }
    };
    let light = match l.kind {
        LightKind::Directional => {
            reject("position", l.position.is_some())?;
            reject("target", l.target.is_some())?;
            reject("fov_deg", l.fov_deg.is_some())?;
            let to_light = match (l.direction, l.to_light) {
                (Some(d), None) => -finite3(d, "direction")?,
                (None, Some(t)) => finite3(t, "to_light")?,
                _ => {
                    return Err(
                        "a directional light takes exactly one of `direction` and `to_light`"
                            .into(),
                    )
                }
            };
            if to_light.length_squared() == 0.0 {
                return Err("the light direction is the zero vector".into());
            }
            Light::Directional {
                to_light: to_light.normalize(),
            }
        }
        LightKind::Spot => {
            reject("to_light", l.to_light.is_some())?;
            let position = finite3(
                l.position.ok_or("a spot light needs `position`")?,
                "position",
            )?;
            let target = match (l.target, l.direction) {
                (Some(t), None) => finite3(t, "target")?,
                (None, Some(d)) => position + finite3(d, "direction")?,
                _ => {
                    return Err("a spot light takes exactly one of `target` and `direction`".into())
                }
            };
            Light::Spot {
                position,
                target,
                fov_deg: l.fov_deg.ok_or("a spot light needs `fov_deg`")?,
            }
        }
        LightKind::Point => {
            reject("direction", l.direction.is_some())?;
            reject("to_light", l.to_light.is_some())?;
            reject("target", l.target.is_some())?;
            reject("fov_deg", l.fov_deg.is_some())?;
            Light::Point {
                position: finite3(
                    l.position.ok_or("a point light needs `position`")?,
                    "position",
                )?,
            }
        }
    };
    light.validate().map_err(|e| e.to_string())?;
    Ok(light)
}
