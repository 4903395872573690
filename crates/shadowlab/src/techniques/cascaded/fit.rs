//! The light-space fit of one cascade of `cascaded`: an orthographic view along the light
//! that covers the camera frustum's slice between two view depths.
//!
//! Two fits, as engines offer them:
//! - tight: the light-space rectangle of the slice's eight corners, clipped to the scene's
//!   light-space rectangle (no texel outside the scene);
//! - stabilized (Valient, "Stable Rendering of Cascaded Shadow Maps", ShaderX⁶; the cure
//!   for shimmering): a square window as wide as the slice's bounding sphere — which does
//!   not depend on the camera's orientation — whose centre is snapped to whole texels of a
//!   light basis fixed in the world, so a translating camera moves the window by whole
//!   texels and every texel keeps rasterizing the same world area.
//!
//! The depth range of every cascade reaches from the scene's nearest point towards the
//! light to the slice's farthest point (clamped to the scene), so every caster between a
//! receiver of the slice and the light is inside.

use crate::camera::{Camera, Projection};
use crate::light::{pick_up, LightView};
use crate::math::{look_at_rh, orthographic_rh, Aabb, Mat4, Vec3};

/// Fraction of the depth span added at both ends of a cascade's depth range, so the
/// nearest caster and the farthest receiver are not on the clip planes.
pub const DEPTH_PAD: f32 = 1e-3;

/// The world-fixed light basis of a directional light: looks along `-to_light` from the
/// scene's centre. It does not depend on the camera, so snapped windows are stable.
pub fn light_basis(to_light: Vec3, scene: &Aabb) -> Mat4 {
    let dir = to_light.normalize();
    let c = scene.center();
    look_at_rh(c + dir * scene.diagonal().max(1e-6), c, pick_up(dir))
}

/// The eight world corners of the camera frustum between view depths `d0` and `d1` (along
/// the view axis): a box for an orthographic camera.
pub fn slice_corners(camera: &Camera, d0: f32, d1: f32) -> [Vec3; 8] {
    let (r, u, f) = camera.basis();
    let mut out = [Vec3::ZERO; 8];
    for (k, o) in out.iter_mut().enumerate() {
        let d = if k < 4 { d0 } else { d1 };
        let sx = if k & 1 == 0 { -1.0 } else { 1.0 };
        let sy = if k & 2 == 0 { -1.0 } else { 1.0 };
        *o = match camera.projection {
            Projection::Perspective => {
                let ty = (camera.fov_y_deg.to_radians() * 0.5).tan();
                let tx = ty * camera.aspect();
                camera.eye + f * d + r * (sx * tx * d) + u * (sy * ty * d)
            }
            Projection::Orthographic { xmag, ymag } => {
                camera.eye + f * d + r * (sx * xmag) + u * (sy * ymag)
            }
        };
    }
    out
}

/// The smallest sphere holding the camera slice between `d0` and `d1`: its centre's view
/// depth and radius. Only the depths and the field of view and aspect (the extent of an
/// orthographic camera) enter, so it is the same for every camera orientation.
pub fn slice_sphere(camera: &Camera, d0: f32, d1: f32) -> (f32, f32) {
    let (d0, d1) = (d0 as f64, d1 as f64);
    let (c, r) = match camera.projection {
        Projection::Perspective => {
            let ty = (camera.fov_y_deg.to_radians() as f64 * 0.5).tan();
            let tx = ty * camera.aspect() as f64;
            // k: corner distance from the axis per unit depth.
            let k2 = tx * tx + ty * ty;
            // The centre on the axis equidistant from the near and far corners, unless the
            // far face's circle already holds the near corners.
            let c = (0.5 * (d0 + d1) * (1.0 + k2)).min(d1);
            let r = ((c - d0).powi(2) + k2 * d0 * d0)
                .max((d1 - c).powi(2) + k2 * d1 * d1)
                .sqrt();
            (c, r)
        }
        Projection::Orthographic { xmag, ymag } => {
            // A box: the sphere about its centre through its corners.
            let (x, y) = (xmag as f64, ymag as f64);
            let half = 0.5 * (d1 - d0);
            (0.5 * (d0 + d1), (half * half + x * x + y * y).sqrt())
        }
    };
    if !(r > 0.0 && r.is_finite()) {
        return (c as f32, r as f32);
    }
    // Rounded up to a multiple of 2⁻¹⁶ of itself so tiny changes of d0, d1 (rounding of the
    // split formula) cannot change the window's size.
    let q = 2f64.powi(r.log2().floor() as i32 - 16);
    (c as f32, ((r / q).ceil() * q) as f32)
}

/// The light-space rectangle of a cascade: `(x0, x1, y0, y1)` in the light basis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Left edge.
    pub x0: f32,
    /// Right edge.
    pub x1: f32,
    /// Bottom edge.
    pub y0: f32,
    /// Top edge.
    pub y1: f32,
}

