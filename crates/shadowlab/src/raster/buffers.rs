//! What the rasterizer fills most often: the nearest surface's depth and triangle per pixel
//! (the camera pass and every light-space depth map), and a fragment count per pixel.

use super::{rasterize, Fragment, SetupTriangle, TileRect};

/// A depth buffer with the id of the nearest triangle per pixel.
#[derive(Clone, Debug)]
pub struct DepthBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Nearest depth per pixel (`+inf` where empty), row-major from the top row.
    pub depth: Vec<f32>,
    /// Triangle id per pixel ([`NO_TRIANGLE`] where empty).
    pub id: Vec<u32>,
}

/// Marks a pixel that no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

impl DepthBuffer {
    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.depth.len() * 4 + self.id.len() * 4
    }
}

/// Rasterizes the nearest surface (smallest depth attribute; ties keep the lower
/// triangle index) into a depth and id buffer.
pub fn depth_buffer(tris: &[SetupTriangle], width: u32, height: u32) -> DepthBuffer {
    depth_buffer_where(tris, width, height, |_| true)
}

/// A tile's nearest depth and id per pixel, row-major.
type NearestTile = (Vec<f32>, Vec<u32>);

/// The nearest kept fragment's depth and id per pixel of each 64×64 tile.
fn nearest_tiles<K>(
    tris: &[SetupTriangle],
    width: u32,
    height: u32,
    keep: K,
) -> Vec<(TileRect, NearestTile)>
where
    K: Fn(&Fragment) -> bool + Sync,
{
    rasterize(
        tris,
        width,
        height,
        |r| {
            let n = (r.width() * r.height()) as usize;
            (vec![f32::INFINITY; n], vec![NO_TRIANGLE; n])
        },
        |(d, id): &mut (Vec<f32>, Vec<u32>), r, f| {
            let k = ((f.y - r.y0) * r.width() + (f.x - r.x0)) as usize;
            if f.depth < d[k] && keep(&f) {
                d[k] = f.depth;
                id[k] = f.id;
            }
        },
    )
}

/// Copies each tile's rows of `of(state)` into the `width`-wide image `out`.
fn merge_tiles<S, T: Copy>(
    tiles: &[(TileRect, S)],
    width: u32,
    out: &mut [T],
    of: impl Fn(&S) -> &[T],
) {
    for (r, state) in tiles {
        let src_all = of(state);
        for y in r.y0..r.y1 {
            let src = ((y - r.y0) * r.width()) as usize;
            let dst = (y * width + r.x0) as usize;
            let w = r.width() as usize;
            out[dst..dst + w].copy_from_slice(&src_all[src..src + w]);
        }
    }
}

/// [`depth_buffer`] of the fragments `keep` accepts only: an alpha-masked caster's
/// fragments are dropped where its texture cuts it out
/// (`|f| !scene.cut_out(f.id as usize, f.bary())`, through the caller's id mapping).
pub fn depth_buffer_where<K>(
    tris: &[SetupTriangle],
    width: u32,
    height: u32,
    keep: K,
) -> DepthBuffer
where
    K: Fn(&Fragment) -> bool + Sync,
{
    let tiles = nearest_tiles(tris, width, height, keep);
    let n = width as usize * height as usize;
    let mut out = DepthBuffer {
        width,
        height,
        depth: vec![f32::INFINITY; n],
        id: vec![NO_TRIANGLE; n],
    };
    merge_tiles(&tiles, width, &mut out.depth, |s| &s.0);
    merge_tiles(&tiles, width, &mut out.id, |s| &s.1);
    out
}

/// The ids of [`depth_buffer_where`] alone, written into `ids` (`width × height`, every
/// pixel written once): the camera pass keeps that buffer across frames and needs no
/// depths.
pub fn nearest_ids_where<K>(
    tris: &[SetupTriangle],
    width: u32,
    height: u32,
    ids: &mut [u32],
    keep: K,
) where
    K: Fn(&Fragment) -> bool + Sync,
{
    let tiles = nearest_tiles(tris, width, height, keep);
    merge_tiles(&tiles, width, ids, |s| &s.1);
}

/// How many fragments each pixel received (for coverage tests and overdraw pictures).
pub fn coverage_count(tris: &[SetupTriangle], width: u32, height: u32) -> Vec<u32> {
    let tiles = rasterize(
        tris,
        width,
        height,
        |r| vec![0u32; (r.width() * r.height()) as usize],
        |c: &mut Vec<u32>, r, f| c[((f.y - r.y0) * r.width() + (f.x - r.x0)) as usize] += 1,
    );
    let mut out = vec![0u32; width as usize * height as usize];
    for (r, c) in tiles {
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                out[(y * width + x) as usize] = c[((y - r.y0) * r.width() + (x - r.x0)) as usize];
            }
        }
    }
    out
}
