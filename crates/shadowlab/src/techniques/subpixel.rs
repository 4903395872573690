//! `subpixel` (being written).

use super::{unknown_param, Frame, ShadowTechnique, Shadows};
use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The `subpixel` technique.
#[derive(Clone, Debug, Default)]
pub struct Subpixel;

impl ShadowTechnique for Subpixel {
    fn name(&self) -> &'static str {
        "subpixel"
    }
    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::new()
    }
    fn set_param(&mut self, key: &str, _value: &str) -> Result<()> {
        Err(unknown_param("subpixel", key, &[]))
    }
    fn render(&mut self, _frame: &Frame) -> Result<Shadows> {
        Err(Error::param("technique subpixel is not available yet"))
    }
}
