//! The receivers of each light view and the map depths under their filter support, from
//! which [`super::depth_range::DepthRange::fitted`] takes its interval; a min-depth pyramid
//! bounds the nearest texel under a support in a few reads.

use super::footprint::light_footprint;
use super::lookup::{level_of_detail, Filter};
use super::settings::FilterSettings;
use super::texture::{fast_ceil, fast_floor};
use super::{light_view_index, PIXEL_CHUNK};
use crate::frame::Frame;
use crate::light::LightView;
use crate::raster::DepthBuffer;
use rayon::prelude::*;

/// Steepest receiver slope (tangent of its angle to the light's image plane) whose own
/// depth change across its filter support [`ReceiverDepths`] accounts for; a steeper
/// receiver always counts as one that may be shadowed (conservative: it only widens the
/// fitted interval).
pub const MAX_RECEIVER_SLOPE: f32 = 8.0;

/// The coarsest mip level whose spill [`ReceiverDepths::of_frame`] reckons with: the spill
/// of level `l` is `2 << l` level-0 texels, computed in a `u32`, and `2 << 30` (2³¹) is the
/// largest such value that fits. A level this coarse already spans any map (whose side is at
/// most [`crate::raster::MAX_RASTER_SIDE`], 2¹⁵), so clamping there never narrows the support.
const MAX_SUPPORT_LEVEL: f32 = 30.0;

/// A min-depth pyramid of a depth map: level `l` texel `(i, j)` is the nearest depth of the
/// level-0 texels `[i·2^l, (i+1)·2^l) × [j·2^l, (j+1)·2^l)` (`+inf` where empty), so the
/// nearest depth of any texel rectangle is bounded from below by at most 2×2 reads. Level 0
/// is the map itself, borrowed.
#[derive(Clone, Debug)]
pub struct MinPyramid<'a> {
    /// `(width, height, depths)` of each level, level 0 (the map's depths) first.
    pub levels: Vec<(u32, u32, std::borrow::Cow<'a, [f32]>)>,
}

impl<'a> MinPyramid<'a> {
    /// The pyramid of `map`, down to 1×1 (each level `⌈side / 2⌉`).
    pub fn build(map: &'a DepthBuffer) -> Self {
        let mut levels = vec![(
            map.width,
            map.height,
            std::borrow::Cow::Borrowed(&map.depth[..]),
        )];
        loop {
            let (w, h, prev) = levels.last().expect("level 0 exists");
            let (w, h) = (*w as usize, *h as usize);
            if w <= 1 && h <= 1 {
                break;
            }
            let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
            let mut next = vec![f32::INFINITY; nw * nh];
            if nw > 0 {
                next.par_chunks_mut(nw).enumerate().for_each(|(y, row)| {
                    let r0 = &prev[2 * y * w..(2 * y + 1) * w];
                    // The last row of an odd height has no partner: it pairs with itself.
                    let r1 = if 2 * y + 1 < h {
                        &prev[(2 * y + 1) * w..(2 * y + 2) * w]
                    } else {
                        r0
                    };
                    // Pairs of columns (min is exact in any order; the final `min` with +inf
                    // turns an all-NaN block into +inf), then an odd last column.
                    for ((o, a), b) in row
                        .iter_mut()
                        .zip(r0.chunks_exact(2))
                        .zip(r1.chunks_exact(2))
                    {
                        *o = a[0].min(a[1]).min(b[0].min(b[1])).min(f32::INFINITY);
                    }
                    if w & 1 == 1 {
                        row[nw - 1] = r0[w - 1].min(r1[w - 1]).min(f32::INFINITY);
                    }
                });
            }
            levels.push((nw as u32, nh as u32, std::borrow::Cow::Owned(next)));
        }
        MinPyramid { levels }
    }

