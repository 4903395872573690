//! Facets of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps", Sections 3.1 and
//! 3.3, Figure 3(a)): each pixel approximated by the quad its footprint cuts out of the
//! tangent plane through its centre sample, projected into the light view; pixels whose
//! projected facet's bounding rectangle holds no silhouette texel (the removal of
//! non-silhouette pixels) take the depth-map test.
//!
//! Two passes: every pixel first checks a cheap box that provably holds its projected facet
//! ([`FrameState::facet_bound`]); only pixels that fail it build their exact facet and
//! bounding rectangle.

use super::lookup_table::Mask;
use super::rasterization::{Poly, RASTER_EPS};
use super::FrameState;
use crate::light::LightView;
use crate::math::{ndc_to_uv, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// A facet corner may lie at most this many pixel widths (at the pixel's depth, facing the
/// camera) from the centre sample; grazing pixels whose footprint is longer use a smaller
/// facet. Larger gives grazing pixels all their samples but many more texels to visit.
pub const MAX_FACET_STRETCH: f32 = 16.0;
/// How many times a grazing facet is halved before it falls back to the centre point.
pub const FACET_SHRINK_STEPS: u32 = 4;
/// [`FrameState::facet_bound`] gives up (the pixel builds its exact facet) when a
/// perspective division varies over the pixel by this fraction of its value or more: the
/// bound widens the linearized box by `1/(1 − r)`, which is finite only for `r < 1` and
/// beyond 2 (at ½) makes the box too loose to spare the exact facet.
const MAX_DIVISION_SPREAD: f32 = 0.5;

/// A silhouette pixel's facet and what its visibility evaluation needs.
pub(super) struct Facet {
    /// Pixel index.
    pub(super) k: u32,
    /// Pixel column and row (of its top-left corner).
    pub(super) x: f32,
    pub(super) y: f32,
    /// Light view the facet is handled in.
    pub(super) view: u32,
    /// Own triangle (never a blocker of its own facet).
    pub(super) own: u32,
    /// The centre sample's surface point.
    pub(super) p: Vec3,
    /// The surface normal there (the tangent plane's).
    pub(super) n: Vec3,
    /// The facet part of every half-plane (see the `ray_plane` module): `−n·d` for the
    /// pixel-corner ray and its per-pixel steps under a perspective camera, `n·(o − p)`
    /// and `n·` the origin's steps under an orthographic one.
    pub(super) an: f32,
    pub(super) bn: f32,
    pub(super) cn: f32,
    /// `−n·(p − eye)` under a perspective camera, `−n·f` under an orthographic one
    /// (positive: the facet faces the camera).
    pub(super) beta: f32,
    /// Samples inside the facet (all unless a grazing facet was shrunk).
    pub(super) valid: u128,
    /// Largest light depth over the facet.
    pub(super) depth_max: f32,
    /// The projected facet in texel space.
    pub(super) poly: Poly,
}

impl<M> FrameState<'_, M> {
    /// Half-extents `(ex, ey)` in texels of a box about the centre of pixel `k` (at column
    /// `x`, row `y`) in light view `lv`, where its centre projects to clip position `c`, that
    /// holds the pixel's whole projected facet; `None` when the pixel is too grazing (to the
    /// camera or the light) for the bound and needs the exact facet.
    ///
    /// The tangent-plane point under image offset `o` from the centre is
    /// `p + k(o)·(o.x·jx + o.y·jy)`, with `jx`, `jy` the derivatives at the centre and
    /// `k(o) = g(0)/g(o) ≤ 1/(1 − r)` where `g(o) = n·d(o)` is affine and
    /// `r = ½(|∂g/∂x| + |∂g/∂y|)/|g(0)|`; the light projection adds a factor `1/(1 − ρ)` of
    /// the same kind for its division by `w`. Both factors multiply the linearized box.
    #[inline]
    fn facet_bound(&self, k: usize, x: f32, y: f32, lv: &LightView, c: Vec4) -> Option<(f32, f32)> {
        let (p, n) = (self.frame.view.position[k], self.frame.view.normal[k]);
        let j = self.rays.tangent_jacobian(n, p, x + 0.5, y + 0.5)?;
        let (jx, jy, r) = (j.jx, j.jy, j.r);
        if r >= MAX_DIVISION_SPREAD {
            return None;
        }
        let f = 1.0 / (1.0 - r);
        let mx = lv.clip_from_world * jx.extend(0.0);
        let my = lv.clip_from_world * jy.extend(0.0);
        let rho = f * 0.5 * (mx.w.abs() + my.w.abs()) / c.w.abs();
        if rho.is_nan() || rho >= MAX_DIVISION_SPREAD {
            return None;
        }
        let scale = f / (1.0 - rho) * 0.5 * (0.5 * self.res as f32) / (c.w * c.w);
        let du = |m: Vec4| (m.x * c.w - c.x * m.w).abs();
        let dv = |m: Vec4| (m.y * c.w - c.y * m.w).abs();
        let ex = (du(mx) + du(my)) * scale;
        let ey = (dv(mx) + dv(my)) * scale;
        (ex.is_finite() && ey.is_finite()).then_some((ex, ey))
    }

    /// The depth-map test of the lit, covered pixel `k` (at column `x`, row `y`), or NaN when
    /// the bound of its projected facet holds a silhouette texel or there is no bound.
    #[inline]
    fn bounded_depth_test(&self, k: usize, x: f32, y: f32) -> f32 {
        let p = self.frame.view.position[k];
        let vi = self.maps.select(self.frame.light, p);
        let lv = &self.maps.views[vi];
        let c = lv.clip_from_world * p.extend(1.0);
        let (u, v) = ndc_to_uv(c);
        match self.facet_bound(k, x, y, lv, c) {
            Some((ex, ey))
                if self.masks[vi].count_around(
                    u * self.res as f32,
                    v * self.res as f32,
                    ex,
                    ey,
                ) == 0 =>
            {
                self.depth_lookup(k, vi, u, v, lv.depth(p))
            }
            _ => f32::NAN,
        }
    }

    /// The facet of candidate pixel `k`, or its depth-map test when the projected facet
    /// leaves the view or its bounding rectangle holds no silhouette texel.
    fn build_facet(&self, k: usize) -> Result<Facet, f32> {
        let (view, rays, w) = (self.frame.view, &self.rays, self.frame.view.width);
        let p = view.position[k];
        let vi = self.maps.select(self.frame.light, p);
        let (x, y) = ((k as u32 % w) as f32, (k as u32 / w) as f32);
        let n = view.normal[k];
        let cap = rays.pixel_widths(MAX_FACET_STRETCH, view.depth[k]);
        // The footprint on the tangent plane of a square of side `s` about the centre.
        let footprint = |s: f32| -> Option<[Vec3; 4]> {
            let mut c = [Vec3::ZERO; 4];
            for (i, (ox, oy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .into_iter()
                .enumerate()
            {
                let (o, d) = rays.ray(x + 0.5 + 0.5 * s * ox, y + 0.5 + 0.5 * s * oy);
                let nd = n.dot(d);
                if nd.is_nan() || nd >= 0.0 {
                    return None;
                }
                c[i] = o + d * (n.dot(p - o) / nd);
                let dist = (c[i] - p).length();
                if dist.is_nan() || dist > cap {
                    return None;
                }
            }
            Some(c)
        };
        let mut scale = 0.0;
        let mut corners = [p; 4];
        let mut s = 1.0;
        for _ in 0..=FACET_SHRINK_STEPS {
            if let Some(c) = footprint(s) {
                scale = s;
                corners = c;
                break;
            }
            s *= 0.5;
        }
        let proj = &self.projectors[vi];
        let poly = proj.project(&corners);
        if poly.n == 0 {
            return Err(self.depth_test(k, vi));
        }
        let (lo, hi) = poly.bounds();
        let rf = self.res as f32;
        let clampf = |v: f32| v.clamp(0.0, rf - 1.0) as u32;
        if hi.x < 0.0 || hi.y < 0.0 || lo.x >= rf || lo.y >= rf {
            return Err(self.depth_test(k, vi));
        }
        let count = self.masks[vi].count(
            clampf(lo.x - RASTER_EPS),
            clampf(lo.y - RASTER_EPS),
            clampf(hi.x + RASTER_EPS),
            clampf(hi.y + RASTER_EPS),
        );
        if count == 0 {
            return Err(self.depth_test(k, vi));
        }
        let mut valid = 0u128;
        for (i, s) in self.lut_cache.samples.iter().enumerate() {
            let o = (*s - Vec2::splat(0.5)).abs();
            if i == self.lut_cache.centre || (o.x <= 0.5 * scale && o.y <= 0.5 * scale) {
                valid |= 1 << i;
            }
        }
        let [an, bn, cn, beta] = rays.facet(n, p, x, y);
        Ok(Facet {
            k: k as u32,
            x,
            y,
            view: vi as u32,
            own: view.triangle[k],
            p,
            n,
            an,
            bn,
            cn,
            beta,
            valid,
            depth_max: proj.depth_span(lo.z, hi.z).1,
            poly,
        })
    }
}

/// First pass, every pixel (the paper's removal of non-silhouette pixels, on a bound of the
/// projected facet): uncovered pixels 1, pixels the light does not reach 0, the others the
/// depth-map test unless the bound holds a silhouette texel — those candidates are NaN.
pub(super) fn non_silhouette_pixels<M: Mask>(st: &FrameState<'_, M>) -> Vec<f32> {
    let view = st.frame.view;
    let w = view.width;
    let mut value = vec![1.0f32; (w * view.height) as usize];
    value
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let k = y * w as usize + x;
                *out = if !view.covered(k) {
                    1.0
                } else if !st.frame.receiver_lit(k) {
                    0.0
                } else {
                    st.bounded_depth_test(k, x as f32, y as f32)
                };
            }
        });
    value
}

/// Second pass, the candidates of the first (NaN in `value`): their exact facets (the
/// paper's bounding-rectangle test on the projected quad). Candidates whose facet turns out
/// to hold no silhouette texel get their depth-map test in `value` instead.
pub(super) fn silhouette_facets<M: Mask>(st: &FrameState<'_, M>, value: &mut [f32]) -> Vec<Facet> {
    let candidates: Vec<u32> = (0..value.len() as u32)
        .into_par_iter()
        .filter(|&k| value[k as usize].is_nan())
        .collect();
    let built: Vec<Result<Facet, f32>> = candidates
        .par_iter()
        .with_min_len(64)
        .map(|&k| st.build_facet(k as usize))
        .collect();
    let mut facets: Vec<Facet> = Vec::with_capacity(built.len());
    for (&k, b) in candidates.iter().zip(built) {
        match b {
            Ok(f) => facets.push(f),
            Err(v) => value[k as usize] = v,
        }
    }
    facets
}
