//! `--dump` images of `gpu:afsm`: each light plane's grid, one square a cell (at least
//! [`DUMP_SIDE`] pixels along the longer side) — its load
//! (samples a cell, grey, white the fullest) and its occlusion culling (red where some
//! triangle skipped a chunk of the cell because all its samples were dark, brighter the
//! more often, over the load in grey).

use shadowlab::picture::RgbImage;

/// The grid of one plane as the frame left it.
pub(super) struct PlaneGrid {
    pub(super) gx: u32,
    pub(super) gy: u32,
    /// Samples of each cell, row-major.
    pub(super) load: Vec<u32>,
    /// Chunk skips for darkness of each cell, row-major.
    pub(super) culled: Vec<u32>,
}

/// Every plane's grid from the planes' records, the cells' starts, each chunk's cell and
/// its cull count.
pub(super) fn plane_grids(
    planes: &[u32],
    starts: &[u32],
    chunk_cell: &[u32],
    culled: &[u32],
) -> Vec<PlaneGrid> {
    let total = starts.len().saturating_sub(1);
    let mut cell_culled = vec![0u32; total];
    for (c, k) in chunk_cell.iter().zip(culled) {
        if let Some(x) = cell_culled.get_mut(*c as usize) {
            *x = x.saturating_add(*k);
        }
    }
    (0..7)
        .filter_map(|pl| {
            let r = &planes[pl * 16..pl * 16 + 16];
            let (gx, gy, base) = (r[8], r[9], r[10] as usize);
            let cells = (gx * gy) as usize;
            if cells == 0 || base + cells > total {
                return None;
            }
            Some(PlaneGrid {
                gx,
                gy,
                load: (base..base + cells)
                    .map(|c| starts[c + 1] - starts[c])
                    .collect(),
                culled: cell_culled[base..base + cells].to_vec(),
            })
        })
        .collect()
}

/// The fewest pixels along a picture's longer side.
const DUMP_SIDE: u32 = 512;

/// A picture of the grid, each cell `colour(i)` (cell `i` row-major) in a square of pixels.
fn picture(g: &PlaneGrid, colour: impl Fn(usize) -> [u8; 3]) -> RgbImage {
    let k = (DUMP_SIDE / g.gx.max(g.gy).max(1)).max(1);
    let mut img = RgbImage::new(g.gx * k, g.gy * k);
    for (x, y, p) in img.enumerate_pixels_mut() {
        p.0 = colour(((y / k) * g.gx + x / k) as usize);
    }
    img
}

fn scale(v: &[u32]) -> f32 {
    v.iter().copied().max().unwrap_or(0).max(1) as f32
}

/// The grid's load, grey.
pub(super) fn load_picture(g: &PlaneGrid) -> RgbImage {
    let m = scale(&g.load);
    picture(g, |i| {
        let v = (g.load[i] as f32 / m * 255.0).round() as u8;
        [v, v, v]
    })
}

/// The culled cells in red over the load.
pub(super) fn culled_picture(g: &PlaneGrid) -> RgbImage {
    let m = scale(&g.load);
    let c = scale(&g.culled);
    picture(g, |i| {
        let grey = (g.load[i] as f32 / m * 96.0).round() as u8;
        if g.culled[i] > 0 {
            let red = (128.0 + g.culled[i] as f32 / c * 127.0).round() as u8;
            [red, grey / 2, grey / 2]
        } else {
            [grey, grey, grey]
        }
    })
}
