//! The `--dump` pictures of sub-pixel shadow maps: the depth maps, the silhouette mask maps
//! and the silhouette pixels.

use super::facets::Facet;
use super::silhouette_mask_map::MaskMap;
use crate::error::Result;
use crate::frame::Frame;
use crate::techniques::shadow_map::LightMaps;

/// Writes the depth maps, the silhouette mask maps (white: silhouette texel, grey: hidden
/// silhouette) and the silhouette pixels.
pub(super) fn dump(
    frame: &Frame,
    maps: &LightMaps,
    masks: &[MaskMap],
    facets: &[Facet],
    w: u32,
    h: u32,
) -> Result<()> {
    for (i, (m, mm)) in maps.maps.iter().zip(masks).enumerate() {
        frame.dump_depth(&format!("subpixel-depth{i}.png"), m)?;
        frame.dump_grey(&format!("subpixel-silhouette-mask{i}.png"), || {
            image::GrayImage::from_fn(mm.res, mm.res, |x, y| {
                image::Luma([match mm.mask[(y * mm.res + x) as usize] {
                    1 => 255,
                    2 => 96,
                    _ => 0,
                }])
            })
        })?;
    }
    frame.dump_grey("subpixel-silhouette-pixels.png", || {
        let mut img = image::GrayImage::new(w, h);
        for f in facets {
            img.put_pixel(f.k % w, f.k / w, image::Luma([255]));
        }
        img
    })
}
