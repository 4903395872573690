//! Wavefront OBJ with its `.mtl` materials, read with the `tobj` crate.
//!
//! Colours come from `Kd`; opacity from `d` (dissolve) or `Tr` (= 1 − d), and an explicit
//! RGB `Tf` (transmission filter), taken as the transmittance when `d` < 1. Missing `.mtl`
//! files and missing textures are not errors: the mesh loads with a default material.
//! Alpha cut-outs come from `map_d`, or from the alpha of `map_Kd` (see `obj_masks`); a
//! cut-out material's faces carry their texture coordinates (`vt`, with `v` turned to
//! count from the image's top row as glTF's do).
//!
//! What cannot cast a shadow is skipped, and said once per kind in [`Scene::warnings`]:
//! faces of one or two vertices (points and edges some exporters write among the
//! triangles), `l` and `p` statements, and statements shadowlab does not read (free-form
//! curves and surfaces, `vp`, display attributes). Polygons of more than three vertices are
//! triangulated as a fan. Refused: a non-finite coordinate, a face naming a vertex that
//! does not exist, and a face of fewer than three vertices on a last line with no newline
//! (the mark of a file cut short).

use super::alpha_mask::AlphaMask;
use super::obj_masks::Masks;
use super::{Material, Scene};
use crate::error::{Error, Result};
use crate::files::{read_regular_file, Access, MAX_FILE_BYTES, MAX_SCENE_TEXT_BYTES};
use crate::math::{vec2, vec3, Mat4, Vec2, Vec3};
use std::borrow::Cow;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

const LOAD_OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    triangulate: true,
    single_index: false,
    ignore_points: true,
    ignore_lines: true,
};

/// Loads an OBJ file; its `mtllib` files must lie in its folder.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &Access::for_scene(path, false))
}

/// Loads an OBJ file whose `mtllib` files resolve as `access` allows. Material libraries
/// that do not exist are not errors (the mesh gets the default material); one that is
/// not a regular file, or lies outside where `access` allows, is.
pub fn load_with(path: &Path, access: &Access) -> Result<Scene> {
    load_opts(path, access, true)
}

