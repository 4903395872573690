//! Alpha-masked casters: a material whose base-colour texture's alpha cuts its triangles
//! out (glTF's `alphaMode: MASK`). A point of such a triangle is transparent — neither a
//! caster nor a receiver — where `alpha · factor < cutoff`, `alpha` read from the texture
//! at the point's interpolated texture coordinates.
//!
//! Sampling is by the nearest texel (no filtering, no mip-mapping): texel `(i, j)` covers
//! `[i, i+1) × [j, j+1)` in `(u·width, v·height)`, row 0 at `v = 0` (glTF's texture
//! coordinates start at the image's top-left corner). Coordinates outside `[0, 1)` wrap as
//! the texture's sampler says (repeat, mirrored repeat or clamp to the edge). Every
//! technique and the reference ask the same [`AlphaMask::keeps`] at the barycentrics
//! their own exact test produced, so exact techniques agree with the reference on the cut.
//!
//! The texture holds alpha only, 8 bits a texel, shared (by reference) between the
//! materials that use it.

use super::Scene;
use crate::math::{Vec2, Vec3};
use std::sync::Arc;

/// The largest side of an alpha texture, in texels; larger images are refused before they
/// are decoded.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// How texture coordinates outside `[0, 1)` map back into the texture (glTF's wrap modes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// The texture tiles the plane (`REPEAT`, glTF's default).
    #[default]
    Repeat,
    /// The texture tiles the plane, every other copy mirrored (`MIRRORED_REPEAT`).
    MirroredRepeat,
    /// The edge texels extend outwards (`CLAMP_TO_EDGE`).
    ClampToEdge,
}

impl Wrap {
    /// The texel index of coordinate `c` (in texels) on a side of `n` texels.
    #[inline]
    fn texel(self, c: f32, n: u32) -> u32 {
        let i = c.floor();
        let n_f = n as f32;
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n_f),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2.0 * n_f);
                if m < n_f {
                    m
                } else {
                    2.0 * n_f - 1.0 - m
                }
            }
            Wrap::ClampToEdge => i.clamp(0.0, n_f - 1.0),
        };
        // A NaN coordinate (a degenerate triangle's barycentrics) reads texel 0.
        (k as u32).min(n - 1)
    }
}

/// An 8-bit alpha texture, row-major from the top row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AlphaTexture {
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// Alpha of each texel, 0 to 255.
    pub alpha: Vec<u8>,
}

/// A material's cut-out: its texture, the factor the texture's alpha is multiplied by
/// (glTF's base colour factor alpha), the cut-off and the wrap modes.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// The alpha texture, shared by the materials that use it.
    pub texture: Arc<AlphaTexture>,
    /// Multiplies the texture's alpha (in `[0, 1]`).
    pub factor: f32,
    /// A point is kept where `alpha · factor ≥ cutoff` (glTF's `alphaCutoff`, default 0.5).
    pub cutoff: f32,
    /// Wrap mode along `u`.
    pub wrap_u: Wrap,
    /// Wrap mode along `v`.
    pub wrap_v: Wrap,
}

impl AlphaMask {
    /// The alpha (texture times factor) at texture coordinates `uv`, by the nearest texel.
    #[inline]
    pub fn alpha_at(&self, uv: Vec2) -> f32 {
        let t = &self.texture;
        let i = self.wrap_u.texel(uv.x * t.width as f32, t.width);
        let j = self.wrap_v.texel(uv.y * t.height as f32, t.height);
        let a = t.alpha[(j as usize) * t.width as usize + i as usize];
        a as f32 / 255.0 * self.factor
    }

    /// True where the surface is kept (blocks light and is seen): alpha at or above the
    /// cut-off.
    #[inline]
    pub fn keeps(&self, uv: Vec2) -> bool {
        self.alpha_at(uv) >= self.cutoff
    }
}

/// The texture coordinates at barycentrics `b` (weights of the three vertices) of a
/// triangle whose vertices have coordinates `uv`.
#[inline]
pub fn interpolate(uv: &[Vec2; 3], b: [f32; 3]) -> Vec2 {
    uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2]
}

impl Scene {
    /// Appends one triangle with texture coordinates `uv` (see [`Scene::uv`]).
    pub fn push_textured(&mut self, t: [Vec3; 3], uv: [Vec2; 3], material: u32) {
        if self.uv.len() < self.len() {
            self.uv.resize(self.len(), [Vec2::ZERO; 3]);
        }
        self.uv.push(uv);
        self.push_position(t, material);
    }

