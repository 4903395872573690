//! Software rasterization in light space, the conservative rasterizer behind the silhouette
//! mask map, the pixel–texel pairs and the triangle–texel pairs of Pan et al. 2009 ("Fast,
//! Sub-pixel Antialiased Shadow Maps", Sections 3.2 and 3.3): small convex polygons
//! projected into a light view's texel grid and walked row by row, every texel whose
//! closed square they touch.

use crate::light::LightView;
use crate::math::{ndc_to_uv, Mat4, Vec3};

/// Conservative rasterization widens every primitive by this many texels so that
/// floating-point rounding never drops a texel the primitive touches.
pub(super) const RASTER_EPS: f32 = 2e-3;

/// Vertices a clipped polygon may hold: a quad clipped by the near plane and then by a texel
/// row's two edges has at most seven; the rest is margin.
const MAX_POLY: usize = 12;

/// A small convex polygon: light-texel `x`, `y` and a depth key `z` that is linear in
/// texel space (depth for orthographic views, 1/depth for perspective ones).
#[derive(Clone, Copy, Debug)]
pub(super) struct Poly {
    v: [Vec3; MAX_POLY],
    /// Vertices in use (0: empty).
    pub(super) n: usize,
}

impl Poly {
    const EMPTY: Poly = Poly {
        v: [Vec3::ZERO; MAX_POLY],
        n: 0,
    };

    #[inline]
    fn push(&mut self, p: Vec3) {
        if self.n < MAX_POLY {
            self.v[self.n] = p;
            self.n += 1;
        }
    }

    #[inline]
    fn verts(&self) -> &[Vec3] {
        &self.v[..self.n]
    }

    /// The part where `f ≥ 0` (Sutherland–Hodgman; a two-vertex polygon is a segment).
    #[inline]
    fn clip(&self, f: impl Fn(Vec3) -> f32) -> Poly {
        let mut out = Poly::EMPTY;
        for i in 0..self.n {
            let a = self.v[i];
            let b = self.v[(i + 1) % self.n];
            let (fa, fb) = (f(a), f(b));
            if fa >= 0.0 {
                out.push(a);
            }
            if (fa >= 0.0) != (fb >= 0.0) {
                out.push(a + (b - a) * (fa / (fa - fb)));
            }
        }
        out
    }

    /// Bounds `(min, max)` of the vertices.
    #[inline]
    pub(super) fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in self.verts() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        (lo, hi)
    }
}

/// Projects world polygons into one light view's texel grid.
pub(super) struct Projector {
    light_from_world: Mat4,
    clip_from_light: Mat4,
    ortho: bool,
    near: f32,
    res: f32,
}

impl Projector {
    /// The projector of `view` into a map of `res`² texels.
    pub(super) fn new(view: &LightView, res: u32) -> Self {
        Projector {
            light_from_world: view.light_from_world,
            clip_from_light: view.clip_from_light,
            ortho: view.orthographic,
            near: view.near,
            res: res as f32,
        }
    }

    /// The polygon (or segment) in texel space, clipped to the near plane of a perspective
    /// view. Empty when nothing is in front of the light.
    pub(super) fn project(&self, world: &[Vec3]) -> Poly {
        let mut p = Poly::EMPTY;
        for w in world {
            p.push(self.light_from_world.transform_point3(*w));
        }
        if !self.ortho {
            let near = self.near;
            p = p.clip(|q| -q.z - near);
        }
        let mut out = Poly::EMPTY;
        for q in p.verts() {
            let c = self.clip_from_light * q.extend(1.0);
            let depth = -q.z;
            let key = if self.ortho { depth } else { 1.0 / depth };
            let (u, v) = ndc_to_uv(c);
            let t = Vec3::new(u * self.res, v * self.res, key);
            if t.is_finite() {
                out.push(t);
            }
        }
        out
    }

    /// The depth range `(min, max)` of depth keys `k0 ≤ k1`.
    #[inline]
    pub(super) fn depth_span(&self, k0: f32, k1: f32) -> (f32, f32) {
        if self.ortho {
            (k0, k1)
        } else {
            (1.0 / k1, 1.0 / k0)
        }
    }
}

/// Calls `f(y, x0, x1, key_min, key_max)` for every texel row the polygon touches, with the
/// inclusive column span of the texels it touches in that row (conservative by
/// [`RASTER_EPS`]) and the range of its depth key over that row.
#[inline]
pub(super) fn row_spans(poly: &Poly, res: u32, mut f: impl FnMut(u32, u32, u32, f32, f32)) {
    if poly.n == 0 {
        return;
    }
    let (lo, hi) = poly.bounds();
    let r = res as f32;
    if !(lo.is_finite() && hi.is_finite())
        || hi.x < -RASTER_EPS
        || hi.y < -RASTER_EPS
        || lo.x > r + RASTER_EPS
        || lo.y > r + RASTER_EPS
    {
        return;
    }
    let cols = |x0: f32, x1: f32| -> Option<(u32, u32)> {
        let a = (x0 - RASTER_EPS).floor().max(0.0);
        let b = (x1 + RASTER_EPS).floor().min(r - 1.0);
        (a <= b).then_some((a as u32, b as u32))
    };
    let y0 = (lo.y - RASTER_EPS).floor().max(0.0) as u32;
    let y1 = (hi.y + RASTER_EPS).floor().min(r - 1.0) as u32;
    if y0 == y1 {
        if let Some((a, b)) = cols(lo.x, hi.x) {
            f(y0, a, b, lo.z, hi.z);
        }
        return;
    }
    for y in y0..=y1 {
        let top = y as f32 - RASTER_EPS;
        let bottom = y as f32 + 1.0 + RASTER_EPS;
        let band = poly.clip(|q| q.y - top).clip(|q| bottom - q.y);
        if band.n == 0 {
            continue;
        }
        let (blo, bhi) = band.bounds();
        if let Some((a, b)) = cols(blo.x, bhi.x) {
            f(y, a, b, blo.z, bhi.z);
        }
    }
}

/// Float bits that order like the (non-negative) float.
#[inline]
pub(super) fn depth_bits(d: f32) -> u32 {
    d.max(0.0).to_bits()
}
