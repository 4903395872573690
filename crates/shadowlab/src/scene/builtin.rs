//! (being written)
use super::Scene;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
/// Generates a built-in scene.
pub fn generate(name: &str, _params: &BTreeMap<String, String>) -> Result<Scene> {
    Err(Error::param(format!("unknown scene {name}")))
}
/// Lists scenes.
pub fn list() -> Vec<(&'static str, &'static str)> {
    Vec::new()
}
