//! `vsm`: variance shadow maps (Donnelly & Lauritzen, "Variance Shadow Maps", I3D 2006),
//! the filtered-shadow baseline the convolution shadow map paper compares against.
//!
//! The map stores the first two moments of the depth distribution, `z` and `z²`; being
//! linear, they can be blurred and mip-mapped like any texture. A look-up recovers the
//! filtered mean μ and variance σ² = E\[z²\] − μ² and bounds the lit fraction of a receiver at
//! depth `d > μ` with the one-tailed Chebyshev inequality `p_max = σ² / (σ² + (d − μ)²)`.
//!
//! Invariants: moments are of the linear light depth normalized (to `[0, 1]`) over the
//! same fitted interval as `csm`'s (`DepthRange::fitted`), stored as f32; blur, mip chain and look-ups are the shared ones
//! of [`super::filtering`], the same as `csm`'s; `d ≤ μ` is fully lit.
//!
//! As in the paper, the second moment of each texel gets the variance of the depth across
//! the texel, `¼((∂z/∂x)² + (∂z/∂y)²)`, from the depth change to the neighbouring texel on
//! the same triangle (the GPU's `ddx/ddy` in the light pass), which removes acne on slopes
//! without a depth bias; a floor on σ² ([`DEFAULT_MIN_VARIANCE`]) absorbs f32 cancellation.
//! The optional light-bleeding reduction (Lauritzen, GPU Gems 3, ch. 8) maps `p_max`
//! through `clamp((p − amount) / (1 − amount), 0, 1)`; it is off by default so `vsm` is the
//! plain baseline.
//!
//! Known artifacts: light bleeding — the bound is exact only for one planar occluder over
//! a planar receiver; where a filter region holds a near occluder, the receiver and a
//! farther surface (high depth complexity: a fence in front of other objects), σ² grows and
//! the shadow lightens. Reduction darkens penumbrae. Point-light cube faces filter up to
//! their own edges only.

use super::filtering::{DepthRange, FilterSettings, FilteredMaps, MapLayout};
use super::shadow_map::{check_resolution, DEFAULT_RESOLUTION};
use super::{
    find_param, in_key_order, not_read, param_value, parse_value, Frame, ParamSpec,
    ShadowTechnique, Shadows, Stats, RESOLUTION,
};
use crate::error::Result;
use crate::raster::{DepthBuffer, NO_TRIANGLE};
use std::collections::BTreeMap;

/// Default floor on the variance, in normalized depth squared (σ ≥ 10⁻³ of the depth
/// range): ten times the f32 cancellation error of `E[z²] − μ²` (≈ 10⁻⁷) so lit planes do
/// not speckle; larger floors soften contact shadows and leak more light.
pub const DEFAULT_MIN_VARIANCE: f32 = 1e-6;
/// Default light-bleeding reduction: none (the original VSM).
pub const DEFAULT_BLEED_REDUCTION: f32 = 0.0;

/// The `vsm` technique.
#[derive(Clone, Debug)]
pub struct Variance {
    /// Map side in texels.
    pub resolution: u32,
    /// Floor on the variance, normalized depth squared.
    pub min_variance: f32,
    /// Light-bleeding reduction amount in `[0, 1)`.
    pub bleed_reduction: f32,
    /// Blur, mip-mapping and look-up filter.
    pub filtering: FilterSettings,
}

impl Default for Variance {
    fn default() -> Self {
        Variance {
            resolution: DEFAULT_RESOLUTION,
            min_variance: DEFAULT_MIN_VARIANCE,
            bleed_reduction: DEFAULT_BLEED_REDUCTION,
            filtering: FilterSettings::default(),
        }
    }
}

/// The parameters of vsm's own, beside the filtering ones.
const OWN: &[ParamSpec] = &[BLEED_REDUCTION, MIN_VARIANCE, RESOLUTION];

/// The light-bleeding reduction of vsm and evsm.
pub const BLEED_REDUCTION: ParamSpec = ParamSpec::real(
    "bleed-reduction",
    0.0,
    0.99,
    "lit fractions below this become 0 and the rest are rescaled: less light bleeding, darker penumbrae",
);
/// The variance floor of vsm and evsm.
pub const MIN_VARIANCE: ParamSpec = ParamSpec::real(
    "min-variance",
    0.0,
    1.0,
    "smallest variance the Chebyshev bound uses, against acne on flat receivers",
);

