//! glTF materials as shadowlab materials: the base colour factor, and the alpha mode as
//! transmittance (`BLEND` lets `1 − alpha` through; `MASK` and `OPAQUE` block).

use super::{Loader, Skip};
use crate::error::Result;
use crate::math::{vec3, Vec3};
use crate::scene::Material;

impl Loader<'_> {
    /// The scene material for a glTF material, converting it on first use.
    pub(super) fn material(&mut self, m: gltf::Material) -> Result<u32> {
        let Some(index) = m.index() else {
            if let Some(d) = self.default_material {
                return Ok(d);
            }
            let d = self.scene.add_material(Material::default());
            self.default_material = Some(d);
            return Ok(d);
        };
        if let Some(i) = self.materials[index] {
            return Ok(i);
        }
        let [r, g, b, a] = m.pbr_metallic_roughness().base_color_factor();
        let label = match m.name() {
            Some(n) => format!("material {index} ({n:?})"),
            None => format!("material {index}"),
        };
        if ![r, g, b, a].iter().all(|x| x.is_finite()) {
            return Err(self.err(format!("{label}: the base colour factor is not finite")));
        }
        let transmittance = match m.alpha_mode() {
            gltf::material::AlphaMode::Blend => {
                *self.skipped.entry(Skip::Blend).or_default() += 1;
                Vec3::splat(1.0 - a.clamp(0.0, 1.0))
            }
            gltf::material::AlphaMode::Mask => {
                *self.skipped.entry(Skip::Mask).or_default() += 1;
                Vec3::ZERO
            }
            gltf::material::AlphaMode::Opaque => Vec3::ZERO,
        };
        let i = self.scene.add_material(Material {
            name: m
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("material{index}")),
            color: vec3(r, g, b).clamp(Vec3::ZERO, Vec3::ONE),
            transmittance,
        });
        self.materials[index] = Some(i);
        Ok(i)
    }
}
