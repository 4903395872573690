//! (being written)
use super::Scene;
use crate::error::{Error, Result};
use std::path::Path;
/// Loads a file.
pub fn load(path: &Path) -> Result<Scene> {
    Err(Error::format(path, "loader not written yet"))
}
