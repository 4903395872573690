//! The near plane of `psm` (Stamminger & Drettakis 2002, Section 6, "Implementation and
//! Results"): "reading back the depth buffer after each frame, searching the minimal depth
//! value, and adapting the near plane accordingly". Here the read-back is the camera pass:
//! the visible receivers the light can reach give the near plane, the far plane and the
//! box that bounds the body of Section 4.1.

use crate::frame::Frame;
use crate::math::Aabb;
use rayon::prelude::*;

/// The pushed near plane sits this fraction of the nearest visible depth in front of it
/// (and the far plane as much beyond the farthest), so receivers at exactly those depths
/// stay strictly inside. Larger values give away a little of the perspective gain.
pub const DEPTH_FIT_PAD: f64 = 1e-3;
/// The far plane lies at least this fraction of the near distance beyond the near plane,
/// so a view whose receivers all share one depth still has a depth range to divide by.
const MIN_DEPTH_RANGE: f64 = 1e-3;

/// The visible receivers the light can reach: the camera-pass read-back of Section 6.
pub(super) struct Receivers {
    /// Per pixel: covered and reachable by the light.
    pub(super) lit: Vec<bool>,
    /// Their bounds.
    pub(super) bounds: Aabb,
    /// Nearest and farthest view depth among them.
    pub(super) depth: (f32, f32),
}

impl Receivers {
    /// The receivers of `frame`; `None` when the light reaches none of them.
    pub(super) fn gather(frame: &Frame) -> Option<Receivers> {
        let view = frame.view;
        let n = view.triangle.len();
        const CHUNK: usize = 8192;
        let mut lit = vec![false; n];
        let parts: Vec<(Aabb, f32, f32)> = lit
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, out)| {
                let base = c * CHUNK;
                let pos = &view.position[base..base + out.len()];
                let depth = &view.depth[base..base + out.len()];
                let mut b = Aabb::EMPTY;
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for (i, l) in out.iter_mut().enumerate() {
                    *l = frame.receiver_lit(base + i);
                    if *l {
                        b.grow(pos[i]);
                        lo = lo.min(depth[i]);
                        hi = hi.max(depth[i]);
                    }
                }
                (b, lo, hi)
            })
            .collect();
        let mut bounds = Aabb::EMPTY;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (b, a, z) in parts {
            bounds = bounds.union(&b);
            lo = lo.min(a);
            hi = hi.max(z);
        }
        if bounds.is_empty() || lo.is_nan() || lo <= 0.0 {
            return None;
        }
        Some(Receivers {
            lit,
            bounds,
            depth: (lo, hi),
        })
    }

    /// The near plane pushed to the nearest receiver and the far plane pulled in to the
    /// farthest, as distances along the view axis.
    pub(super) fn near_far(&self) -> (f64, f64) {
        let near = self.depth.0 as f64 * (1.0 - DEPTH_FIT_PAD);
        let far = (self.depth.1 as f64 * (1.0 + DEPTH_FIT_PAD)).max(near * (1.0 + MIN_DEPTH_RANGE));
        (near, far)
    }
}
