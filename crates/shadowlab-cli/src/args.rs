//! The command line as `clap` parses it: every command, flag and default, and nothing
//! else. What the flags mean together — which values are allowed, which files may be
//! written, which scene is loaded — is decided by `config`, before any work starts.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

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
    /// The GPU adapter for `gpu:` techniques: a substring of its name (default: the
    /// `SHADOWLAB_ADAPTER` variable, else the first hardware adapter, else a software one).
    #[arg(long, global = true, value_name = "NAME")]
    pub adapter: Option<String>,
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render one technique's shadows to an image.
    Render(RenderArgs),
    /// Run several techniques on one frame, measure them against the ray-traced
    /// reference and write a report.
    Compare(CompareArgs),
    /// List the built-in scenes.
    Scenes,
    /// List the techniques with their parameters: key, default, range and meaning.
    Techniques(TechniquesArgs),
    /// Run a benchmark suite that reproduces a paper's table.
    Bench(BenchArgs),
    /// Open a window showing the scene shaded by a technique: fly the camera, drag the
    /// light, switch techniques, see the error against the reference and the technique's
    /// own images.
    View(ViewArgs),
}

/// The scene-related flags `render` and `compare` share.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// A built-in scene name (see `shadowlab scenes`), a `.toml` scene file, or a mesh
    /// (`.obj`, `.ply`, `.gltf`, `.glb`).
    #[arg(long, default_value = "bunny")]
    pub scene: String,
    /// A built-in scene's parameter, e.g. `count=1000000` for random-triangles.
    #[arg(long = "scene-param", value_name = "K=V")]
    pub scene_params: Vec<String>,
    /// Image width in pixels.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    pub height: Option<u32>,
    /// Camera override: `EX,EY,EZ:TX,TY,TZ[:FOV_DEG]`.
    #[arg(long, value_name = "EYE:TARGET[:FOV]")]
    pub camera: Option<String>,
    /// Move the camera along its view ray to F times its distance from its target.
    #[arg(
        long = "camera-distance",
        value_name = "F",
        allow_negative_numbers = true
    )]
    pub camera_distance: Option<f32>,
    /// Make the camera orthographic: `auto` (the rectangle the camera frames at its
    /// target's depth) or half the viewed height in world units; the width follows the
    /// image's aspect.
    #[arg(long, value_name = "auto|HALF_HEIGHT", allow_negative_numbers = true)]
    pub orthographic: Option<String>,
    /// Which of the scene's cameras to use: a glTF file's camera nodes in the order its
    /// node hierarchy is walked (0 = the first).
    #[arg(long = "camera-index", value_name = "N", default_value_t = 0)]
    pub camera_index: usize,
    /// Light override: `directional:DX,DY,DZ`, `point:X,Y,Z` or `spot:X,Y,Z:TX,TY,TZ:FOV_DEG`;
    /// area lights `rect:X,Y,Z:UX,UY,UZ:VX,VY,VZ` (centre, two full edges),
    /// `disk:X,Y,Z:NX,NY,NZ:R` (centre, normal, radius) or `sphere:X,Y,Z:R`.
    #[arg(long)]
    pub light: Option<String>,
    /// Give the punctual light a size, making it an area light: a point light a sphere of
    /// radius S, a spot light a disk of radius S facing its target, a directional light a
    /// sun of angular diameter S degrees.
    #[arg(long = "light-size", value_name = "S", allow_negative_numbers = true)]
    pub light_size: Option<f32>,
    /// Light samples per pixel of the area-light reference and of the soft techniques
    /// that sample the light (1..=65536).
    #[arg(long = "light-samples", value_name = "N", default_value_t = 256)]
    pub light_samples: u32,
    /// Render the camera path (or a still camera) this many times; reports describe the last.
    #[arg(long, default_value_t = 1)]
    pub frames: usize,
    /// Shade the surfaces behind semi-transparent ones too, each with its own shadow term,
    /// and composite them (techniques afsm and raytrace; the others shade the nearest
    /// surface only).
    #[arg(long)]
    pub layers: bool,
    /// Let a scene file's references (glTF buffer URIs, OBJ `mtllib`, TOML mesh `file`)
    /// name files outside its folder; by default they are refused.
    #[arg(long = "allow-outside-scene-dir")]
    pub allow_outside_scene_dir: bool,
    /// The axis of a mesh file that points up: x, y, z, -x, -y or -z. `--up z` stands a
    /// Z-up file (SketchUp, 3ds Max, CAD tools, many scanners) upright: its point (x, y, z)
    /// lands at (x, z, -y); the automatic camera, light and ground fit the turned scene.
    #[arg(
        long,
        value_name = "AXIS",
        default_value = "y",
        allow_hyphen_values = true
    )]
    pub up: String,
    /// Whether an OBJ material without `map_d` is cut out by the alpha channel of its
    /// `map_Kd` image (when the image has one).
    #[arg(
        long = "obj-kd-alpha",
        value_name = "true|false",
        default_value_t = true,
        action = clap::ArgAction::Set
    )]
    pub obj_kd_alpha: bool,
}

