//! Frustum culling for each cell in the topmost level of the hierarchy (Fernando et al.
//! 2001, Section 4.3): "since it is inefficient to redraw the whole scene for each grid cell
//! during refinement", each root cell keeps the list of triangles whose projection overlaps
//! it, and a new node's tile is drawn from its root cell's list alone.

use super::tree::{Face, Square, Tree, MAX_EFFECTIVE_RESOLUTION, NO_NODE};
use crate::light::LightView;
use crate::math::{ndc_to_uv, Vec4};
use crate::scene::Scene;
use rayon::prelude::*;

/// Slack around a triangle's root-view rectangle when it is binned: one texel of the
/// finest level, so that the f32 rounding of the rectangle never leaves a triangle out of
/// a root cell whose deepest tiles it reaches.
const BIN_MARGIN: f32 = 1.0 / MAX_EFFECTIVE_RESOLUTION as f32;

impl Face {
    /// Light view `view` of `scene` with a root of `resolution²` texels in `grid²` cells,
    /// its culling lists made and its root still to be made.
    pub(super) fn new(scene: &Scene, view: LightView, resolution: u32, grid: u32) -> Face {
        let mut face = Face {
            view,
            clip_from_world: view.clip_from_world.as_dmat4(),
            resolution,
            root: NO_NODE,
            grid,
            bins: Vec::new(),
        };
        face.bins = bin_triangles(scene, &face);
        face
    }

    /// Bytes held by this view's per-root-cell triangle lists.
    fn bins_bytes(&self) -> u64 {
        self.bins
            .iter()
            .map(|b| b.capacity() as u64 * 4 + std::mem::size_of::<Vec<u32>>() as u64)
            .sum()
    }
}

impl Tree {
    /// Bytes held by the per-root-cell triangle lists.
    pub(super) fn culling_bytes(&self) -> u64 {
        self.faces.iter().flatten().map(Face::bins_bytes).sum()
    }
}

/// The root-view image rectangle `[u0, u1] × [v0, v1]` covered by the part of a
/// triangle (clip-space vertices `c`) in front of the near plane, or `None` when no part
/// is; the clipping matches the rasterizer's, so the rectangle bounds what it covers
/// (`gpu:asm`'s culling lists use it too).
pub fn clipped_uv_bounds(c: [Vec4; 3]) -> Option<[f32; 4]> {
    if !c.iter().all(|c| c.is_finite()) {
        return None;
    }
    let mut pts = [Vec4::ZERO; 4];
    let mut n = 0;
    for i in 0..3 {
        let (a, b) = (c[i], c[(i + 1) % 3]);
        if a.z >= 0.0 {
            pts[n] = a;
            n += 1;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            // Computed from the inside vertex, as the rasterizer does.
            let (i, o) = if a.z >= 0.0 { (a, b) } else { (b, a) };
            pts[n] = i + (o - i) * (i.z / (i.z - o.z));
            n += 1;
        }
    }
    let mut r = [
        f32::INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NEG_INFINITY,
    ];
    for p in &pts[..n] {
        if p.w <= 0.0 {
            // On the light's eye plane itself: unbounded.
            return Some([
                f32::NEG_INFINITY,
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::INFINITY,
            ]);
        }
        let (u, v) = ndc_to_uv(*p);
        r = [r[0].min(u), r[1].min(v), r[2].max(u), r[3].max(v)];
    }
    (n >= 3).then_some(r)
}

/// The root-view rectangle of scene triangle `t` in `face` (see [`clipped_uv_bounds`]).
#[inline]
fn triangle_uv_bounds(scene: &Scene, face: &Face, t: usize) -> Option<[f32; 4]> {
    let m = face.view.clip_from_world;
    clipped_uv_bounds(scene.triangle(t).map(|p| m * p.extend(1.0)))
}

/// Lists, per root cell of `face`, the triangles whose projection overlaps it.
fn bin_triangles(scene: &Scene, face: &Face) -> Vec<Vec<u32>> {
    let g = face.grid as usize;
    let margin = BIN_MARGIN;
    // Cell ranges per triangle, computed in parallel and filled in triangle order.
    let ranges: Vec<Option<[u32; 4]>> = (0..scene.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let [u0, v0, u1, v1] = triangle_uv_bounds(scene, face, i)?;
            if !(u1 >= -margin && v1 >= -margin && u0 <= 1.0 + margin && v0 <= 1.0 + margin) {
                return None;
            }
            let cell = |x: f32| ((x * g as f32).floor() as i64).clamp(0, g as i64 - 1) as u32;
            Some([
                cell(u0 - margin),
                cell(v0 - margin),
                cell(u1 + margin),
                cell(v1 + margin),
            ])
        })
        .collect();
    let mut bins = vec![Vec::new(); g * g];
    for (i, r) in ranges.into_iter().enumerate() {
        if let Some([x0, y0, x1, y1]) = r {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    bins[y as usize * g + x as usize].push(i as u32);
                }
            }
        }
    }
    for b in &mut bins {
        b.shrink_to_fit();
    }
    bins
}

/// The triangles to draw into a `res × res` tile over `square` of `face`: all of them for
/// a root, else those of the square's root cell whose projection overlaps the square.
pub(super) fn tile_triangles(scene: &Scene, face: &Face, square: Square, res: u32) -> Vec<u32> {
    let Square { u0, v0, size } = square;
    if size >= 1.0 {
        return (0..scene.len() as u32).collect();
    }
    // A non-root node lies inside one root cell.
    let g = face.grid as f64;
    let gx = (((u0 + 0.5 * size) * g).floor() as i64).clamp(0, face.grid as i64 - 1) as usize;
    let gy = (((v0 + 0.5 * size) * g).floor() as i64).clamp(0, face.grid as i64 - 1) as usize;
    // One texel of margin: the rasterizer samples texel centres, so a triangle whose
    // box ends outside the square by less than that cannot cover one, but rounding can.
    let margin = size / res as f64;
    let (lo_u, hi_u, lo_v, hi_v) = (
        u0 - margin,
        u0 + size + margin,
        v0 - margin,
        v0 + size + margin,
    );
    face.bins[gy * face.grid as usize + gx]
        .iter()
        .copied()
        .filter(|&t| {
            triangle_uv_bounds(scene, face, t as usize).is_some_and(|[u0, v0, u1, v1]| {
                u1 as f64 >= lo_u && u0 as f64 <= hi_u && v1 as f64 >= lo_v && v0 as f64 <= hi_v
            })
        })
        .collect()
}
