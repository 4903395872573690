//! Stanford PLY meshes, ASCII and binary (either byte order), read with the `ply-rs-bw`
//! crate.
//!
//! What is read: the `vertex` element's `x`, `y`, `z` (any scalar type; float and double
//! in practice) and the `face` element's `vertex_indices` or `vertex_index` list (any
//! integer type). Polygons are fan-triangulated from their first vertex; faces with fewer
//! than three vertices hold no area and add no triangle. Every other element and property
//! (normals, colours, `tristrips`, …) is skipped, so all triangles share one default
//! material.
//!
//! Every failure is an [`Error::Format`] naming the file, the element (`vertex 12`,
//! `face 17`, or a header line) and the problem: a truncated header or body, a value that
//! does not parse, a vertex index out of range or negative, a non-finite coordinate.

use super::{Material, Scene};
use crate::error::{Error, Result};
use crate::files::MAX_FILE_BYTES;
use crate::math::{vec3, Mat4};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Header, Property, PropertyAccess, PropertyAccessResult, PropertyType};
use std::path::Path;

/// Names the face element's index list may carry.
const INDEX_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// The properties of one PLY element that the loader keeps; one type serves every element
/// kind, and properties it does not know are ignored.
#[derive(Default)]
struct Element {
    /// `x`, `y`, `z` in double precision (any scalar type converts exactly).
    xyz: [f64; 3],
    /// The face's vertex indices, widened so negative values can be reported.
    indices: Vec<i64>,
}

impl PropertyAccess for Element {
    fn new() -> Self {
        Element::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        if let Some(axis) = axis {
            let v = match property {
                Property::Char(v) => f64::from(v),
                Property::UChar(v) => f64::from(v),
                Property::Short(v) => f64::from(v),
                Property::UShort(v) => f64::from(v),
                Property::Int(v) => f64::from(v),
                Property::UInt(v) => f64::from(v),
                Property::Float(v) => f64::from(v),
                Property::Double(v) => v,
                _ => return PropertyAccessResult::UnsupportedType,
            };
            self.xyz[axis] = v;
            return PropertyAccessResult::Set;
        }
        if INDEX_LISTS.contains(&name) {
            self.indices = match property {
                Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
                _ => return PropertyAccessResult::UnsupportedType,
            };
            return PropertyAccessResult::Set;
        }
        PropertyAccessResult::Ignored
    }
}

/// The format check on a PLY file's first bytes: the magic line `ply` (or a start of it,
/// which the header parser reports as truncated).
fn sniff(head: &[u8]) -> std::result::Result<(), String> {
    let magic = |m: &[u8]| head.starts_with(m) || m.starts_with(head);
    if magic(b"ply\n") || magic(b"ply\r\n") {
        Ok(())
    } else {
        Err("the PLY header is invalid: the file does not start with the line `ply`".into())
    }
}

/// Loads a PLY file.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = super::read_input(path, MAX_FILE_BYTES, sniff)?;
    let fmt = |what: String| Error::format(path, what);
    let parser = Parser::<Element>::new();
    let mut reader = Reader::new(bytes.as_slice());
    let header = parser.read_header(&mut reader).map_err(|e| {
        let msg = e.to_string();
        let problem = if e.kind() == std::io::ErrorKind::UnexpectedEof {
            "it ends before `end_header` (truncated)".to_string()
        } else if let Some(q) = quoted_line(&msg) {
            let l = e.line().map(|l| format!("line {l} ")).unwrap_or_default();
            format!("{l}({q:?}) is not a valid header line")
        } else {
            one_line(&msg)
        };
        fmt(format!("the PLY header is invalid: {problem}"))
    })?;
    check_header(&header).map_err(fmt)?;
    check_counts(&header, bytes.len() as u64).map_err(fmt)?;
    // The parser counts one line per element in binary bodies as in ASCII ones, so a
    // line number maps back to the element at fault.
    let first_body_line = reader.line().max(1);
    let mut payload = parser.read_payload(&mut reader, &header).map_err(|e| {
        let at = e
            .line()
            .map(|l| element_at(&header, l.saturating_sub(first_body_line)))
            .unwrap_or_else(|| "the body".into());
        let problem = if e.kind() == std::io::ErrorKind::UnexpectedEof {
            "the file ends early (truncated)".to_string()
        } else {
            describe_body_error(&e.to_string(), e.line())
        };
        fmt(format!("{at}: {problem}"))
    })?;

    let vertices = payload.swap_remove("vertex").unwrap_or_default();
    let faces = payload.swap_remove("face").unwrap_or_default();
    let mut positions = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let p = vec3(v.xyz[0] as f32, v.xyz[1] as f32, v.xyz[2] as f32);
        if !p.is_finite() {
            return Err(fmt(format!(
                "vertex {i} has a non-finite coordinate ({}, {}, {})",
                v.xyz[0], v.xyz[1], v.xyz[2]
            )));
        }
        positions.push(p);
    }
    let triangles: u64 = faces
        .iter()
        .map(|f| f.indices.len().saturating_sub(2) as u64)
        .sum();
    super::check_triangle_count(path, triangles)?;
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(triangles as usize);
    for (f, face) in faces.iter().enumerate() {
        for &i in &face.indices {
            if i < 0 || i as u64 >= positions.len() as u64 {
                return Err(fmt(format!(
                    "face {f} refers to vertex {i}, which does not exist (the file has {} vertices)",
                    positions.len()
                )));
            }
        }
        // Fan triangulation from the first corner; exact for convex polygons.
        let idx = &face.indices;
        for k in 1..idx.len().saturating_sub(1) {
            tris.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
    }
    let name = super::file_name(path);
    let mut scene = Scene::new(name);
    let m = scene.add_material(Material::default());
    scene.push_indexed(&positions, &tris, Mat4::IDENTITY, m);
    Ok(scene)
}

