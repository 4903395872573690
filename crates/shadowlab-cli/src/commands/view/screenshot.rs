//! Screenshots: the window as a PNG, and beside it a JSON file with the `render` command
//! line that reproduces the view (also printed), the view's rectangle and those the
//! overlays cover — inside the view and outside them the screenshot is that command's
//! image, pixel for pixel — and where each of the panel's widgets lies.

use super::app::App;
use super::window::PANEL_WIDTH;
use crate::output;
use anyhow::Result;
use serde::Serialize;
use shadowlab::picture::{self, RgbImage};
use std::path::{Path, PathBuf};

/// The most numbered screenshots the screenshot key writes into one folder.
pub const MAX_NUMBERED: u32 = 9999;

/// A rectangle `[x0, x1) × [y0, y1)` of the window.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Rect {
    /// What it shows: `view`, or an overlay: `panel`, `error`.
    pub name: String,
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// One past the right column.
    pub x1: u32,
    /// One past the bottom row.
    pub y1: u32,
}

impl Rect {
    /// The rectangle `name` at (x, y) of `w` × `h` pixels.
    pub fn new(name: &str, x: u32, y: u32, w: u32, h: u32) -> Self {
        Rect {
            name: name.to_string(),
            x0: x,
            y0: y,
            x1: x + w,
            y1: y + h,
        }
    }
}

/// The JSON file beside a screenshot.
#[derive(Serialize)]
struct Sidecar<'a> {
    /// The command line to paste into a shell.
    command_line: String,
    /// Its arguments, without the program's name.
    command: &'a [String],
    /// The image the command writes.
    render_output: String,
    /// Where the view lies in the window: outside the overlays, its pixels are
    /// `render`'s image.
    view: &'a Rect,
    /// The rectangles covered by overlays.
    overlays: &'a [Rect],
    /// The panel's widgets by label, where a pointer finds them.
    widgets: &'a [Rect],
    /// The error against the reference, when its overlay shows it.
    error: Option<&'a ErrorFigures>,
    /// Whether the error overlay is on (its figures may still be on their way).
    error_overlay: bool,
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

/// What a screenshot's JSON says besides the command line.
pub struct Layout<'a> {
    /// The view's rectangle.
    pub view: &'a Rect,
    /// The overlays.
    pub overlays: &'a [Rect],
    /// The widgets.
    pub widgets: &'a [Rect],
    /// The error shown.
    pub error: Option<&'a ErrorFigures>,
    /// Whether the error overlay is on.
    pub error_overlay: bool,
}

/// Writes the screenshot `image` at `path`, and beside it its command line `command`, the
/// view's and overlays' rectangles and the error it shows; returns the command line.
pub fn write(path: &Path, image: &RgbImage, layout: &Layout, command: &[String]) -> Result<String> {
    picture::save_png(image, path)?;
    let line = super::reproduce::command_line(command);
    output::write_json(
        &path.with_extension("json"),
        &Sidecar {
            command_line: line.clone(),
            command,
            render_output: render_output(path).display().to_string(),
            view: layout.view,
            overlays: layout.overlays,
            widgets: layout.widgets,
            error: layout.error,
            error_overlay: layout.error_overlay,
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

impl App<'_> {
    /// Writes the window's image `img` to `path`, with its command line.
    pub(super) fn screenshot(&self, path: &Path, img: &shadowlab::picture::RgbImage) -> Result<()> {
        let s = &self.session;
        let (w, h) = (s.camera.width, s.camera.height);
        let view = Rect::new("view", 0, 0, w, h);
        let mut overlays = Vec::new();
        if s.show.overlays {
            overlays.push(Rect::new("panel", w, 0, PANEL_WIDTH, img.height()));
            if s.show.error && self.error.is_some() {
                overlays.push(Rect::new("error", 0, 0, w, h));
            }
        }
        let widgets: Vec<Rect> = self
            .widgets
            .rects
            .iter()
            .map(|(l, r)| {
                let (x0, y0) = (r.min.x.max(0.0) as u32, r.min.y.max(0.0) as u32);
                Rect {
                    name: l.clone(),
                    x0,
                    y0,
                    x1: (r.max.x.ceil() as u32).max(x0),
                    y1: (r.max.y.ceil() as u32).max(y0),
                }
            })
            .collect();
        let error = self
            .error
            .as_ref()
            .filter(|_| s.show.overlays && s.show.error);
        let layout = Layout {
            view: &view,
            overlays: &overlays,
            widgets: &widgets,
            error,
            error_overlay: s.show.overlays && s.show.error,
        };
        let line = write(path, img, &layout, &self.render_args(path))?;
        println!("{}: {line}", path.display());
        Ok(())
    }

    /// The screenshot key: the next free numbered file, taken with the next frame.
    pub(super) fn key_screenshot(&mut self) {
        match next_free(&self.screenshot_dir) {
            Some(p) => self.shot = Some(p),
            None => {
                self.session.status = format!(
                    "{} holds {} screenshots already",
                    self.screenshot_dir.display(),
                    MAX_NUMBERED
                );
                self.session.stale = true;
            }
        }
    }

    /// The view's `render` command line to the clipboard (and the terminal).
    pub(super) fn copy_command(&mut self) {
        let line = super::reproduce::command_line(&self.render_args(Path::new("view.png")));
        println!("{line}");
        let copied = match &mut self.clipboard {
            Some(c) => c.set_text(line.clone()),
            None => arboard::Clipboard::new().and_then(|mut c| {
                let r = c.set_text(line.clone());
                self.clipboard = Some(c);
                r
            }),
        };
        self.session.status = match copied {
            Ok(()) => "the command line is on the clipboard".to_string(),
            Err(e) => format!("the clipboard refused the command line ({e}); it is printed"),
        };
    }
}
