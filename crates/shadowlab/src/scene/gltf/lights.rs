//! `KHR_lights_punctual` lights as shadowlab lights: directional, point and spot, placed
//! by their node's transform.

use super::MAX_SPOT_FOV_DEG;
use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::{Mat4, Vec3};
use std::path::Path;

/// The scene light for `KHR_lights_punctual` light `index` on a node with world transform
/// `world`, with a note of what of it is ignored.
pub(super) fn convert_light(
    path: &Path,
    doc: &gltf::Document,
    index: usize,
    world: Mat4,
) -> Result<(Light, Option<String>)> {
    let fmt = |what: String| Error::format(path, what);
    let light = doc
        .lights()
        .and_then(|mut l| l.nth(index))
        .ok_or_else(|| fmt(format!("light {index} does not exist")))?;
    let position = world.transform_point3(Vec3::ZERO);
    let dir = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let mut note = None;
    let out = match light.kind() {
        gltf::khr_lights_punctual::Kind::Directional => Light::Directional { to_light: -dir },
        gltf::khr_lights_punctual::Kind::Point => Light::Point { position },
        gltf::khr_lights_punctual::Kind::Spot {
            outer_cone_angle,
            inner_cone_angle,
        } => {
            let half_pi = std::f32::consts::FRAC_PI_2;
            if !(outer_cone_angle > 0.0 && outer_cone_angle <= half_pi) {
                return Err(fmt(format!(
                    "light {index}: outerConeAngle {outer_cone_angle} rad is outside (0, π/2]"
                )));
            }
            if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer_cone_angle) {
                return Err(fmt(format!(
                    "light {index}: innerConeAngle {inner_cone_angle} rad is outside [0, outerConeAngle)"
                )));
            }
            note = Some(format!(
                "spot light {index}: its inner cone ({:.1}°) is ignored, the light reaching the whole outer cone ({:.1}°): the falloff between them shades, it does not change a shadow",
                inner_cone_angle.to_degrees(),
                outer_cone_angle.to_degrees()
            ));
            Light::Spot {
                position,
                target: position + dir,
                fov_deg: (2.0 * outer_cone_angle).to_degrees().min(MAX_SPOT_FOV_DEG),
            }
        }
    };
    if matches!(out, Light::Directional { .. } | Light::Spot { .. }) && dir == Vec3::ZERO {
        return Err(fmt(format!(
            "light {index}: its node's transform is degenerate"
        )));
    }
    out.validate()
        .map_err(|e| fmt(format!("light {index}: {e}")))?;
    Ok((out, note))
}
