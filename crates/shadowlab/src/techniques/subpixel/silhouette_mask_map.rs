//! The silhouette mask map of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps",
//! Section 3.2, Figure 4): the texels of each light view crossed by a silhouette edge that
//! the depth map does not hide, and the summed-area table over them that counts silhouette
//! texels in any rectangle with four look-ups.

use super::rasterization::{depth_bits, row_spans, Projector, RASTER_EPS};
use super::silhouette_edges::Adjacency;
use crate::light::LightView;
use crate::techniques::shadow_map::LightMaps;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// An edge is hidden in a texel when the depth map is nearer than the edge by this many
/// texels (world size at that depth) at all nine texel centres around it. Larger keeps more
/// hidden silhouettes (more pixels take the exact, slower path; never wrong); smaller drops
/// texels whose edge bounds the very surface the depth map sees, giving those pixels a
/// point-sampled, aliased answer.
pub const HIDDEN_SILHOUETTE_BIAS: f32 = 2.0;

/// The silhouette mask map of every light view, from the silhouette edges `edges`.
pub(super) fn silhouette_mask_maps(
    edges: &[u32],
    adj: &Adjacency,
    maps: &LightMaps,
    projectors: &[Projector],
) -> Vec<MaskMap> {
    maps.views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            MaskMap::build(
                edges,
                adj,
                &projectors[i],
                v,
                &maps.maps[i].depth,
                maps.resolution,
            )
        })
        .collect()
}

/// The silhouette mask map of one light view and its summed-area table.
pub(super) struct MaskMap {
    /// Side in texels.
    pub(super) res: u32,
    /// 1 for a silhouette texel, 2 for a texel whose silhouettes are all hidden, else 0.
    pub(super) mask: Vec<u8>,
    /// `(res + 1)²` prefix sums of silhouette texels.
    sat: Vec<u32>,
}

impl MaskMap {
    /// The map of one view: `edges` rasterized conservatively, the nearest edge depth kept
    /// per texel, hidden ones dropped, then the summed-area table.
    fn build(
        edges: &[u32],
        adj: &Adjacency,
        proj: &Projector,
        view: &LightView,
        depth: &[f32],
        res: u32,
    ) -> Self {
        let r = res as usize;
        let nearest: Vec<AtomicU32> = (0..r * r)
            .map(|_| AtomicU32::new(f32::INFINITY.to_bits()))
            .collect();
        edges.par_iter().with_min_len(64).for_each(|&e| {
            let poly = proj.project(&[adj.a[e as usize], adj.b[e as usize]]);
            row_spans(&poly, res, |y, x0, x1, k0, k1| {
                let d = depth_bits(proj.depth_span(k0, k1).0);
                for x in x0..=x1 {
                    nearest[y as usize * r + x as usize].fetch_min(d, Ordering::Relaxed);
                }
            });
        });
        let mask: Vec<u8> = (0..r)
            .into_par_iter()
            .flat_map_iter(|y| {
                let nearest = &nearest;
                (0..r).map(move |x| {
                    let e = f32::from_bits(nearest[y * r + x].load(Ordering::Relaxed));
                    if !e.is_finite() {
                        return 0;
                    }
                    let bias = HIDDEN_SILHOUETTE_BIAS * view.texel_size(res, e);
                    // Hidden only if the map is nearer at all nine texel centres around.
                    let mut far = f32::NEG_INFINITY;
                    for yy in y.saturating_sub(1)..(y + 2).min(r) {
                        for xx in x.saturating_sub(1)..(x + 2).min(r) {
                            far = far.max(depth[yy * r + xx]);
                        }
                    }
                    let border = x == 0 || y == 0 || x + 1 == r || y + 1 == r;
                    if !border && far < e - bias {
                        2
                    } else {
                        1
                    }
                })
            })
            .collect();
        let w = r + 1;
        let mut sat = vec![0u32; w * w];
        for y in 0..r {
            let mut row = 0u32;
            for x in 0..r {
                row += (mask[y * r + x] == 1) as u32;
                sat[(y + 1) * w + x + 1] = sat[y * w + x + 1] + row;
            }
        }
        MaskMap { res, mask, sat }
    }

    /// Silhouette texels in the inclusive rectangle.
    #[inline]
    pub(super) fn count(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> u32 {
        let w = self.res as usize + 1;
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize + 1, y1 as usize + 1);
        self.sat[y1 * w + x1] + self.sat[y0 * w + x0]
            - self.sat[y0 * w + x1]
            - self.sat[y1 * w + x0]
    }

    /// Silhouette texels touched by the box `(tx ± ex, ty ± ey)` in texel coordinates
    /// (widened by [`RASTER_EPS`]); 0 when the box misses the map.
    #[inline]
    pub(super) fn count_around(&self, tx: f32, ty: f32, ex: f32, ey: f32) -> u32 {
        let r = self.res as f32;
        let (x0, x1) = (tx - ex - RASTER_EPS, tx + ex + RASTER_EPS);
        let (y0, y1) = (ty - ey - RASTER_EPS, ty + ey + RASTER_EPS);
        if !(x1 >= 0.0 && y1 >= 0.0 && x0 < r && y0 < r) {
            return 0;
        }
        let c = |v: f32| v.clamp(0.0, r - 1.0) as u32;
        self.count(c(x0), c(y0), c(x1), c(y1))
    }

    /// Whether texel `(x, y)` is a silhouette texel.
    #[inline]
    pub(super) fn is_silhouette(&self, x: u32, y: u32) -> bool {
        self.mask[(y * self.res + x) as usize] == 1
    }

    /// Silhouette texels in the map.
    pub(super) fn texels(&self) -> usize {
        self.sat[self.sat.len() - 1] as usize
    }

    /// Bytes held (the map, its table and the nearest-edge depths it was built from).
    pub(super) fn bytes(&self) -> u64 {
        (self.mask.len() + self.sat.len() * 4 + self.mask.len() * 4) as u64
    }
}
