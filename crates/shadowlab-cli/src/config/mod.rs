//! Raw command-line arguments turned into a validated configuration before any work
//! starts, one per command: every flag value parsed and checked, the techniques made with
//! their parameters, the outputs checked (extensions, existing files, folders), then the
//! scene loaded with the camera and light resolved. What fails here is the user's input
//! (exit status 2); the commands then run on a configuration they need not doubt.
//!
//! The checks run in the order their errors are reported: a run refused for a bad flag
//! never loads its scene, and a scene that does not load leaves no output behind.

pub mod parse;
pub mod plan;
pub mod scene;
pub mod view;

pub use plan::{ReferencePlan, RunPlan};
pub use scene::Setup;
pub use view::ViewConfig;

use crate::args::{BenchArgs, CompareArgs, RenderArgs, TechniquesArgs};
use crate::failure::bad_input;
use crate::output::{self, Planned};
use crate::progress;
use anyhow::Result;
use shadowlab::techniques;
use std::path::PathBuf;

/// The most worker threads `--threads` may ask for.
pub const MAX_THREADS: usize = 1024;

/// `--threads`, checked.
pub fn threads(n: Option<usize>) -> Result<Option<usize>> {
    match n {
        Some(n) if n == 0 || n > MAX_THREADS => Err(bad_input(format!(
            "--threads {n} is outside 1..={MAX_THREADS}"
        ))),
        _ => Ok(n),
    }
}

/// Loads the scene of a command under a spinner and checks that `results` kept results
/// fit in memory at its image size.
fn load_scene(args: &crate::args::SceneArgs, results: usize) -> Result<Setup> {
    let pb = progress::step(format!("loading {}", args.scene));
    let setup = scene::resolve(args)?;
    setup.check_pixel_budget(results)?;
    pb.finish_and_clear();
    Ok(setup)
}

/// `shadowlab render`, validated.
pub struct RenderConfig {
    /// The technique with its parameters set, labelled as the user spelled it
    /// (`convolution` for `csm`, say).
    pub plan: RunPlan,
    /// The loaded scene, camera and light.
    pub setup: Setup,
    /// The files to write.
    pub outputs: RenderOutputs,
    /// True for the GPU's own camera pass (`--camera-pass gpu`).
    pub gpu_camera_pass: bool,
}

/// The files `render` writes, checked.
pub struct RenderOutputs {
    /// The shaded image (and, for a sequence, the stem of its frames and animation).
    pub output: PathBuf,
    /// The raw shadow term (EXR).
    pub visibility: Option<PathBuf>,
    /// The stats file (JSON).
    pub stats: Option<PathBuf>,
    /// The world-space triangles (OBJ).
    pub export_scene: Option<PathBuf>,
    /// The folder of intermediate images.
    pub dump: Option<PathBuf>,
}

impl RenderConfig {
    /// Checks every output, makes the technique and loads the scene.
    pub fn from_args(a: &RenderArgs) -> Result<Self> {
        check_render_outputs(a)?;
        let params = parse::parse_kvs(&a.params, "--param")?;
        let params: Vec<(String, String)> = params.into_iter().collect();
        let technique = parse::make_technique(&a.technique, &params)?;
        let setup = load_scene(&a.scene, 1)?;
        Ok(RenderConfig {
            plan: RunPlan {
                technique,
                label: a.technique.clone(),
            },
            setup,
            outputs: RenderOutputs {
                output: a.output.clone(),
                visibility: a.visibility.clone(),
                stats: a.stats.clone(),
                export_scene: a.export_scene.clone(),
                dump: a.dump.clone(),
            },
            gpu_camera_pass: a.camera_pass == "gpu",
        })
    }
}

/// Every file `render` will write, checked before any work.
fn check_render_outputs(a: &RenderArgs) -> Result<()> {
    let mut planned = vec![Planned::new(&a.output, "--output", &["png"])];
    if a.scene.frames > 1 && a.scene.frames <= scene::MAX_FRAMES {
        for i in 0..a.scene.frames {
            planned.push(Planned::new(
                &output::frame_file(&a.output, i),
                format!("--output (frame {i})"),
                &[],
            ));
        }
        planned.push(Planned::new(
            &a.output.with_extension("gif"),
            "--output (animation)",
            &[],
        ));
    }
    if let Some(p) = &a.visibility {
        planned.push(Planned::new(p, "--visibility", &["exr"]));
    }
    if let Some(p) = &a.stats {
        planned.push(Planned::new(p, "--stats", &["json"]));
    }
    if let Some(p) = &a.export_scene {
        planned.push(Planned::new(p, "--export-scene", &["obj"]));
        planned.push(Planned::new(
            &p.with_extension("mtl"),
            "--export-scene (materials)",
            &[],
        ));
    }
    if let Some(d) = &a.dump {
        planned.push(Planned::folder(d, "--dump"));
    }
    output::check(&planned, a.force)
}

/// `shadowlab compare`, validated.
pub struct CompareConfig {
    /// The runs, each a technique with its parameters and label.
    pub runs: Vec<RunPlan>,
    /// The references the verdicts need.
    pub references: ReferencePlan,
    /// The loaded scene, camera and light.
    pub setup: Setup,
    /// The report folder (checked, not yet created).
    pub out: PathBuf,
    /// Whether the techniques dump their intermediate images into `out/dump`.
    pub dump: bool,
}

