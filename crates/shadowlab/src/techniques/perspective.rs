//! `psm` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `psm` technique.
#[derive(Clone, Debug, Default)]
pub struct Perspective;

impl ShadowTechnique for Perspective {
    fn name(&self) -> &'static str {
        "psm"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("psm", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique psm is not available yet"))
    }
}
