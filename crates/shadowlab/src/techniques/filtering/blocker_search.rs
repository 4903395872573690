//! The blocker search and penumbra estimate of percentage-closer soft shadows (Fernando
//! 2005), shared by `pcss` and the soft variants of the filtered maps (`vsm-soft`,
//! `evsm-soft`, `msm-soft`, `csm-soft`), which size their filter per pixel from it as the
//! convolution shadow map paper's conclusion proposes.
//!
//! 1. *Blocker search*: the map region that can hold casters between a receiver and the
//!    light — the light's cone from the receiver, cut at the nearest depth the map holds
//!    (the paper cuts it at the near plane, which in a scene whose near plane hugs the
//!    light makes the region the whole map), at most [`MAX_SEARCH_FRACTION`] of the map
//!    wide — is read on a regular grid of taps; the texels closer to the light than the
//!    receiver give the mean blocker depth (none: the receiver is fully lit).
//! 2. *Penumbra estimation*: by similar triangles, the penumbra width at the receiver is
//!    `(d_receiver − d_blocker) · w_light / d_blocker` (a distant light of angular width θ:
//!    `(d_receiver − d_blocker) · θ`).

use super::footprint::Footprint;
use super::receivers::MinPyramid;
use super::settings::FilterSettings;
use crate::frame::Frame;
use crate::light::{LightSample, LightView};
use crate::math::vec2;
use crate::raster::DepthBuffer;
use crate::techniques::shadow_map::{receiver_bias, DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS};

/// Blocker-search taps of the soft filtered maps (an 8 × 8 grid, as `pcss`'s default).
pub const SOFT_BLOCKER_SAMPLES: u32 = 64;

/// The largest search or filter radius, as a fraction of the map side: beyond this a
/// region spans much of the light's view and its average says little.
pub const MAX_SEARCH_FRACTION: f32 = 0.125;

/// One light view's depth map, ready for blocker searches.
pub struct BlockerSearch<'a> {
    /// The view.
    pub view: &'a LightView,
    /// Its linear-depth map.
    pub map: &'a DepthBuffer,
    /// Its min-depth pyramid: no caster in a region is nearer than the region's minimum.
    pyramid: MinPyramid<'a>,
}

impl<'a> BlockerSearch<'a> {
    /// The search over `map`, the depth map of `view`.
    pub fn new(view: &'a LightView, map: &'a DepthBuffer) -> Self {
        BlockerSearch {
            view,
            map,
            pyramid: MinPyramid::build(map),
        }
    }

    /// Texels per world unit at linear depth `depth`.
    fn texels_per_unit(&self, depth: f32) -> f32 {
        1.0 / self.view.texel_size(self.map.width, depth)
    }

    /// The penumbra's half width in texels at the receiver projected to `s`, for a light
    /// `width` wide (see the module doc), searching on a `side²` grid for texels nearer
    /// than `depth` (the receiver's biased depth). `None` when no blocker is found: the
    /// receiver is fully lit.
    pub fn penumbra_radius(
        &self,
        s: &LightSample,
        depth: f32,
        width: f32,
        side: u32,
    ) -> Option<f32> {
        let res = self.map.width as f32;
        let max_radius = MAX_SEARCH_FRACTION * res;
        let (fx, fy) = (s.u * res, s.v * res);
        // The cone's radius at the nearest depth in a region bounds the radius of the
        // region blockers can shadow from; twice, each region inside the last.
        let mut search = max_radius;
        for _ in 0..2 {
            let z = self.nearest_in(fx, fy, search).min(s.depth);
            let cone = 0.5 * search_width(self.view.orthographic, width, s.depth, z);
            search = clamp_radius(cone * self.texels_per_unit(z), search);
        }
        let blocker = self.blockers(fx, fy, search, side, depth)?;
        let w = penumbra_width(self.view.orthographic, width, s.depth, blocker);
        Some(clamp_radius(
            0.5 * w * self.texels_per_unit(s.depth),
            max_radius,
        ))
    }

    /// A lower bound of the depths within `radius` texels of `(fx, fy)`.
    fn nearest_in(&self, fx: f32, fy: f32, radius: f32) -> f32 {
        let n = self.map.width as i64;
        let clamp = |v: f32| (v.floor() as i64).clamp(0, n - 1) as u32;
        let (x0, x1) = (clamp(fx - radius), clamp(fx + radius));
        let (y0, y1) = (clamp(fy - radius), clamp(fy + radius));
        self.pyramid.min_in(x0, x1, y0, y1).0
    }

