//! glTF accessors decoded to numbers: dense data through a buffer view (with its stride),
//! sparse substitutions, and normalized integers, each access checked against its buffer
//! view and buffer before anything is allocated.

use super::Loader;
use crate::error::{Error, Result};
use crate::limits;
use crate::scene::{BYTES_PER_TRIANGLE, MAX_TRIANGLES};
use gltf::accessor::DataType;

impl Loader<'_> {
    /// Decodes every component of `acc` (sparse substitutions applied, integers normalized
    /// where the accessor says so) in element order.
    pub(super) fn read_accessor(&self, acc: &gltf::Accessor, at: &str) -> Result<Vec<f64>> {
        let ty = acc.data_type();
        let n = acc.dimensions().multiplicity();
        let count = acc.count();
        let elem = ty.size() * n;
        let what = format!("{at}: accessor {}", acc.index());
        let total = count
            .checked_mul(n)
            .filter(|&t| t <= 3 * (MAX_TRIANGLES + 2))
            .ok_or_else(|| {
                Error::Limit(format!(
                    "{}: {what} has too many elements ({count})",
                    self.path.display()
                ))
            })?;
        // What the decoded accessor and the scene's copy of it take, checked first.
        limits::check_bytes(
            || format!("{}: {what}: its {count} elements", self.path.display()),
            (total as u64).saturating_mul(8 + 4 + BYTES_PER_TRIANGLE / 3),
        )?;
        // The data is checked to be there before anything is allocated.
        let dense = match acc.view() {
            Some(view) => {
                let stride = view.stride().unwrap_or(elem);
                if stride < elem {
                    return Err(self.err(format!(
                        "{what}: buffer view {} has a stride of {stride} bytes, less than the {elem}-byte element",
                        view.index()
                    )));
                }
                let data = self.view_bytes(&view, &what)?;
                let end = match count {
                    0 => Some(0),
                    _ => (count - 1)
                        .checked_mul(stride)
                        .and_then(|x| x.checked_add(acc.offset()))
                        .and_then(|x| x.checked_add(elem)),
                };
                if end.is_none_or(|e| e > data.len()) {
                    return Err(self.err(format!(
                        "{what}: {count} elements from byte {} reach past the end of buffer view {} ({} bytes)",
                        acc.offset(),
                        view.index(),
                        data.len()
                    )));
                }
                Some((data, stride))
            }
            // No buffer view: zeros, to be replaced by sparse entries.
            None => None,
        };
        let mut out = limits::try_filled(total, 0.0f64, &what)?;
        if let Some((data, stride)) = dense {
            for i in 0..count {
                let start = acc.offset() + i * stride;
                decode(
                    ty,
                    acc.normalized(),
                    &data[start..start + elem],
                    &mut out[i * n..(i + 1) * n],
                );
            }
        }
        if let Some(sparse) = acc.sparse() {
            let k = sparse.count();
            let idx_view = sparse.indices().view();
            let idx_data = self.view_bytes(&idx_view, &what)?;
            let idx_size = match sparse.indices().index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let val_view = sparse.values().view();
            let val_data = self.view_bytes(&val_view, &what)?;
            let idx_off = sparse.indices().offset();
            let val_off = sparse.values().offset();
            let fits = |off: usize, size: usize, len: usize| {
                k.checked_mul(size)
                    .and_then(|b| b.checked_add(off))
                    .is_some_and(|e| e <= len)
            };
            if !fits(idx_off, idx_size, idx_data.len()) || !fits(val_off, elem, val_data.len()) {
                return Err(self.err(format!(
                    "{what}: its {k} sparse entries reach past the end of their buffer views"
                )));
            }
            for j in 0..k {
                let b = &idx_data[idx_off + j * idx_size..idx_off + (j + 1) * idx_size];
                let target = match idx_size {
                    1 => b[0] as usize,
                    2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                };
                if target >= count {
                    return Err(self.err(format!(
                        "{what}: sparse entry {j} replaces element {target}, but the accessor has {count}"
                    )));
                }
                let v = &val_data[val_off + j * elem..val_off + (j + 1) * elem];
                decode(
                    ty,
                    acc.normalized(),
                    v,
                    &mut out[target * n..(target + 1) * n],
                );
            }
        }
        Ok(out)
    }

    /// The bytes of a buffer view, checked against its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View, what: &str) -> Result<&[u8]> {
        let buffer = &self.buffers[view.buffer().index()];
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= buffer.len() => Ok(&buffer[view.offset()..end]),
            _ => Err(self.err(format!(
                "{what}: buffer view {} (bytes {}..+{}) reaches past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            ))),
        }
    }
}

/// Decodes one element's components from little-endian bytes; normalized integers map to
/// [0, 1] (unsigned) or [−1, 1] (signed) as the glTF specification defines.
fn decode(ty: DataType, normalized: bool, bytes: &[u8], out: &mut [f64]) {
    let size = ty.size();
    for (c, o) in out.iter_mut().enumerate() {
        let b = &bytes[c * size..(c + 1) * size];
        // The value, and the largest magnitude of its type where it may be normalized.
        let (v, unit) = match ty {
            DataType::I8 => (f64::from(b[0] as i8), Some(127.0)),
            DataType::U8 => (f64::from(b[0]), Some(255.0)),
            DataType::I16 => (f64::from(i16::from_le_bytes([b[0], b[1]])), Some(32767.0)),
            DataType::U16 => (f64::from(u16::from_le_bytes([b[0], b[1]])), Some(65535.0)),
            DataType::U32 => (
                f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                None,
            ),
            DataType::F32 => (
                f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                None,
            ),
        };
        *o = match unit {
            // The signed minimum maps below −1 and is clamped; unsigned values stay ≥ 0.
            Some(unit) if normalized => (v / unit).max(-1.0),
            _ => v,
        };
    }
}
