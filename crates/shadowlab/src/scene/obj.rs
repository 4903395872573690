//! Wavefront OBJ with its `.mtl` materials, read with the `tobj` crate.
//!
//! Colours come from `Kd`; opacity from `d` (dissolve) or `Tr` (= 1 − d), and an explicit
//! RGB `Tf` (transmission filter) when present together with `d` < 1. Missing `.mtl`
//! files and missing textures are not errors: the mesh loads with a default material.

use super::{Material, Scene};
use crate::error::{Error, Result};
use crate::math::{vec3, Mat4, Vec3};
use std::path::Path;

/// Loads an OBJ file.
pub fn load(path: &Path) -> Result<Scene> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, mats) = tobj::load_obj(path, &opts).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => Error::Io {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "the file cannot be opened"),
        },
        other => Error::format(path, format!("not a valid OBJ file ({other})")),
    })?;
    // A missing or broken .mtl leaves every triangle with the default material.
    let mats = mats.unwrap_or_default();
    let mut scene = Scene::new(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
    let default = scene.add_material(Material::default());
    let base = scene.materials.len() as u32;
    for m in &mats {
        scene.add_material(convert(m));
    }
    for model in &models {
        let mesh = &model.mesh;
        let nverts = mesh.positions.len() / 3;
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|c| vec3(c[0] as f32, c[1] as f32, c[2] as f32))
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::format(
                path,
                format!("object {:?}: vertex {} has a non-finite coordinate", model.name, i + 1),
            ));
        }
        let mut tris = Vec::with_capacity(mesh.indices.len() / 3);
        for c in mesh.indices.chunks_exact(3) {
            if c.iter().any(|&i| i as usize >= nverts) {
                return Err(Error::format(
                    path,
                    format!("object {:?}: a face refers to a vertex that does not exist", model.name),
                ));
            }
            tris.push([c[0], c[1], c[2]]);
        }
        let m = match mesh.material_id {
            Some(id) if id < mats.len() => base + id as u32,
            _ => default,
        };
        scene.push_indexed(&positions, &tris, Mat4::IDENTITY, m);
    }
    Ok(scene)
}

fn convert(m: &tobj::Material) -> Material {
    let color = m
        .diffuse
        .map(|d| vec3(d[0] as f32, d[1] as f32, d[2] as f32))
        .unwrap_or(Vec3::splat(0.8))
        .clamp(Vec3::ZERO, Vec3::ONE);
    let mut opacity = m.dissolve.map(|d| d as f32).unwrap_or(1.0);
    if let Some(tr) = m.unknown_param.get("Tr").and_then(|s| s.trim().parse::<f32>().ok()) {
        if m.dissolve.is_none() {
            opacity = 1.0 - tr;
        }
    }
    let opacity = if opacity.is_finite() { opacity.clamp(0.0, 1.0) } else { 1.0 };
    let mut transmittance = Vec3::splat(1.0 - opacity);
    if opacity < 1.0 {
        if let Some(tf) = m.unknown_param.get("Tf") {
            let v: Vec<f32> = tf.split_whitespace().filter_map(|s| s.parse().ok()).collect();
            if v.len() == 3 && v.iter().all(|x| x.is_finite()) {
                transmittance = vec3(v[0], v[1], v[2]).clamp(Vec3::ZERO, Vec3::ONE) * (1.0 - opacity);
            }
        }
    }
    Material {
        name: m.name.clone(),
        color,
        transmittance,
    }
}
