//! The parameters every filtered technique shares: blur kernel, look-up filter and
//! anisotropy.

use super::blur::{blur, parse_blur};
use super::lookup::{Filter, DEFAULT_ANISOTROPY, MAX_ANISOTROPY};
use super::mip::MipChain;
use super::texture::{Channel, Texture};
use crate::error::Result;

/// Blur, mip-mapping and look-up settings shared by the filtered techniques.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSettings {
    /// Blur kernel side (0 = none).
    pub blur: u32,
    /// Look-up filter.
    pub filter: Filter,
    /// Most probes of an anisotropic look-up.
    pub max_aniso: u32,
}

impl Default for FilterSettings {
    fn default() -> Self {
        FilterSettings {
            blur: 0,
            filter: Filter::Anisotropic,
            max_aniso: DEFAULT_ANISOTROPY,
        }
    }
}

impl FilterSettings {
    /// The parameter keys these settings answer to.
    pub const KEYS: [&'static str; 3] = ["blur", "filter", "max-aniso"];

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
    }

    /// Sets one of the keys in [`Self::KEYS`]; `Ok(false)` when `key` is not one of them.
    pub fn set_param(&mut self, technique: &str, key: &str, value: &str) -> Result<bool> {
        match key {
            "blur" => self.blur = parse_blur(technique, value)?,
            "filter" => self.filter = Filter::parse(technique, value)?,
            "max-aniso" => {
                let v = super::super::technique::parse_value(technique, key, value)?;
                self.max_aniso =
                    super::super::technique::check_range(technique, key, v, 1, MAX_ANISOTROPY)?;
            }
            _ => return Ok(false),
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