/// [`load_with`], where `kd_alpha` says whether the alpha channel of a material's
/// `map_Kd` image cuts it out when it has no `map_d`.
pub fn load_opts(path: &Path, access: &Access, kd_alpha: bool) -> Result<Scene> {
    let bytes = super::read_input(path, MAX_FILE_BYTES, |h| {
        crate::files::sniff_text(h, "an OBJ file")
    })?;
    let (text, warnings) = prefilter(path, &bytes)?;
    let triangles = check_lines(path, &bytes)?;
    super::check_triangle_count(path, triangles)?;
    let base = path.parent().unwrap_or(Path::new(""));
    let refused: RefCell<Option<String>> = RefCell::new(None);
    // The folder of each library read, with its number of materials, in order.
    let libraries: RefCell<Vec<(PathBuf, usize)>> = RefCell::new(Vec::new());
    let loader = |mtl: &Path| {
        let name = mtl.to_string_lossy();
        let read = access.resolve(base, &name).and_then(|full| {
            let text = read_regular_file(&full, MAX_SCENE_TEXT_BYTES)?;
            Ok((full, text))
        });
        match read {
            Ok((full, text)) => {
                let r = tobj::load_mtl_buf(&mut text.as_slice());
                if let Ok((m, _)) = &r {
                    let dir = full.parent().unwrap_or(Path::new("")).to_path_buf();
                    libraries.borrow_mut().push((dir, m.len()));
                }
                r
            }
            Err(why) => {
                if why != "does not exist" && refused.borrow().is_none() {
                    *refused.borrow_mut() = Some(format!("its material library {name:?} {why}"));
                }
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    let (models, mats) = tobj::load_obj_buf(&mut text.as_ref(), &LOAD_OPTIONS, loader)
        .map_err(|e| Error::format(path, format!("not a valid OBJ file ({e})")))?;
    if let Some(why) = refused.into_inner() {
        return Err(Error::format(path, why));
    }
    let mut reader = Masks::new(path, access, kd_alpha);
    let mut masks = Vec::new();
    if let Ok(mats) = &mats {
        let dirs = libraries
            .into_inner()
            .into_iter()
            .flat_map(|(dir, n)| std::iter::repeat_n(dir, n));
        for (m, dir) in mats.iter().zip(dirs) {
            masks.push(reader.mask(m, &dir)?);
        }
    }
    let mut scene = build(path, &models, mats, &masks)?;
    let mut all = warnings;
    all.append(&mut scene.warnings);
    all.extend(reader.warnings());
    scene.warnings = all;
    Ok(scene)
}

/// Loads OBJ text held in memory, with the text of its `.mtl` file if it has one (every
/// `mtllib` line resolves to that text). `name` names the mesh in the scene and in errors.
pub fn load_from_str(name: &str, obj: &str, mtl: Option<&str>) -> Result<Scene> {
    let path = Path::new(name);
    let loader = |_: &Path| match mtl {
        Some(text) => tobj::load_mtl_buf(&mut text.as_bytes()),
        None => Err(tobj::LoadError::OpenFileFailed),
    };
    let (text, warnings) = prefilter(path, obj.as_bytes())?;
    let (models, mats) = tobj::load_obj_buf(&mut text.as_ref(), &LOAD_OPTIONS, loader)
        .map_err(|e| Error::format(path, format!("not a valid OBJ file ({e})")))?;
    let mut scene = build(path, &models, mats, &[])?;
    scene.warnings = warnings;
    Ok(scene)
}

/// Statements read (`v`, `f`, …) or dropped on purpose without a word: `s` (smoothing
/// groups) only changes interpolated normals, which shadows never use.
const KNOWN_STATEMENTS: &[&[u8]] = &[
    b"v", b"vt", b"vn", b"f", b"o", b"g", b"s", b"mtllib", b"usemtl",
];

/// What [`prefilter`] left out of an OBJ text.
#[derive(Default)]
struct Skipped {
    /// `f` lines with fewer than three vertices (edges and points written as faces).
    short_faces: usize,
    /// `l` (polyline) statements.
    lines: usize,
    /// `p` (point) statements.
    points: usize,
    /// Other statements shadowlab does not read, by keyword.
    unknown: std::collections::BTreeMap<String, usize>,
}

/// The OBJ text without what cannot cast a shadow — faces of fewer than 3 vertices, `l`
/// and `p` statements (`tobj` would make triangles of a 3-vertex `l`) — and one warning
/// per kind of thing left out, naming the file. Fails on a face of fewer than 3 vertices
/// on an unterminated last line: that is how a file cut short in its face list ends.
fn prefilter<'a>(path: &Path, bytes: &'a [u8]) -> Result<(Cow<'a, [u8]>, Vec<String>)> {
    let mut skipped = Skipped::default();
    let mut kept: Vec<u8> = Vec::new();
    // Bytes up to `copied` are kept verbatim; filtering starts at the first dropped line.
    let mut copied = 0;
    let mut start = 0;
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let end = start + line.len();
        let last = end == bytes.len();
        let mut tokens = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty());
        let keyword = tokens.next();
        let drop = match keyword {
            Some(b"f") => {
                let k = tokens.count();
                if k < 3 && last {
                    return Err(Error::format(
                        path,
                        format!(
                            "line {}: a face with {k} vertices, fewer than 3, on a last line without a newline (is the file truncated?)",
                            n + 1
                        ),
                    ));
                }
                skipped.short_faces += usize::from(k < 3);
                k < 3
            }
            Some(b"l") => {
                skipped.lines += 1;
                true
            }
            Some(b"p") => {
                skipped.points += 1;
                true
            }
            Some(k) if k.starts_with(b"#") || KNOWN_STATEMENTS.contains(&k) => false,
            Some(k) => {
                let name = String::from_utf8_lossy(&k[..k.len().min(32)]).into_owned();
                *skipped.unknown.entry(name).or_default() += 1;
                false
            }
            None => false,
        };
        if drop {
            kept.extend_from_slice(&bytes[copied..start]);
            copied = (end + 1).min(bytes.len());
        }
        start = end + 1;
    }
    let text = if copied == 0 {
        Cow::Borrowed(bytes)
    } else {
        kept.extend_from_slice(&bytes[copied..]);
        Cow::Owned(kept)
    };
    Ok((text, skipped.warnings(path)))
}

