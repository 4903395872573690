//! `--dump` images of `gpu:afsm`: each light plane's grid, one pixel a cell — its load
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

fn scale(v: &[u32]) -> f32 {
    v.iter().copied().max().unwrap_or(0).max(1) as f32
}

/// The grid's load, grey.
pub(super) fn load_picture(g: &PlaneGrid) -> RgbImage {
    let m = scale(&g.load);
    let mut img = RgbImage::new(g.gx, g.gy);
    for (i, &l) in g.load.iter().enumerate() {
        let v = (l as f32 / m * 255.0).round() as u8;
        img.get_pixel_mut(i as u32 % g.gx, i as u32 / g.gx).0 = [v, v, v];
    }
    img
}

/// The culled cells in red over the load.
pub(super) fn culled_picture(g: &PlaneGrid) -> RgbImage {
    let m = scale(&g.load);
    let c = scale(&g.culled);
    let mut img = RgbImage::new(g.gx, g.gy);
    for i in 0..g.load.len() {
        let grey = (g.load[i] as f32 / m * 96.0).round() as u8;
        let px = if g.culled[i] > 0 {
            [
                (128.0 + g.culled[i] as f32 / c * 127.0).round() as u8,
                grey / 2,
                grey / 2,
            ]
        } else {
            [grey, grey, grey]
        };
        img.get_pixel_mut(i as u32 % g.gx, i as u32 / g.gx).0 = px;
    }
    img
}
