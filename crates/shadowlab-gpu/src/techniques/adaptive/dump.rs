//! The picture of `gpu:asm`'s virtual map, for `--dump` and the viewer's technique view:
//! per light view, the outline of every resident page finer than the always-resident
//! coarsest level, coloured by its level below that one as the library's `asm` colours
//! its tree's nodes (`asm-face{f}-tree.png`). It is drawn from the pool's own record of
//! which page each slot holds, on the CPU: nothing is read back from the device.

use super::pool::{Layout, Pool};
use shadowlab::error::Result;
use shadowlab::picture::{outline_rect, RgbImage};
use shadowlab::techniques::adaptive::LEVEL_COLOURS;
use shadowlab::techniques::Frame;

/// Side of the picture in pixels.
const SIDE: u32 = 1024;

/// The grey of the ground under the outlines.
const GROUND: u8 = 40;

/// Hands `gpu-asm-face{f}-pages.png` for every light view `f` to `frame`'s dump sink.
pub(super) fn write_dump(layout: &Layout, pool: &Pool, frame: &Frame) -> Result<()> {
    for f in 0..layout.faces {
        frame.dump_image(&format!("gpu-asm-face{f}-pages.png"), || {
            pages_picture(layout, pool, f)
        })?;
    }
    Ok(())
}

/// The resident pages of light view `f` over a dark ground, finer levels drawn last.
fn pages_picture(layout: &Layout, pool: &Pool, f: u32) -> RgbImage {
    let ground = vec![GROUND; (SIDE * SIDE * 3) as usize];
    let mut img = RgbImage::from_raw(SIDE, SIDE, ground).unwrap_or_default();
    let mut pages: Vec<_> = pool
        .entries()
        .map(|e| layout.page(e))
        .filter(|p| p.face == f && p.level + 1 < layout.levels)
        .collect();
    pages.sort_by_key(|p| (std::cmp::Reverse(p.level), p.y, p.x));
    let to_px =
        |t: u64| ((t * u64::from(SIDE)) / u64::from(layout.side)).min(u64::from(SIDE - 1)) as u32;
    for p in pages {
        let span = u64::from(layout.page) << p.level;
        let (x0, y0) = (u64::from(p.x) * span, u64::from(p.y) * span);
        let below_root = (layout.levels - 1 - p.level) as usize;
        let c = LEVEL_COLOURS[(below_root - 1) % LEVEL_COLOURS.len()];
        outline_rect(
            &mut img,
            to_px(x0),
            to_px(y0),
            to_px(x0 + span),
            to_px(y0 + span),
            c,
        );
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_finer_page_is_outlined_in_its_level_colour_where_it_lies() {
        let layout = Layout {
            page: 32,
            levels: 3,
            side: 256,
            faces: 1,
        };
        // The coarsest level is 64 texels of 2 pages across; the finest 8 pages across.
        let mut pool = Pool::new(8, 4);
        pool.pin(layout.coarsest(), 1);
        let finest = layout.level_base(0);
        pool.assign(&[(finest, 1)], 2, 8);
        let img = pages_picture(&layout, &pool, 0);
        // Finest page (0, 0) covers a 32-texel square of 256: 128 pixels of 1024.
        assert_eq!(img.get_pixel(0, 64).0, LEVEL_COLOURS[1]);
        assert_eq!(img.get_pixel(128, 64).0, LEVEL_COLOURS[1]);
        assert_eq!(img.get_pixel(64, 64).0, [GROUND; 3]);
        assert_eq!(img.get_pixel(600, 600).0, [GROUND; 3]);
    }
}
