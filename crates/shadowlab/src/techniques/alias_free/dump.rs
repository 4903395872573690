//! The `--dump` picture of alias-free shadow maps (Aila & Laine 2004, Figure 4): one light
//! image plane's sampling points and the leaves of the 2D BSP built over them.

use super::bsp::Bsp;
use crate::picture::{outline_rect, RgbImage};

/// Side of the BSP picture written by `--dump`.
const DUMP_SIDE: u32 = 1024;

/// Draws one light plane's sample points (grey, brighter where denser) and the rectangles
/// of the BSP leaves (blue) over the root's rectangle.
pub(super) fn bsp_picture(t: &Bsp) -> RgbImage {
    let side = DUMP_SIDE;
    let mut img = RgbImage::new(side, side);
    let Some(root) = t.nodes.first() else {
        return img;
    };
    let (lo, hi) = (root.lo, root.hi);
    let span = [
        (hi[0] - lo[0]).max(f32::MIN_POSITIVE),
        (hi[1] - lo[1]).max(f32::MIN_POSITIVE),
    ];
    let to_px = |u: f32, v: f32| {
        let x = ((u - lo[0]) / span[0] * (side - 1) as f32).clamp(0.0, (side - 1) as f32) as u32;
        let y = ((v - lo[1]) / span[1] * (side - 1) as f32).clamp(0.0, (side - 1) as f32) as u32;
        (x, y)
    };
    for (&u, &v) in t.su.iter().zip(&t.sv) {
        let (x, y) = to_px(u, v);
        let p = img.get_pixel_mut(x, y);
        p.0 = p.0.map(|c| c.saturating_add(48));
    }
    for n in t.nodes.iter().filter(|n| n.is_leaf() && n.len > 0) {
        let (x0, y0) = to_px(n.lo[0], n.lo[1]);
        let (x1, y1) = to_px(n.hi[0], n.hi[1]);
        outline_rect(&mut img, x0, y0, x1, y1, [40, 110, 255]);
    }
    img
}
