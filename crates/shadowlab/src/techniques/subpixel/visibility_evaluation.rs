//! Visibility evaluation of Pan et al. 2009 ("Fast, Sub-pixel Antialiased Shadow Maps",
//! Section 3.4, Figures 6 and 7): for each silhouette pixel, each blocker of its texels is
//! tested once; the blocker's planes restrict, on the facet's tangent plane, to the occluded
//! area, which maps to half-planes on the screen whose bitmasks come from the look-up
//! table. Their AND is ORed into the pixel's occlusion mask; the validity mask drops samples
//! beyond the line where a triangle that cuts the facet rises above it. The occlusion ratio
//! is `popcount(occlusion & validity) / popcount(validity)`.
//!
//! An alpha-masked blocker's half-planes bound its whole triangle; each sample they cover
//! is then tested exactly where its shadow ray meets the triangle's plane, and dropped
//! where the texture cuts the triangle out (the reference's test at that point).

use super::blockers::Blocker;
use super::facets::Facet;
use super::lookup_table::Mask;
use super::pairs::Pairs;
use super::FrameState;
use crate::math::{intersect_plane, ndc_to_uv, Mat4, Vec2, Vec3};
use crate::scene::Scene;
use crate::view::ViewSamples;
use rayon::prelude::*;

/// Triangle vertices within this fraction of their distance from the pixel's surface point
/// count as lying on its tangent plane. Larger ignores real blockers at extreme grazing
/// light; smaller lets floating-point noise turn coplanar neighbours (a tessellated plane)
/// into triangles that cut the facet and invalidate samples.
pub const COPLANAR_TOLERANCE: f32 = 1e-5;

/// Occlusion and validity of every silhouette pixel of `pairs`, facet by facet: each facet
/// against the union of its texels' blockers, deduplicated.
pub(super) fn evaluate_silhouette_pixels<M: Mask>(
    st: &FrameState<'_, M>,
    pairs: &Pairs,
) -> Vec<Evaluated> {
    let screen = ScreenMap::new(st.frame.view);
    let p = pairs;
    p.facets
        .par_iter()
        .enumerate()
        .with_min_len(16)
        .map_init(Vec::new, |cand: &mut Vec<u32>, (fi, f)| {
            cand.clear();
            for &g in &p.pt_texels[p.pt_start[fi] as usize..p.pt_start[fi + 1] as usize] {
                let s = p.slot[g as usize] as usize;
                cand.extend_from_slice(
                    &p.tt_blocker[p.tt_start[s] as usize..p.tt_start[s + 1] as usize],
                );
            }
            cand.sort_unstable();
            cand.dedup();
            evaluate(f, cand, &p.blockers, st, &screen)
        })
        .collect()
}

/// Sums of the silhouette pixels' evaluations, for the counters.
#[derive(Default)]
pub(super) struct Totals {
    /// Triangle–pixel pairs evaluated.
    pub(super) evaluations: u64,
    /// Valid samples over every silhouette pixel.
    pub(super) valid: u64,
    /// Silhouette pixels partly in shadow.
    pub(super) boundary: u64,
    /// Valid samples over those.
    pub(super) boundary_valid: u64,
}

/// Writes each facet's shadow term into `value` and sums the evaluations.
pub(super) fn combine(facets: &[Facet], results: &[Evaluated], value: &mut [f32]) -> Totals {
    let mut t = Totals::default();
    for (f, e) in facets.iter().zip(results) {
        value[f.k as usize] = e.lit;
        t.evaluations += e.evaluations as u64;
        t.valid += e.valid as u64;
        if e.boundary {
            t.boundary += 1;
            t.boundary_valid += e.valid as u64;
        }
    }
    t
}

/// The clip-space-to-pixel mapping of the camera, for the validity test's segments.
struct ScreenMap {
    clip_from_world: Mat4,
    w: f32,
    h: f32,
}

impl ScreenMap {
    fn new(view: &ViewSamples) -> Self {
        ScreenMap {
            clip_from_world: view.camera.clip_from_world(),
            w: view.width as f32,
            h: view.height as f32,
        }
    }

    /// The image position of `p`, `None` behind the camera.
    #[inline]
    fn pixel(&self, p: Vec3) -> Option<Vec2> {
        let c = self.clip_from_world * p.extend(1.0);
        (c.w > 0.0).then(|| {
            let (u, v) = ndc_to_uv(c);
            Vec2::new(u * self.w, v * self.h)
        })
    }
}

