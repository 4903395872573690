//! `shadowlab`: render, compare and benchmark shadow techniques from the command line.
//!
//! A run flows from the flags as clap parses them (`args`) to a configuration validated
//! before any work (`config`) to the command (`commands`, one module per command). Each
//! module uses only those after it in this list: `commands`, `bench` (the suites),
//! `report`, `sequence` (per-frame references and verdicts of `compare`), `frames`
//! (techniques over the frames of a view), `metrics` (the records
//! written), `config`, `args`, `output` (every file written), `charts`, `progress`,
//! `failure` (exit codes).
//!
//! Exit codes: 0 on success, 2 for bad input (a file, a flag, a parameter, a scene), 1 for
//! other failures (see `failure`). Errors are one sentence on stderr naming the culprit.
//! A closed standard output (`shadowlab scenes | head -1`) ends the run quietly by
//! SIGPIPE, as it ends `cat` or `grep`.

mod args;
mod bench;
mod charts;
mod commands;
mod config;
mod failure;
mod frames;
mod metrics;
mod output;
mod progress;
mod report;
mod sequence;

use args::{Cli, Command, CompareArgs};
use clap::Parser;
use std::process::ExitCode;

/// A failed allocation ends the run with a sentence and exit status 2, never an abort.
#[global_allocator]
static ALLOC: shadowlab::limits::GuardedAlloc = shadowlab::limits::GuardedAlloc;

fn main() -> ExitCode {
    failure::set_signals();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => return usage_error(e),
    };
    progress::set_quiet(cli.quiet);
    // The `gpu:` techniques, created by name wherever a technique is named.
    shadowlab_gpu::register();
    if let Some(name) = &cli.adapter {
        shadowlab_gpu::device::choose_adapter(name);
    }
    match failure::catch_panics(|| run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            failure::say(&format!("error: {}", failure::sentence(&e)));
            ExitCode::from(failure::exit_code(&e))
        }
    }
}

/// Validates the configuration of the command, then runs it.
fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(n) = config::threads(cli.threads)? {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| anyhow::anyhow!("cannot start {n} threads: {e}"))?;
    }
    match cli.command {
        None => commands::compare::run(config::CompareConfig::from_args(
            &CompareArgs::default_run(),
        )?),
        Some(Command::Render(a)) => commands::render::run(config::RenderConfig::from_args(&a)?),
        Some(Command::Compare(a)) => commands::compare::run(config::CompareConfig::from_args(&a)?),
        Some(Command::Scenes) => commands::scenes::run(),
        Some(Command::Techniques(a)) => {
            commands::techniques::run(config::TechniquesConfig::from_args(&a)?)
        }
        Some(Command::Bench(a)) => commands::bench::run(config::BenchConfig::from_args(&a)?),
        Some(Command::View(a)) => commands::view::run(config::ViewConfig::from_args(&a)?),
    }
}

/// What clap refuses: help and version are printed and succeed; anything else is one
/// sentence and exit status 2.
fn usage_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    // One sentence, like every other error; `--help` has the usage.
    let text = e.to_string();
    let first = text
        .lines()
        .next()
        .unwrap_or("invalid arguments")
        .trim_start_matches("error: ");
    failure::say(&format!("error: {first} (see shadowlab --help)"));
    ExitCode::from(failure::BAD_INPUT)
}
