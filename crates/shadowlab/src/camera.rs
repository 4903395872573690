//! The camera — perspective or orthographic — and its key-framed paths.
//!
//! Conventions (also in the README): pixel `(px, py)` covers `[px, px+1) × [py, py+1)`,
//! row 0 at the top; its primary ray passes through `(px + 0.5, py + 0.5)` on the image
//! plane; `fov_y_deg` is the vertical field of view of a perspective camera. An
//! orthographic camera (glTF's `xmag`, `ymag`: half the width and half the height of the
//! viewed rectangle) casts parallel rays along its view direction, each starting on the
//! plane through the eye across the view axis, so that for either projection a primary
//! ray's parameter is the view depth of the point it reaches. Clip space follows glam's
//! right-handed conventions with depth in `[0, 1]`; an orthographic camera's clip `w` is 1.

use crate::error::{Error, Result};
use crate::math::{vec3, Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// The largest image side accepted (each side); larger requests are refused before any
/// allocation. Raise it with care: a frame's buffers grow with the pixel count.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most pixels an image may have (8192²): the camera pass holds about 70 bytes a
/// pixel, so this caps a frame's buffers near 5 GB.
pub const MAX_PIXELS: u64 = 1 << 26;

/// The nearest far plane [`Camera::fit_depth_range`] sets (world units). A light's views
/// use the light module's `LIGHT_MIN_FAR`, ten times smaller: the two fits differ only there,
/// and each keeps its own so that every image stays as it was.
pub const CAMERA_MIN_FAR: f32 = 1e-3;

/// How a camera projects: through a pinhole (its field of view is the camera's
/// `fov_y_deg`) or along parallel rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Projection {
    /// A pinhole at the eye; the vertical field of view is [`Camera::fov_y_deg`].
    #[default]
    Perspective,
    /// Parallel rays along the view direction; the image is the rectangle `2·xmag × 2·ymag`
    /// (world units) centred on the view axis, as glTF defines them.
    Orthographic {
        /// Half the width of the viewed rectangle.
        xmag: f32,
        /// Half the height of the viewed rectangle.
        ymag: f32,
    },
}

impl Projection {
    /// The projection's name as files and command lines spell it.
    pub fn name(&self) -> &'static str {
        match self {
            Projection::Perspective => "perspective",
            Projection::Orthographic { .. } => "orthographic",
        }
    }

    /// Whether the rays are parallel.
    pub fn is_orthographic(&self) -> bool {
        matches!(self, Projection::Orthographic { .. })
    }
}