/// `shadowlab render`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The technique: sm, pcf, psm, lispsm, cascaded, asm, afsm, subpixel, csm (convolution
    /// shadow map, also spelled `convolution`), vsm, evsm, msm or raytrace. `cascaded` is the
    /// cascaded shadow map; `csm` keeps its meaning, the convolution shadow map.
    #[arg(long, default_value = "afsm")]
    pub technique: String,
    /// A technique parameter, e.g. `resolution=2048` (`shadowlab techniques` lists them).
    #[arg(long = "param", value_name = "K=V")]
    pub params: Vec<String>,
    /// The shaded image (PNG).
    #[arg(long, default_value = "shadowlab.png")]
    pub output: PathBuf,
    /// The raw shadow term as float32 EXR (R, G, B = transmittance, A = coverage).
    #[arg(long)]
    pub visibility: Option<PathBuf>,
    /// Timings, counters, the resolved camera and light, and every parameter, as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// The world-space triangles the renderer used, as OBJ (one `o` group per material).
    #[arg(long = "export-scene")]
    pub export_scene: Option<PathBuf>,
    /// Write the technique's intermediate images into this folder.
    #[arg(long)]
    pub dump: Option<PathBuf>,
    /// The camera pass: `cpu`, the library's (every verdict's), or `gpu`, the GPU's own (a
    /// hardware G-buffer made into the same samples on the device: the viewer's pass for a
    /// `gpu:` technique). The GPU's coverage follows the rasterizer's rounding, so a few
    /// edge pixels may see another triangle than the CPU's.
    #[arg(
        long = "camera-pass",
        value_name = "cpu|gpu",
        default_value = "cpu",
        value_parser = ["cpu", "gpu"]
    )]
    pub camera_pass: String,
    /// Overwrite existing output files.
    #[arg(long)]
    pub force: bool,
}

/// `shadowlab compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Comma-separated technique names, or `all` (see `render --help`; `csm` and
    /// `convolution` are the convolution shadow map, `cascaded` the cascaded shadow maps).
    #[arg(long, default_value = "all")]
    pub techniques: String,
    /// A technique parameter prefixed with its technique: `sm.resolution=4096`.
    #[arg(long = "param", value_name = "T.K=V")]
    pub params: Vec<String>,
    /// One result per value of a technique parameter: `sm.resolution=512,1024,2048`.
    #[arg(long = "sweep", value_name = "T.K=V1,V2,...")]
    pub sweeps: Vec<String>,
    /// Primary rays per pixel of the reference (at sub-pixel positions when > 1), for every
    /// technique. Default: 1 for hard-shadow techniques, 16 for those that filter or
    /// anti-alias (pcf, subpixel, csm, vsm), each judged against its own.
    #[arg(long = "reference-spp")]
    pub reference_spp: Option<u32>,
    /// Sub-pixel pattern of the supersampled reference: grid or rotated-grid.
    #[arg(long = "reference-pattern", default_value = "grid")]
    pub reference_pattern: String,
    /// The report folder.
    #[arg(long, default_value = "shadowlab-report")]
    pub out: PathBuf,
    /// Write each technique's intermediate images into DIR/dump.
    #[arg(long)]
    pub dump: bool,
    /// Allow writing into a non-empty folder that is not an earlier report.
    #[arg(long)]
    pub force: bool,
}

impl CompareArgs {
    /// What `shadowlab` with no arguments runs: compare on the default scene.
    pub fn default_run() -> Self {
        #[derive(Parser)]
        struct Wrap {
            #[command(flatten)]
            c: CompareArgs,
        }
        Wrap::parse_from(["shadowlab"]).c
    }
}

/// `shadowlab techniques`.
#[derive(clap::Args, Debug, Clone)]
pub struct TechniquesArgs {
    /// One technique to describe, or `all` / `gpu:all` (default: every CPU technique).
    pub name: Option<String>,
}

/// `shadowlab bench`.
#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// The suite: afsm-scaling, subpixel-scaling, csm-table, asm-walkthrough, psm-lights,
    /// engines, soft-exact.
    pub suite: String,
    /// Also write the rows as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// A reduced run that finishes in under a minute on two cores.
    #[arg(long)]
    pub quick: bool,
    /// Write the suite's plots (SVG) into this folder (`engines`: error against memory, and
    /// error against time with the Pareto front marked, per scene).
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Runs per measurement (the median is reported), at least 1.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Let --json and --plots replace existing files.
    #[arg(long)]
    pub force: bool,
    /// What `engines` measures: `cpu` (the library's techniques) or `gpu` (every `gpu:`
    /// technique, timed by the GPU).
    #[arg(long, default_value = "cpu")]
    pub backend: String,
}

/// `shadowlab view`.
#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The technique shown first (Tab and Shift+Tab switch).
    #[arg(long, default_value = "afsm")]
    pub technique: String,
    /// A parameter of the first technique, e.g. `resolution=2048`.
    #[arg(long = "param", value_name = "K=V")]
    pub params: Vec<String>,
    /// Play the key and mouse events of this file instead of waiting for a person, then
    /// quit (the line format is in docs/CLI.md).
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Render this many frames, each from scratch, print the time per stage and quit.
    #[arg(long = "benchmark-frames", value_name = "N")]
    pub benchmark_frames: Option<usize>,
    /// With --benchmark-frames: draw each frame into a texture of the window's size and wait
    /// for it, instead of presenting it (chosen by itself when the adapter cannot present to
    /// the display).
    #[arg(long)]
    pub offscreen: bool,
    /// Start with the error overlay on (the error against the reference, measured on the
    /// GPU for techniques that stay on the device; benchmarks then time it too).
    #[arg(long = "error-overlay")]
    pub error_overlay: bool,
    /// The folder the screenshot key (P) writes into.
    #[arg(long = "screenshot-dir", value_name = "DIR", default_value = ".")]
    pub screenshot_dir: PathBuf,
    /// Let a script's screenshots replace existing files.
    #[arg(long)]
    pub force: bool,
}
