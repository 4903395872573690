//! The light-space perspective warp of `lispsm` (Wimmer, Scherzer & Purgathofer, "Light
//! Space Perspective Shadow Maps", EGSR 2004, Sections 3–4).
//!
//! Light space: `z` along the light (the map's depth), `y` the view direction projected
//! onto the plane perpendicular to the light, `x` completing the frame. A perspective
//! frustum `P` looks along `+y` from an eye `n` before the body's near face (at the camera's
//! `x`); its post-perspective coordinates `X = (x − eₓ)/y′`, `Y = −1/y′` (`y′ = y − e_y`) are
//! fitted to the unit square. Light rays (lines along `z`) stay parallel in this space, so
//! the map is an orthographic view along them, and the stored depth can stay the linear
//! light depth (affine on every triangle, so perspective-correct interpolation is exact).
//!
//! `n` sets the warp's strength: the paper's `n_opt = (z_n + √(z_n·z_f)) / sin γ` with `z_n`
//! the nearest receiver's view depth, `z_f = z_n + d·sin γ`, `d` the body's depth along
//! `y` and γ the angle between the view and light directions. It spreads the aliasing
//! error evenly between near and far; `n → ∞` is a uniform map, `n → 0` the strongest warp.

use crate::math::{Mat4, Vec3};
use glam::{DMat4, DVec4};

/// The largest `n` used, as a multiple of the body's depth `d`: beyond it the warp's
/// texel density differs from a uniform map's by less than `d/n` (0.01%), and larger
/// values only cost f32 precision in the matrix.
pub const MAX_N_RATIO: f64 = 1e4;

/// `sin γ` below which the view looks along the light: the warp is the uniform map's
/// (Section 4.3: nothing can be gained there).
pub const MIN_SIN_GAMMA: f64 = 1e-3;

/// The paper's optimal `n` for a body of depth `d` along `y`, nearest view depth `z_n` and
/// `sin γ` (capped at [`MAX_N_RATIO`]`·d`).
pub fn n_opt(z_n: f64, d: f64, sin_gamma: f64) -> f64 {
    if sin_gamma < MIN_SIN_GAMMA {
        return MAX_N_RATIO * d;
    }
    let z_f = z_n + d * sin_gamma;
    ((z_n + (z_n * z_f).sqrt()) / sin_gamma).min(MAX_N_RATIO * d)
}

/// The extent of the receivers in light space: `x`, `y` and linear depth ranges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// `x` range.
    pub x: (f64, f64),
    /// `y` range (along the projected view direction).
    pub y: (f64, f64),
    /// Linear light depth range of everything that must be in the map (casters included).
    pub depth: (f64, f64),
}

/// A fitted warp: the eye of `P` and the post-perspective window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    /// Eye `x` of `P` (the camera's).
    pub ex: f64,
    /// Eye `y` of `P` (`n` before the body's near face).
    pub ey: f64,
    /// The `n` in effect.
    pub n: f64,
    /// Post-perspective `X` window.
    pub x_window: (f64, f64),
    /// Body `y` range.
    pub y: (f64, f64),
    /// Linear light depth range.
    pub depth: (f64, f64),
}

impl Warp {
    /// The warp for `n` with the camera at light-space `x = ex`: its `X` window holds every
    /// receiver whose light-space `(x, y)` is in `points` (`X` is projective, so the window
    /// of the points is the window of their convex hull).
    pub fn fit(ext: &Extent, ex: f64, n: f64, points: impl Iterator<Item = (f64, f64)>) -> Self {
        let ey = ext.y.0 - n;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (x, y) in points {
            let xx = (x - ex) / (y - ey);
            lo = lo.min(xx);
            hi = hi.max(xx);
        }
        // Also true when the points gave no window (empty, or NaN).
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            (lo, hi) = (lo.min(hi) - 1e-6, lo.max(hi) + 1e-6);
        }
        Warp {
            ex,
            ey,
            n,
            x_window: (lo, hi),
            y: ext.y,
            depth: ext.depth,
        }
    }

    /// Light space to clip space: `x, y` in `[−w, w]` over the window, `z` in `[0, w]` over
    /// the post-perspective depth range, `w = y′`.
    pub fn clip_from_light(&self) -> Mat4 {
        self.clip_from_light_f64().as_mat4()
    }

    /// [`Self::clip_from_light`] in f64.
    pub fn clip_from_light_f64(&self) -> DMat4 {
        let (x0, x1) = self.x_window;
        let ax = 2.0 / (x1 - x0);
        let bx = 2.0 * x0 / (x1 - x0) + 1.0;
        let n = self.n;
        let d = (self.y.1 - self.y.0).max(1e-12);
        // NDC.y = 2(y′ − n)/(n·y′·(Y₁ − Y₀)) − 1 with Y₁ − Y₀ = d/(n(n + d)), i.e.
        // k(y − y₀)/y′ − 1: written so, f32 rounding stays relative to w = y′.
        let k = 2.0 * (n + d) / d;
        // Post-perspective depth Z = depth/y′ over [depth₀/(n + d), depth₁/n].
        let z0 = self.depth.0 / (n + d);
        let z1 = self.depth.1 / n;
        let dz = (z1 - z0).max(1e-12);
        // Rows acting on (x, y, z, 1); the light's depth is −z.
        let rows = [
            [ax, -bx, 0.0, -ax * self.ex + bx * self.ey],
            [0.0, k - 1.0, 0.0, -k * self.y.0 + self.ey],
            [0.0, -z0 / dz, -1.0 / dz, z0 * self.ey / dz],
            [0.0, 1.0, 0.0, -self.ey],
        ];
        DMat4::from_cols_array_2d(&rows).transpose()
    }

    /// Map coordinates `(u, v)` in `[0, 1]²` of light-space `(x, y)`, in f64.
    pub fn map(&self, x: f64, y: f64) -> (f64, f64) {
        let c = self.clip_from_light_f64() * DVec4::new(x, y, 0.0, 1.0);
        (c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5)
    }

    /// World size of one texel of a `res`-texel map at light-space `y`, along `x` and `y`.
    pub fn texel_sizes(&self, y: f64, res: u32) -> (f64, f64) {
        let yp = (y - self.ey).max(1e-12);
        let (x0, x1) = self.x_window;
        let d = (self.y.1 - self.y.0).max(1e-12);
        // ∂X/∂x = 1/y′ over a window of x1 − x0; ∂NDC.y/∂y = k·n/y′² (from k(y′ − n)/y′).
        let k = 2.0 * (self.n + d) / d;
        let sx = (x1 - x0) * yp / res as f64;
        let sy = 2.0 * yp * yp / (k * self.n * res as f64);
        (sx, sy)
    }
}

