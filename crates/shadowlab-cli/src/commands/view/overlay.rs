//! The overlays drawn over the shaded image, each in its own rectangle (recorded, so that
//! a screenshot tells which pixels are the view's): the panel of text at the top left
//! (technique, main parameter, frame time per stage, keys), the error against the
//! reference at the bottom left and the technique's images at the bottom right, each
//! scaled into a third of the window with its caption.

use font8x8::UnicodeFonts;
use image::Rgb;
use serde::Serialize;
use shadowlab::picture::RgbImage;

/// Pixels of a glyph's side (the 8×8 font at scale 1).
const GLYPH: u32 = 8;

/// Pixels from one line of text to the next.
const LINE: u32 = 10;

/// Padding inside a box.
const PAD: u32 = 4;

/// A rectangle `[x0, x1) × [y0, y1)` of the window covered by an overlay.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Rect {
    /// What it shows: `panel`, `error` or `dump`.
    pub name: String,
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// One past the right column.
    pub x1: u32,
    /// One past the bottom row.
    pub y1: u32,
}

/// An image shown in a corner with its caption.
pub struct Inset<'a> {
    /// The image.
    pub image: &'a RgbImage,
    /// One line above it.
    pub caption: String,
}

/// What is drawn over the view.
#[derive(Default)]
pub struct Overlays<'a> {
    /// The panel's lines.
    pub panel: Vec<String>,
    /// The error against the reference (bottom left).
    pub error: Option<Inset<'a>>,
    /// The technique's image (bottom right).
    pub dump: Option<Inset<'a>>,
}

/// The view with the overlays drawn over it, and the rectangles they cover.
pub fn compose(view: &RgbImage, o: &Overlays) -> (RgbImage, Vec<Rect>) {
    let mut img = view.clone();
    let mut rects = Vec::new();
    if !o.panel.is_empty() {
        rects.push(text_box(&mut img, 0, 0, &o.panel, "panel"));
    }
    if let Some(i) = &o.error {
        rects.push(inset(&mut img, i, false, "error"));
    }
    if let Some(i) = &o.dump {
        rects.push(inset(&mut img, i, true, "dump"));
    }
    rects.retain(|r| r.x1 > r.x0 && r.y1 > r.y0);
    (img, rects)
}

/// Draws `lines` in a darkened box with its top-left corner at (x, y).
fn text_box(img: &mut RgbImage, x: u32, y: u32, lines: &[String], name: &str) -> Rect {
    let cols = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
    let r = clip(
        img,
        name,
        x,
        y,
        x + cols * GLYPH + 2 * PAD,
        y + lines.len() as u32 * LINE + 2 * PAD,
    );
    darken(img, &r);
    for (i, l) in lines.iter().enumerate() {
        text(img, x + PAD, y + PAD + i as u32 * LINE, l, &r);
    }
    r
}

/// Draws an inset in a bottom corner (the right one when `right`).
fn inset(img: &mut RgbImage, i: &Inset, right: bool, name: &str) -> Rect {
    let (w, h) = img.dimensions();
    let (iw, ih) = i.image.dimensions();
    let (bw, bh) = (w / 3, h / 3);
    if iw == 0 || ih == 0 || bw == 0 || bh == 0 {
        return clip(img, name, 0, 0, 0, 0);
    }
    // The largest size with the image's aspect that fits the box.
    let scale = (bw as f64 / iw as f64).min(bh as f64 / ih as f64);
    let sw = ((iw as f64 * scale) as u32).max(1);
    let sh = ((ih as f64 * scale) as u32).max(1);
    let x0 = if right {
        w.saturating_sub(sw + 2 * PAD)
    } else {
        0
    };
    let y0 = h.saturating_sub(sh + LINE + 3 * PAD);
    let r = clip(img, name, x0, y0, x0 + sw + 2 * PAD, h);
    darken(img, &r);
    text(img, x0 + PAD, y0 + PAD, &i.caption, &r);
    let (ix, iy) = (x0 + PAD, y0 + 2 * PAD + LINE);
    for y in 0..sh {
        for x in 0..sw {
            let sx = ((x as u64 * iw as u64) / sw as u64) as u32;
            let sy = ((y as u64 * ih as u64) / sh as u64) as u32;
            if ix + x < r.x1 && iy + y < r.y1 {
                img.put_pixel(ix + x, iy + y, *i.image.get_pixel(sx, sy));
            }
        }
    }
    r
}

/// The rectangle clipped to the image.
fn clip(img: &RgbImage, name: &str, x0: u32, y0: u32, x1: u32, y1: u32) -> Rect {
    let (w, h) = img.dimensions();
    Rect {
        name: name.to_string(),
        x0: x0.min(w),
        y0: y0.min(h),
        x1: x1.min(w),
        y1: y1.min(h),
    }
}

/// Dims the pixels of `r` to a quarter, so text over them reads.
fn darken(img: &mut RgbImage, r: &Rect) {
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            let p = img.get_pixel_mut(x, y);
            *p = Rgb(p.0.map(|c| c / 4));
        }
    }
}

/// Draws one line of text in white from (x, y), clipped to `r`; characters the font
/// lacks are drawn as `?`.
fn text(img: &mut RgbImage, x: u32, y: u32, s: &str, r: &Rect) {
    for (i, c) in s.chars().enumerate() {
        let glyph = font8x8::BASIC_FONTS
            .get(c)
            .or_else(|| font8x8::BASIC_FONTS.get('?'))
            .unwrap_or([0; 8]);
        let gx = x + i as u32 * GLYPH;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..GLYPH {
                let (px, py) = (gx + col, y + row as u32);
                if bits & (1 << col) != 0 && px < r.x1 && py < r.y1 {
                    img.put_pixel(px, py, Rgb([255, 255, 255]));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlays_change_only_the_pixels_of_their_rectangles() {
        let view = RgbImage::from_fn(200, 150, |x, y| Rgb([x as u8, y as u8, 99]));
        let small = RgbImage::from_pixel(30, 10, Rgb([200, 0, 0]));
        let o = Overlays {
            panel: vec!["sm  resolution 2048".into(), "12.5 ms".into()],
            error: Some(Inset {
                image: &small,
                caption: "error".into(),
            }),
            dump: Some(Inset {
                image: &view,
                caption: "map".into(),
            }),
        };
        let (img, rects) = compose(&view, &o);
        assert_eq!(rects.len(), 3);
        let mut changed = 0;
        for (x, y, p) in img.enumerate_pixels() {
            let inside = rects
                .iter()
                .any(|r| x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1);
            if *p != *view.get_pixel(x, y) {
                assert!(inside, "pixel {x},{y} changed outside the overlays");
                changed += 1;
            }
        }
        assert!(changed > 0);
        // The error inset shows the error image's colour.
        let e = &rects[1];
        assert!(img
            .enumerate_pixels()
            .any(|(x, y, p)| x < e.x1 && y >= e.y0 && *p == Rgb([200, 0, 0])));
    }
}