    /// Mean depth of the texels nearer than `depth` on a `side²` grid over a square of
    /// `radius` texels about `(fx, fy)` (texel coordinates); `None` when there are none.
    fn blockers(&self, fx: f32, fy: f32, radius: f32, side: u32, depth: f32) -> Option<f32> {
        let n = self.map.width as i64;
        let (mut sum, mut count) = (0.0f64, 0u32);
        for j in 0..side {
            for i in 0..side {
                let x = ((fx + grid_offset(i, side) * radius).floor() as i64).clamp(0, n - 1);
                let y = ((fy + grid_offset(j, side) * radius).floor() as i64).clamp(0, n - 1);
                let d = self.map.depth[(y * n + x) as usize];
                if d < depth {
                    sum += d as f64;
                    count += 1;
                }
            }
        }
        (count > 0).then(|| (sum / count as f64) as f32)
    }
}

/// The blocker searches of a soft filtered map's views, and the light's width.
pub struct SoftSearch<'a> {
    faces: Vec<BlockerSearch<'a>>,
    width: f32,
}

impl<'a> SoftSearch<'a> {
    /// The searches over the kept depth maps of `views`, when the settings ask for soft
    /// filtering and the frame has an area light.
    pub fn new(
        frame: &Frame,
        settings: &FilterSettings,
        views: &'a [LightView],
        maps: &'a [DepthBuffer],
    ) -> Option<Self> {
        let width = frame.area?.equivalent_width();
        if !settings.soft || maps.len() != views.len() || width <= 0.0 {
            return None;
        }
        let faces = views
            .iter()
            .zip(maps)
            .map(|(v, m)| BlockerSearch::new(v, m))
            .collect();
        Some(SoftSearch { faces, width })
    }

    /// The isotropic footprint, in map coordinates, of the penumbra at pixel `k` of
    /// `frame`, projected to `s` in view `i`; `None` when no blocker is found (fully lit).
    pub fn footprint(
        &self,
        frame: &Frame,
        k: usize,
        i: usize,
        s: &LightSample,
    ) -> Option<Footprint> {
        let face = &self.faces[i];
        let p = frame.view.position[k];
        let l = frame.light.shadow_ray(p).0;
        let texel = face.view.texel_size(face.map.width, s.depth);
        let bias = receiver_bias(
            texel,
            frame.view.normal[k],
            l,
            DEFAULT_CONSTANT_BIAS,
            DEFAULT_SLOPE_BIAS,
        );
        let side = grid_side(SOFT_BLOCKER_SAMPLES);
        let radius = face.penumbra_radius(s, s.depth - bias, self.width, side)?;
        // The filter's side is the penumbra's width: twice the radius, in map coordinates.
        let w = 2.0 * radius / face.map.width as f32;
        Some(Footprint {
            dx: vec2(w, 0.0),
            dy: vec2(0.0, w),
        })
    }
}

/// The larger of two footprints (by their longer axis).
pub fn wider(a: Footprint, b: Footprint) -> Footprint {
    let len = |f: &Footprint| f.dx.length().max(f.dy.length());
    if len(&a) >= len(&b) {
        a
    } else {
        b
    }
}

/// A radius in texels kept in `[0.5, max]`; a radius that is not a number (a receiver at
/// a degenerate depth) is `max`.
fn clamp_radius(r: f32, max: f32) -> f32 {
    if r.is_nan() {
        max
    } else {
        r.clamp(0.5, max)
    }
}

/// The side of the square grid of at least `samples` taps.
pub fn grid_side(samples: u32) -> u32 {
    (samples as f32).sqrt().ceil().max(1.0) as u32
}

/// The `i`-th of `side` tap offsets across `[-1, 1]` (cell centres; 0 for one tap).
#[inline]
pub fn grid_offset(i: u32, side: u32) -> f32 {
    (2.0 * i as f32 + 1.0) / side as f32 - 1.0
}

/// The width at linear depth `z` of the cone from a receiver at depth `receiver` to a
/// light `width` wide (a distant light: of angular width `width`, a cylinder widening
/// with the gap as an orthographic view sees it): where blockers can be.
pub fn search_width(orthographic: bool, width: f32, receiver: f32, z: f32) -> f32 {
    let gap = (receiver - z).max(0.0);
    if orthographic {
        gap * width
    } else {
        width * gap / receiver.max(f32::MIN_POSITIVE)
    }
}

/// The penumbra width at a receiver at linear depth `receiver` behind a blocker at
/// `blocker` from a light `width` wide (Fernando's similar triangles).
pub fn penumbra_width(orthographic: bool, width: f32, receiver: f32, blocker: f32) -> f32 {
    let gap = (receiver - blocker).max(0.0);
    if orthographic {
        gap * width
    } else {
        gap * width / blocker.max(f32::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similar_triangles() {
        // A light 1 wide, a blocker halfway to the receiver: the penumbra is as wide as
        // the light.
        assert_eq!(penumbra_width(false, 1.0, 4.0, 2.0), 1.0);
        // At contact, none.
        assert_eq!(penumbra_width(false, 1.0, 4.0, 4.0), 0.0);
        // The search cone is the light's width at the light and nothing at the receiver.
        assert_eq!(search_width(false, 2.0, 4.0, 0.0), 2.0);
        assert_eq!(search_width(false, 2.0, 4.0, 4.0), 0.0);
    }
}