/// Chebyshev's upper bound on the lit fraction of a receiver at depth `d`, from the filtered
/// moments `(μ, E[z²])`, with the variance floored at `min_variance` and the light-bleeding
/// reduction `reduction` applied.
#[inline]
pub fn chebyshev(d: f32, mean: f32, second: f32, min_variance: f32, reduction: f32) -> f32 {
    if d <= mean {
        return 1.0;
    }
    if !(mean.is_finite() && second.is_finite() && d.is_finite()) {
        // Moments that are not finite carry no occlusion information (seen on degenerate
        // frames found by fuzzing); never let them turn into a NaN shadow term.
        return 1.0;
    }
    let var = (second - mean * mean).max(min_variance);
    let t = d - mean;
    let p = var / (var + t * t);
    if reduction > 0.0 {
        ((p - reduction) / (1.0 - reduction)).clamp(0.0, 1.0)
    } else {
        p
    }
}

/// The normalized depth of texel `(x, y)` of `m` and the variance of the depth across the
/// texel, `¼((∂z/∂x)² + (∂z/∂y)²)`, from the depth change to the neighbouring texel on the
/// same triangle (0 across silhouettes, where it is not defined); see the module doc.
pub fn texel_depth_and_variance(m: &DepthBuffer, r: &DepthRange, x: u32, y: u32) -> (f32, f32) {
    let w = m.width;
    let k = (y * w + x) as usize;
    let z = r.normalize(m.depth[k]);
    let id = m.id[k];
    // Depth change per texel on this texel's own triangle, towards whichever neighbour
    // shares it.
    let slope = |nb: Option<usize>, other: Option<usize>| -> f32 {
        for (j, sign) in [(nb, 1.0f32), (other, -1.0)] {
            if let Some(j) = j {
                if id != NO_TRIANGLE && m.id[j] == id {
                    return sign * (r.normalize(m.depth[j]) - z);
                }
            }
        }
        0.0
    };
    let dx = slope((x + 1 < w).then(|| k + 1), (x > 0).then(|| k - 1));
    let dy = slope(
        (y + 1 < m.height).then(|| k + w as usize),
        (y > 0).then(|| k - w as usize),
    );
    (z, 0.25 * (dx * dx + dy * dy))
}

impl ShadowTechnique for Variance {
    fn name(&self) -> &'static str {
        "vsm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        let mut m = BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("min-variance".to_string(), param_value(self.min_variance)),
            (
                "bleed-reduction".to_string(),
                param_value(self.bleed_reduction),
            ),
        ]);
        self.filtering.params(&mut m);
        m
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        in_key_order([OWN, &FilterSettings::SPECS].concat())
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "vsm";
        let spec = find_param(t, &self.param_specs(), key)?;
        if self.filtering.set_param(t, key, value)? {
            return Ok(());
        }
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "min-variance" => self.min_variance = spec.f32(t, value)?,
            "bleed-reduction" => self.bleed_reduction = spec.f32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let layout = MapLayout {
            technique: "vsm",
            resolution: check_resolution("vsm", self.resolution)?,
            channels: 2,
            span: 1.0,
        };
        let mut stats = Stats::default();
        let (min_var, reduction) = (self.min_variance, self.bleed_reduction);
        let (maps, value) = FilteredMaps::<f32>::shade_texels(
            frame,
            &layout,
            &self.filtering,
            &mut stats,
            |m, r, x, y, out| {
                let (z, var) = texel_depth_and_variance(m, r, x, y);
                out[0] = z;
                out[1] = z * z + var;
            },
            |d, mo| chebyshev(d, mo[0], mo[1], min_var, reduction),
        )?;
        stats.count("mip_levels", maps.mip_levels() as f64);
        Ok(Shadows::of_frame(frame, value, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chebyshev_is_exact_for_two_depths_with_the_receiver_behind() {
        // A fraction w of the filter region at depth 0.2, the rest at the receiver's 0.6:
        // the lit fraction is 1 − w, and the one-tailed bound reaches it.
        for w in [0.1f32, 0.5, 0.9] {
            let mean = w * 0.2 + (1.0 - w) * 0.6;
            let second = w * 0.04 + (1.0 - w) * 0.36;
            assert!((chebyshev(0.6, mean, second, 0.0, 0.0) - (1.0 - w)).abs() < 1e-4);
        }
        assert_eq!(chebyshev(0.1, 0.3, 0.09, DEFAULT_MIN_VARIANCE, 0.0), 1.0);
    }

    #[test]
    fn bleed_reduction_cuts_the_low_tail() {
        assert_eq!(chebyshev(0.6, 0.5, 0.2501, 0.0, 0.5), 0.0);
        assert!(chebyshev(0.6, 0.5, 0.26, 0.0, 0.2) < chebyshev(0.6, 0.5, 0.26, 0.0, 0.0));
    }
}