/// A camera: a pinhole (perspective) or parallel (orthographic) projection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position in world units.
    pub eye: Vec3,
    /// The point looked at.
    pub target: Vec3,
    /// The up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees (a perspective camera's; an orthographic one
    /// keeps it only to return to perspective).
    pub fov_y_deg: f32,
    /// Perspective (the default) or orthographic.
    #[serde(default)]
    pub projection: Projection,
    /// Near plane distance (along the view axis).
    pub near: f32,
    /// Far plane distance (along the view axis).
    pub far: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `eye` looking at `target` with +Y up, near/far to be fitted later by
    /// [`Camera::fit_depth_range`] (set to 0.01 and 1000 here).
    pub fn look_at(eye: Vec3, target: Vec3, fov_y_deg: f32, width: u32, height: u32) -> Self {
        let mut up = Vec3::Y;
        if (target - eye)
            .normalize_or_zero()
            .cross(up)
            .length_squared()
            < 1e-8
        {
            up = Vec3::Z;
        }
        Camera {
            eye,
            target,
            up,
            fov_y_deg,
            projection: Projection::Perspective,
            near: 0.01,
            far: 1000.0,
            width,
            height,
        }
    }

    /// An orthographic camera at `eye` looking at `target` with +Y up, viewing the
    /// rectangle `2·xmag × 2·ymag`; near/far as in [`Camera::look_at`].
    pub fn orthographic(
        eye: Vec3,
        target: Vec3,
        (xmag, ymag): (f32, f32),
        width: u32,
        height: u32,
    ) -> Self {
        let mut c = Camera::look_at(eye, target, 45.0, width, height);
        c.projection = Projection::Orthographic { xmag, ymag };
        c
    }

    /// Whether the primary rays are parallel.
    pub fn is_orthographic(&self) -> bool {
        self.projection.is_orthographic()
    }

    /// Checks that the camera can form an image; names the problem otherwise.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::param(format!(
                "image size {}x{} is empty: width and height must be at least 1",
                self.width, self.height
            )));
        }
        if self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(Error::Limit(format!(
                "image size {}x{} exceeds the limit of {MAX_IMAGE_SIDE} pixels a side",
                self.width, self.height
            )));
        }
        if self.width as u64 * self.height as u64 > MAX_PIXELS {
            return Err(Error::Limit(format!(
                "image size {}x{} has more than the limit of {MAX_PIXELS} pixels; lower --width or --height",
                self.width, self.height
            )));
        }
        let finite = self.eye.is_finite() && self.target.is_finite() && self.up.is_finite();
        if !finite || !self.fov_y_deg.is_finite() {
            return Err(Error::param(
                "camera has a non-finite eye, target, up or field of view",
            ));
        }
        crate::light::far_out("camera eye", self.eye)?;
        crate::light::far_out("camera target", self.target)?;
        if (self.target - self.eye).length_squared() == 0.0 {
            return Err(Error::param("camera eye and target are the same point"));
        }
        if !self.forward().is_finite() {
            return Err(Error::param(
                "camera target is too far from its eye to form a view direction",
            ));
        }
        if self.forward().cross(self.up).length_squared() < 1e-12 {
            return Err(Error::param(
                "camera up direction is parallel to the view direction",
            ));
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 179.0) {
            return Err(Error::param(format!(
                "camera field of view {}° is outside (0°, 179°)",
                self.fov_y_deg
            )));
        }
        if let Projection::Orthographic { xmag, ymag } = self.projection {
            if !(xmag.is_finite() && ymag.is_finite() && xmag > 0.0 && ymag > 0.0) {
                return Err(Error::param(format!(
                    "orthographic camera extent xmag {xmag}, ymag {ymag} must be finite and positive"
                )));
            }
        }
        if !(self.near > 0.0 && self.far > self.near) {
            return Err(Error::param(format!(
                "camera near {} and far {} must satisfy 0 < near < far",
                self.near, self.far
            )));
        }
        Ok(())
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize()
    }

    /// Orthonormal camera basis: (right, true up, forward).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let f = self.forward();
        let r = f.cross(self.up).normalize();
        let u = r.cross(f);
        (r, u, f)
    }

    /// Width over height.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// World to camera space (right-handed, looking down −Z).
    pub fn view_from_world(&self) -> Mat4 {
        crate::math::look_at_rh(self.eye, self.target, self.up)
    }

    /// Camera space to clip space, depth in [0, 1]; clip `w` is the view depth for a
    /// perspective camera and 1 for an orthographic one.
    pub fn clip_from_view(&self) -> Mat4 {
        match self.projection {
            Projection::Perspective => crate::math::perspective_rh(
                self.fov_y_deg.to_radians(),
                self.aspect(),
                self.near,
                self.far,
            ),
            Projection::Orthographic { xmag, ymag } => {
                crate::math::orthographic_rh(-xmag, xmag, -ymag, ymag, self.near, self.far)
            }
        }
    }

    /// The view depth of world point `p`: its distance from the eye along the view axis.
    pub fn view_depth(&self, p: Vec3) -> f32 {
        (p - self.eye).dot(self.forward())
    }

    /// World to clip space.
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_view() * self.view_from_world()
    }

    /// The (unnormalized) direction of the primary ray through image position `(x, y)` in
    /// pixels (pixel centres at `+0.5`). Its component along `forward` is 1, so the ray
    /// parameter equals the view depth. For many rays, [`Camera::rays`] avoids recomputing
    /// the basis each time. An orthographic camera's rays all run along `forward` and
    /// start apart: see [`Camera::ray`].
    pub fn ray_direction(&self, x: f32, y: f32) -> Vec3 {
        self.rays().direction(x, y)
    }

    /// The primary ray through image position `(x, y)`: origin and direction as
    /// [`RayGenerator::ray`] gives them.
    pub fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        self.rays().ray(x, y)
    }

    /// The camera's primary-ray generator.
    pub fn rays(&self) -> RayGenerator {
        let (r, u, f) = self.basis();
        let (half_x, half_y, parallel) = match self.projection {
            Projection::Perspective => {
                let th = (self.fov_y_deg.to_radians() * 0.5).tan();
                (th * self.aspect(), th, false)
            }
            Projection::Orthographic { xmag, ymag } => (xmag, ymag, true),
        };
        RayGenerator {
            eye: self.eye,
            forward: f,
            right: r * half_x,
            up: u * half_y,
            inv_width: 1.0 / self.width as f32,
            inv_height: 1.0 / self.height as f32,
            parallel,
        }
    }

    /// Sets near and far so the box `bounds` lies inside the depth range: far just beyond
    /// its farthest corner, near at a fraction of far (or the nearest corner when the box is
    /// entirely in front), so depth precision is spent where the scene is.
    pub fn fit_depth_range(&mut self, bounds: &crate::math::Aabb) {
        let f = self.forward();
        let depths = bounds.corners().map(|c| (c - self.eye).dot(f));
        (self.near, self.far) = crate::math::fit_near_far(depths, CAMERA_MIN_FAR);
    }

    /// Moves the camera along its view ray to `factor` times its distance from its target;
    /// an orthographic camera's extent scales with it, so the framing changes as a
    /// perspective camera's would at its target.
    pub fn scale_distance(&mut self, factor: f32) {
        self.eye = self.target + (self.eye - self.target) * factor;
        if let Projection::Orthographic { xmag, ymag } = self.projection {
            self.projection = Projection::Orthographic {
                xmag: xmag * factor,
                ymag: ymag * factor,
            };
        }
    }

    /// The half-extents `(xmag, ymag)` of the rectangle this camera frames at its
    /// target's depth: an orthographic camera's own, a perspective one's from its field
    /// of view.
    pub fn orthographic_extent_at_target(&self) -> (f32, f32) {
        match self.projection {
            Projection::Orthographic { xmag, ymag } => (xmag, ymag),
            Projection::Perspective => {
                let d = (self.target - self.eye).length();
                let ymag = d * (self.fov_y_deg.to_radians() * 0.5).tan();
                (ymag * self.aspect(), ymag)
            }
        }
    }
}

