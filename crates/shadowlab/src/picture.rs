//! Pictures: the 8-bit RGB image every PNG of shadowlab is, the sRGB encoding, grey
//! pictures of depth maps and the rectangle outlines that the tree dumps draw.
//!
//! This module knows nothing of scenes or techniques: it sits low in the data flow so
//! that the shading of a frame, the techniques' dump images and the command line's report
//! all draw with the same few functions.

use crate::error::{Error, Result};
use crate::math::Vec3;
use image::{ImageBuffer, ImageFormat, Pixel, PixelWithColorType, Rgb};
use std::path::Path;

/// An 8-bit sRGB image.
pub type RgbImage = ImageBuffer<Rgb<u8>, Vec<u8>>;
/// An 8-bit grey image (masks).
pub type GreyImage = image::GrayImage;

/// Linear RGB in `[0, 1]` (clamped) to 8-bit sRGB.
pub fn to_srgb8(c: Vec3) -> [u8; 3] {
    c.to_array().map(|x| {
        let x = x.clamp(0.0, 1.0);
        let s = if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    })
}

/// Writes `bytes` to `path` whole or not at all ([`crate::files::write_whole`]), naming
/// the file when the write fails.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::files::write_whole(path, bytes).map_err(|e| Error::Output {
        path: path.into(),
        what: e.to_string(),
    })
}

/// Encodes an image in memory, then writes it in one go: a write that fails (a full disk,
/// a file-size limit) is an error here, where `image`'s own `save` can lose it in the
/// flush of a dropped buffer. The bytes are those `save` writes.
pub fn save_image<P>(
    img: &ImageBuffer<P, Vec<P::Subpixel>>,
    format: ImageFormat,
    path: &Path,
) -> Result<()>
where
    P: Pixel + PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
{
    let mut encoded = std::io::Cursor::new(Vec::new());
    img.write_to(&mut encoded, format)
        .map_err(|e| Error::Output {
            path: path.into(),
            what: e.to_string(),
        })?;
    write_file(path, encoded.get_ref())
}

/// Saves an image as PNG (see [`save_image`]).
pub fn save_png(img: &RgbImage, path: &Path) -> Result<()> {
    save_image(img, ImageFormat::Png, path)
}

/// Saves a grey image as PNG (see [`save_image`]).
pub fn save_grey_png(img: &GreyImage, path: &Path) -> Result<()> {
    save_image(img, ImageFormat::Png, path)
}

/// Writes a text file (a dump's description of what its images show).
pub fn save_text(text: &str, path: &Path) -> Result<()> {
    write_file(path, text.as_bytes())
}

/// A depth map as a grey picture, `width × height` row-major depths: the nearest depth
/// white (255), the farthest dark grey (40), texels without depth (not finite) black.
pub fn depth_image(width: u32, height: u32, depth: &[f32]) -> RgbImage {
    let finite = depth.iter().copied().filter(|d| d.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), d| {
        (a.min(d), b.max(d))
    });
    let span = (hi - lo).max(1e-20);
    ImageBuffer::from_fn(width, height, |x, y| {
        let d = depth[(y * width + x) as usize];
        if !d.is_finite() {
            return Rgb([0, 0, 0]);
        }
        let g = (255.0 - (d - lo) / span * 215.0) as u8;
        Rgb([g, g, g])
    })
}

/// Draws the outline of the rectangle `x0..=x1 × y0..=y1` (corners inclusive) in `colour`.
/// The corners must lie inside the image.
pub fn outline_rect(img: &mut RgbImage, x0: u32, y0: u32, x1: u32, y1: u32, colour: [u8; 3]) {
    for x in x0..=x1 {
        img.put_pixel(x, y0, Rgb(colour));
        img.put_pixel(x, y1, Rgb(colour));
    }
    for y in y0..=y1 {
        img.put_pixel(x0, y, Rgb(colour));
        img.put_pixel(x1, y, Rgb(colour));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_image_maps_near_to_white_far_to_grey_and_empty_to_black() {
        let img = depth_image(3, 1, &[1.0, 3.0, f32::INFINITY]);
        assert_eq!(img.get_pixel(0, 0).0, [255; 3]);
        assert_eq!(img.get_pixel(1, 0).0, [40; 3]);
        assert_eq!(img.get_pixel(2, 0).0, [0; 3]);
    }

    #[test]
    fn outline_rect_draws_edges_only() {
        let mut img = RgbImage::new(5, 5);
        outline_rect(&mut img, 1, 1, 3, 3, [9, 8, 7]);
        let lit = img.pixels().filter(|p| p.0 == [9, 8, 7]).count();
        assert_eq!(lit, 8);
        assert_eq!(img.get_pixel(2, 2).0, [0; 3]);
        assert_eq!(img.get_pixel(1, 3).0, [9, 8, 7]);
    }

    #[test]
    fn srgb_encodes_the_ends_and_clamps() {
        assert_eq!(to_srgb8(Vec3::new(0.0, 1.0, 2.0)), [0, 255, 255]);
        assert_eq!(to_srgb8(Vec3::splat(-1.0)), [0, 0, 0]);
    }
}