    /// The nearest depth of a block of texels that contains the texel rectangle `[x0, x1] ×
    /// [y0, y1]` (inclusive, inside level 0): at most 2×2 texels of the finest level whose
    /// texels cover it so. Returns the depth and the block read, as level-0 texel bounds
    /// `(x_begin, x_end, y_begin, y_end)` (end exclusive, clamped to the map).
    pub fn min_in(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> (f32, [u32; 4]) {
        // No level finer than ⌊log2(extent)⌋ holds the rectangle in 2 texels a side, and the
        // test below only turns true once: start there.
        let extent = (x1 - x0).max(y1 - y0);
        let mut l = if extent > 1 {
            (31 - extent.leading_zeros() as usize).min(self.levels.len() - 1)
        } else {
            0
        };
        while l + 1 < self.levels.len() && ((x1 >> l) - (x0 >> l) > 1 || (y1 >> l) - (y0 >> l) > 1)
        {
            l += 1;
        }
        let (w, h, d) = &self.levels[l];
        let (w, h) = (*w as usize, *h as usize);
        let (xa, xb) = ((x0 >> l) as usize, ((x1 >> l) as usize).min(w - 1));
        let (ya, yb) = ((y0 >> l) as usize, ((y1 >> l) as usize).min(h - 1));
        let mut m = f32::INFINITY;
        for y in ya..=yb {
            for x in xa..=xb {
                m = m.min(d[y * w + x]);
            }
        }
        let (w0, h0) = (self.levels[0].0, self.levels[0].1);
        let block = [
            (xa as u32) << l,
            (((xb + 1) as u32) << l).min(w0),
            (ya as u32) << l,
            (((yb + 1) as u32) << l).min(h0),
        ];
        (m, block)
    }
}

/// The light depths that matter to the receivers of one light view, from which
/// [`DepthRange::fitted`](super::depth_range::DepthRange::fitted) takes its interval.
///
/// A receiver *may be shadowed* when some map texel under its filter support (the texels its
/// look-up can read: the footprint's parallelogram, the bilinear and mip-level spill of the
/// level of detail it uses, and `pad` texels more for the blur) is nearer than its own surface
/// there: nearer than its depth minus the depth change of its tangent plane across the
/// support and one texel. A receiver that cannot be shadowed is lit whatever the interval
/// (see [`DepthRange::fitted`](super::depth_range::DepthRange::fitted)), so the interval need only cover the others: on a wide
/// ground under a low sun this is the ground round the casters, not the whole visible ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReceiverDepths {
    /// Nearest texel under the support of any receiver.
    pub near: f32,
    /// Farthest receiver.
    pub far: f32,
    /// Nearest texel under the support of a receiver that may be shadowed.
    pub shadowable_near: f32,
    /// Farthest receiver that may be shadowed.
    pub shadowable_far: f32,
    /// Number of receivers.
    pub count: u64,
    /// Number of receivers that may be shadowed.
    pub shadowable: u64,
}

impl ReceiverDepths {
    const EMPTY: ReceiverDepths = ReceiverDepths {
        near: f32::INFINITY,
        far: f32::NEG_INFINITY,
        shadowable_near: f32::INFINITY,
        shadowable_far: f32::NEG_INFINITY,
        count: 0,
        shadowable: 0,
    };

    fn merge(self, o: Self) -> Self {
        ReceiverDepths {
            near: self.near.min(o.near),
            far: self.far.max(o.far),
            shadowable_near: self.shadowable_near.min(o.shadowable_near),
            shadowable_far: self.shadowable_far.max(o.shadowable_far),
            count: self.count + o.count,
            shadowable: self.shadowable + o.shadowable,
        }
    }