impl CompareConfig {
    /// Plans the runs and references, checks the report folder and loads the scene.
    pub fn from_args(a: &CompareArgs) -> Result<Self> {
        let (runs, references) = plan::plan(a)?;
        output::check_report_dir(&a.out, a.force)?;
        // A sequence keeps the frame before too: each run's shadow term and references.
        let per_frame = runs.len() + references.spps.len();
        let kept = if a.scene.frames > 1 {
            2 * per_frame
        } else {
            per_frame
        };
        let setup = load_scene(&a.scene, kept)?;
        Ok(CompareConfig {
            runs,
            references,
            setup,
            out: a.out.clone(),
            dump: a.dump,
        })
    }
}

/// `shadowlab techniques`, validated: the techniques to describe.
pub struct TechniquesConfig {
    /// Their names as the command line spells them, in the order reports list them.
    pub names: Vec<String>,
}

impl TechniquesConfig {
    /// Every technique, or those named (`all`, `gpu:all` or one name, which must exist).
    pub fn from_args(a: &TechniquesArgs) -> Result<Self> {
        let names = match &a.name {
            Some(n) => {
                let names = techniques::expand_names(&[n]);
                for n in &names {
                    techniques::create(n)?;
                }
                names
            }
            None => techniques::ALL.iter().map(|s| s.to_string()).collect(),
        };
        Ok(TechniquesConfig { names })
    }
}

/// A bench suite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Suite {
    /// The alias-free shadow map paper's Table 1.
    AfsmScaling,
    /// The sub-pixel paper's Figure 10.
    SubpixelScaling,
    /// The convolution paper's Table 1.
    CsmTable,
    /// The adaptive shadow map paper's walkthrough.
    AsmWalkthrough,
    /// Perspective against uniform shadow maps across light directions.
    PsmLights,
    /// Every technique at equal memory.
    Engines,
    /// Exact soft shadows against the hard technique once per light sample.
    SoftExact,
    /// The `gpu:` techniques' stage times beside their CPU twins.
    Gpu,
}

impl Suite {
    /// Every suite, as the command line names them.
    pub const ALL: [(Suite, &'static str); 8] = [
        (Suite::AfsmScaling, "afsm-scaling"),
        (Suite::SubpixelScaling, "subpixel-scaling"),
        (Suite::CsmTable, "csm-table"),
        (Suite::AsmWalkthrough, "asm-walkthrough"),
        (Suite::PsmLights, "psm-lights"),
        (Suite::Engines, "engines"),
        (Suite::SoftExact, "soft-exact"),
        (Suite::Gpu, "gpu"),
    ];

    /// The suite's name.
    pub fn name(self) -> &'static str {
        Suite::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map(|(_, n)| *n)
            .expect("every suite is listed")
    }
}

/// The most runs per measurement `bench --repeat` takes.
pub const MAX_REPEAT: usize = 1000;

/// `shadowlab bench`, validated.
pub struct BenchConfig {
    /// The suite.
    pub suite: Suite,
    /// Where to write the rows as JSON.
    pub json: Option<PathBuf>,
    /// A reduced run.
    pub quick: bool,
    /// Runs per measurement.
    pub repeat: usize,
    /// Where to write the suite's plots.
    pub plots: Option<PathBuf>,
    /// `engines` measures the `gpu:` techniques.
    pub gpu: bool,
}

impl BenchConfig {
    /// Checks the suite's name, the number of runs and, before the suite runs, the files
    /// it will write.
    pub fn from_args(a: &BenchArgs) -> Result<Self> {
        let Some(&(suite, _)) = Suite::ALL.iter().find(|(_, n)| *n == a.suite) else {
            let names: Vec<&str> = Suite::ALL.iter().map(|(_, n)| *n).collect();
            return Err(bad_input(format!(
                "unknown bench suite {:?}: known suites are {}",
                a.suite,
                names.join(", ")
            )));
        };
        let gpu = match a.backend.trim() {
            "cpu" => false,
            "gpu" if suite == Suite::Engines => true,
            "gpu" => {
                return Err(bad_input(format!(
                    "--backend gpu applies to the engines suite, not {} (the gpu suite is already the GPU's)",
                    a.suite
                )))
            }
            other => {
                return Err(bad_input(format!(
                    "--backend {other:?} is neither cpu nor gpu"
                )))
            }
        };
        if !(1..=MAX_REPEAT).contains(&a.repeat) {
            return Err(bad_input(format!(
                "--repeat {} is outside 1..={MAX_REPEAT} (each measurement is the median of that many runs)",
                a.repeat
            )));
        }
        let mut planned = Vec::new();
        if let Some(p) = &a.json {
            planned.push(Planned::new(p, "--json", &["json"]));
        }
        if let Some(p) = &a.plots {
            planned.push(Planned::folder(p, "--plots"));
        }
        output::check(&planned, a.force)?;
        Ok(BenchConfig {
            suite,
            json: a.json.clone(),
            quick: a.quick,
            repeat: a.repeat,
            plots: a.plots.clone(),
            gpu,
        })
    }
}
