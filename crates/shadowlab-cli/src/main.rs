//! `shadowlab`: render, compare and benchmark shadow techniques from the command line.
//!
//! Exit codes: 0 on success, 2 for bad input (a file, a flag, a parameter), 1 for other
//! failures. Errors are one sentence on stderr naming the culprit.

mod bench;
mod commands;
mod config;
mod outputs;
mod plots;
mod progress;
mod report;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// A failed allocation ends the run with a sentence and exit status 2, never an abort.
#[global_allocator]
static ALLOC: shadowlab::limits::GuardedAlloc = shadowlab::limits::GuardedAlloc;

/// Shadow algorithms — alias-free, adaptive, sub-pixel, perspective and convolution shadow
/// maps beside standard maps, PCF and variance maps, and the ones engines ship (cascaded,
/// light-space perspective, exponential variance and moment shadow maps) — measured
/// against ray tracing. `csm` (or `convolution`) is the convolution shadow map; cascaded
/// shadow maps are `cascaded`.
#[derive(Parser, Debug)]
#[command(name = "shadowlab", version, about, long_about = None)]
pub struct Cli {
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long, global = true)]
    pub threads: Option<usize>,
    /// No progress bars or status lines.
    #[arg(long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render one technique's shadows to an image.
    Render(commands::RenderArgs),
    /// Run several techniques on one frame, measure them against the ray-traced
    /// reference and write a report.
    Compare(commands::CompareArgs),
    /// List the built-in scenes.
    Scenes,
    /// Run a benchmark suite that reproduces a paper's table.
    Bench(bench::BenchArgs),
}

/// Errors that come from the user's input exit with 2; everything else with 1.
fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(se) = cause.downcast_ref::<shadowlab::Error>() {
            return if se.is_bad_input() { 2 } else { 1 };
        }
        if cause.downcast_ref::<commands::BadInput>().is_some() {
            return 2;
        }
        if cause.downcast_ref::<std::io::Error>().is_some() {
            return 1;
        }
    }
    // Configuration errors raised by the command line itself (bail! in config) are input.
    2
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
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
            eprintln!("error: {first} (see shadowlab --help)");
            return ExitCode::from(2);
        }
    };
    progress::set_quiet(cli.quiet);
    if let Some(n) = cli.threads {
        if n == 0 || n > 1024 {
            eprintln!("error: --threads {n} is outside 1..=1024");
            return ExitCode::from(2);
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("error: cannot start {n} threads: {e}");
            return ExitCode::from(1);
        }
    }
    let result = match cli.command {
        None => commands::compare(&commands::CompareArgs::default_run()),
        Some(Command::Render(a)) => commands::render(&a),
        Some(Command::Compare(a)) => commands::compare(&a),
        Some(Command::Scenes) => commands::scenes(),
        Some(Command::Bench(a)) => bench::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One sentence: the chain joined, outermost context first.
            let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", msg.join(": "));
            ExitCode::from(exit_code(&e))
        }
    }
}
