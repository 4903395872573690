//! `afsm` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `afsm` technique.
#[derive(Clone, Debug, Default)]
pub struct AliasFree;

impl ShadowTechnique for AliasFree {
    fn name(&self) -> &'static str {
        "afsm"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("afsm", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique afsm is not available yet"))
    }
}