/// Fails with a sentence when the header lacks what a triangle mesh needs: a `vertex`
/// element with `x`, `y`, `z` and a `face` element with an index list of integers.
fn check_header(header: &Header) -> std::result::Result<(), String> {
    let vertex = header
        .elements
        .get("vertex")
        .ok_or("the header declares no `vertex` element")?;
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return Err(format!("vertex property `{axis}` is a list, not a number"));
            }
            None => return Err(format!("the `vertex` element has no `{axis}` property")),
        }
    }
    let face = header
        .elements
        .get("face")
        .ok_or("the header declares no `face` element (a point cloud has no triangles)")?;
    let list = INDEX_LISTS
        .iter()
        .find_map(|n| face.properties.get(*n))
        .ok_or("the `face` element has no `vertex_indices` or `vertex_index` list")?;
    use ply_rs_bw::ply::ScalarType::{Double, Float};
    match &list.data_type {
        PropertyType::List(_, Float | Double) => Err(format!(
            "face property `{}` holds floats, not integers",
            list.name
        )),
        PropertyType::Scalar(_) => Err(format!(
            "face property `{}` is a number, not a list",
            list.name
        )),
        PropertyType::List(..) => Ok(()),
    }
}

/// Fails when the header's version is not 1.0, the only PLY version there is, or when its
/// element counts cannot fit in a body of `file_bytes` bytes (each element takes at least
/// one byte a property in binary and two, a value and a separator, in ASCII), so a lying
/// count is refused before anything is read.
fn check_counts(header: &Header, file_bytes: u64) -> std::result::Result<(), String> {
    let v = &header.version;
    if (v.major, v.minor) != (1, 0) {
        return Err(format!(
            "the header declares PLY format version {}.{}; only 1.0 exists",
            v.major, v.minor
        ));
    }
    let ascii = matches!(header.encoding, ply_rs_bw::ply::Encoding::Ascii);
    let mut need: u64 = 0;
    for (name, def) in &header.elements {
        let per: u64 = def
            .properties
            .values()
            .map(|p| match (&p.data_type, ascii) {
                (_, true) => 2,
                (PropertyType::Scalar(t), false) => scalar_size(t),
                (PropertyType::List(t, _), false) => scalar_size(t),
            })
            .sum();
        need = need.saturating_add((def.count as u64).saturating_mul(per));
        if need > file_bytes {
            return Err(format!(
                "the header declares {} `{name}` elements, more than the file's {file_bytes} bytes can hold",
                def.count
            ));
        }
    }
    Ok(())
}

/// Bytes of one binary PLY scalar.
fn scalar_size(t: &ply_rs_bw::ply::ScalarType) -> u64 {
    use ply_rs_bw::ply::ScalarType as S;
    match t {
        S::Char | S::UChar => 1,
        S::Short | S::UShort => 2,
        S::Int | S::UInt | S::Float => 4,
        S::Double => 8,
    }
}

/// Names the element at body position `k` (0-based, over all elements in header order):
/// `vertex 12`, `face 3`, or the end of the declared body.
fn element_at(header: &Header, mut k: usize) -> String {
    for (name, def) in &header.elements {
        if k < def.count {
            return format!("{name} {k}");
        }
        k -= def.count;
    }
    "after the last declared element".into()
}

/// One sentence for a body parse error: the ASCII line quoted, and the parser's last
/// (innermost) complaint, or a plain statement where that complaint is grammar jargon.
fn describe_body_error(msg: &str, line: Option<usize>) -> String {
    let Some(quoted) = quoted_line(msg) else {
        return one_line(msg);
    };
    let problem = if msg.contains("Couldn't parse element line") {
        "it is not a list of numbers".to_string()
    } else {
        one_line(msg.rsplit("Error: ").next().unwrap_or(msg))
    };
    match line {
        Some(l) => format!("line {l} ({quoted:?}): {problem}"),
        None => format!("{quoted:?}: {problem}"),
    }
}

/// The input line a parser message quotes (`String: '…'`), if any.
fn quoted_line(msg: &str) -> Option<String> {
    msg.split("String: '")
        .nth(1)
        .and_then(|r| r.split('\'').next())
        .map(|q| one_line(q.trim()))
}

/// Joins a multi-line parser message into one line of bounded length.
fn one_line(msg: &str) -> String {
    /// Longer messages (which quote the offending line) are cut here.
    const MAX_CHARS: usize = 240;
    let s = msg.split_whitespace().collect::<Vec<_>>().join(" ");
    if s.chars().count() > MAX_CHARS {
        let cut: String = s.chars().take(MAX_CHARS).collect();
        format!("{cut}…")
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_positions_map_across_elements() {
        let txt = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nelement face 2\n\
                   property list uchar int vertex_indices\nend_header\n";
        let header = Parser::<Element>::new()
            .read_header(&mut Reader::new(txt.as_bytes()))
            .unwrap();
        assert_eq!(element_at(&header, 0), "vertex 0");
        assert_eq!(element_at(&header, 3), "face 0");
        assert_eq!(element_at(&header, 4), "face 1");
        assert_eq!(element_at(&header, 5), "after the last declared element");
    }
}