impl Skipped {
    /// One sentence per kind of thing skipped.
    fn warnings(&self, path: &Path) -> Vec<String> {
        let name = super::file_name(path);
        let mut out = Vec::new();
        let mut say = |n: usize, one: &str, many: &str, why: &str| {
            if n > 0 {
                let what = if n == 1 { one } else { many };
                out.push(format!("{name}: skipped {n} {what} ({why})"));
            }
        };
        say(
            self.short_faces,
            "face with fewer than 3 vertices",
            "faces with fewer than 3 vertices",
            "edges and points cast no shadow",
        );
        say(
            self.lines,
            "line element (`l`)",
            "line elements (`l`)",
            "lines cast no shadow",
        );
        say(
            self.points,
            "point element (`p`)",
            "point elements (`p`)",
            "points cast no shadow",
        );
        if !self.unknown.is_empty() {
            let n: usize = self.unknown.values().sum();
            let kinds: Vec<String> = self
                .unknown
                .iter()
                .map(|(k, c)| format!("{k:?} ×{c}"))
                .collect();
            out.push(format!(
                "{name}: skipped {n} statement{} shadowlab does not read ({})",
                if n == 1 { "" } else { "s" },
                kinds.join(", ")
            ));
        }
        out
    }
}

/// Converts tobj's models and materials into a scene, material `i` cut out by `masks[i]`
/// where there is one; `path` names the source in errors.
fn build(
    path: &Path,
    models: &[tobj::Model],
    mats: std::result::Result<Vec<tobj::Material>, tobj::LoadError>,
    masks: &[Option<AlphaMask>],
) -> Result<Scene> {
    // A missing or broken .mtl leaves every triangle with the default material.
    let mats = mats.unwrap_or_default();
    let mut scene = Scene::new(super::file_name(path));
    let default = scene.add_material(Material::default());
    let base = scene.materials.len() as u32;
    for (i, m) in mats.iter().enumerate() {
        let mut material = convert(m);
        material.alpha_mask = masks.get(i).cloned().flatten();
        scene.add_material(material);
    }
    let mut untextured = 0usize;
    for model in models {
        let mesh = &model.mesh;
        let nverts = mesh.positions.len() / 3;
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|c| vec3(c[0], c[1], c[2]))
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::format(
                path,
                format!(
                    "object {:?}: vertex {} has a non-finite coordinate",
                    model.name,
                    i + 1
                ),
            ));
        }
        let mut tris = Vec::with_capacity(mesh.indices.len() / 3);
        for c in mesh.indices.chunks_exact(3) {
            if c.iter().any(|&i| i as usize >= nverts) {
                return Err(Error::format(
                    path,
                    format!(
                        "object {:?}: a face refers to a vertex that does not exist",
                        model.name
                    ),
                ));
            }
            tris.push([c[0], c[1], c[2]]);
        }
        let m = match mesh.material_id {
            Some(id) if id < mats.len() => base + id as u32,
            _ => default,
        };
        if scene.materials[m as usize].alpha_mask.is_none() {
            scene.push_indexed(&positions, &tris, Mat4::IDENTITY, m);
            continue;
        }
        let uv = tex_coords(mesh);
        untextured += usize::from(uv.is_none()) * tris.len();
        scene.reserve(tris.len());
        for (k, tri) in tris.iter().enumerate() {
            let t = tri.map(|i| positions[i as usize]);
            let c = uv.as_ref().map_or([Vec2::ZERO; 3], |uv| {
                [0, 1, 2].map(|j| uv[mesh.texcoord_indices[3 * k + j] as usize])
            });
            scene.push_textured(t, c, m);
        }
    }
    if untextured > 0 {
        scene.warn(format!(
            "{}: {untextured} faces of cut-out materials have no texture coordinates (vt) and read their texture at (0, 0)",
            scene.name
        ));
    }
    Ok(scene)
}

