//! `--script FILE`: a session of key presses and mouse drags played instead of a person,
//! one step a line, so that what the window shows can be tested. `#` starts a comment.
//!
//! ```text
//! key NAME [N]          press and release NAME (N times); names as in `input`
//! hold NAME FRAMES      hold a flight key (w a s d e q) down for FRAMES frames
//! drag BUTTON DX DY     drag with the left (turn the camera) or right (turn the light)
//!                       mouse button by DX, DY pixels
//! frames N              let N frames pass (a progressive technique refines)
//! wait-reference        show the error against the reference and wait until it is ready
//! screenshot PATH       write the window as PATH (PNG) and PATH's .json: the view's and
//!                       the overlays' rectangles, the widgets', and the `render` command
//!                       line of the view
//! click LABEL           click the panel's widget LABEL where the last frame drew it: the
//!                       pointer's press, release and a frame for what it opened; a
//!                       widget scrolled out of view is scrolled to first
//! type TEXT             into the widget with the keyboard: select all, TEXT, Enter
//! ```
//!
//! Labels: `cpu technique` and `gpu technique` (the pickers; once open, each technique by
//! its name), each parameter's key (its field) and `KEY slider`, `KEY=WORD` in an open
//! choice, `directional` `point` `spot` `area` (then `disk` `rect` `sphere` `sun` and
//! `area size`), `light x` `light y` `light z`, `error overlay`,
//! `technique view` (then `view NAME`, `view shadow map N`, `view none`), `screenshot`,
//! `copy command line`.

use super::input::{Drag, Key, Move};
use crate::failure::bad_input;
use crate::output::{self, Planned};
use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// The largest script file read.
pub const MAX_SCRIPT_BYTES: u64 = 1 << 20;

/// The most frames or presses one line may ask for.
pub const MAX_COUNT: usize = 100_000;

/// The largest drag in pixels along an axis.
pub const MAX_DRAG: f32 = 100_000.0;

/// One step of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// A press and release.
    Key(Key),
    /// A flight key held for this many frames.
    Hold(Move, usize),
    /// A drag by (dx, dy) pixels.
    Drag(Drag, f32, f32),
    /// Frames to let pass.
    Frames(usize),
    /// Show the error overlay and wait for it.
    WaitReference,
    /// Write a screenshot.
    Screenshot(PathBuf),
    /// Click the widget with this label.
    Click(String),
    /// Type this text into the widget that has the keyboard, then Enter.
    Type(String),
    /// The second frame of a click: the button released at (x, y).
    Release(f32, f32),
    /// A frame for what a click opened (a picker's list).
    Settle,
}

/// Reads and checks the script at `path`; its screenshots may replace files only with
/// `force`.
pub fn load(path: &Path, force: bool) -> Result<VecDeque<Step>> {
    let bytes = shadowlab::files::read_sniffed(path, MAX_SCRIPT_BYTES, |h| {
        shadowlab::files::sniff_text(h, "a script")
    })
    .map_err(|e| match e {
        shadowlab::files::Unread::File(why) => {
            bad_input(format!("--script {} {why}", path.display()))
        }
        shadowlab::files::Unread::Format(what) => {
            bad_input(format!("--script {}: {what}", path.display()))
        }
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        bad_input(format!(
            "--script {} is not UTF-8 text (byte {} is invalid)",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })?;
    let steps = parse(&text).with_context(|| format!("--script {}", path.display()))?;
    let mut planned = Vec::new();
    for s in &steps {
        if let Step::Screenshot(p) = s {
            planned.push(Planned::new(p, "a script's screenshot", &["png"]));
            planned.push(Planned::new(
                &p.with_extension("json"),
                "a script's screenshot (its command line)",
                &[],
            ));
        }
    }
    output::check(&planned, force)?;
    Ok(steps)
}

/// Parses a script's text.
pub fn parse(text: &str) -> Result<VecDeque<Step>> {
    let mut steps = VecDeque::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        parse_line(&words, &mut steps).with_context(|| format!("line {} ({line:?})", i + 1))?;
    }
    Ok(steps)
}

/// Appends the steps of one line.
fn parse_line(words: &[&str], steps: &mut VecDeque<Step>) -> Result<()> {
    match words {
        ["key", name] => steps.push_back(Step::Key(key(name)?)),
        ["key", name, n] => {
            let k = key(name)?;
            for _ in 0..count(n)? {
                steps.push_back(Step::Key(k));
            }
        }
        ["hold", name, n] => match key(name)? {
            Key::Move(m) => steps.push_back(Step::Hold(m, count(n)?)),
            _ => {
                return Err(bad_input(format!(
                    "{name} is not a flight key (w, a, s, d, e, q), the only keys held"
                )))
            }
        },
        ["drag", button, dx, dy] => {
            let d = Drag::from_name(button).ok_or_else(|| {
                bad_input(format!("{button:?} is not a mouse button: left or right"))
            })?;
            steps.push_back(Step::Drag(d, pixels(dx)?, pixels(dy)?));
        }
        ["frames", n] => steps.push_back(Step::Frames(count(n)?)),
        ["wait-reference"] => steps.push_back(Step::WaitReference),
        ["screenshot", path] => steps.push_back(Step::Screenshot(PathBuf::from(path))),
        ["click", label @ ..] if !label.is_empty() => {
            steps.push_back(Step::Click(label.join(" ")));
        }
        ["type", text @ ..] if !text.is_empty() => steps.push_back(Step::Type(text.join(" "))),
        _ => {
            return Err(bad_input(
                "not a step: key NAME [N], hold NAME FRAMES, drag left|right DX DY, frames N, wait-reference, screenshot PATH, click LABEL or type TEXT",
            ))
        }
    }
    Ok(())
}

fn key(name: &str) -> Result<Key> {
    Key::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = super::input::KEYS.iter().map(|(n, _)| *n).collect();
        bad_input(format!(
            "unknown key {name:?}: known keys are {}",
            names.join(" ")
        ))
    })
}

fn count(s: &str) -> Result<usize> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(bad_input(format!(
            "{s:?} is not a count in 1..={MAX_COUNT}"
        ))),
    }
}

fn pixels(s: &str) -> Result<f32> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_DRAG => Ok(v),
        _ => Err(bad_input(format!(
            "{s:?} is not a distance in pixels within ±{MAX_DRAG}"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_step_parses_and_bad_lines_name_their_line() {
        let s = parse(
            "# a session\nkey tab 2\nhold w 3\ndrag left 10 -4.5\nframes 2\nwait-reference\nscreenshot a.png # shot\nclick error overlay\ntype 256\n",
        )
        .unwrap();
        assert_eq!(
            Vec::from(s),
            vec![
                Step::Key(Key::NextTechnique),
                Step::Key(Key::NextTechnique),
                Step::Hold(Move::Forward, 3),
                Step::Drag(Drag::Look, 10.0, -4.5),
                Step::Frames(2),
                Step::WaitReference,
                Step::Screenshot(PathBuf::from("a.png")),
                Step::Click("error overlay".into()),
                Step::Type("256".into()),
            ]
        );
        for bad in [
            "key x",
            "hold tab 2",
            "drag middle 1 1",
            "frames 0",
            "frames -1",
            "drag left nan 0",
            "jump",
            "click",
            "type",
        ] {
            let e = parse(&format!("frames 1\n{bad}\n")).unwrap_err();
            assert!(format!("{e:#}").contains("line 2"), "{bad}: {e:#}");
        }
    }
}
