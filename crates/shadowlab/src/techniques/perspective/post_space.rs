//! Post-perspective space of `psm` (Stamminger & Drettakis 2002, Section 4.2,
//! "Post-perspective Space", and Section 3, "Post-Perspective Light Sources"), in f64.
//!
//! - Virtual camera shift (Section 4.2): when the body `H` reaches nearer than the near
//!   plane, the camera is moved back along its axis until it does not; the near plane stays
//!   and the far plane grows by the shift. The post-perspective transform is the OpenGL
//!   projection of this virtual camera (the paper's unit cube, its infinity plane at
//!   `z = (f + n)/(f − n)`).
//! - The light (Sections 3.1–3.2) becomes the homogeneous point `l' = post_from_world · l`:
//!   `l'.w = 0` (a directional light parallel to the image plane, a point light on the
//!   camera plane) a directional light; `l'.w > 0` (a directional light from the front, a
//!   point light in front of the viewer) a point light at `q = l'.xyz / l'.w`; `l'.w < 0`
//!   (from behind) an inverted point light at `q`, whose rays converge.

use crate::camera::{Camera, Projection};
use crate::light::Light;
use crate::math::{look_along_rh_f64, Mat4};
use glam::{DMat4, DVec3, DVec4};

/// The camera is shifted back only when the body reaches nearer than this fraction of the
/// near distance in front of the near plane; smaller shifts are not worth the lost
/// perspective, and the few points nearer than the near plane still map to finite points.
pub const SHIFT_SLACK: f64 = 1e-3;
/// A post-perspective light farther than this many body diameters away is treated as
/// directional: its rays across the body then diverge by less than 1e-7 rad, far below a
/// texel, while a perspective frustum that far away would lose f32 precision.
pub const DIRECTIONAL_DISTANCE_RATIO: f64 = 1e7;
/// The smallest extent of a post-space body or map window that is divided by: a body
/// that collapses to a point still gives finite ratios.
pub(super) const MIN_POST_EXTENT: f64 = 1e-12;

/// How the light looks from post-perspective space (Sections 3.1–3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PostLight {
    /// A point light: rays leave `q`.
    Point,
    /// An inverted point light: rays converge towards `q`; the depth test is reversed.
    Inverted,
    /// A directional light (the world light lies on the virtual camera plane).
    Directional,
}

/// What one frame's perspective shadow map was built from (for tests, dumps and reports).
#[derive(Clone, Debug)]
pub struct PostSpace {
    /// World to post-perspective space of the (virtually shifted) camera.
    pub post_from_world: Mat4,
    /// The light's case in post-perspective space.
    pub light: PostLight,
    /// The light in post-perspective space as a homogeneous point.
    pub light_post: DVec4,
    /// How far the camera was moved back along its view direction (world units).
    pub virtual_shift: f64,
    /// Near plane distance of the virtual camera (the pushed near plane).
    pub near: f64,
    /// Far plane distance of the virtual camera.
    pub far: f64,
    /// Vertices of the body `H` in world space.
    pub body: Vec<DVec3>,
    /// Number of maps (1, or up to 6 for a cube around a post-perspective point light).
    pub maps: usize,
}

/// The OpenGL perspective projection (NDC cube `[-1, 1]³`), as the paper uses: the
/// infinity plane lies at `z = (f + n) / (f − n)`.
fn perspective_gl(fov_y: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    DMat4::from_cols(
        DVec4::new(h / aspect, 0.0, 0.0, 0.0),
        DVec4::new(0.0, h, 0.0, 0.0),
        DVec4::new(0.0, 0.0, (far + near) / (near - far), -1.0),
        DVec4::new(0.0, 0.0, 2.0 * far * near / (near - far), 0.0),
    )
}

/// The OpenGL orthographic projection (NDC cube `[-1, 1]³`) of the rectangle
/// `2·xmag × 2·ymag`: an affine map, `w` = 1, so post-perspective space is the world itself
/// scaled into the cube.
fn orthographic_gl(xmag: f64, ymag: f64, near: f64, far: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(1.0 / xmag, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0 / ymag, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 2.0 / (near - far), 0.0),
        DVec4::new(0.0, 0.0, (far + near) / (near - far), 1.0),
    )
}

