//! The camera's primary rays as affine functions of image position, in the form the facets
//! (Pan et al. 2009, Section 3.3) and the blockers' screen half-planes (Section 3.4) need.
//!
//! A perspective camera's rays share the eye and their directions are affine in the image
//! position: `d(x, y) = d0 + dx·x + dy·y`. An orthographic camera's rays share the direction
//! `f` and their origins are affine: `o(x, y) = o0 + ox·x + oy·y`. Either way a ray meets the
//! tangent plane `n·(X − p) = 0` at `t = n·(p − o)/n·d`, and a point `X` of the ray is on
//! the positive side of a blocker's plane `m·(X − q) ≥ 0` exactly where
//!
//! `E(x, y) = −(n·d)·m·(o − q) − (m·d)·n·(p − o) ≥ 0`
//!
//! (multiplied by `−n·d > 0`: the facet faces the camera). One factor of each product is
//! constant over the image and the other affine, so `E` is affine in `(x, y)`: a half-plane.
//! Both cases are written as `E = P0·F_s + F_β·P_s` for the step `s` (x, y, and the constant
//! at the pixel's corner), with a plane part `P` per blocker plane
//! ([`RayPlane::plane`]) and a facet part `F` per pixel ([`RayPlane::facet`]):
//! - perspective: `P = (m·(eye − q), m·dx, m·dy, m·d0)`, `F = (−n·dx, −n·dy, −n·d(x, y),
//!   −n·(p − eye))`;
//! - orthographic: `P = (m·f, m·ox, m·oy, m·(o0 − q))`, `F = (n·ox, n·oy, n·(o(x, y) − p),
//!   −n·f)`.
//!
//! With an orthographic view the tangent-plane point is affine in the image position (no
//! division), so the facet bound's perspective-division spread is zero.

use crate::camera::{Camera, Projection};
use crate::math::Vec3;

/// The camera's primary rays: origin `o0 + ox·x + oy·y`, direction `d0 + dx·x + dy·y`
/// (pixel centres at +0.5); `ox = oy = 0` for a perspective camera, `dx = dy = 0` for an
/// orthographic one.
pub(super) struct RayPlane {
    /// The origin of the ray through the image corner `(0, 0)`.
    o0: Vec3,
    /// The change of origin per pixel to the right and down.
    ox: Vec3,
    oy: Vec3,
    /// The direction through the image corner `(0, 0)`.
    d0: Vec3,
    /// The change of direction per pixel to the right and down.
    dx: Vec3,
    dy: Vec3,
    /// Whether the rays are parallel.
    parallel: bool,
}

/// The derivatives of the tangent-plane point with respect to the image position, and the
/// relative spread `r` of the perspective division over the pixel (0 for parallel rays).
pub(super) struct TangentJacobian {
    pub(super) jx: Vec3,
    pub(super) jy: Vec3,
    pub(super) r: f32,
}

impl RayPlane {
    /// The ray plane of camera `c`.
    pub(super) fn new(c: &Camera) -> Self {
        let (r, u, f) = c.basis();
        let (w, h) = (c.width as f32, c.height as f32);
        match c.projection {
            Projection::Perspective => {
                let th = (c.fov_y_deg.to_radians() * 0.5).tan();
                let asp = c.aspect();
                RayPlane {
                    o0: c.eye,
                    ox: Vec3::ZERO,
                    oy: Vec3::ZERO,
                    d0: f - r * (th * asp) + u * th,
                    dx: r * (2.0 * th * asp / w),
                    dy: -u * (2.0 * th / h),
                    parallel: false,
                }
            }
            Projection::Orthographic { xmag, ymag } => RayPlane {
                o0: c.eye - r * xmag + u * ymag,
                ox: r * (2.0 * xmag / w),
                oy: -u * (2.0 * ymag / h),
                d0: f,
                dx: Vec3::ZERO,
                dy: Vec3::ZERO,
                parallel: true,
            },
        }
    }

    /// The origin and direction of the ray through image position `(x, y)`.
    #[inline]
    pub(super) fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        if self.parallel {
            (self.o0 + self.ox * x + self.oy * y, self.d0)
        } else {
            (self.o0, self.d0 + self.dx * x + self.dy * y)
        }
    }

    /// `stretch` pixel widths across the view at view depth `depth`.
    pub(super) fn pixel_widths(&self, stretch: f32, depth: f32) -> f32 {
        if self.parallel {
            stretch * self.ox.length()
        } else {
            stretch * self.dx.length() * depth.max(0.0)
        }
    }

    /// The plane part `P` of the blocker plane `m·(X − q) ≥ 0` (see the module doc).
    #[inline]
    pub(super) fn plane(&self, m: Vec3, q: Vec3) -> [f32; 4] {
        if self.parallel {
            [
                m.dot(self.d0),
                m.dot(self.ox),
                m.dot(self.oy),
                m.dot(self.o0 - q),
            ]
        } else {
            [
                m.dot(self.o0 - q),
                m.dot(self.dx),
                m.dot(self.dy),
                m.dot(self.d0),
            ]
        }
    }

    /// The facet part `F = (an, bn, cn, β)` of the pixel whose top-left corner is at
    /// `(x, y)`, with tangent plane through `p` of normal `n` (see the module doc).
    #[inline]
    pub(super) fn facet(&self, n: Vec3, p: Vec3, x: f32, y: f32) -> [f32; 4] {
        let (o, d) = self.ray(x, y);
        if self.parallel {
            [n.dot(self.ox), n.dot(self.oy), n.dot(o - p), -n.dot(d)]
        } else {
            [-n.dot(self.dx), -n.dot(self.dy), -n.dot(d), -n.dot(p - o)]
        }
    }

    /// The derivatives of the point where the ray through `(x, y)` meets the tangent plane
    /// through `p` of normal `n`, with the spread of the perspective division over the
    /// pixel; `None` where that spread is not a number (the ray runs along the plane).
    #[inline]
    pub(super) fn tangent_jacobian(
        &self,
        n: Vec3,
        p: Vec3,
        x: f32,
        y: f32,
    ) -> Option<TangentJacobian> {
        let (o, dc) = self.ray(x, y);
        let gc = n.dot(dc);
        if self.parallel {
            // q = o + f·n·(p − o)/n·f: affine in the image position.
            let jx = self.ox - dc * (n.dot(self.ox) / gc);
            let jy = self.oy - dc * (n.dot(self.oy) / gc);
            return (jx.is_finite() && jy.is_finite()).then_some(TangentJacobian {
                jx,
                jy,
                r: 0.0,
            });
        }
        let (gx, gy) = (n.dot(self.dx), n.dot(self.dy));
        let r = 0.5 * (gx.abs() + gy.abs()) / gc.abs();
        if r.is_nan() {
            return None;
        }
        let s = n.dot(p - o) / (gc * gc);
        let jx = (self.dx * gc - dc * gx) * s;
        let jy = (self.dy * gc - dc * gy) * s;
        Some(TangentJacobian { jx, jy, r })
    }
}
