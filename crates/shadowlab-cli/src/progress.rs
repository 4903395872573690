//! Progress on stderr: a spinner for each long step of unknown length (loading a scene,
//! the camera pass, the reference, writing the report) and a bar over known counts
//! (techniques × frames, benchmark rows, images). Both redraw on a timer, so a step that
//! takes seconds — a million-triangle BVH, say — still shows a moving line and a clock.
//!
//! Drawn only when stderr is a terminal and `--quiet` was not given; otherwise every bar
//! is hidden and costs nothing. A bar dropped on an error path clears itself, so the
//! error sentence is the last thing on the screen.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Redraw period of every spinner and bar: often enough that the terminal never looks
/// still, rare enough to cost nothing against the work it reports.
pub const TICK: Duration = Duration::from_millis(100);

static QUIET: AtomicBool = AtomicBool::new(false);

/// Silences every bar and status line.
pub fn set_quiet(q: bool) {
    QUIET.store(q, Ordering::Relaxed);
}

/// True when progress should be drawn.
pub fn enabled() -> bool {
    !QUIET.load(Ordering::Relaxed) && std::io::stderr().is_terminal()
}

/// True when `--quiet` was given.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

fn target(len: Option<u64>) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(
        len,
        if enabled() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    pb.with_finish(ProgressFinish::AndClear)
}

/// A spinner for one step of unknown length, ticking so the terminal is never still.
pub fn step(msg: impl Into<String>) -> ProgressBar {
    let pb = target(None);
    pb.set_style(
        ProgressStyle::with_template("{spinner:.cyan} {msg} {elapsed:.dim}")
            .expect("valid template")
            .tick_chars("⠋⠙⠹⠸⠼⠴⠦⠧⠇⠏ "),
    );
    pb.set_message(msg.into());
    pb.enable_steady_tick(TICK);
    pb
}

/// A bar over `n` items (techniques × frames, benchmark rows, images); its message names
/// the item in progress. A spinner at its left keeps turning while one item takes long.
pub fn bar(n: u64, msg: impl Into<String>) -> ProgressBar {
    let pb = target(Some(n));
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner:.cyan} [{bar:30.cyan/blue}] {pos}/{len} {msg} {elapsed:.dim}",
        )
        .expect("valid template")
        .tick_chars("⠋⠙⠹⠸⠼⠴⠦⠧⠇⠏ ")
        .progress_chars("=> "),
    );
    pb.set_message(msg.into());
    pb.enable_steady_tick(TICK);
    pb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quiet_hides_every_bar() {
        set_quiet(true);
        assert!(!enabled());
        for pb in [step("x"), bar(3, "y")] {
            assert!(pb.is_hidden());
            pb.inc(1);
            pb.finish_and_clear();
        }
        set_quiet(false);
    }

    #[test]
    fn bar_counts_items() {
        let pb = bar(4, "techniques");
        pb.inc(3);
        assert_eq!(pb.position(), 3);
        assert_eq!(pb.length(), Some(4));
        pb.finish_and_clear();
    }
}
