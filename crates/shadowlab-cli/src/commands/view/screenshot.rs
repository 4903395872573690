//! Screenshots: the window as a PNG, and beside it a JSON file with the `render` command
//! line that reproduces the view (also printed) and the rectangles the overlays cover —
//! outside them the screenshot is that command's image, pixel for pixel.

use super::overlay::Rect;
use crate::output;
use anyhow::Result;
use serde::Serialize;
use shadowlab::picture::{self, RgbImage};
use std::path::{Path, PathBuf};

/// The most numbered screenshots the screenshot key writes into one folder.
pub const MAX_NUMBERED: u32 = 9999;

/// The JSON file beside a screenshot.
#[derive(Serialize)]
struct Sidecar<'a> {
    /// The command line to paste into a shell.
    command_line: String,
    /// Its arguments, without the program's name.
    command: &'a [String],
    /// The image the command writes.
    render_output: String,
    /// The rectangles covered by overlays.
    overlays: &'a [Rect],
    /// The error against the reference, when its overlay shows it.
    error: Option<&'a ErrorFigures>,
}

/// The error against the reference that a screenshot shows.
#[derive(Clone, Debug, Serialize)]
pub struct ErrorFigures {
    /// Share of covered pixels whose shadow term is off by 0.5 or more.
    pub mismatch_rate: f64,
    /// Mean absolute error of the shadow term's luminance.
    pub mean_abs_error: f64,
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
}

/// The image the reproducing command of screenshot `path` writes: `NAME-render.png`.
pub fn render_output(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}-render.png"))
}

/// Writes the screenshot `image` at `path`, its command line `command` and overlays
/// `rects` and the error it shows beside it; returns the command line.
pub fn write(
    path: &Path,
    image: &RgbImage,
    rects: &[Rect],
    error: Option<&ErrorFigures>,
    command: &[String],
) -> Result<String> {
    picture::save_png(image, path)?;
    let line = super::reproduce::command_line(command);
    output::write_json(
        &path.with_extension("json"),
        &Sidecar {
            command_line: line.clone(),
            command,
            render_output: render_output(path).display().to_string(),
            overlays: rects,
            error,
        },
    )?;
    Ok(line)
}

/// The first `shadowlab-view-NNNN.png` in `dir` that is not there yet (nor its JSON, nor
/// its render output); `None` when all are taken.
pub fn next_free(dir: &Path) -> Option<PathBuf> {
    (1..=MAX_NUMBERED)
        .map(|i| dir.join(format!("shadowlab-view-{i:04}.png")))
        .find(|p| !p.exists() && !p.with_extension("json").exists() && !render_output(p).exists())
}