/// The light-space frame of a directional light towards `to_light` for a camera looking
/// along `forward`: world to light space (x, y = projected view direction, z towards the
/// light), from an eye at `origin`. Also returns `sin γ`.
pub fn light_frame(to_light: Vec3, forward: Vec3, origin: Vec3) -> (Mat4, f64) {
    let l = to_light.normalize().as_dvec3();
    let v = forward.normalize().as_dvec3();
    let cos = v.dot(l).clamp(-1.0, 1.0);
    let sin = (1.0 - cos * cos).sqrt();
    let mut up = v - l * cos;
    if up.length() < MIN_SIN_GAMMA {
        up = crate::light::pick_up(to_light).as_dvec3();
        up = (up - l * up.dot(l)).normalize();
    } else {
        up = up.normalize();
    }
    let m = crate::math::look_at_rh(origin, origin - l.as_vec3(), up.as_vec3());
    (m, sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn extent() -> Extent {
        Extent {
            x: (-10.0, 10.0),
            y: (2.0, 60.0),
            depth: (1.0, 30.0),
        }
    }

    /// Ratio of the largest to the smallest texel along `y` over the body.
    fn non_uniformity(w: &Warp) -> f64 {
        let (_, near) = w.texel_sizes(w.y.0, 1024);
        let (_, far) = w.texel_sizes(w.y.1, 1024);
        far / near
    }

    #[test]
    fn lispsm_tends_to_a_uniform_map_as_n_grows() {
        let ext = extent();
        let corners = [(-10.0, 2.0), (10.0, 2.0), (-10.0, 60.0), (10.0, 60.0)];
        let d = ext.y.1 - ext.y.0;
        let mut last = f64::INFINITY;
        for n in [1.0, 10.0, 100.0, 1e3, 1e4].map(|f| f * d) {
            let w = Warp::fit(&ext, 0.0, n, corners.into_iter());
            let r = non_uniformity(&w);
            assert!(r < last, "n {n}: ratio {r} after {last}");
            last = r;
            // The map coordinates approach the uniform map's affine ones.
            let (_, v_mid) = w.map(0.0, 0.5 * (ext.y.0 + ext.y.1));
            let uniform_v = 0.5;
            if n >= 1e3 * d {
                assert!((v_mid - uniform_v).abs() < 1e-3, "n {n}: v {v_mid}");
            }
        }
        assert!(
            last - 1.0 < 1e-3,
            "at n = 10⁴·d the texels still differ by {last}"
        );
        // At n_opt the warp is far from uniform: near texels are finer.
        let w = Warp::fit(&ext, 0.0, n_opt(1.0, d, 1.0), corners.into_iter());
        assert!(non_uniformity(&w) > 5.0);
    }

    #[test]
    fn n_opt_matches_the_paper_at_ninety_degrees() {
        // γ = 90°: n_opt = z_n + √(z_n z_f) with z_f = z_n + d.
        let (zn, d) = (1.0f64, 99.0f64);
        assert!((n_opt(zn, d, 1.0) - (1.0 + 100f64.sqrt())).abs() < 1e-9);
        // Smaller γ: a larger n, up to the uniform map along the view direction.
        assert!(n_opt(zn, d, 0.5) > n_opt(zn, d, 1.0));
        assert_eq!(n_opt(zn, d, 0.0), MAX_N_RATIO * d);
    }

    #[test]
    fn the_window_holds_the_receivers() {
        let ext = extent();
        let pts = [
            (-10.0, 2.0),
            (10.0, 2.0),
            (-10.0, 60.0),
            (10.0, 60.0),
            (3.0, 20.0),
        ];
        let w = Warp::fit(&ext, 1.5, n_opt(2.0, 58.0, 0.8), pts.into_iter());
        for (x, y) in pts {
            let (u, v) = w.map(x, y);
            assert!(
                (-1e-9..=1.0 + 1e-9).contains(&u) && (-1e-9..=1.0 + 1e-9).contains(&v),
                "{u} {v}"
            );
        }
    }
}
