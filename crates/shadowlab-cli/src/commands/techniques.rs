//! `shadowlab techniques [NAME]`: every technique (or the one named) with its parameters.

use crate::config::TechniquesConfig;
use anyhow::Result;

/// Runs `techniques`.
pub fn run(cfg: TechniquesConfig) -> Result<()> {
    for name in &cfg.names {
        let t = shadowlab::techniques::create(name)?;
        println!("{}", t.name());
        for (k, v) in t.params() {
            println!("  {k:<16} {v}");
        }
    }
    Ok(())
}
