//! The glTF document as a whole: the GLB container, the version, the sizes of the
//! top-level arrays (checked before the document is decoded), the `gltf` crate's
//! validation, and the extensions the file uses or requires.

use super::{MAX_ELEMENTS, READ_EXTENSIONS, SHADING_ONLY_EXTENSIONS};
use crate::error::{Error, Result};
use std::path::Path;

/// "glTF 1.0 is not supported (…); convert it to glTF 2.0", or the like for another
/// version.
pub(super) fn unsupported_version(found: &str) -> String {
    if found.contains("\"1") || found.ends_with(" 1") {
        format!("glTF 1.0 is not supported ({found}); convert it to glTF 2.0")
    } else {
        format!("only glTF 2.0 is supported, not {found}")
    }
}

/// `asset.version` of a glTF JSON document (or of a GLB's JSON chunk), read on its own
/// so that a file of another version can be named as such when it does not parse as 2.0.
pub(super) fn json_version(bytes: &[u8]) -> Option<String> {
    #[derive(serde::Deserialize)]
    struct Asset {
        version: serde_json::Value,
    }
    #[derive(serde::Deserialize)]
    struct Root {
        asset: Asset,
    }
    let json = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        bytes.get(20..20usize.checked_add(len)?)?
    } else {
        bytes
    };
    let root: Root = serde_json::from_slice(json).ok()?;
    Some(match root.asset.version {
        serde_json::Value::String(s) => s,
        other => other.to_string(),
    })
}

/// Refuses a required extension shadowlab lacks (naming it); says which optional ones,
/// and which required shading-only ones, are ignored.
pub(super) fn extension_warnings(path: &Path, root: &gltf::json::Root) -> Result<Vec<String>> {
    let read = |e: &str| READ_EXTENSIONS.contains(&e);
    let shading = |e: &str| SHADING_ONLY_EXTENSIONS.contains(&e);
    if let Some(e) = root
        .extensions_required
        .iter()
        .find(|e| !read(e) && !shading(e))
    {
        return Err(Error::format(
            path,
            format!("the file requires the extension {e}, which shadowlab does not support"),
        ));
    }
    let name = crate::scene::file_name(path);
    let ignored: Vec<&str> = root
        .extensions_used
        .iter()
        .chain(&root.extensions_required)
        .map(String::as_str)
        .filter(|e| !read(e))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let mut out = Vec::new();
    if !ignored.is_empty() {
        out.push(format!(
            "{name}: ignored the extension{} {} (optional, or changing shading only)",
            if ignored.len() == 1 { "" } else { "s" },
            ignored.join(", ")
        ));
    }
    Ok(out)
}

/// The JSON chunk of a GLB file, after checking that the header's length is the file's
/// and that every chunk lies inside it.
pub(super) fn glb_json(bytes: &[u8]) -> std::result::Result<&[u8], String> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64)
    };
    let (Some(version), Some(declared)) = (word(4), word(8)) else {
        return Err("the GLB header is truncated".into());
    };
    if version != 2 {
        return Err(format!(
            "the GLB header declares container version {version}, not 2"
        ));
    }
    if declared != bytes.len() as u64 {
        return Err(format!(
            "the GLB header declares {declared} bytes but the file holds {}",
            bytes.len()
        ));
    }
    let mut at = 12u64;
    let mut json = None;
    let mut chunk = 0;
    while at < declared {
        let (Some(len), Some(kind)) = (word(at as usize), word(at as usize + 4)) else {
            return Err(format!("GLB chunk {chunk}: its header is truncated"));
        };
        let end = at + 8 + len;
        if end > declared {
            return Err(format!(
                "GLB chunk {chunk} declares {len} bytes, past the end of the file"
            ));
        }
        if chunk == 0 {
            if kind != 0x4E4F_534A {
                return Err("the first GLB chunk is not JSON".into());
            }
            json = Some(&bytes[at as usize + 8..end as usize]);
        }
        at = end;
        chunk += 1;
    }
    json.ok_or_else(|| "the GLB file has no JSON chunk".into())
}

