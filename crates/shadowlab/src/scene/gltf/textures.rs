//! glTF images as alpha textures, for alpha-masked materials: the image's bytes from a
//! buffer view, a `data:` URI or a file beside the glTF file (where the file's access
//! allows), decoded by the load's [`TextureCache`] (once per distinct image, its size
//! checked against the texture limits and, with every texture decoded before it, the
//! memory limit; a JPEG has no alpha and is opaque without being decoded), and its alpha
//! channel kept (255 everywhere for an image without one).

use super::buffers::resolve_uri;
use super::Loader;
use crate::files::MAX_FILE_BYTES;
use crate::scene::alpha_mask::AlphaTexture;
#[cfg(doc)]
use crate::scene::texture_cache::TextureCache;
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
        let t = self
            .read_image(image)
            .and_then(|b| self.texture_cache.alpha(&b));
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
