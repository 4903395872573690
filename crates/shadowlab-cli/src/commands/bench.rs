//! `shadowlab bench SUITE`: runs one of the suites that reproduce the papers' tables (each
//! prints its own table) and, with `--json`, writes its rows as
//! `{"suite", "machine", "rows"}`.

use crate::bench::{self, afsm_scaling, asm_walkthrough, csm_table, engines, psm_lights};
use crate::bench::{engines_gpu, gpu, soft_exact, subpixel_scaling, BenchReport};
use crate::config::{BenchConfig, Suite};
use crate::output;
use anyhow::Result;
use serde_json::json;

/// Runs `bench`.
pub fn run(cfg: BenchConfig) -> Result<()> {
    let report: BenchReport = match cfg.suite {
        Suite::AfsmScaling => afsm_scaling::run(&cfg)?,
        Suite::SubpixelScaling => subpixel_scaling::run(&cfg)?,
        Suite::CsmTable => csm_table::run(&cfg)?,
        Suite::AsmWalkthrough => asm_walkthrough::run(&cfg)?,
        Suite::PsmLights => psm_lights::run(&cfg)?,
        Suite::Engines if cfg.gpu => engines_gpu::run(&cfg)?,
        Suite::Engines => engines::run(&cfg)?,
        Suite::SoftExact => soft_exact::run(&cfg)?,
        Suite::Gpu => gpu::run(&cfg)?,
    };
    if let Some(p) = &cfg.json {
        output::write_json(
            p,
            &json!({"suite": cfg.suite.name(), "machine": bench::machine(), "rows": report.rows}),
        )?;
    }
    Ok(())
}
