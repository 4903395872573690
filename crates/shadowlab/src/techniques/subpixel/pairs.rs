//! Pixel–texel pairs and triangle–texel pairs of Pan et al. 2009 ("Fast, Sub-pixel
//! Antialiased Shadow Maps", Section 3.3): the silhouette pixels' facets rasterized
//! conservatively into the light view's texels (PT-pairs, kept per facet), then every
//! triangle rasterized the same way against the texels that hold pixels (TT-pairs, sorted
//! by texel), and the triangles that appear in a pair set up once as blockers.
//!
//! Facets that touch no silhouette texel after all leave here with the depth-map test. The
//! per-row spans of [`row_spans`] are the exact spans of the projected polygon, which is the
//! paper's separating-axis test done row by row.

use super::blockers::Blocker;
use super::facets::Facet;
use super::lookup_table::Mask;
use super::rasterization::{depth_bits, row_spans};
use super::FrameState;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Marks an empty slot.
const NONE: u32 = u32::MAX;
/// Triangles per parallel task of the triangle–texel rasterization.
const TRIANGLE_CHUNK: usize = 1024;

/// The pairs of one frame, as lists per facet and per texel slot. A global texel index is
/// `view · res² + y · res + x`.
pub(super) struct Pairs {
    /// The shadow term of every pixel so far: final outside the silhouette pixels.
    pub(super) value: Vec<f32>,
    /// The silhouette pixels' facets.
    pub(super) facets: Vec<Facet>,
    /// Facet `i` touches the global texels `pt_texels[pt_start[i]..pt_start[i + 1]]`.
    pub(super) pt_start: Vec<u32>,
    /// The PT-pairs' texels, facet by facet.
    pub(super) pt_texels: Vec<u32>,
    /// Per global texel, its slot: texels that hold pixels are numbered in texel order, the
    /// others are [`NONE`].
    pub(super) slot: Vec<u32>,
    /// Slot `s` holds the blockers `tt_blocker[tt_start[s]..tt_start[s + 1]]`.
    pub(super) tt_start: Vec<u32>,
    /// The TT-pairs' blockers (indices into `blockers`), slot by slot.
    pub(super) tt_blocker: Vec<u32>,
    /// Every triangle in a TT-pair, in triangle order (`None`: it casts no area).
    pub(super) blockers: Vec<Option<Blocker>>,
}

/// The PT-pairs, TT-pairs and blockers of the silhouette pixels' `facets`; `value` holds
/// the shadow term of the other pixels and gains the depth-map test of facets that touch
/// no silhouette texel.
pub(super) fn pairs<M: Mask>(st: &FrameState<'_, M>, value: Vec<f32>, facets: Vec<Facet>) -> Pairs {
    let mut value = value;
    let pt = pixel_texel_pairs(st, facets, &mut value);
    let tt = triangle_texel_pairs(st, &pt.slot, &pt.slot_depth);
    let (tt_start, tt_blocker, blockers) = blockers(st, &tt, pt.slot_depth.len());
    Pairs {
        value,
        facets: pt.facets,
        pt_start: pt.pt_start,
        pt_texels: pt.pt_texels,
        slot: pt.slot,
        tt_start,
        tt_blocker,
        blockers,
    }
}

/// The PT-pairs of the facets that touch a silhouette texel, and the texel slots.
struct PixelTexelPairs {
    facets: Vec<Facet>,
    pt_start: Vec<u32>,
    pt_texels: Vec<u32>,
    slot: Vec<u32>,
    /// Per slot, the largest light depth of the facets over it.
    slot_depth: Vec<f32>,
}

