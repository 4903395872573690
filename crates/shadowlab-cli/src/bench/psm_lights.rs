//! `psm-lights` (being written).

use super::{BenchArgs, BenchReport};
use anyhow::{bail, Result};

/// Runs the suite.
pub fn run(_a: &BenchArgs) -> Result<BenchReport> {
    bail!("bench suite psm-lights is not available yet")
}