/// The window of the slice `[d0, d1]` for a map of `res` texels: stabilized (bounding sphere,
/// texel-snapped centre) or tight (the corners' rectangle within the scene's).
pub fn fit_window(
    camera: &Camera,
    basis: &Mat4,
    scene: &Aabb,
    (d0, d1): (f32, f32),
    res: u32,
    stabilize: bool,
) -> Window {
    if stabilize {
        let (c, r) = slice_sphere(camera, d0, d1);
        let centre = basis.transform_point3(camera.eye + camera.forward() * c);
        let texel = 2.0 * r / res as f32;
        let snap = |v: f32| (v / texel).floor() * texel;
        let (cx, cy) = (snap(centre.x), snap(centre.y));
        return Window {
            x0: cx - r,
            x1: cx + r,
            y0: cy - r,
            y1: cy + r,
        };
    }
    let mut b = Aabb::EMPTY;
    for p in slice_corners(camera, d0, d1) {
        b.grow(basis.transform_point3(p));
    }
    let mut s = Aabb::EMPTY;
    for p in scene.corners() {
        s.grow(basis.transform_point3(p));
    }
    let (x0, x1) = (b.min.x.max(s.min.x), b.max.x.min(s.max.x));
    let (y0, y1) = (b.min.y.max(s.min.y), b.max.y.min(s.max.y));
    // Square texels: the longer side sets both, centred.
    let half = (x1 - x0).max(y1 - y0).max(scene.diagonal() * 1e-6) * 0.5;
    let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
    Window {
        x0: cx - half,
        x1: cx + half,
        y0: cy - half,
        y1: cy + half,
    }
}

/// The orthographic light view of a window: depth from the scene's nearest point towards
/// the light to the slice's farthest point within the scene.
pub fn cascade_view(
    camera: &Camera,
    basis: &Mat4,
    scene: &Aabb,
    (d0, d1): (f32, f32),
    w: &Window,
) -> LightView {
    let depth = |p: Vec3| -basis.transform_point3(p).z;
    let (mut near, mut scene_far) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in scene.corners() {
        near = near.min(depth(p));
        scene_far = scene_far.max(depth(p));
    }
    let slice_far = slice_corners(camera, d0, d1)
        .iter()
        .map(|&p| depth(p))
        .fold(f32::NEG_INFINITY, f32::max);
    let far = slice_far.min(scene_far).max(near + scene.diagonal() * 1e-6);
    let pad = (far - near) * DEPTH_PAD;
    let (near, far) = (near - pad, far + pad);
    let clip = orthographic_rh(w.x0, w.x1, w.y0, w.y1, near, far);
    LightView::new(*basis, clip, true, near, far, w.x1 - w.x0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::vec3;

    fn scene() -> Aabb {
        Aabb::from_points(&[vec3(-50.0, 0.0, -50.0), vec3(50.0, 10.0, 50.0)])
    }

    #[test]
    fn stabilized_windows_move_by_whole_texels_and_keep_their_size() {
        let basis = light_basis(vec3(0.3, 0.8, -0.5), &scene());
        let res = 1024;
        let base = Camera::look_at(vec3(0.0, 3.0, 10.0), vec3(0.0, 1.0, 0.0), 50.0, 800, 600);
        let slice = (2.0, 15.0);
        let w0 = fit_window(&base, &basis, &scene(), slice, res, true);
        let texel = (w0.x1 - w0.x0) / res as f32;
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 - 0.5
        };
        for _ in 0..20 {
            // Translation: the window moves by whole texels.
            let t = vec3(rnd(), rnd(), rnd()) * 3.0;
            let mut cam = base;
            cam.eye += t;
            cam.target += t;
            let w = fit_window(&cam, &basis, &scene(), slice, res, true);
            for (a, b) in [(w.x0, w0.x0), (w.y0, w0.y0)] {
                let moved = (a - b) / texel;
                assert!((moved - moved.round()).abs() < 2e-2, "moved {moved} texels");
            }
            assert!(((w.x1 - w.x0) - (w0.x1 - w0.x0)).abs() < 1e-5);
            // Rotation: the size stays exactly.
            let mut cam = base;
            cam.target = cam.eye + vec3(rnd() * 4.0, rnd(), rnd() * 4.0 - 3.0);
            let w = fit_window(&cam, &basis, &scene(), slice, res, true);
            // The same radius on both sides of a different centre: equal up to the
            // rounding of centre ± radius.
            let size = w0.x1 - w0.x0;
            assert!(((w.x1 - w.x0) - size).abs() <= 1e-5 * size);
            assert!(((w.y1 - w.y0) - (w0.y1 - w0.y0)).abs() <= 1e-5 * size);
            assert_eq!(
                slice_sphere(&cam, slice.0, slice.1).1,
                slice_sphere(&base, slice.0, slice.1).1
            );
        }
    }

    #[test]
    fn windows_hold_their_slice() {
        let basis = light_basis(vec3(-0.2, 1.0, 0.4), &scene());
        let cam = Camera::look_at(vec3(5.0, 4.0, 20.0), vec3(0.0, 0.0, 0.0), 45.0, 640, 480);
        for stabilize in [false, true] {
            let w = fit_window(&cam, &basis, &scene(), (1.0, 12.0), 512, stabilize);
            for p in slice_corners(&cam, 1.0, 12.0) {
                let q = basis.transform_point3(p);
                assert!(
                    q.x >= w.x0 - 1e-3 && q.x <= w.x1 + 1e-3,
                    "{stabilize}: {q} {w:?}"
                );
                assert!(
                    q.y >= w.y0 - 1e-3 && q.y <= w.y1 + 1e-3,
                    "{stabilize}: {q} {w:?}"
                );
            }
        }
    }
}
