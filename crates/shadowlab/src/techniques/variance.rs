//! `vsm` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `vsm` technique.
#[derive(Clone, Debug, Default)]
pub struct Variance;

impl ShadowTechnique for Variance {
    fn name(&self) -> &'static str {
        "vsm"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("vsm", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique vsm is not available yet"))
    }
}
