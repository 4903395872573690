//! The parameters every filtered technique shares: blur kernel, look-up filter and
//! anisotropy.

use super::blur::MAX_BLUR;
use super::blur::{blur, parse_blur};
use super::lookup::{Filter, DEFAULT_ANISOTROPY, MAX_ANISOTROPY};
use super::mip::MipChain;
use super::texture::{Channel, Texture};
use crate::error::Result;
use crate::techniques::technique::{find_param, ParamSpec};

/// Blur, mip-mapping and look-up settings shared by the filtered techniques.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSettings {
    /// Blur kernel side (0 = none).
    pub blur: u32,
    /// Look-up filter.
    pub filter: Filter,
    /// Most probes of an anisotropic look-up.
    pub max_aniso: u32,
    /// Soft shadows: each pixel's filter is widened to the penumbra a blocker search
    /// estimates (see [`super::blocker_search`]) under the frame's area light.
    pub soft: bool,
}

impl Default for FilterSettings {
    fn default() -> Self {
        FilterSettings {
            blur: 0,
            filter: Filter::Anisotropic,
            max_aniso: DEFAULT_ANISOTROPY,
            soft: false,
        }
    }
}

impl FilterSettings {
    /// The parameters these settings answer to, in key order.
    pub const SPECS: [ParamSpec; 4] = [
        ParamSpec::int(
            "blur",
            0,
            MAX_BLUR as i64,
            "side of the separable binomial blur of the map, odd, or none (0 and 1 too)",
        ),
        ParamSpec::choice(
            "filter",
            &["bilinear", "trilinear", "anisotropic"],
            "look-up filter: bilinear on the full map, tri-linear mip-mapped, or anisotropic",
        ),
        ParamSpec::int(
            "max-aniso",
            1,
            MAX_ANISOTROPY as i64,
            "most tri-linear probes of one anisotropic look-up (the paper's 16)",
        ),
        ParamSpec::flag(
            "soft",
            "widen each pixel's filter to the penumbra a PCSS blocker search estimates under the area light (the -soft variants); needs a mip-mapped filter",
        ),
    ];

    /// Adds the settings to a technique's parameter list.
    pub fn params(&self, m: &mut std::collections::BTreeMap<String, serde_json::Value>) {
        let blur = if self.blur == 0 {
            serde_json::Value::from("none")
        } else {
            self.blur.into()
        };
        m.insert("blur".into(), blur);
        m.insert("filter".into(), self.filter.name().into());
        m.insert("max-aniso".into(), self.max_aniso.into());
        m.insert("soft".into(), self.soft.into());
    }

    /// Sets one of the keys in [`Self::SPECS`]; `Ok(false)` when `key` is not one of them.
    pub fn set_param(&mut self, technique: &str, key: &str, value: &str) -> Result<bool> {
        if !Self::SPECS.iter().any(|s| s.key == key) {
            return Ok(false);
        }
        let spec = find_param(technique, &Self::SPECS, key)?;
        match key {
            "blur" => self.blur = parse_blur(technique, value)?,
            "filter" => self.filter = Filter::parse(technique, value)?,
            "soft" => self.soft = spec.bool(technique, value)?,
            _ => self.max_aniso = spec.u32(technique, value)?,
        }
        Ok(true)
    }

    /// Blurs `base` and builds the chain the look-up filter needs.
    pub fn prefilter<T: Channel>(&self, base: Texture<T>) -> MipChain<T> {
        self.mip_chain(self.blurred(base))
    }

    /// `base` blurred with the kernel in effect (itself without one).
    pub fn blurred<T: Channel>(&self, base: Texture<T>) -> Texture<T> {
        if self.blur > 1 {
            blur(&base, self.blur)
        } else {
            base
        }
    }

    /// The mip chain the look-up filter needs: level 0 alone for bilinear look-ups, else
    /// the full chain.
    pub fn mip_chain<T: Channel>(&self, base: Texture<T>) -> MipChain<T> {
        match self.filter {
            Filter::Bilinear => MipChain::single(base),
            _ => MipChain::build(base),
        }
    }
}