/// The virtually shifted camera of Section 4.2 and its post-perspective transform.
pub(super) struct VirtualCamera {
    /// How far the camera was moved back along its view direction.
    pub(super) shift: f64,
    /// Its near plane distance (the pushed near plane of the real camera).
    pub(super) near: f64,
    /// Its far plane distance: the real far plane plus the shift.
    pub(super) far: f64,
    /// World to its post-perspective space.
    pub(super) post_from_world: DMat4,
}

impl VirtualCamera {
    /// The camera `cam` with the view depths `near..far`, moved back until every vertex of
    /// the body lies beyond the near plane.
    pub(super) fn shifted(cam: &Camera, body: &[DVec3], (near, far): (f64, f64)) -> Self {
        let (_, _, fwd) = cam.basis();
        let fwd = fwd.as_dvec3();
        let eye = cam.eye.as_dvec3();
        let min_depth = body
            .iter()
            .map(|p| (*p - eye).dot(fwd))
            .fold(f64::INFINITY, f64::min);
        // An orthographic view's map is affine, defined behind the eye as well: no shift.
        let shift = if min_depth < near * (1.0 - SHIFT_SLACK) && !cam.is_orthographic() {
            near - min_depth
        } else {
            0.0
        };
        let veye = eye - fwd * shift;
        // Near stays, far grows to hold the whole previous frustum.
        let vfar = far + shift;
        let clip = match cam.projection {
            Projection::Perspective => perspective_gl(
                (cam.fov_y_deg as f64).to_radians(),
                cam.aspect() as f64,
                near,
                vfar,
            ),
            Projection::Orthographic { xmag, ymag } => {
                orthographic_gl(xmag as f64, ymag as f64, near, vfar)
            }
        };
        let post_from_world = clip * look_along_rh_f64(veye, fwd, cam.up.as_dvec3());
        VirtualCamera {
            shift,
            near,
            far: vfar,
            post_from_world,
        }
    }
}

/// The body `H'` in post-perspective space.
pub(super) struct PostBody {
    /// Its vertices (the images of `H`'s: `H'` is their convex hull).
    pub(super) pts: Vec<DVec3>,
    /// The centre of their bounding box.
    pub(super) centre: DVec3,
    /// The diagonal of their bounding box.
    pub(super) size: f64,
}

impl PostBody {
    /// The post-perspective image of the body with world vertices `body`.
    pub(super) fn of(camera: &VirtualCamera, body: &[DVec3]) -> Self {
        let pts: Vec<DVec3> = body
            .iter()
            .map(|p| {
                let h = camera.post_from_world * p.extend(1.0);
                h.truncate() / h.w
            })
            .collect();
        let (lo, hi) = pts
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        PostBody {
            pts,
            centre: (lo + hi) * 0.5,
            size: (hi - lo).length().max(MIN_POST_EXTENT),
        }
    }
}

/// The light as it appears in post-perspective space.
pub(super) struct PostLightSource {
    /// Its case.
    pub(super) kind: PostLight,
    /// The homogeneous point `l' = post_from_world · l`.
    pub(super) light_post: DVec4,
    /// Its position `q` (zero for a directional light).
    pub(super) q: DVec3,
    /// Unit direction towards it (zero unless directional).
    pub(super) dir: DVec3,
}

impl PostLightSource {
    /// The case of `light` seen from `camera`'s post-perspective space, where the body has
    /// the diameter `size`.
    pub(super) fn of(light: &Light, camera: &VirtualCamera, size: f64) -> Self {
        let lh = match *light {
            Light::Directional { to_light } => to_light.as_dvec3().normalize().extend(0.0),
            Light::Point { position } | Light::Spot { position, .. } => {
                position.as_dvec3().extend(1.0)
            }
        };
        let lp = camera.post_from_world * lh;
        let xyz = lp.truncate();
        let directional =
            lp.w == 0.0 || xyz.length() / lp.w.abs() > DIRECTIONAL_DISTANCE_RATIO * size;
        let (kind, q, dir) = if directional {
            (PostLight::Directional, DVec3::ZERO, xyz.normalize())
        } else if lp.w > 0.0 {
            (PostLight::Point, xyz / lp.w, DVec3::ZERO)
        } else {
            (PostLight::Inverted, xyz / lp.w, DVec3::ZERO)
        };
        PostLightSource {
            kind,
            light_post: lp,
            q,
            dir,
        }
    }
}