/// Primary rays of a camera, with its basis computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayGenerator {
    eye: Vec3,
    forward: Vec3,
    /// The image's right half-extent: at unit depth (perspective) or in world units
    /// (orthographic).
    right: Vec3,
    /// The image's upper half-extent, likewise.
    up: Vec3,
    inv_width: f32,
    inv_height: f32,
    parallel: bool,
}

impl RayGenerator {
    /// The generator's parts, for a backend that forms the same rays elsewhere (the GPU
    /// crate): eye, forward axis, right and upper half-extents, 1/width, 1/height, and
    /// whether the rays are parallel (orthographic).
    pub fn parts(&self) -> (Vec3, Vec3, Vec3, Vec3, f32, f32, bool) {
        (
            self.eye,
            self.forward,
            self.right,
            self.up,
            self.inv_width,
            self.inv_height,
            self.parallel,
        )
    }

    /// The image position `(x, y)` in normalized device coordinates.
    #[inline]
    fn ndc(&self, x: f32, y: f32) -> (f32, f32) {
        (
            x * self.inv_width * 2.0 - 1.0,
            1.0 - y * self.inv_height * 2.0,
        )
    }

    /// The offset of image position `(x, y)` from the image centre on the eye's plane
    /// (orthographic).
    #[inline]
    fn offset(&self, x: f32, y: f32) -> Vec3 {
        let (nx, ny) = self.ndc(x, y);
        self.right * nx + self.up * ny
    }