    /// True when some material is alpha-masked (see [`Scene::cut_out`]).
    pub fn has_alpha_masks(&self) -> bool {
        self.materials.iter().any(|m| m.alpha_mask.is_some())
    }

    /// True when triangle `i` is cut out by its material's alpha mask at barycentrics `b`
    /// (the weights of its three vertices): there it neither casts a shadow nor is seen.
    /// False for every triangle without a mask.
    #[inline]
    pub fn cut_out(&self, i: usize, b: [f32; 3]) -> bool {
        match &self.materials[self.material[i] as usize].alpha_mask {
            None => false,
            Some(m) => !m.keeps(interpolate(&self.uv[i], b)),
        }
    }

    /// [`Scene::cut_out`] at the point `p` of triangle `i`'s plane (for a piece of the
    /// triangle cut by a clip plane, whose own barycentrics are not the triangle's).
    pub fn cut_out_at(&self, i: usize, p: Vec3) -> bool {
        if self.materials[self.material[i] as usize]
            .alpha_mask
            .is_none()
        {
            return false;
        }
        let [v0, v1, v2] = self.triangle(i);
        let (e1, e2, d) = (v1 - v0, v2 - v0, p - v0);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d20, d21) = (d.dot(e1), d.dot(e2));
        let den = d00 * d11 - d01 * d01;
        let b1 = (d11 * d20 - d01 * d21) / den;
        let b2 = (d00 * d21 - d01 * d20) / den;
        self.cut_out(i, [1.0 - b1 - b2, b1, b2])
    }

    /// The part of [`Scene::validate`] about masks: texture coordinates for every
    /// triangle, finite, and usable textures and cut-offs.
    pub(super) fn validate_alpha_masks(&self) -> Result<(), String> {
        if !self.has_alpha_masks() {
            return Ok(());
        }
        if self.uv.len() != self.len() {
            return Err(format!(
                "it has alpha-masked materials but texture coordinates for {} of its {} triangles",
                self.uv.len(),
                self.len()
            ));
        }
        if !self.uv.iter().flatten().all(|t| t.is_finite()) {
            return Err("a texture coordinate is not finite".into());
        }
        for m in &self.materials {
            if let Some(a) = &m.alpha_mask {
                let t = &a.texture;
                let ok = t.width > 0 && t.alpha.len() == t.width as usize * t.height as usize;
                if !ok || t.alpha.is_empty() || !(a.factor.is_finite() && a.cutoff.is_finite()) {
                    return Err(format!(
                        "material {:?} has an empty alpha texture or a non-finite cut-off",
                        m.name
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::vec2;

    fn mask(wrap: Wrap) -> AlphaMask {
        AlphaMask {
            texture: Arc::new(AlphaTexture {
                width: 2,
                height: 2,
                alpha: vec![255, 0, 128, 127],
            }),
            factor: 1.0,
            cutoff: 0.5,
            wrap_u: wrap,
            wrap_v: wrap,
        }
    }

    #[test]
    fn nearest_texel_from_the_top_left_and_the_cutoff() {
        let m = mask(Wrap::Repeat);
        assert!(m.keeps(vec2(0.25, 0.25)));
        assert!(!m.keeps(vec2(0.75, 0.25)));
        assert!(m.keeps(vec2(0.25, 0.75)), "128/255 ≥ 0.5");
        assert!(!m.keeps(vec2(0.75, 0.75)), "127/255 < 0.5");
        // Texel boundaries belong to the texel on their right and below.
        assert!(!m.keeps(vec2(0.5, 0.0)));
    }

    #[test]
    fn wrap_modes() {
        let r = mask(Wrap::Repeat);
        assert!(r.keeps(vec2(1.25, -0.75)));
        assert!(!r.keeps(vec2(-0.25, 0.25)), "u = −0.25 repeats to 0.75");
        let m = mask(Wrap::MirroredRepeat);
        assert!(m.keeps(vec2(1.75, 0.25)), "u = 1.75 mirrors to 0.25");
        assert!(!m.keeps(vec2(1.25, 0.25)), "u = 1.25 mirrors to 0.75");
        let c = mask(Wrap::ClampToEdge);
        assert!(!c.keeps(vec2(7.0, 0.25)));
        assert!(c.keeps(vec2(-7.0, 0.25)));
        assert!(r.alpha_at(vec2(f32::NAN, f32::NAN)).is_finite());
    }

    #[test]
    fn the_factor_scales_the_texture() {
        let mut m = mask(Wrap::Repeat);
        m.factor = 0.4;
        assert!(!m.keeps(vec2(0.25, 0.25)));
    }
}
