//! The buffers of a glTF file: the GLB binary chunk, `data:` URIs, or files beside it,
//! each URI percent-decoded and resolved where the file's access allows.

use crate::error::{Error, Result};
use crate::files::{read_prefix, Access};
use std::path::{Path, PathBuf};

/// Loads every buffer: the GLB binary chunk, `data:` URIs, or files beside the glTF file.
pub(super) fn load_buffers(
    path: &Path,
    base: &Path,
    access: &Access,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    let fmt = |what: String| Error::format(path, what);
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let (data, label) = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let data = blob.take().ok_or_else(|| {
                    fmt(format!(
                        "buffer {i} refers to the GLB binary chunk, which the file lacks"
                    ))
                })?;
                (data, "the GLB binary chunk".to_string())
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let data =
                    gltf::buffer::Data::from_source(buffer.source(), Some(base)).map_err(|e| {
                        fmt(format!("buffer {i}: its data: URI cannot be decoded ({e})"))
                    })?;
                (data.0, "its data: URI".to_string())
            }
            gltf::buffer::Source::Uri(uri) => {
                let shown: String = uri.chars().take(120).collect();
                let file = resolve_uri(base, access, uri)
                    .map_err(|why| fmt(format!("buffer {i} ({shown:?}) {why}")))?;
                // Never more than the declared length: the rest of the file is not the
                // buffer's.
                let data = read_prefix(&file, buffer.length() as u64).map_err(|why| {
                    fmt(format!(
                        "buffer {i} refers to the file {shown:?} ({}), which {why}",
                        file.display()
                    ))
                })?;
                (data, format!("the file {shown:?}"))
            }
        };
        if data.len() < buffer.length() {
            return Err(fmt(format!(
                "buffer {i} declares {} bytes but {label} holds only {}",
                buffer.length(),
                data.len()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a non-`data:` buffer URI names: a relative, percent-encoded reference
/// resolved against the glTF file's folder, or a `file:` URI, decoded first and then
/// kept where `access` allows. `Err` is a phrase following the URI.
pub(super) fn resolve_uri(
    base: &Path,
    access: &Access,
    uri: &str,
) -> std::result::Result<PathBuf, String> {
    let decoded = if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        percent_decode(rest)?
    } else if uri.contains(':') {
        return Err(
            "uses a URI scheme that is not supported (only relative paths, file: and data: are)"
                .into(),
        );
    } else {
        percent_decode(uri)?
    };
    access.resolve(base, &decoded)
}

/// Decodes `%XX` escapes; a `%` not followed by two hex digits stays as it is.
fn percent_decode(s: &str) -> std::result::Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).map_err(|_| "the URI decodes to a name that is not UTF-8".into())
}
