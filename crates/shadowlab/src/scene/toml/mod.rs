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
//! # projection = "orthographic"    # default "perspective"; orthographic takes, instead of
//! # ymag = 1.5                     # fov_y_deg, half the viewed height (required) and
//! # xmag = 2.0                     # half its width (default ymag × width / height)
//! width = 1024                     # default 1024
//! height = 768                     # default 768
//! near = 0.05                      # near and far: default fitted to the scene
//! far = 20.0
//! path = [                         # optional key frames for walkthroughs (--frames N)
//!     { eye = [0.0, 1.2, 3.0], target = [0.0, 0.3, 0.0] },
//!     { eye = [2.0, 1.0, 2.0], target = [0.0, 0.3, 0.0] },
//! ]
//! pace = 48                        # optional: frames from the first key to the last, so
//!                                  # any --frames N walks at that pace (and stays at the
//!                                  # last key after it); default: stretched over the N frames
//!
//! [light]                          # optional; default: directional from above
//! kind = "spot"                    # "directional", "spot" or "point"
//! position = [1.5, 3.0, 1.0]       # spot and point
//! target = [0.0, 0.0, 0.0]         # spot: the cone's axis passes through it ...
//! # direction = [-0.4, -1.0, -0.3] # ... or the direction it shines in
//! fov_deg = 60.0                   # spot: full cone angle
//! # A directional light takes `direction` (where the light travels) or `to_light`
//! # (towards the light), e.g. kind = "directional", to_light = [0.3, 1.0, 0.2].
//! # size = 0.2                     # any of the three: becomes an area light (a point a
//! #                                # sphere of that radius, a spot a disk of that radius,
//! #                                # a directional light a sun of that angular diameter, °)
//! # Area lights: kind = "rect", centre = [..], edge_u = [..], edge_v = [..] (full edges);
//! # kind = "disk", centre, normal, radius; kind = "sphere", centre, radius.
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
//! up = "y"                         # the file's up axis: x, y, z, -x, -y or -z (turned first)
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
//!   are not used — the `[camera]` and `[light]` here are. `up` names the file's up axis
//!   (see [`crate::scene::up`]; a Z-up file takes `up = "z"`), turned before `scale`, the
//!   rotation and `translate`; `obj_kd_alpha = false` keeps an OBJ file's materials
//!   without `map_d` whole where their `map_Kd` image has alpha (the command line's
//!   `--obj-kd-alpha` is the default).
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
//!
//! The reader is in four parts: `spec` (the file's structure, deserialized with every key
//! checked), `mesh` (each `[[mesh]]` entry: a file or a generator, its material overrides
//! and its transform), `sections` (the `[camera]` and `[light]` sections) and this module,
//! which puts them together.

mod mesh;
mod sections;
mod spec;

use super::Scene;
use crate::error::{Error, Result};
use crate::files::{Access, MAX_SCENE_TEXT_BYTES};
use crate::math::Vec3;
use spec::V3;
use std::path::Path;

/// Default number of segments around a generated sphere.
pub const DEFAULT_SPHERE_SEGMENTS: u32 = 32;
/// The most segments around a generated sphere (its triangle count grows with the square).
pub const MAX_SPHERE_SEGMENTS: u32 = 2048;

/// The most key frames a camera path may have.
pub const MAX_KEY_FRAMES: usize = 100_000;

/// Loads a TOML scene file; its mesh files must lie in its folder.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &Access::for_scene(path, false))
}

/// Loads a TOML scene file whose mesh `file` paths resolve as `access` allows.
pub fn load_with(path: &Path, access: &Access) -> Result<Scene> {
    load_opts(path, access, true)
}

/// [`load_with`], its OBJ meshes cut out by their `map_Kd` alpha (where they have no
/// `map_d`) when `obj_kd_alpha`, unless a mesh's own `obj_kd_alpha` key says otherwise.
pub fn load_opts(path: &Path, access: &Access, obj_kd_alpha: bool) -> Result<Scene> {
    let bytes = super::read_input(path, MAX_SCENE_TEXT_BYTES, |h| {
        crate::files::sniff_text(h, "a TOML scene")
    })?;
    let fmt = |what: String| Error::format(path, what);
    let text = String::from_utf8(bytes).map_err(|e| {
        fmt(format!(
            "it is not UTF-8 text (byte {} is invalid)",
            e.utf8_error().valid_up_to()
        ))
    })?;
    let file = spec::parse(&text).map_err(fmt)?;
    if file.mesh.is_empty() {
        return Err(fmt("the scene has no [[mesh]] entries".into()));
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let name = file.name.clone().unwrap_or_else(|| super::file_name(path));
    let mut scene = Scene::new(name);
    for (i, spec) in file.mesh.iter().enumerate() {
        let label = format!("[[mesh]] {}", i + 1);
        let part = mesh::build(base, access, spec, obj_kd_alpha)
            .map_err(|what| fmt(format!("{label}: {what}")))?;
        super::check_triangle_count(path, (scene.len() + part.len()) as u64)?;
        scene.append(&part);
    }
    if let Some(c) = &file.camera {
        let (camera, camera_path) =
            sections::camera(c, &scene).map_err(|what| fmt(format!("[camera]: {what}")))?;
        scene.camera = Some(camera);
        scene.camera_path = camera_path;
    }
    if let Some(l) = &file.light {
        let (light, area) =
            sections::light_with_area(l).map_err(|what| fmt(format!("[light]: {what}")))?;
        scene.light = Some(light);
        scene.area_light = area;
    }
    Ok(scene)
}

/// A result whose error is the phrase naming what is wrong, to be prefixed with where.
type Msg<T> = std::result::Result<T, String>;

/// `v` as a vector, which must be finite (`key` names it in the message).
fn finite3(v: impl Into<[f32; 3]>, key: &str) -> Msg<Vec3> {
    let v = Vec3::from(v.into());
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("`{key}` has a non-finite component"))
    }
}

/// `v` as a vector in `[0, 1]³` (`key` names it in the message).
fn unit_range3(v: V3, key: &str) -> Msg<Vec3> {
    let v = finite3(v, key)?;
    if v.min_element() < 0.0 || v.max_element() > 1.0 {
        return Err(format!("`{key}` = {v} is outside [0, 1]"));
    }
    Ok(v)
}
