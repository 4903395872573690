//! `csm` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `csm` technique.
#[derive(Clone, Debug, Default)]
pub struct Convolution;

impl ShadowTechnique for Convolution {
    fn name(&self) -> &'static str {
        "csm"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("csm", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique csm is not available yet"))
    }
}
