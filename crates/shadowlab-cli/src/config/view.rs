//! `shadowlab view`, validated: the first technique with its parameters, the scene at the
//! window's size, and what drives the window (a person, a script or a benchmark).

use super::parse::{make_technique, parse_kvs};
use super::scene::{self, Setup};
use crate::args::{SceneArgs, ViewArgs};
use crate::failure::bad_input;
use anyhow::Result;
use std::path::PathBuf;

/// The window's size when `--width`/`--height` are not given.
pub const DEFAULT_SIZE: (u32, u32) = (640, 480);

/// The most frames `--benchmark-frames` may ask for.
pub const MAX_BENCHMARK_FRAMES: usize = 100_000;

/// `shadowlab view`, validated.
pub struct ViewConfig {
    /// The technique shown first, as the command line spells it.
    pub technique: String,
    /// Its `--param` values, in the order given.
    pub params: Vec<(String, String)>,
    /// The loaded scene, camera and light (the camera at the window's size).
    pub setup: Setup,
    /// The scene flags as given, with the window's size filled in (for the `render`
    /// command line of a view).
    pub scene_args: SceneArgs,
    /// The script to play instead of a person.
    pub script: Option<PathBuf>,
    /// Frames to time, then quit.
    pub benchmark_frames: Option<usize>,
    /// Draw the benchmark's frames into a texture instead of the window.
    pub offscreen: bool,
    /// Start with the error overlay on.
    pub error_overlay: bool,
    /// Where the screenshot key writes.
    pub screenshot_dir: PathBuf,
    /// Whether a script's screenshots may replace files.
    pub force: bool,
}

impl ViewConfig {
    /// Checks the flags, makes the first technique and loads the scene.
    pub fn from_args(a: &ViewArgs) -> Result<Self> {
        if a.scene.frames != 1 {
            return Err(bad_input(format!(
                "--frames {} is not for view, which shows a still camera you move yourself (render and compare run camera paths)",
                a.scene.frames
            )));
        }
        if let Some(n) = a.benchmark_frames {
            if n == 0 || n > MAX_BENCHMARK_FRAMES {
                return Err(bad_input(format!(
                    "--benchmark-frames {n} is outside 1..={MAX_BENCHMARK_FRAMES}"
                )));
            }
        }
        if a.offscreen && a.benchmark_frames.is_none() {
            return Err(bad_input(
                "--offscreen is for --benchmark-frames, whose frames nobody watches",
            ));
        }
        if !a.screenshot_dir.is_dir() {
            return Err(bad_input(format!(
                "--screenshot-dir {} is not a folder",
                a.screenshot_dir.display()
            )));
        }
        let params: Vec<(String, String)> = parse_kvs(&a.params, "--param")?.into_iter().collect();
        make_technique(&a.technique, &params)?;
        let mut scene_args = a.scene.clone();
        scene_args.width = Some(a.scene.width.unwrap_or(DEFAULT_SIZE.0));
        scene_args.height = Some(a.scene.height.unwrap_or(DEFAULT_SIZE.1));
        let setup = scene::resolve(&scene_args)?;
        setup.check_pixel_budget(2)?;
        Ok(ViewConfig {
            technique: a.technique.clone(),
            params,
            setup,
            scene_args,
            script: a.script.clone(),
            benchmark_frames: a.benchmark_frames,
            offscreen: a.offscreen,
            error_overlay: a.error_overlay,
            screenshot_dir: a.screenshot_dir.clone(),
            force: a.force,
        })
    }
}
