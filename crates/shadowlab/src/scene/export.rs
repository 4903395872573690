//! Writes the world-space triangles a frame was rendered from as OBJ, one `o` group per
//! material, with an `.mtl` beside it carrying colour and opacity — so another renderer
//! can re-trace exactly what shadowlab saw.

use super::Scene;
use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// Writes `scene` to `path` (and `path` with extension `.mtl`).
pub fn write_obj(scene: &Scene, path: &Path) -> Result<()> {
    let out_err = |e: std::io::Error| Error::Output {
        path: path.into(),
        what: e.to_string(),
    };
    let mtl_path = path.with_extension("mtl");
    let mtl_name = super::file_name(&mtl_path);
    let mut obj = String::with_capacity(scene.len() * 100);
    let _ = writeln!(
        obj,
        "# shadowlab scene export: {} ({} triangles, world space)",
        scene.name,
        scene.len()
    );
    let _ = writeln!(obj, "mtllib {mtl_name}");
    let mut mtl = String::new();
    let names: Vec<String> = scene
        .materials
        .iter()
        .enumerate()
        .map(|(mi, m)| format!("m{mi}_{}", m.name.replace(|c: char| c.is_whitespace(), "_")))
        .collect();
    for (m, name) in scene.materials.iter().zip(&names) {
        // `{:?}` prints the shortest text that parses back to the same f32.
        let _ = writeln!(
            mtl,
            "newmtl {name}\nKd {:?} {:?} {:?}",
            m.color.x, m.color.y, m.color.z
        );
        let t = m.transmittance;
        // Opaque: d 1. Otherwise d < 1 and Tf carries the RGB transmittance exactly.
        let opacity = if m.is_opaque() {
            1.0
        } else {
            (1.0 - t.max_element()).min(0.999)
        };
        let _ = writeln!(mtl, "d {opacity:?}\nTf {:?} {:?} {:?}\n", t.x, t.y, t.z);
    }
    // Triangles keep their order (ties between coincident surfaces resolve the same way on
    // re-import); a new `o` group starts where the material changes, which for scenes built
    // mesh by mesh is one group per material.
    let mut current = u32::MAX;
    let mut next_vertex = 1usize;
    for i in 0..scene.len() {
        let mi = scene.material[i];
        if mi != current {
            current = mi;
            let name = &names[mi as usize];
            let _ = writeln!(obj, "o {name}\nusemtl {name}");
        }
        for p in scene.triangle(i) {
            let _ = writeln!(obj, "v {:?} {:?} {:?}", p.x, p.y, p.z);
        }
        let _ = writeln!(
            obj,
            "f {} {} {}",
            next_vertex,
            next_vertex + 1,
            next_vertex + 2
        );
        next_vertex += 3;
    }
    crate::files::write_whole(path, obj.as_bytes()).map_err(out_err)?;
    crate::files::write_whole(&mtl_path, mtl.as_bytes()).map_err(|e| Error::Output {
        path: mtl_path.clone(),
        what: e.to_string(),
    })?;
    Ok(())
}