/// Fails when a top-level array of the document has more than [`MAX_ELEMENTS`] entries,
/// counted without decoding them.
pub(super) fn check_counts(json: &[u8]) -> std::result::Result<(), String> {
    use serde::de::{IgnoredAny, SeqAccess, Visitor};
    /// The length of a JSON array whose elements are skipped.
    #[derive(Default)]
    struct Count(usize);
    impl<'de> serde::Deserialize<'de> for Count {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
            struct V;
            impl<'de> Visitor<'de> for V {
                type Value = Count;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("an array")
                }
                fn visit_seq<A: SeqAccess<'de>>(
                    self,
                    mut seq: A,
                ) -> std::result::Result<Count, A::Error> {
                    let mut n = 0;
                    while seq.next_element::<IgnoredAny>()?.is_some() {
                        n += 1;
                    }
                    Ok(Count(n))
                }
            }
            d.deserialize_any(V)
        }
    }
    #[derive(serde::Deserialize)]
    struct Top {
        #[serde(default)]
        nodes: Count,
        #[serde(default)]
        meshes: Count,
        #[serde(default)]
        accessors: Count,
        #[serde(default, rename = "bufferViews")]
        buffer_views: Count,
        #[serde(default)]
        buffers: Count,
        #[serde(default)]
        materials: Count,
        #[serde(default)]
        scenes: Count,
        #[serde(default)]
        cameras: Count,
    }
    // A document that does not parse is left to the glTF crate, which says why.
    let Ok(top) = serde_json::from_slice::<Top>(json) else {
        return Ok(());
    };
    for (name, n) in [
        ("nodes", top.nodes.0),
        ("meshes", top.meshes.0),
        ("accessors", top.accessors.0),
        ("bufferViews", top.buffer_views.0),
        ("buffers", top.buffers.0),
        ("materials", top.materials.0),
        ("scenes", top.scenes.0),
        ("cameras", top.cameras.0),
    ] {
        if n > MAX_ELEMENTS {
            return Err(format!(
                "it declares {n} {name}, more than the limit of {MAX_ELEMENTS}"
            ));
        }
    }
    Ok(())
}

/// The format check on a glTF file's first bytes: the GLB magic `glTF`, or a JSON
/// document (after white space and a byte-order mark) opening with `{`.
pub(super) fn sniff(head: &[u8]) -> std::result::Result<(), String> {
    if head.starts_with(b"glTF") {
        return Ok(());
    }
    let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok(()),
        _ => Err("not valid glTF JSON (it neither starts with `{` nor is a GLB file)".into()),
    }
}

/// The `gltf` crate's validation, less two rules: the `min`/`max` a `POSITION` accessor
/// must carry (many exporters omit them and the loader never reads them: it computes
/// bounds itself), and the crate's own list of required extensions (the loader checks
/// `extensionsRequired` against what shadowlab reads, which includes
/// `KHR_mesh_quantization`). Every other rule is kept: the crate's accessors rely on them.
pub(super) fn validate(root: &gltf::json::Root) -> std::result::Result<(), gltf::Error> {
    use gltf::json::validation::{Error as Rule, Validate};
    // The crate's own primitive check indexes the POSITION accessor before any bounds
    // check, so out-of-range attribute accessors are caught here first.
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for acc in prim.attributes.values() {
                if acc.value() >= root.accessors.len() {
                    let path =
                        gltf::json::Path(format!("meshes[{mi}].primitives[{pi}].attributes"));
                    return Err(gltf::Error::Validation(vec![(
                        path,
                        Rule::IndexOutOfBounds,
                    )]));
                }
            }
        }
    }
    // An image needs a `uri` or a `bufferView`; the crate's accessor panics on neither.
    for (i, image) in root.images.iter().enumerate() {
        if image.uri.is_none() && image.buffer_view.is_none() {
            let path = gltf::json::Path(format!("images[{i}].uri or images[{i}].bufferView"));
            return Err(gltf::Error::Validation(vec![(path, Rule::Missing)]));
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let p = path.as_str();
        let bounds =
            p.contains("attributes[\"POSITION\"]") && (p.ends_with(".min") || p.ends_with(".max"));
        // Required extensions are checked against shadowlab's own list instead.
        let required = p.starts_with("extensionsRequired") && matches!(error, Rule::Unsupported);
        let dropped = required || (bounds && matches!(error, Rule::Missing));
        if !dropped {
            errors.push((path, error));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        Err(gltf::Error::Validation(errors))
    }
}

/// One sentence for a parse or validation failure of the glTF crate.
pub(super) fn describe(e: gltf::Error) -> String {
    match e {
        gltf::Error::Validation(list) => {
            let shown: Vec<String> = list
                .iter()
                .take(4)
                .map(|(p, e)| format!("{p}: {e}"))
                .collect();
            let more = if list.len() > 4 {
                format!(" (and {} more)", list.len() - 4)
            } else {
                String::new()
            };
            format!("not a valid glTF 2.0 file: {}{more}", shown.join("; "))
        }
        gltf::Error::Deserialize(e) => format!("not valid glTF JSON ({e})"),
        gltf::Error::Binary(e) => format!("not a valid GLB container ({e})"),
        other => format!("cannot be read as glTF ({other})"),
    }
}