    /// The perspective direction through image position `(x, y)`, summed from the forward
    /// axis outwards (the order every perspective image has always been computed in).
    #[inline]
    fn perspective_direction(&self, x: f32, y: f32) -> Vec3 {
        let (nx, ny) = self.ndc(x, y);
        self.forward + self.right * nx + self.up * ny
    }

    /// See [`Camera::ray_direction`].
    #[inline]
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        if self.parallel {
            self.forward
        } else {
            self.perspective_direction(x, y)
        }
    }

    /// The primary ray through image position `(x, y)` as origin and direction: from the
    /// eye (perspective) or from the point of the eye's plane across the view axis that
    /// the pixel sees (orthographic). Either way the direction's component along the
    /// view axis is 1 and the origin's view depth 0, so the ray parameter of a point is its
    /// view depth.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        if self.parallel {
            (self.eye + self.offset(x, y), self.forward)
        } else {
            (self.eye, self.perspective_direction(x, y))
        }
    }

    /// The primary ray, through the pixel that sees it, reaching world point `p`: origin
    /// and direction as [`RayGenerator::ray`] gives them (the direction not normalized).
    #[inline]
    pub fn ray_to(&self, p: Vec3) -> (Vec3, Vec3) {
        if self.parallel {
            let depth = (p - self.eye).dot(self.forward);
            (p - self.forward * depth, self.forward)
        } else {
            (self.eye, p - self.eye)
        }
    }
}

/// One key frame of a camera path.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraKey {
    /// Eye position.
    pub eye: Vec3,
    /// Look-at point.
    pub target: Vec3,
}

/// A key-framed camera path: eye and target interpolated linearly between keys.
///
/// A path with a `pace` is walked at that pace whatever the frame count: frame `i` is at
/// `i / (pace − 1)` of the way from the first key to the last (the camera stays at the
/// last key after it), so the first `n` frames of a walkthrough move the camera the same
/// distance per frame for any `n`, as a real walkthrough does, and a progressive
/// technique sees the coherent motion it is built for. A path without one is stretched
/// over whatever frame count is asked: `n` evenly spaced frames from the first key to the
/// last.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraPath {
    /// The keys, in order.
    pub keys: Vec<CameraKey>,
    /// The frames from the first key to the last at the path's own pace (at least 2), or
    /// `None` to stretch the path over every sequence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pace: Option<u32>,
}

impl CameraPath {
    /// A path stretched over every sequence.
    pub fn stretched(keys: Vec<CameraKey>) -> Self {
        CameraPath { keys, pace: None }
    }

    /// The camera of frame `i` of `n`, starting from `base` (which gives fov, up, size):
    /// at the path's pace when it has one, else stretched over the `n` frames.
    pub fn camera_at(&self, base: &Camera, i: usize, n: usize) -> Camera {
        match self.pace {
            Some(pace) => self.camera_along(base, i, pace.max(2) as usize),
            None => self.camera_along(base, i, n),
        }
    }

    /// The camera of frame `i` when `n` evenly spaced frames span the path from its first
    /// key to its last (frames past the end stay at the last key).
    pub fn camera_along(&self, base: &Camera, i: usize, n: usize) -> Camera {
        let mut c = *base;
        if self.keys.is_empty() {
            return c;
        }
        if self.keys.len() == 1 || n <= 1 {
            c.eye = self.keys[0].eye;
            c.target = self.keys[0].target;
            return c;
        }
        let s = (i.min(n - 1)) as f32 / (n - 1) as f32 * (self.keys.len() - 1) as f32;
        let k = (s.floor() as usize).min(self.keys.len() - 2);
        let t = s - k as f32;
        let (a, b) = (self.keys[k], self.keys[k + 1]);
        c.eye = a.eye.lerp(b.eye, t);
        c.target = a.target.lerp(b.target, t);
        c
    }
}

