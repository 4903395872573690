//! The `[camera]` and `[light]` sections of a TOML scene.

use super::spec::{CameraSpec, LightKind, LightSpec, ProjectionKind, V3};
use super::{finite3, Msg, MAX_KEY_FRAMES};
use crate::area_light::AreaLight;
use crate::camera::{Camera, CameraKey, CameraPath, Projection};
use crate::light::Light;
use crate::scene::Scene;

/// The `[camera]` section: the camera (near and far fitted to `scene` unless given) and
/// its key-framed path, each key checked as a camera.
pub(super) fn camera(c: &CameraSpec, scene: &Scene) -> Msg<(Camera, Option<CameraPath>)> {
    let eye = finite3(c.eye, "eye")?;
    let target = finite3(c.target, "target")?;
    let mut camera = Camera::look_at(
        eye,
        target,
        c.fov_y_deg.unwrap_or(45.0),
        c.width.unwrap_or(1024),
        c.height.unwrap_or(768),
    );
    if let Some(up) = c.up {
        camera.up = finite3(up, "up")?;
    }
    camera.projection = projection(c)?;
    camera.fit_depth_range(&scene.bounds);
    match (c.near, c.far) {
        (Some(n), Some(f)) => (camera.near, camera.far) = (n, f),
        (Some(n), None) => camera.near = n,
        (None, Some(f)) => camera.far = f,
        (None, None) => {}
    }
    camera.validate().map_err(|e| e.to_string())?;
    let pace = match (c.pace, &c.path) {
        (Some(_), None) => return Err("`pace` is given without a `path`".into()),
        (Some(p), _) if !(2..=MAX_KEY_FRAMES as u32).contains(&p) => {
            return Err(format!("`pace` {p} is outside 2..={MAX_KEY_FRAMES}"))
        }
        (p, _) => p,
    };
    let path = match &c.path {
        None => None,
        Some(keys) if keys.is_empty() => return Err("`path` has no key frames".into()),
        Some(keys) if keys.len() > MAX_KEY_FRAMES => {
            return Err(format!(
                "`path` has {} key frames, more than the limit of {MAX_KEY_FRAMES}",
                keys.len()
            ))
        }
        Some(keys) => {
            let mut out = Vec::with_capacity(keys.len());
            for (i, k) in keys.iter().enumerate() {
                let key = CameraKey {
                    eye: finite3(k.eye, &format!("path[{i}].eye"))?,
                    target: finite3(k.target, &format!("path[{i}].target"))?,
                };
                let mut check = camera;
                (check.eye, check.target) = (key.eye, key.target);
                check.validate().map_err(|e| format!("path[{i}]: {e}"))?;
                out.push(key);
            }
            Some(CameraPath { keys: out, pace })
        }
    };
    Ok((camera, path))
}

/// The camera's projection: perspective unless `projection = "orthographic"`, which takes
/// `ymag` (half the viewed height) and `xmag` (half the width; default `ymag` times the
/// image's aspect) instead of `fov_y_deg`.
fn projection(c: &CameraSpec) -> Msg<Projection> {
    match c.projection.unwrap_or(ProjectionKind::Perspective) {
        ProjectionKind::Perspective => {
            if c.xmag.is_some() || c.ymag.is_some() {
                return Err(
                    "`xmag` and `ymag` belong to projection = \"orthographic\"; a perspective camera takes `fov_y_deg`".into(),
                );
            }
            Ok(Projection::Perspective)
        }
        ProjectionKind::Orthographic => {
            if c.fov_y_deg.is_some() {
                return Err(
                    "`fov_y_deg` belongs to a perspective camera; an orthographic one takes `ymag` (and `xmag`)".into(),
                );
            }
            let ymag = c
                .ymag
                .ok_or("projection = \"orthographic\" needs `ymag`, half the viewed height")?;
            let aspect = c.width.unwrap_or(1024) as f32 / c.height.unwrap_or(768).max(1) as f32;
            let xmag = c.xmag.unwrap_or(ymag * aspect);
            Ok(Projection::Orthographic { xmag, ymag })
        }
    }
}

