//! `asm` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `asm` technique.
#[derive(Clone, Debug, Default)]
pub struct Adaptive;

impl ShadowTechnique for Adaptive {
    fn name(&self) -> &'static str {
        "asm"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("asm", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique asm is not available yet"))
    }
}
