//! One `[[mesh]]` entry of a TOML scene: a mesh file (by the loader for its extension) or
//! a generator (a shape, or a built-in scene's triangles), its material overrides, and the
//! transform that places it.

use super::spec::{MeshSpec, Scale, V3};
use super::{finite3, unit_range3, Msg, DEFAULT_SPHERE_SEGMENTS, MAX_SPHERE_SEGMENTS};
use crate::files::Access;
use crate::math::{vec3, Mat4, Vec3};
use crate::scene::builtin::{
    self, shapes::add_box_faces, shapes::add_quad, shapes::add_unit_sphere, shapes::BoxFace,
};
use crate::scene::{gltf, obj, ply, Material, Scene, UpAxis};
use glam::Quat;
use std::collections::BTreeMap;
use std::path::Path;

/// One `[[mesh]]` entry: its triangles in world space with their materials.
pub(super) fn build(
    base: &Path,
    access: &Access,
    spec: &MeshSpec,
    obj_kd_alpha: bool,
) -> Msg<Scene> {
    let up = match &spec.up {
        Some(u) => u.parse::<UpAxis>().map_err(|e| format!("`up` = {e}"))?,
        None => UpAxis::Y,
    };
    let kd_alpha = spec.obj_kd_alpha.unwrap_or(obj_kd_alpha);
    let mut part = match (&spec.file, &spec.generator) {
        (Some(_), Some(_)) => return Err("give either `file` or `generator`, not both".into()),
        (None, None) => return Err("give a `file` or a `generator`".into()),
        (Some(f), None) => {
            if spec.params.is_some() {
                return Err("`params` applies to generators only, not to files".into());
            }
            load_file(base, access, f, kd_alpha)?
        }
        (None, Some(g)) => {
            if spec.obj_kd_alpha.is_some() {
                return Err("`obj_kd_alpha` applies to OBJ files only, not to generators".into());
            }
            generate(g, spec.params.as_ref(), spec.name.as_deref().unwrap_or(g))?
        }
    };
    // The file's up axis first; `scale`, the rotation and `translate` act on the upright
    // mesh.
    part.turn_up(up);
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
        part.transform_triangles(0..part.len(), world);
    }
    Ok(part)
}

/// Loads a mesh file named relative to the scene file (inside its folder unless `access`
/// allows more); its camera and light are dropped.
fn load_file(base: &Path, access: &Access, file: &str, kd_alpha: bool) -> Msg<Scene> {
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
        "obj" => obj::load_opts(&full, access, kd_alpha),
        "ply" => ply::load(&full),
        "gltf" | "glb" => gltf::load_with(&full, access, 0),
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
            let (Some(axis), true) = (crate::math::direction(axis), angle.is_finite()) else {
                return Err("`rotate_axis` must be non-zero and `rotate_angle_deg` finite".into());
            };
            Quat::from_axis_angle(axis, angle.to_radians())
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
fn generate(name: &str, params: Option<&::toml::Table>, material_name: &str) -> Msg<Scene> {
    let mut text = BTreeMap::new();
    for (k, v) in params.into_iter().flatten() {
        let s = match v {
            ::toml::Value::String(s) => s.clone(),
            ::toml::Value::Integer(i) => i.to_string(),
            ::toml::Value::Float(f) => f.to_string(),
            ::toml::Value::Boolean(b) => b.to_string(),
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
            // Counter-clockwise seen from +Y.
            let corner = vec3(-0.5, 0.0, -0.5);
            add_quad(&mut s, corner, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), m);
        }
        "box" => {
            own(&[])?;
            let h = Vec3::splat(0.5);
            add_box_faces(&mut s, -h, h, BoxFace::AXIS_ORDER, m);
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
            add_unit_sphere(&mut s, segments, m);
        }
        _ => {
            let scenes = builtin::list();
            if !scenes.iter().any(|(n, _)| *n == name) {
                let names: Vec<&str> = scenes.iter().map(|(n, _)| *n).collect();
                return Err(format!(
                    "generator {name:?} is neither a shape (plane, quad, box, sphere) nor a built-in scene ({})",
                    names.join(", ")
                ));
            }
            let mut b =
                builtin::generate(name, &text).map_err(|e| format!("generator {name:?}: {e}"))?;
            b.camera = None;
            b.camera_path = None;
            b.light = None;
            return Ok(b);
        }
    }
    Ok(s)
}
