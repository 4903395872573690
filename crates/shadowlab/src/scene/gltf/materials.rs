//! glTF materials as shadowlab materials: the base colour factor, and the alpha mode as
//! transmittance (`BLEND` lets `1 − alpha` through; `OPAQUE` blocks) or as an alpha mask
//! (`MASK`: the base colour texture's alpha times the factor's, against `alphaCutoff`).

use super::{Loader, Skip};
use crate::error::Result;
use crate::math::{vec3, Vec3};
use crate::scene::alpha_mask::{AlphaMask, AlphaTexture, Wrap};
use crate::scene::Material;
use std::sync::Arc;

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
            gltf::material::AlphaMode::Mask => Vec3::ZERO,
            gltf::material::AlphaMode::Opaque => Vec3::ZERO,
        };
        let alpha_mask = match m.alpha_mode() {
            gltf::material::AlphaMode::Mask => self.alpha_mask(&m, a, &label),
            _ => None,
        };
        let i = self.scene.add_material(Material {
            name: m
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("material{index}")),
            color: vec3(r, g, b).clamp(Vec3::ZERO, Vec3::ONE),
            transmittance,
            alpha_mask,
        });
        self.materials[index] = Some(i);
        Ok(i)
    }
}

impl Loader<'_> {
    /// The alpha mask of `MASK` material `m` (base colour factor alpha `a`): its base colour
    /// texture's alpha, or a constant `a` without a texture. A texture that cannot be read
    /// leaves the material opaque, counted in the warnings with the reason.
    fn alpha_mask(&mut self, m: &gltf::Material, a: f32, label: &str) -> Option<AlphaMask> {
        let cutoff = m.alpha_cutoff().unwrap_or(0.5);
        let factor = a.clamp(0.0, 1.0);
        let Some(info) = m.pbr_metallic_roughness().base_color_texture() else {
            return Some(AlphaMask {
                texture: Arc::new(AlphaTexture {
                    width: 1,
                    height: 1,
                    alpha: vec![255],
                }),
                factor,
                cutoff,
                wrap_u: Wrap::Repeat,
                wrap_v: Wrap::Repeat,
            });
        };
        let tex = info.texture();
        let image = tex.source();
        match self.alpha_texture(&image) {
            Ok(texture) => {
                let wrap = |w: gltf::texture::WrappingMode| match w {
                    gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
                    gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
                    gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
                };
                let sampler = tex.sampler();
                Some(AlphaMask {
                    texture,
                    factor,
                    cutoff,
                    wrap_u: wrap(sampler.wrap_s()),
                    wrap_v: wrap(sampler.wrap_t()),
                })
            }
            Err(why) => {
                *self.skipped.entry(Skip::Mask).or_default() += 1;
                self.notes.push(format!(
                    "{label}: image {} of its base colour texture cannot be read: {why}",
                    image.index()
                ));
                None
            }
        }
    }
}