/// Pixel–texel pairs: every texel a facet touches, kept per facet, for facets that touch a
/// silhouette texel at all; the others take the depth-map test in `value`.
fn pixel_texel_pairs<M: Mask>(
    st: &FrameState<'_, M>,
    facets: Vec<Facet>,
    value: &mut [f32],
) -> PixelTexelPairs {
    let res = st.res;
    let r2 = res as usize * res as usize;
    let max_depth: Vec<AtomicU32> = (0..r2 * st.maps.views.len())
        .map(|_| AtomicU32::new(0))
        .collect();
    let pt: Vec<Vec<u32>> = facets
        .par_iter()
        .with_min_len(64)
        .map(|f| {
            let mut out = Vec::new();
            let mm = &st.masks[f.view as usize];
            let base = f.view as usize * r2;
            let mut touches = false;
            row_spans(&f.poly, res, |y, x0, x1, _, _| {
                for x in x0..=x1 {
                    touches |= mm.is_silhouette(x, y);
                    out.push((base + (y * res + x) as usize) as u32);
                }
            });
            if !touches {
                return Vec::new();
            }
            let dbits = depth_bits(f.depth_max);
            for &g in &out {
                max_depth[g as usize].fetch_max(dbits, Ordering::Relaxed);
            }
            out
        })
        .collect();
    // Compaction: facets that touch no silhouette texel take the depth-map test.
    let mut kept = Vec::with_capacity(facets.len());
    let mut pt_start = vec![0u32];
    let mut pt_texels = Vec::new();
    for (f, list) in facets.into_iter().zip(pt) {
        if list.is_empty() {
            value[f.k as usize] = st.depth_test(f.k as usize, f.view as usize);
        } else {
            pt_texels.extend_from_slice(&list);
            pt_start.push(pt_texels.len() as u32);
            kept.push(f);
        }
    }
    // Texels with pixels get slots, in texel order.
    let mut slot: Vec<u32> = max_depth.into_iter().map(AtomicU32::into_inner).collect();
    let mut slot_depth = Vec::new();
    for d in slot.iter_mut() {
        if *d == 0 {
            *d = NONE;
        } else {
            slot_depth.push(f32::from_bits(*d));
            *d = slot_depth.len() as u32 - 1;
        }
    }
    PixelTexelPairs {
        facets: kept,
        pt_start,
        pt_texels,
        slot,
        slot_depth,
    }
}

/// Triangle–texel pairs `slot << 32 | triangle` for the texels with slots, sorted by texel:
/// every triangle that touches the texel nearer the light than the farthest facet there.
fn triangle_texel_pairs<M: Mask>(
    st: &FrameState<'_, M>,
    slot: &[u32],
    slot_depth: &[f32],
) -> Vec<u64> {
    let scene = st.frame.scene;
    let ntri = scene.len();
    let res = st.res;
    let r2 = res as usize * res as usize;
    let mut tt: Vec<u64> = Vec::new();
    if slot_depth.is_empty() {
        return tt;
    }
    for (vi, proj) in st.projectors.iter().enumerate() {
        let base = vi * r2;
        let parts: Vec<Vec<u64>> = (0..ntri.div_ceil(TRIANGLE_CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut out = Vec::new();
                for i in c * TRIANGLE_CHUNK..((c + 1) * TRIANGLE_CHUNK).min(ntri) {
                    let poly = proj.project(&scene.triangle(i));
                    row_spans(&poly, res, |y, x0, x1, k0, k1| {
                        let dmin = proj.depth_span(k0, k1).0;
                        let row = base + (y * res) as usize;
                        for x in x0..=x1 {
                            let s = slot[row + x as usize];
                            if s != NONE && dmin < slot_depth[s as usize] {
                                out.push((s as u64) << 32 | i as u64);
                            }
                        }
                    });
                }
                out
            })
            .collect();
        tt.extend(parts.into_iter().flatten());
    }
    tt.par_sort_unstable();
    tt
}

/// The blockers: every triangle in a TT-pair `tt`, in triangle order, set up once; and the
/// pairs as per-slot lists of blocker indices `(tt_start, tt_blocker)` over `slots` slots.
fn blockers<M: Mask>(
    st: &FrameState<'_, M>,
    tt: &[u64],
    slots: usize,
) -> (Vec<u32>, Vec<u32>, Vec<Option<Blocker>>) {
    let scene = st.frame.scene;
    let mut used = vec![NONE; scene.len()];
    for &e in tt {
        used[(e & 0xffff_ffff) as usize] = 0;
    }
    let mut ids = Vec::new();
    for (i, u) in used.iter_mut().enumerate() {
        if *u == 0 {
            *u = ids.len() as u32;
            ids.push(i as u32);
        }
    }
    let blockers: Vec<Option<Blocker>> = ids
        .par_iter()
        .with_min_len(256)
        .map(|&i| Blocker::new(i, scene.triangle(i as usize), &st.toward, &st.rays))
        .collect();
    let mut tt_start = vec![0u32; slots + 1];
    for &e in tt {
        tt_start[(e >> 32) as usize + 1] += 1;
    }
    for s in 0..slots {
        tt_start[s + 1] += tt_start[s];
    }
    let tt_blocker: Vec<u32> = tt
        .iter()
        .map(|&e| used[(e & 0xffff_ffff) as usize])
        .collect();
    (tt_start, tt_blocker, blockers)
}
