//! The worst error region of each technique, as the report shows it: the square window
//! where its shadow term is furthest from the reference (found with a summed-area table,
//! so every window is weighed), and the crop image that enlarges it beside the reference
//! and the error image.

use crate::metrics::WorstRegion;
use crate::output::create_dir;
use anyhow::Result;
use shadowlab::frame::{luminance, Visibility};
use shadowlab::picture::save_png;
use shadowlab::picture::RgbImage;
use shadowlab::view::ViewSamples;
use std::path::Path;

/// Side of the worst-error window as a fraction of the image's shorter side: small enough
/// to show single texels, large enough to show the shape of the artifact.
pub const CROP_FRACTION: f64 = 1.0 / 8.0;
/// Smallest and largest side of the worst-error window in pixels.
pub const CROP_SIDE_RANGE: (u32, u32) = (16, 128);
/// Each panel of a crop is enlarged (nearest neighbour, so pixels stay visible) to about
/// this many pixels across.
pub const CROP_PANEL_PIXELS: u32 = 256;
/// White gap between the panels of a crop, in pixels.
const CROP_GAP: u32 = 6;

/// The square window where a technique's shadow term is furthest from the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Side in pixels.
    pub side: u32,
    /// Mean absolute luminance error over the window's pixels (uncovered ones count 0).
    pub mean_abs_error: f64,
}

impl Region {
    /// The region as `metrics.json` records it, with its crop image's file name.
    pub fn record(self, crop: String) -> WorstRegion {
        WorstRegion {
            x: self.x,
            y: self.y,
            width: self.side,
            height: self.side,
            mean_abs_error: self.mean_abs_error,
            crop,
        }
    }
}

/// The side of the worst-error window for a `width × height` image.
pub fn crop_side(width: u32, height: u32) -> u32 {
    let s = (width.min(height) as f64 * CROP_FRACTION).round() as u32;
    s.clamp(CROP_SIDE_RANGE.0, CROP_SIDE_RANGE.1)
        .min(width.min(height))
        .max(1)
}

/// Finds the window of [`crop_side`] pixels with the largest summed absolute luminance
/// error of `vis` against `reference` over covered pixels; the first in row order wins a
/// tie. `None` when the two agree everywhere.
pub fn worst_region(
    view: &ViewSamples,
    vis: &Visibility,
    reference: &Visibility,
) -> Option<Region> {
    let n = view.width as usize * view.height as usize;
    if vis.value.len() != n || reference.value.len() != n {
        return None;
    }
    let error: Vec<f64> = (0..n)
        .map(|k| {
            if view.covered(k) {
                (luminance(vis.value[k]) - luminance(reference.value[k])).abs() as f64
            } else {
                0.0
            }
        })
        .collect();
    worst_window(
        &error,
        view.width,
        view.height,
        crop_side(view.width, view.height),
    )
}

/// The `side × side` window of largest summed `error` (row-major, `width × height`); the
/// first in row order wins a tie. `None` when the largest sum is rounding noise.
pub fn worst_window(error: &[f64], width: u32, height: u32, side: u32) -> Option<Region> {
    let (w, h, side) = (width as usize, height as usize, side as usize);
    if w == 0 || h == 0 || side == 0 || side > w.min(h) || error.len() != w * h {
        return None;
    }
    // Summed-area table, built in a fixed order so the answer depends on the images alone.
    let mut sat = vec![0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0f64;
        for x in 0..w {
            row += error[y * w + x];
            sat[(y + 1) * (w + 1) + x + 1] = sat[y * (w + 1) + x + 1] + row;
        }
    }
    let window = |x: usize, y: usize| {
        let (x1, y1) = (x + side, y + side);
        sat[y1 * (w + 1) + x1] - sat[y * (w + 1) + x1] - sat[y1 * (w + 1) + x]
            + sat[y * (w + 1) + x]
    };
    let mut best = (0.0, 0, 0);
    for y in 0..=h - side {
        for x in 0..=w - side {
            let s = window(x, y);
            if s > best.0 + WINDOW_TIE {
                best = (s, x, y);
            }
        }
    }
    (best.0 > WINDOW_NOISE).then(|| Region {
        x: best.1 as u32,
        y: best.2 as u32,
        side: side as u32,
        mean_abs_error: best.0 / (side * side) as f64,
    })
}

/// Window sums closer than this count as equal, so the summed-area table's rounding
/// cannot move the chosen window between equally bad places.
const WINDOW_TIE: f64 = 1e-9;
/// A window whose summed error is below this shows rounding noise, not an error worth a
/// crop.
const WINDOW_NOISE: f64 = 1e-6;

/// Writes `DIR/crops/<stem>.png`: the region of each image side by side (reference,
/// technique, error), enlarged with nearest-neighbour sampling. Returns the path relative
/// to `dir`.
pub fn write_crop(dir: &Path, stem: &str, region: &Region, panels: &[&RgbImage]) -> Result<String> {
    let zoom = (CROP_PANEL_PIXELS / region.side).max(1);
    let p = region.side * zoom;
    let n = panels.len() as u32;
    let mut out = RgbImage::from_pixel(
        n * p + n.saturating_sub(1) * CROP_GAP,
        p,
        image::Rgb([255, 255, 255]),
    );
    for (i, img) in panels.iter().enumerate() {
        let x0 = i as u32 * (p + CROP_GAP);
        for y in 0..p {
            for x in 0..p {
                let (sx, sy) = (region.x + x / zoom, region.y + y / zoom);
                if sx < img.width() && sy < img.height() {
                    out.put_pixel(x0 + x, y, *img.get_pixel(sx, sy));
                }
            }
        }
    }
    let rel = format!("crops/{stem}.png");
    let path = dir.join(&rel);
    create_dir(&dir.join("crops"))?;
    save_png(&out, &path)?;
    Ok(rel)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_side_follows_image_size() {
        assert_eq!(crop_side(1024, 768), 96);
        assert_eq!(crop_side(64, 48), 16);
        assert_eq!(crop_side(8, 8), 8);
        assert_eq!(crop_side(8000, 8000), 128);
    }

    #[test]
    fn worst_window_matches_brute_force() {
        let (w, h, side) = (37u32, 23u32, 5u32);
        // A deterministic pseudo-random error field with one hot spot.
        let mut e: Vec<f64> = (0..w * h)
            .map(|i| ((i.wrapping_mul(2654435761) >> 7) % 97) as f64 / 970.0)
            .collect();
        for y in 14..18 {
            for x in 25..29 {
                e[(y * w + x) as usize] += 1.0;
            }
        }
        let got = worst_window(&e, w, h, side).unwrap();
        let mut best = (f64::NEG_INFINITY, 0, 0);
        for y in 0..=h - side {
            for x in 0..=w - side {
                let mut s = 0.0;
                for yy in y..y + side {
                    for xx in x..x + side {
                        s += e[(yy * w + xx) as usize];
                    }
                }
                if s > best.0 + 1e-9 {
                    best = (s, x, y);
                }
            }
        }
        assert_eq!((got.x, got.y), (best.1, best.2));
        assert!((got.mean_abs_error - best.0 / 25.0).abs() < 1e-9);
        assert!(
            got.x <= 25 && got.x + side >= 29 && got.y <= 14 && got.y + side >= 18,
            "{got:?}"
        );
    }

    #[test]
    fn worst_window_of_no_error_is_none() {
        assert_eq!(worst_window(&[0.0; 100], 10, 10, 4), None);
        assert_eq!(worst_window(&[1.0; 100], 10, 10, 11), None);
    }
}
