//! glTF cameras as shadowlab cameras, perspective or orthographic, as they are.

use super::{CAMERA_DEFAULT_WIDTH, CAMERA_HEIGHT};
use crate::camera::{Camera, Projection, MAX_IMAGE_SIDE};
use crate::error::{Error, Result};
use crate::math::{Aabb, Mat4, Vec3};
use gltf::json::validation::Checked;
use std::path::Path;

/// The scene camera for glTF camera `index` on a node with world transform `world`.
pub(super) fn convert_camera(
    path: &Path,
    doc: &gltf::Document,
    index: usize,
    world: Mat4,
    bounds: &Aabb,
) -> Result<Camera> {
    let fmt = |what: String| Error::format(path, what);
    let json = &doc.as_json().cameras[index];
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if !eye.is_finite()
        || forward == Vec3::ZERO
        || up == Vec3::ZERO
        || forward.cross(up).length_squared() < 1e-12
    {
        return Err(fmt(format!(
            "camera {index}: its node's transform is degenerate"
        )));
    }
    // The scene centre's depth along the view axis: where the target goes.
    let center_depth = (bounds.center() - eye).dot(forward);
    let image = |aspect: f32| -> Result<(u32, u32)> {
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(fmt(format!(
                "camera {index}: aspect ratio {aspect} is not a positive number"
            )));
        }
        let w = (CAMERA_HEIGHT as f32 * aspect).round();
        if !(1.0..=MAX_IMAGE_SIDE as f32).contains(&w) {
            return Err(fmt(format!(
                "camera {index}: aspect ratio {aspect} gives an image {w} pixels wide, outside 1..={MAX_IMAGE_SIDE}"
            )));
        }
        Ok((w as u32, CAMERA_HEIGHT))
    };
    let kind = match &json.type_ {
        Checked::Valid(k) => *k,
        Checked::Invalid => return Err(fmt(format!("camera {index}: unknown camera type"))),
    };
    let mut camera = match (kind, &json.perspective, &json.orthographic) {
        (gltf::json::camera::Type::Perspective, Some(p), _) => {
            let fov = p.yfov.to_degrees();
            if !(fov > 0.0 && fov < 179.0) {
                return Err(fmt(format!(
                    "camera {index}: yfov {} rad is outside (0°, 179°)",
                    p.yfov
                )));
            }
            let (width, height) = match p.aspect_ratio {
                Some(a) => image(a)?,
                None => (CAMERA_DEFAULT_WIDTH, CAMERA_HEIGHT),
            };
            let dist = if center_depth > 0.0 {
                center_depth
            } else {
                1.0
            };
            let mut c = fitted(eye, eye + forward * dist, up, fov, (width, height), bounds);
            if p.znear.is_finite() && p.znear > 0.0 {
                c.near = p.znear;
            }
            if let Some(f) = p.zfar.filter(|f| f.is_finite() && *f > c.near) {
                c.far = f;
            }
            c
        }
        (gltf::json::camera::Type::Orthographic, _, Some(o)) => {
            let (xmag, ymag) = (o.xmag, o.ymag);
            if !(xmag.is_finite() && ymag.is_finite() && xmag > 0.0 && ymag > 0.0) {
                return Err(fmt(format!(
                    "camera {index}: orthographic xmag {xmag} and ymag {ymag} must be finite and positive"
                )));
            }
            if !(o.znear.is_finite() && o.znear >= 0.0 && o.zfar.is_finite() && o.zfar > o.znear) {
                return Err(fmt(format!(
                    "camera {index}: orthographic znear {} and zfar {} must satisfy 0 <= znear < zfar",
                    o.znear, o.zfar
                )));
            }
            let (width, height) = image(xmag / ymag)?;
            let dist = if center_depth > 0.0 {
                center_depth
            } else {
                1.0
            };
            let mut c = fitted(eye, eye + forward * dist, up, 45.0, (width, height), bounds);
            c.projection = Projection::Orthographic { xmag, ymag };
            // The file's depth range as it is (a znear of 0 is lifted to the least near
            // plane below).
            (c.near, c.far) = (o.znear, o.zfar);
            c
        }
        _ => {
            return Err(fmt(format!(
            "camera {index}: its type's parameters (`perspective` or `orthographic`) are missing"
        )))
        }
    };
    camera.near = camera.near.max(camera.far * MIN_NEAR_SHARE);
    camera
        .validate()
        .map_err(|e| fmt(format!("camera {index}: {e}")))?;
    Ok(camera)
}

/// The least near plane of a glTF camera, as a share of its far plane: a file's `znear`
/// may be tiny, and a depth range wider than this ratio has no precision left.
const MIN_NEAR_SHARE: f32 = 1e-7;

/// A camera of `fov_y_deg` and image `size` at `eye` looking at `target` with `up`, its
/// near and far fitted to `bounds`.
fn fitted(
    eye: Vec3,
    target: Vec3,
    up: Vec3,
    fov_y_deg: f32,
    size: (u32, u32),
    bounds: &Aabb,
) -> Camera {
    let mut c = Camera::look_at(eye, target, fov_y_deg, size.0, size.1);
    c.up = up;
    c.fit_depth_range(bounds);
    c
}
