//! The pictures of an adaptive shadow map's tree (Fernando et al. 2001, Section 3): per
//! light view, the root's depth map, and the outlines of the nodes over the root map,
//! coloured by level.

use super::tree::{Face, Tree};
use crate::error::Result;
use crate::frame::Frame;
use crate::picture::{outline_rect, RgbImage};
use crate::raster::DepthBuffer;

/// Side of the tree picture in pixels.
const SIDE: u32 = 1024;

/// Outline colours of the tree picture, by level below the root (`gpu:asm`'s page picture
/// uses them too).
pub const LEVEL_COLOURS: [[u8; 3]; 6] = [
    [70, 130, 255],
    [60, 200, 90],
    [240, 220, 60],
    [255, 140, 40],
    [240, 50, 50],
    [230, 80, 230],
];

/// Hands `asm-face{f}-root.png` (the root's depths) and `asm-face{f}-tree.png` (the
/// node outlines) for every light view `f` with a root to `frame`'s dump sink.
pub(super) fn write_dump(tree: &Tree, frame: &Frame) -> Result<()> {
    for (f, face) in tree.faces.iter().enumerate() {
        let Some(face) = face else { continue };
        let root = tree.node(face.root);
        let map = DepthBuffer {
            width: root.res,
            height: root.res,
            depth: root.depth.clone(),
            id: root.id.clone(),
        };
        frame.dump_depth(&format!("asm-face{f}-root.png"), &map)?;
        frame.dump_image(&format!("asm-face{f}-tree.png"), || {
            tree_picture(tree, f, face)
        })?;
    }
    Ok(())
}

/// The tile tree of light view `f`: node outlines over the root map, coloured by level.
fn tree_picture(tree: &Tree, f: usize, face: &Face) -> RgbImage {
    let root = tree.node(face.root);
    let mut img = RgbImage::from_fn(SIDE, SIDE, |x, y| {
        let tx = (x as u64 * root.res as u64 / SIDE as u64) as u32;
        let ty = (y as u64 * root.res as u64 / SIDE as u64) as u32;
        let g = if root.depth[(ty * root.res + tx) as usize].is_finite() {
            60
        } else {
            20
        };
        image::Rgb([g, g, g])
    });
    for n in tree
        .live_nodes()
        .filter(|n| n.face as usize == f && n.level > 0)
    {
        let e = tree.scale(face, n.level);
        let to_px = |t: u32| ((t as f64 / e) * SIDE as f64) as u32;
        let (x0, y0) = (to_px(n.x0).min(SIDE - 1), to_px(n.y0).min(SIDE - 1));
        let (x1, y1) = (
            to_px(n.x0 + n.res).min(SIDE - 1),
            to_px(n.y0 + n.res).min(SIDE - 1),
        );
        let c = LEVEL_COLOURS[(n.level as usize - 1) % LEVEL_COLOURS.len()];
        outline_rect(&mut img, x0, y0, x1, y1, c);
    }
    img
}