/// The `[light]` section: a directional, spot or point light, refusing the keys that do
/// not apply to its kind.
pub(super) fn light(l: &LightSpec) -> Msg<Light> {
    let kind = match l.kind {
        LightKind::Directional => "directional",
        LightKind::Spot => "spot",
        LightKind::Point => "point",
        LightKind::Rect | LightKind::Disk | LightKind::Sphere => {
            return Err("an area light has no punctual form here".into())
        }
    };
    let reject = |key: &str, given: bool| -> Msg<()> {
        if given {
            Err(format!("`{key}` does not apply to a {kind} light"))
        } else {
            Ok(())
        }
    };
    let light = match l.kind {
        LightKind::Directional => {
            reject("position", l.position.is_some())?;
            reject("target", l.target.is_some())?;
            reject("fov_deg", l.fov_deg.is_some())?;
            let to_light = match (l.direction, l.to_light) {
                (Some(d), None) => -finite3(d, "direction")?,
                (None, Some(t)) => finite3(t, "to_light")?,
                _ => {
                    return Err(
                        "a directional light takes exactly one of `direction` and `to_light`"
                            .into(),
                    )
                }
            };
            if to_light.length_squared() == 0.0 {
                return Err("the light direction is the zero vector".into());
            }
            Light::Directional {
                to_light: to_light.normalize(),
            }
        }
        LightKind::Spot => {
            reject("to_light", l.to_light.is_some())?;
            let position = finite3(
                l.position.ok_or("a spot light needs `position`")?,
                "position",
            )?;
            let target = match (l.target, l.direction) {
                (Some(t), None) => finite3(t, "target")?,
                (None, Some(d)) => position + finite3(d, "direction")?,
                _ => {
                    return Err("a spot light takes exactly one of `target` and `direction`".into())
                }
            };
            Light::Spot {
                position,
                target,
                fov_deg: l.fov_deg.ok_or("a spot light needs `fov_deg`")?,
            }
        }
        LightKind::Rect | LightKind::Disk | LightKind::Sphere => {
            return Err("an area light has no punctual form here".into())
        }
        LightKind::Point => {
            reject("direction", l.direction.is_some())?;
            reject("to_light", l.to_light.is_some())?;
            reject("target", l.target.is_some())?;
            reject("fov_deg", l.fov_deg.is_some())?;
            Light::Point {
                position: finite3(
                    l.position.ok_or("a point light needs `position`")?,
                    "position",
                )?,
            }
        }
    };
    light.validate().map_err(|e| e.to_string())?;
    Ok(light)
}

/// The `[light]` section with its area: an area light (`rect`, `disk`, `sphere`) and its
/// punctual stand-in, a punctual light given a `size` and the area light it becomes, or a
/// punctual light alone. Keys that do not apply to the kind are refused.
pub(super) fn light_with_area(l: &LightSpec) -> Msg<(Light, Option<AreaLight>)> {
    let area_keys = [
        ("centre", l.centre.is_some()),
        ("edge_u", l.edge_u.is_some()),
        ("edge_v", l.edge_v.is_some()),
        ("normal", l.normal.is_some()),
        ("radius", l.radius.is_some()),
    ];
    let punctual_keys = [
        ("direction", l.direction.is_some()),
        ("to_light", l.to_light.is_some()),
        ("position", l.position.is_some()),
        ("target", l.target.is_some()),
        ("fov_deg", l.fov_deg.is_some()),
        ("size", l.size.is_some()),
    ];
    let refuse = |keys: &[(&str, bool)], kind: &str| -> Msg<()> {
        match keys.iter().find(|k| k.1) {
            Some((key, _)) => Err(format!("`{key}` does not apply to a {kind} light")),
            None => Ok(()),
        }
    };
    let need = |v: Option<V3>, key: &str, kind: &str| -> Msg<crate::math::Vec3> {
        finite3(v.ok_or(format!("a {kind} light needs `{key}`"))?, key)
    };
    let area = match l.kind {
        LightKind::Directional | LightKind::Spot | LightKind::Point => {
            refuse(&area_keys, "punctual")?;
            let light = light(l)?;
            return match l.size {
                None => Ok((light, None)),
                Some(size) => {
                    let a = AreaLight::sized(&light, size)
                        .map_err(|e| format!("`size` {size}: {e}"))?;
                    Ok((light, Some(a)))
                }
            };
        }
        LightKind::Rect => {
            refuse(&punctual_keys, "rect")?;
            refuse(&area_keys[3..], "rect")?;
            AreaLight::Rect {
                centre: need(l.centre, "centre", "rect")?,
                edge_u: need(l.edge_u, "edge_u", "rect")?,
                edge_v: need(l.edge_v, "edge_v", "rect")?,
            }
        }
        LightKind::Disk => {
            refuse(&punctual_keys, "disk")?;
            refuse(&area_keys[1..3], "disk")?;
            AreaLight::Disk {
                centre: need(l.centre, "centre", "disk")?,
                normal: need(l.normal, "normal", "disk")?,
                radius: l.radius.ok_or("a disk light needs `radius`")?,
            }
        }
        LightKind::Sphere => {
            refuse(&punctual_keys, "sphere")?;
            refuse(&area_keys[1..4], "sphere")?;
            AreaLight::Sphere {
                centre: need(l.centre, "centre", "sphere")?,
                radius: l.radius.ok_or("a sphere light needs `radius`")?,
            }
        }
    };
    area.validate().map_err(|e| e.to_string())?;
    let area = area.normalized();
    Ok((area.punctual(), Some(area)))
}
