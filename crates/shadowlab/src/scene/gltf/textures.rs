//! glTF images as alpha textures, for alpha-masked materials: the image's bytes from a
//! buffer view, a `data:` URI or a file beside the glTF file (where the file's access
//! allows), its size checked against [`MAX_TEXTURE_SIDE`] and the memory limit before it
//! is decoded (PNG, GIF; a JPEG has no alpha and is opaque without being decoded), and its
//! alpha channel kept (255 everywhere for an image without one). The OBJ loader decodes
//! its `map_d` and `map_Kd` images here too ([`decode_channel`]).

use super::buffers::resolve_uri;
use super::Loader;
use crate::files::MAX_FILE_BYTES;
use crate::limits;
use crate::scene::alpha_mask::{AlphaTexture, MAX_TEXTURE_SIDE};
use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

/// A decoded texture, or the phrase saying why it could not be read.
pub(super) type TextureResult = std::result::Result<Arc<AlphaTexture>, String>;

impl Loader<'_> {
    /// The alpha texture of glTF image `index`, read on first use.
    pub(super) fn alpha_texture(&mut self, image: &gltf::Image) -> TextureResult {
        if let Some(t) = self.textures.get(&image.index()) {
            return t.clone();
        }
        let t = self.read_image(image).and_then(|b| decode_alpha(&b));
        self.textures.insert(image.index(), t.clone());
        t
    }

    /// The encoded bytes of `image`.
    fn read_image(&self, image: &gltf::Image) -> std::result::Result<Vec<u8>, String> {
        match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buf = &self.buffers[view.buffer().index()];
                let (start, len) = (view.offset(), view.length());
                start
                    .checked_add(len)
                    .and_then(|end| buf.get(start..end))
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| format!("buffer view {} reaches past its buffer", view.index()))
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                let source = gltf::buffer::Source::Uri(uri);
                gltf::buffer::Data::from_source(source, None)
                    .map(|d| d.0)
                    .map_err(|e| format!("its data: URI cannot be decoded ({e})"))
            }
            gltf::image::Source::Uri { uri, .. } => {
                let base = self.path.parent().unwrap_or(Path::new("."));
                let shown: String = uri.chars().take(120).collect();
                let file =
                    resolve_uri(base, self.access, uri).map_err(|w| format!("{shown:?} {w}"))?;
                crate::files::read_regular_file(&file, MAX_FILE_BYTES)
                    .map_err(|why| format!("the file {shown:?} ({}) {why}", file.display()))
            }
        }
    }
}

/// The alpha channel of an encoded image, refused (with a phrase) when it cannot be
/// decoded or is larger than the limits allow.
pub(crate) fn decode_alpha(bytes: &[u8]) -> TextureResult {
    if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        // JPEG carries no alpha: opaque everywhere, whatever its size.
        return Ok(Arc::new(AlphaTexture {
            width: 1,
            height: 1,
            alpha: vec![255],
        }));
    }
    decode_channel(bytes, Channel::Alpha).map(|t| t.expect("Alpha always gives a texture"))
}

/// Which channel of an image [`decode_channel`] keeps as the alpha texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Channel {
    /// The alpha channel; 255 everywhere for an image without one.
    Alpha,
    /// The alpha channel; `None` (without decoding) for an image without one.
    AlphaOnly,
    /// The alpha channel, or for an image without one its grey level (an OBJ `map_d`).
    AlphaOrGrey,
}

/// The `channel` of an encoded image as an alpha texture, refused (with a phrase) when it
/// cannot be decoded or is larger than the limits allow; `None` for [`Channel::AlphaOnly`]
/// and an image without alpha.
pub(crate) fn decode_channel(
    bytes: &[u8],
    channel: Channel,
) -> std::result::Result<Option<Arc<AlphaTexture>>, String> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("its format cannot be read ({e})"))?;
    let decoder = reader
        .into_decoder()
        .map_err(|e| format!("it cannot be decoded ({e})"))?;
    let (w, h) = image::ImageDecoder::dimensions(&decoder);
    let has_alpha = image::ImageDecoder::color_type(&decoder).has_alpha();
    drop(decoder);
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!(
            "its size {w}x{h} is outside 1..={MAX_TEXTURE_SIDE} texels a side"
        ));
    }
    if channel == Channel::AlphaOnly && !has_alpha {
        return Ok(None);
    }
    // The decoder's RGBA buffer (up to 16 bytes a texel) and the kept alpha.
    let estimate = w as u64 * h as u64 * 17;
    limits::check_bytes(|| format!("its {w}x{h} texels"), estimate).map_err(|e| e.to_string())?;
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("its format cannot be read ({e})"))?;
    let mut lim = image::Limits::default();
    lim.max_image_width = Some(MAX_TEXTURE_SIDE);
    lim.max_image_height = Some(MAX_TEXTURE_SIDE);
    lim.max_alloc = Some(estimate);
    reader.limits(lim);
    let img = reader
        .decode()
        .map_err(|e| format!("it cannot be decoded ({e})"))?;
    let alpha = if has_alpha {
        img.to_rgba8().pixels().map(|p| p.0[3]).collect()
    } else if channel == Channel::AlphaOrGrey {
        img.to_luma8().into_raw()
    } else {
        vec![255; w as usize * h as usize]
    };
    Ok(Some(Arc::new(AlphaTexture {
        width: w,
        height: h,
        alpha,
    })))
}