/// The texture coordinates of `mesh`'s `vt` statements, `v` turned to count from the
/// image's top row (`1 − v`, as glTF's coordinates count); `None` when its faces carry
/// none (or not one per face vertex).
fn tex_coords(mesh: &tobj::Mesh) -> Option<Vec<Vec2>> {
    let n = mesh.texcoords.len() / 2;
    let whole = !mesh.texcoords.is_empty()
        && mesh.texcoord_indices.len() == mesh.indices.len()
        && mesh.texcoord_indices.iter().all(|&i| (i as usize) < n);
    whole.then(|| {
        mesh.texcoords
            .chunks_exact(2)
            .map(|c| vec2(c[0], 1.0 - c[1]))
            .collect()
    })
}

/// Checks the lines `tobj` would reject or silently drop, so the error can name the
/// line: a face with fewer than three vertices (what a file cut short ends with), a
/// vertex whose coordinates are not numbers or not finite, a face index that is not a
/// number or names a vertex not defined before it. Returns the number of triangles the
/// faces make, to be checked before any is built.
fn check_lines(path: &Path, bytes: &[u8]) -> Result<u64> {
    let mut vertices: u64 = 0;
    let mut triangles: u64 = 0;
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let at = |what: String| Error::format(path, format!("line {}: {what}", n + 1));
        let mut tokens = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"v") => {
                vertices += 1;
                for (axis, t) in tokens.take(3).enumerate() {
                    let v = std::str::from_utf8(t)
                        .ok()
                        .and_then(|t| t.parse::<f32>().ok());
                    match v {
                        Some(v) if v.is_finite() => {}
                        Some(_) => {
                            return Err(at(format!(
                                "vertex {vertices} has a non-finite coordinate {}",
                                ["x", "y", "z"][axis]
                            )))
                        }
                        None => {
                            return Err(at(format!(
                                "vertex {vertices}: coordinate {} is not a number",
                                ["x", "y", "z"][axis]
                            )))
                        }
                    }
                }
            }
            Some(b"f") => {
                let mut k = 0u64;
                for t in tokens {
                    k += 1;
                    let first = t.split(|&b| b == b'/').next().unwrap_or_default();
                    let i = std::str::from_utf8(first)
                        .ok()
                        .and_then(|s| s.parse::<i64>().ok());
                    let ok = match i {
                        Some(i) if i > 0 => i as u64 <= vertices,
                        Some(i) if i < 0 => i.unsigned_abs() <= vertices,
                        _ => false,
                    };
                    if !ok {
                        let shown = String::from_utf8_lossy(first);
                        let shown: String = shown.chars().take(24).collect();
                        return Err(at(format!(
                            "face vertex {k} ({shown:?}) does not name one of the {vertices} vertices defined before it"
                        )));
                    }
                }
                // Shorter faces are skipped (see `prefilter`), cut-short files refused there.
                triangles += k.saturating_sub(2);
            }
            _ => {}
        }
    }
    Ok(triangles)
}

fn convert(m: &tobj::Material) -> Material {
    let color = m
        .diffuse
        .map(|d| vec3(d[0], d[1], d[2]))
        .unwrap_or(Vec3::splat(0.8))
        .clamp(Vec3::ZERO, Vec3::ONE);
    let mut opacity = m.dissolve.unwrap_or(1.0);
    if let Some(tr) = m
        .unknown_param
        .get("Tr")
        .and_then(|s| s.trim().parse::<f32>().ok())
    {
        if m.dissolve.is_none() {
            opacity = 1.0 - tr;
        }
    }
    let opacity = if opacity.is_finite() {
        opacity.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let mut transmittance = Vec3::splat(1.0 - opacity);
    if opacity < 1.0 {
        if let Some(tf) = m.unknown_param.get("Tf") {
            let v: Vec<f32> = tf
                .split_whitespace()
                .filter_map(|s| s.parse().ok())
                .collect();
            if v.len() == 3 && v.iter().all(|x| x.is_finite()) {
                // Tf is the RGB share of light passing a non-opaque surface: taken as the
                // transmittance itself, so an exported scene reads back exactly.
                transmittance = vec3(v[0], v[1], v[2]).clamp(Vec3::ZERO, Vec3::ONE);
            }
        }
    }
    Material {
        name: m.name.clone(),
        color,
        transmittance,
        alpha_mask: None,
    }
}
