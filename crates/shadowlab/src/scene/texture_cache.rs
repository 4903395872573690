//! Decoding alpha textures once per load, against the memory limit as a sum.
//!
//! Every loader that reads alpha textures (glTF images, OBJ `map_d`) hands the encoded
//! bytes of each image to one [`TextureCache`] per scene load:
//!
//! ```ignore
//! let mut cache = TextureCache::default();
//! let texture: Arc<AlphaTexture> = cache.alpha(&encoded_bytes)?; // Err: a phrase
//! ```
//!
//! The same bytes (one image named by 40 materials, or 40 names of one file) are decoded
//! once and the [`AlphaTexture`] shared. Before an image is decoded, its size is read
//! from its header and checked against [`MAX_TEXTURE_SIDE`] and against the memory limit
//! together with every texture the cache already holds, so 40 different large images
//! are refused by their sum, not accepted one by one. A JPEG carries no alpha: it is
//! opaque without being decoded.

use super::alpha_mask::{AlphaTexture, MAX_TEXTURE_SIDE};
use crate::limits;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::io::Cursor;
use std::sync::Arc;

/// Bytes the decoder needs per texel beyond the kept alpha: its RGBA buffer at up to 16
/// bytes a texel (16-bit RGBA, or f32 channels).
const DECODE_BYTES_PER_TEXEL: u64 = 16;

/// A decoded texture (`None`: [`Channel::AlphaOnly`] of an image without alpha) with the
/// encoded bytes it came from.
type Decoded = (Arc<[u8]>, Option<Arc<AlphaTexture>>);

/// Which channel of an image [`TextureCache::channel`] keeps as the alpha texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// The alpha channel; 255 everywhere for an image without one (glTF's images).
    Alpha,
    /// The alpha channel; nothing (and nothing decoded) for an image without one (an OBJ
    /// `map_Kd`, which cuts out only by an alpha channel it has).
    AlphaOnly,
    /// The alpha channel, or for an image without one its grey level (an OBJ `map_d`).
    AlphaOrGrey,
}

/// The alpha textures decoded so far in one scene load (see the module doc).
#[derive(Default)]
pub struct TextureCache {
    /// Decoded textures by a hash of their encoded bytes and the channel kept; each entry
    /// keeps the bytes, so a hash shared by two images never mixes them up.
    decoded: HashMap<(u64, Channel), Vec<Decoded>>,
    /// Bytes of alpha the cache holds (one per texel).
    held: u64,
}

impl TextureCache {
    /// The alpha texture of the encoded image `bytes` (PNG, GIF, JPEG or any format the
    /// `image` crate reads), decoded on first sight; `Err` is a phrase saying why it cannot
    /// be used ("its size 20000x10 is outside 1..=16384 texels a side", …).
    pub fn alpha(&mut self, bytes: &[u8]) -> Result<Arc<AlphaTexture>, String> {
        self.channel(bytes, Channel::Alpha)
            .map(|t| t.expect("the alpha channel always gives a texture"))
    }

    /// The `channel` of the encoded image `bytes` as an alpha texture, decoded on first
    /// sight (checked as [`TextureCache::alpha`]); `None` for [`Channel::AlphaOnly`] of an
    /// image without alpha, which is then not decoded.
    pub fn channel(
        &mut self,
        bytes: &[u8],
        channel: Channel,
    ) -> Result<Option<Arc<AlphaTexture>>, String> {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        bytes.hash(&mut h);
        let key = (h.finish(), channel);
        if let Some((_, t)) = self
            .decoded
            .get(&key)
            .and_then(|list| list.iter().find(|(b, _)| &b[..] == bytes))
        {
            return Ok(t.clone());
        }
        let t = self.decode(bytes, channel)?;
        self.held += t.as_ref().map_or(0, |t| t.alpha.len() as u64);
        self.decoded
            .entry(key)
            .or_default()
            .push((Arc::from(bytes), t.clone()));
        Ok(t)
    }

    /// Bytes of alpha the decoded textures hold.
    pub fn held_bytes(&self) -> u64 {
        self.held
    }

    /// Decodes `bytes` after checking its size, alone and with what is held.
    fn decode(&self, bytes: &[u8], channel: Channel) -> Result<Option<Arc<AlphaTexture>>, String> {
        if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) && channel != Channel::AlphaOrGrey {
            // JPEG carries no alpha: opaque everywhere, whatever its size.
            if channel == Channel::AlphaOnly {
                return Ok(None);
            }
            return Ok(Some(Arc::new(AlphaTexture {
                width: 1,
                height: 1,
                alpha: vec![255],
            })));
        }
        let reader = || {
            image::ImageReader::new(Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| format!("its format cannot be read ({e})"))
        };
        let decoder = reader()?
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
        let texels = w as u64 * h as u64;
        let scratch = texels * DECODE_BYTES_PER_TEXEL;
        let held = self.held;
        limits::check_bytes(
            || {
                if held == 0 {
                    format!("its {w}x{h} texels")
                } else {
                    format!(
                        "its {w}x{h} texels, with the {} MiB of alpha textures decoded before it,",
                        limits::mib(held)
                    )
                }
            },
            held + texels + scratch,
        )
        .map_err(|e| e.to_string())?;
        let mut reader = reader()?;
        let mut lim = image::Limits::default();
        lim.max_image_width = Some(MAX_TEXTURE_SIDE);
        lim.max_image_height = Some(MAX_TEXTURE_SIDE);
        lim.max_alloc = Some(scratch + texels);
        reader.limits(lim);
        let img = reader
            .decode()
            .map_err(|e| format!("it cannot be decoded ({e})"))?;
        let alpha = if img.color().has_alpha() {
            img.to_rgba8().pixels().map(|p| p.0[3]).collect()
        } else if channel == Channel::AlphaOrGrey {
            img.to_luma8().into_raw()
        } else {
            vec![255; texels as usize]
        };
        Ok(Some(Arc::new(AlphaTexture {
            width: w,
            height: h,
            alpha,
        })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, a: u8) -> Vec<u8> {
        let img = image::RgbaImage::from_pixel(w, h, image::Rgba([0, 0, 0, a]));
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn one_image_is_decoded_once_and_shared() {
        let mut cache = TextureCache::default();
        let bytes = png(8, 4, 7);
        let a = cache.alpha(&bytes).unwrap();
        let b = cache.alpha(&bytes.clone()).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.held_bytes(), 32);
        assert_eq!(a.alpha, vec![7; 32]);
        let c = cache.alpha(&png(8, 4, 9)).unwrap();
        assert!(!Arc::ptr_eq(&a, &c));
        assert_eq!(cache.held_bytes(), 64);
    }

    #[test]
    fn oversized_images_are_refused_before_decoding() {
        let mut cache = TextureCache::default();
        let e = cache.alpha(&png(MAX_TEXTURE_SIDE + 1, 1, 0)).unwrap_err();
        assert!(e.contains("outside 1..=16384"), "{e}");
        assert_eq!(cache.held_bytes(), 0);
    }
}
