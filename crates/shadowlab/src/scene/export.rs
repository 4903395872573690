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
    let mtl_name = mtl_path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut obj = String::with_capacity(scene.len() * 100);
    let _ = writeln!(obj, "# shadowlab scene export: {} ({} triangles, world space)", scene.name, scene.len());
    let _ = writeln!(obj, "mtllib {mtl_name}");
    let mut mtl = String::new();
    let mut next_vertex = 1usize;
    for (mi, m) in scene.materials.iter().enumerate() {
        let tris: Vec<usize> = (0..scene.len()).filter(|&i| scene.material[i] as usize == mi).collect();
        let name = format!("m{mi}_{}", m.name.replace(|c: char| c.is_whitespace(), "_"));
        let _ = writeln!(mtl, "newmtl {name}\nKd {} {} {}", m.color.x, m.color.y, m.color.z);
        let t = m.transmittance;
        let opacity = 1.0 - t.max_element();
        let _ = writeln!(mtl, "d {opacity}\nTf {} {} {}\n", t.x, t.y, t.z);
        if tris.is_empty() {
            continue;
        }
        let _ = writeln!(obj, "o {name}\nusemtl {name}");
        for &i in &tris {
            for p in scene.triangle(i) {
                // `{:?}` prints the shortest text that parses back to the same f32.
                let _ = writeln!(obj, "v {:?} {:?} {:?}", p.x, p.y, p.z);
            }
        }
        for k in 0..tris.len() {
            let b = next_vertex + 3 * k;
            let _ = writeln!(obj, "f {} {} {}", b, b + 1, b + 2);
        }
        next_vertex += 3 * tris.len();
    }
    std::fs::write(path, obj).map_err(out_err)?;
    std::fs::write(&mtl_path, mtl).map_err(|e| Error::Output {
        path: mtl_path.clone(),
        what: e.to_string(),
    })?;
    Ok(())
}
