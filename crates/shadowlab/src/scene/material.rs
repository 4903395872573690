//! A group of triangles' surface and shadow-casting properties.

use super::alpha_mask::AlphaMask;
use crate::math::Vec3;
use serde::{Deserialize, Serialize};

/// Surface and shadow-casting properties of a group of triangles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (from the file, or given by a generator).
    pub name: String,
    /// Diffuse albedo, linear RGB in [0, 1].
    pub color: Vec3,
    /// RGB transmittance of light passing *through* the surface: (0,0,0) for an opaque
    /// caster, (0.9, 0.9, 0.9) for a 10%-opaque one.
    pub transmittance: Vec3,
    /// The texture alpha that cuts the triangles out where it is below a cut-off (glTF's
    /// `alphaMode: MASK`); their texture coordinates are [`Scene::uv`](crate::scene::Scene::uv). Not serialized.
    #[serde(skip)]
    pub alpha_mask: Option<AlphaMask>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            color: Vec3::splat(0.8),
            transmittance: Vec3::ZERO,
            alpha_mask: None,
        }
    }
}

impl Material {
    /// An opaque material of colour `color`.
    pub fn opaque(name: &str, color: Vec3) -> Self {
        Material {
            name: name.into(),
            color,
            transmittance: Vec3::ZERO,
            alpha_mask: None,
        }
    }

    /// True when the surface blocks all light.
    pub fn is_opaque(&self) -> bool {
        self.transmittance == Vec3::ZERO
    }
}