    /// The depths of each light view for the pixels of `frame` the light reaches (the point
    /// light's cube faces each get the pixels whose direction selects them), with `maps` the
    /// views' depth maps and `settings` the look-up filter whose support is checked. Minima
    /// and maxima are exact in any order, so the result does not depend on the thread count.
    pub fn of_frame(
        frame: &Frame,
        views: &[LightView],
        maps: &[DepthBuffer],
        settings: &FilterSettings,
    ) -> Vec<Self> {
        let n = views.len();
        let pyramids: Vec<MinPyramid<'_>> = maps.iter().map(MinPyramid::build).collect();
        let view = frame.view;
        let pad = settings.blur / 2 + 1;
        // One pixel's receiver depths into `acc`; pixels are visited in chunks so the many
        // pixels the light does not reach cost a test each, not a call each.
        let visit = |acc: &mut Vec<Self>, k: usize| {
            if !frame.receiver_lit(k) {
                return;
            }
            let p = view.position[k];
            let i = light_view_index(frame.light, p);
            let (Some(lv), Some(map), Some(pyr)) = (views.get(i), maps.get(i), pyramids.get(i))
            else {
                return;
            };
            if map.width == 0 || map.height == 0 {
                return;
            }
            let s = lv.project(p);
            if !(s.u.is_finite() && s.v.is_finite() && s.depth.is_finite()) {
                return;
            }
            let fp = light_footprint(lv, p, view.dpdx[k], view.dpdy[k]);
            let (w, h) = (map.width as f32, map.height as f32);
            let lod = level_of_detail(
                &fp,
                map.width.max(map.height),
                settings.filter,
                settings.max_aniso,
            );
            // Half-extents of the support in texels: the probes' parallelogram, the
            // bilinear taps of the coarser of the two levels blended (within two of
            // its texels, 2^⌈λ⌉ level-0 texels each), the blur.
            let level = if lod.lambda.is_finite() {
                fast_ceil(lod.lambda.clamp(0.0, MAX_SUPPORT_LEVEL)) as u32
            } else {
                0
            };
            let spill = (2u32 << level) as f32 + pad as f32;
            let (ex, ey) = if settings.filter == Filter::Anisotropic {
                (
                    0.5 * (fp.dx.x.abs() + fp.dy.x.abs()) * w,
                    0.5 * (fp.dx.y.abs() + fp.dy.y.abs()) * h,
                )
            } else {
                (0.0, 0.0)
            };
            let (hx, hy) = (ex + spill, ey + spill);
            let (cx, cy) = (s.u * w, s.v * h);
            let clampx = |t: f32| t.clamp(0.0, w - 1.0) as u32;
            let clampy = |t: f32| t.clamp(0.0, h - 1.0) as u32;
            let (zmin, b) = pyr.min_in(
                clampx(fast_floor(cx - hx)),
                clampx(fast_floor(cx + hx)),
                clampy(fast_floor(cy - hy)),
                clampy(fast_floor(cy + hy)),
            );
            // The receiver's own depth change across the block read (which holds the
            // support), from its tangent plane in light space, plus one texel.
            let bx = (cx - b[0] as f32).max(b[1] as f32 - cx).max(0.0);
            let by = (cy - b[2] as f32).max(b[3] as f32 - cy).max(0.0);
            let texel = lv.texel_size(map.width.max(map.height), s.depth);
            let nl = lv.light_from_world.transform_vector3(view.normal[k]);
            let slope = (nl.x.abs() * bx + nl.y.abs() * by) * texel;
            let own = if nl.z.abs() * MAX_RECEIVER_SLOPE >= nl.x.abs().max(nl.y.abs()) {
                slope / nl.z.abs() + texel
            } else {
                f32::NEG_INFINITY
            };
            let a = &mut acc[i];
            a.count += 1;
            a.far = a.far.max(s.depth);
            a.near = a.near.min(zmin.min(s.depth));
            if zmin < s.depth - own {
                a.shadowable += 1;
                a.shadowable_far = a.shadowable_far.max(s.depth);
                a.shadowable_near = a.shadowable_near.min(zmin);
            }
        };
        let len = view.position.len();
        (0..len.div_ceil(PIXEL_CHUNK))
            .into_par_iter()
            .fold(
                || vec![Self::EMPTY; n],
                |mut acc, c| {
                    for k in c * PIXEL_CHUNK..((c + 1) * PIXEL_CHUNK).min(len) {
                        visit(&mut acc, k);
                    }
                    acc
                },
            )
            .reduce(
                || vec![Self::EMPTY; n],
                |a, b| a.into_iter().zip(b).map(|(x, y)| x.merge(y)).collect(),
            )
    }
}