/// Whether the segment `a–b` meets the square `[x, x+1] × [y, y+1]` (Liang–Barsky).
fn segment_meets_pixel(a: Vec2, b: Vec2, x: f32, y: f32) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d.x, a.x - x),
        (d.x, x + 1.0 - a.x),
        (-d.y, a.y - y),
        (d.y, y + 1.0 - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// What one silhouette pixel's evaluation produced.
#[derive(Clone, Copy)]
pub(super) struct Evaluated {
    /// The shadow term: the lit share of the valid samples.
    lit: f32,
    /// Blockers evaluated.
    evaluations: u32,
    /// Valid samples.
    valid: u32,
    /// Whether the pixel is partly in shadow.
    boundary: bool,
}

/// Occlusion and validity of one facet against its candidate blockers.
fn evaluate<M: Mask>(
    f: &Facet,
    blockers: &[u32],
    all: &[Option<Blocker>],
    st: &FrameState<'_, M>,
    screen: &ScreenMap,
) -> Evaluated {
    let (lut, centre) = (&st.lut, st.centre);
    let scene = st.frame.scene;
    let mut occ = M::ZERO;
    let mut valid = M::from_u128(f.valid) & lut.all;
    let half = |pl: &[f32; 4]| {
        let a = pl[0] * f.an + f.beta * pl[1];
        let b = pl[0] * f.bn + f.beta * pl[2];
        let c = pl[0] * f.cn + f.beta * (pl[3] + f.x * pl[1] + f.y * pl[2]);
        lut.half_plane(a, b, c)
    };
    let mut evaluations = 0;
    for &bi in blockers {
        let Some(bl) = &all[bi as usize] else {
            continue;
        };
        if bl.tri == f.own {
            continue;
        }
        evaluations += 1;
        // Signed heights of the vertices above the tangent plane (the light's side).
        let rel = bl.v.map(|v| v - f.p);
        let d = rel.map(|r| f.n.dot(r));
        let scale = rel.iter().fold(0.0f32, |s, r| s.max(r.abs().max_element()));
        let eps = COPLANAR_TOLERANCE * scale;
        let dmax = d[0].max(d[1]).max(d[2]);
        if dmax <= eps {
            // On or below the facet's plane: the segment from any facet point to the light
            // stays above it.
            continue;
        }
        let mut behind: Option<M> = None;
        if d[0].min(d[1]).min(d[2]) <= eps {
            // The triangle cuts (or touches along an edge) the facet's plane: samples past
            // the cut line, where it rises above the facet, are invalid (Section 3.4).
            let mut pts = [Vec3::ZERO; 3];
            let mut np = 0;
            for i in 0..3 {
                let j = (i + 1) % 3;
                if d[i].abs() <= eps {
                    pts[np.min(2)] = bl.v[i];
                    np += 1;
                } else if d[j].abs() > eps && (d[i] > 0.0) != (d[j] > 0.0) {
                    pts[np.min(2)] = bl.v[i] + (bl.v[j] - bl.v[i]) * (d[i] / (d[i] - d[j]));
                    np += 1;
                }
            }
            if np >= 2 {
                if let (Some(a), Some(b)) = (screen.pixel(pts[0]), screen.pixel(pts[1])) {
                    if segment_meets_pixel(a, b, f.x, f.y) {
                        let m = half(&bl.planes[3]);
                        behind = Some(m);
                        // The centre sample is valid by definition; the other side of the
                        // line holds the invalid samples, unless the triangle lies behind the
                        // facet from the light there (a convex crease).
                        if m & centre == M::ZERO {
                            valid &= !m;
                        }
                    }
                }
            }
        }
        let mut m = lut.all;
        for pl in &bl.planes[..3] {
            m &= half(pl);
            if m == M::ZERO {
                break;
            }
        }
        if m != M::ZERO {
            m &= behind.unwrap_or_else(|| half(&bl.planes[3]));
        }
        if m != M::ZERO && scene.material_of(bl.tri as usize).alpha_mask.is_some() {
            m = kept_by_mask(m, f, bl, st, scene);
        }
        occ |= m;
    }
    let nv = valid.ones();
    let shadowed = (occ & valid).ones();
    Evaluated {
        lit: 1.0 - shadowed as f32 / nv as f32,
        evaluations,
        valid: nv,
        boundary: shadowed > 0 && shadowed < nv,
    }
}

/// The samples of `m` whose shadow rays meet the alpha-masked blocker `bl` where its
/// texture keeps it: each sample's point on the facet's tangent plane, its shadow ray, and
/// [`Scene::cut_out`] at the barycentrics where that ray meets the triangle's plane.
fn kept_by_mask<M: Mask>(
    m: M,
    f: &Facet,
    bl: &Blocker,
    st: &FrameState<'_, M>,
    scene: &Scene,
) -> M {
    let mut kept = m;
    for (i, s) in st.lut.samples().iter().enumerate() {
        let bit = M::from_u128(1u128 << i);
        if m & bit == M::ZERO {
            continue;
        }
        let (o, d) = st.rays.ray(f.x + s.x, f.y + s.y);
        let t = f.n.dot(f.p - o) / f.n.dot(d);
        let x = o + d * t;
        let (dir, _) = st.frame.light.shadow_ray(x);
        let cut = match intersect_plane(x, dir, bl.v) {
            Some(h) => scene.cut_out(bl.tri as usize, h.b),
            None => true,
        };
        if cut || !t.is_finite() {
            kept &= !bit;
        }
    }
    kept
}