/// A default viewing direction for auto-framing: from the front, above and to the right.
pub const AUTO_VIEW_DIRECTION: Vec3 = vec3(0.45, 0.35, 0.82);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_direction_matches_projection() {
        let mut cam = Camera::look_at(vec3(1.0, 2.0, 3.0), vec3(0.0, 0.5, 0.0), 50.0, 320, 200);
        cam.near = 0.1;
        cam.far = 100.0;
        let m = cam.clip_from_world();
        for &(x, y) in &[(0.5f32, 0.5f32), (160.0, 100.0), (319.5, 10.25)] {
            let p = cam.eye + cam.ray_direction(x, y) * 7.0;
            let c = m * p.extend(1.0);
            let sx = (c.x / c.w * 0.5 + 0.5) * 320.0;
            let sy = (0.5 - c.y / c.w * 0.5) * 200.0;
            assert!(
                (sx - x).abs() < 1e-3 && (sy - y).abs() < 1e-3,
                "{sx},{sy} vs {x},{y}"
            );
            assert!((c.w - 7.0).abs() < 1e-4);
        }
    }

    #[test]
    fn a_paced_path_moves_as_far_per_frame_for_any_frame_count() {
        let base = Camera::look_at(vec3(0.0, 0.0, 5.0), Vec3::ZERO, 50.0, 64, 48);
        let key = |x: f32| CameraKey {
            eye: vec3(x, 0.0, 5.0),
            target: vec3(x, 0.0, 0.0),
        };
        let mut path = CameraPath::stretched(vec![key(0.0), key(1.0), key(3.0)]);
        // Stretched: the last of n frames is at the last key, whatever n.
        for n in [2, 5, 9] {
            assert_eq!(path.camera_at(&base, n - 1, n).eye.x, 3.0);
        }
        path.pace = Some(5);
        for n in [2, 5, 9] {
            for i in 0..n {
                let c = path.camera_at(&base, i, n);
                // At the pace, 4 frames from the first key to the last, then standing still.
                let s = (i.min(4) as f32) / 2.0;
                let x = if s <= 1.0 { s } else { 1.0 + 2.0 * (s - 1.0) };
                assert!((c.eye.x - x).abs() < 1e-6, "frame {i} of {n}: {}", c.eye.x);
            }
        }
    }

    #[test]
    fn orthographic_rays_match_projection_and_keep_t_as_view_depth() {
        let mut cam = Camera::orthographic(
            vec3(1.0, 2.0, 3.0),
            vec3(0.0, 0.5, 0.0),
            (1.6, 1.0),
            320,
            200,
        );
        cam.near = 0.1;
        cam.far = 100.0;
        cam.validate().unwrap();
        let m = cam.clip_from_world();
        for &(x, y) in &[(0.5f32, 0.5f32), (160.0, 100.0), (319.5, 10.25)] {
            let (o, d) = cam.ray(x, y);
            assert_eq!(d, cam.forward());
            assert!(cam.view_depth(o).abs() < 1e-5);
            let p = o + d * 7.0;
            assert!((cam.view_depth(p) - 7.0).abs() < 1e-4);
            let c = m * p.extend(1.0);
            assert_eq!(c.w, 1.0);
            let sx = (c.x * 0.5 + 0.5) * 320.0;
            let sy = (0.5 - c.y * 0.5) * 200.0;
            assert!(
                (sx - x).abs() < 1e-3 && (sy - y).abs() < 1e-3,
                "{sx},{sy} vs {x},{y}"
            );
        }
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let mut c = cam;
            c.projection = Projection::Orthographic {
                xmag: bad,
                ymag: 1.0,
            };
            assert!(c.validate().unwrap_err().to_string().contains("xmag"));
        }
    }
}
