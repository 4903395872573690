//! `render`, `compare` and `scenes`.

use crate::config::{parse_kvs, parse_prefixed_params, SceneArgs, Setup};
use crate::outputs::{self, Planned};
use crate::{progress, report};
use anyhow::{bail, Context, Result};
use serde_json::{json, Value};
use shadowlab::camera::Camera;
use shadowlab::compare::{compare as measure, Metrics};
use shadowlab::frame::{DumpDir, DumpSink};
use shadowlab::light::Light;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::shade;
use shadowlab::techniques::{self, Frame, ShadowTechnique, Shadows};
use shadowlab::view::{ViewLayers, ViewSamples};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// An input error found by the command line itself (exit code 2).
#[derive(Debug)]
pub struct BadInput(pub String);
impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for BadInput {}

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
    /// A technique parameter, e.g. `resolution=2048`.
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
        use clap::Parser;
        #[derive(Parser)]
        struct Wrap {
            #[command(flatten)]
            c: CompareArgs,
        }
        Wrap::parse_from(["shadowlab"]).c
    }
}

/// The resolved camera and light in world units, as CLI.md's provenance section says.
pub fn provenance(camera: &Camera, light: &Light) -> (Value, Value) {
    let v = |p: shadowlab::math::Vec3| json!([p.x, p.y, p.z]);
    let cam = json!({
        "eye": v(camera.eye), "target": v(camera.target), "up": v(camera.up),
        "fov_y_deg": camera.fov_y_deg, "near": camera.near, "far": camera.far,
        "width": camera.width, "height": camera.height,
    });
    let l = match *light {
        Light::Directional { to_light } => json!({"kind": "directional", "to_light": v(to_light)}),
        Light::Point { position } => json!({"kind": "point", "position": v(position)}),
        Light::Spot {
            position,
            target,
            fov_deg,
        } => {
            json!({"kind": "spot", "position": v(position), "target": v(target), "fov_deg": fov_deg})
        }
    };
    (cam, l)
}

fn stats_json(s: &Shadows, time_ms: f64) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    m.insert("time_ms".into(), json!(time_ms));
    let stages: serde_json::Map<String, Value> = s
        .stats
        .stages_ms
        .iter()
        .map(|(k, v)| (k.clone(), json!(v)))
        .collect();
    m.insert("stages_ms".into(), Value::Object(stages));
    m.insert("memory_bytes".into(), json!(s.stats.memory_bytes));
    m.insert("counters".into(), json!(s.stats.counters));
    m
}

/// The most values one `--sweep` may list.
pub const MAX_SWEEP_VALUES: usize = 64;

/// The most runs one `compare` may plan (techniques times sweep values): each keeps its
/// result for the report until the end.
pub const MAX_RUNS: usize = 128;

/// The file of frame `i` of a sequence written beside `output`.
fn frame_file(output: &Path, i: usize) -> PathBuf {
    let stem = output.with_extension("");
    PathBuf::from(format!("{}-{i:04}.png", stem.display()))
}

/// Every file `render` will write, checked before any work.
fn check_render_outputs(a: &RenderArgs) -> Result<()> {
    let mut planned = vec![Planned::new(&a.output, "--output", &["png"])];
    if a.scene.frames > 1 && a.scene.frames <= crate::config::MAX_FRAMES {
        for i in 0..a.scene.frames {
            planned.push(Planned::new(
                &frame_file(&a.output, i),
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
    outputs::check(&planned, a.force)
}

/// Makes a technique with `params` applied.
pub fn make_technique(name: &str, params: &[(String, String)]) -> Result<Box<dyn ShadowTechnique>> {
    let mut t = techniques::create(name)?;
    for (k, v) in params {
        t.set_param(k, v)?;
    }
    Ok(t)
}

/// One technique run over every frame of a sequence: the last frame's result and the
/// per-frame figures.
pub struct Run {
    pub technique: Box<dyn ShadowTechnique>,
    pub label: String,
    pub last: Option<(Shadows, f64)>,
    pub frames: Vec<Value>,
}

/// Renders frame `i`: the camera pass, shared by all techniques.
pub fn camera_pass(setup: &Setup, i: usize) -> Result<(Camera, ViewSamples)> {
    let camera = setup.camera_at(i);
    camera
        .validate()
        .with_context(|| format!("frame {i} of the camera path of {}", setup.scene.name))?;
    let view = ViewSamples::try_render(&setup.scene, &camera)?;
    Ok((camera, view))
}

/// The layers behind the semi-transparent surfaces of a camera pass, when asked for.
fn layers_of(
    setup: &Setup,
    camera: &Camera,
    view: &ViewSamples,
    want: bool,
) -> Result<Option<ViewLayers>> {
    Ok(if want {
        Some(ViewLayers::render(&setup.scene, camera, view)?)
    } else {
        None
    })
}

/// The shaded image of a technique's result (see [`shade_result`]).
fn shade_shadows(
    setup: &Setup,
    view: &ViewSamples,
    layers: Option<&ViewLayers>,
    s: &Shadows,
) -> shade::RgbImage {
    shade_result(setup, view, layers, &s.visibility, s.layers.as_deref())
}

/// The shaded image of a result: the layers composited when the frame has them and the
/// technique shaded them, else the nearest surfaces.
fn shade_result(
    setup: &Setup,
    view: &ViewSamples,
    layers: Option<&ViewLayers>,
    vis: &shadowlab::techniques::Visibility,
    layer_vis: Option<&[shadowlab::math::Vec3]>,
) -> shade::RgbImage {
    match (layers, layer_vis) {
        (Some(l), Some(lv)) => shade::shade_layers(&setup.scene, view, l, &setup.light, vis, lv),
        _ => shade::shade(&setup.scene, view, &setup.light, vis),
    }
}

/// The most frames a still view gives a progressive technique to converge in.
pub const MAX_STILL_FRAMES: usize = 64;

/// Techniques whose shadow terms are filtered or anti-aliased (soft or fractional at
/// edges): by default `compare` judges them against a supersampled reference.
pub const FILTERED: &[&str] = &["pcf", "subpixel", "csm", "vsm", "evsm", "msm", "pcss"];

/// Samples per pixel of the default reference for [`FILTERED`] techniques: a 4×4 grid,
/// whose own error on an edge pixel is at most 1/32 of the pixel's area.
pub const FILTERED_REFERENCE_SPP: u32 = 16;

/// The reference samples per pixel that a technique's verdict uses.
pub fn reference_spp_for(technique: &str, asked: Option<u32>) -> u32 {
    match asked {
        Some(n) => n,
        None if FILTERED.contains(&technique) => FILTERED_REFERENCE_SPP,
        None => 1,
    }
}

/// Renders a still frame: a progressive technique (see [`ShadowTechnique::converged`]) is
/// run on it again until it converges or has had [`MAX_STILL_FRAMES`] frames.
fn run_still(run: &mut Run, frame: &Frame) -> Result<()> {
    run_frame(run, frame)?;
    while run.technique.converged() == Some(false) && run.frames.len() < MAX_STILL_FRAMES {
        run_frame(run, frame)?;
    }
    Ok(())
}

fn run_frame(run: &mut Run, frame: &Frame) -> Result<()> {
    let t0 = Instant::now();
    let s = run
        .technique
        .render(frame)
        .with_context(|| format!("technique {}", run.label))?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    run.frames
        .push(json!({"frame": frame.index, "time_ms": ms, "memory_bytes": s.stats.memory_bytes}));
    run.last = Some((s, ms));
    Ok(())
}

/// `shadowlab render`.
pub fn render(a: &RenderArgs) -> Result<()> {
    check_render_outputs(a)?;
    let params = parse_kvs(&a.params, "--param")?;
    let params: Vec<(String, String)> = params.into_iter().collect();
    let technique = make_technique(&a.technique, &params)?;
    let pb = progress::step(format!("loading {}", a.scene.scene));
    let setup = a.scene.resolve()?;
    setup.check_pixel_budget(1)?;
    pb.finish_and_clear();
    let mut run = Run {
        label: a.technique.clone(),
        technique,
        last: None,
        frames: Vec::new(),
    };
    if let Some(d) = &a.dump {
        std::fs::create_dir_all(d)
            .with_context(|| format!("cannot create --dump folder {}", d.display()))?;
    }
    let bar = progress::bar(setup.frames as u64, format!("rendering {}", a.technique));
    let mut last = None;
    let mut camera_pass_ms = 0.0;
    // A sequence also becomes an animated GIF beside the numbered PNGs.
    let mut animation = None;
    if a.scene.frames > 1 {
        let gif = a.output.with_extension("gif");
        animation = Some(report::Animation::create(&gif)?);
    }
    for i in 0..setup.frames {
        let (camera, view) = camera_pass(&setup, i)?;
        camera_pass_ms = view.time_ms;
        let layers = layers_of(&setup, &camera, &view, a.scene.layers)?;
        let mut frame = Frame::new(&setup.scene, &camera, &setup.light, &view);
        if let Some(l) = &layers {
            frame = frame.with_layers(l);
        }
        frame.index = i;
        let dump_sink = a.dump.as_deref().map(DumpDir::new);
        frame.dump = dump_sink.as_ref().map(|d| d as &dyn DumpSink);
        if setup.frames == 1 {
            run_still(&mut run, &frame)?;
        } else {
            run_frame(&mut run, &frame)?;
        }
        if a.scene.frames > 1 {
            let s = &run.last.as_ref().unwrap().0;
            let img = shade_shadows(&setup, &view, layers.as_ref(), s);
            shade::save_png(&img, &frame_file(&a.output, i))?;
            if let Some(anim) = animation.as_mut() {
                anim.push(&img)?;
            }
        }
        bar.inc(1);
        last = Some((camera, view, layers));
    }
    bar.finish_and_clear();
    let pb = progress::step("writing outputs");
    if let Some(anim) = animation {
        anim.finish()?;
    }
    let (camera, view, layers) = last.expect("at least one frame");
    let (shadows, time_ms) = run.last.take().expect("rendered");
    let img = shade_shadows(&setup, &view, layers.as_ref(), &shadows);
    shade::save_png(&img, &a.output)?;
    if let Some(p) = &a.visibility {
        shade::write_visibility_exr(p, &view, &shadows.visibility)?;
    }
    if let Some(p) = &a.export_scene {
        shadowlab::scene::export::write_obj(&setup.scene, p)?;
    }
    let (cam_json, light_json) = provenance(&camera, &setup.light);
    let mut st = stats_json(&shadows, time_ms);
    st.insert("technique".into(), json!(run.label));
    st.insert("params".into(), json!(run.technique.params()));
    st.insert("scene".into(), json!(setup.scene.name));
    st.insert("scene_source".into(), json!(a.scene.scene));
    st.insert(
        "scene_params".into(),
        json!(parse_kvs(&a.scene.scene_params, "--scene-param")?),
    );
    st.insert("triangles".into(), json!(setup.scene.len()));
    st.insert("warnings".into(), json!(setup.scene.warnings));
    st.insert("shadowlab_version".into(), json!(env!("CARGO_PKG_VERSION")));
    st.insert("camera".into(), cam_json);
    st.insert("light".into(), light_json);
    st.insert("camera_pass_ms".into(), json!(camera_pass_ms));
    st.insert("covered_pixels".into(), json!(view.covered_count()));
    if let Some(l) = &layers {
        st.insert("layer_samples".into(), json!(l.len()));
        st.insert("layers_ms".into(), json!(l.time_ms));
        st.insert("layers_shaded".into(), json!(shadows.layers.is_some()));
    }
    if a.scene.frames > 1 {
        st.insert("frames".into(), json!(run.frames));
    }
    st.insert("frames_run".into(), json!(run.frames.len()));
    st.insert("converged".into(), json!(run.technique.converged()));
    if let Some(p) = &a.stats {
        write_json(p, &Value::Object(st))?;
    }
    pb.finish_and_clear();
    if !progress::quiet() {
        eprintln!(
            "{}: {} in {:.1} ms{}, wrote {}",
            setup.scene.name,
            run.label,
            time_ms,
            frames_note(run.frames.len(), run.technique.converged(), setup.frames),
            a.output.display()
        );
    }
    Ok(())
}

/// How many frames a progressive technique had, for the terminal: empty for the others.
fn frames_note(frames: usize, converged: Option<bool>, asked: usize) -> String {
    match converged {
        None => String::new(),
        Some(_) if asked > 1 => format!(" (last of {frames} frames)"),
        Some(true) => format!(" (converged after {frames} frames)"),
        Some(false) => format!(" (not converged after {frames} frames, the cap)"),
    }
}

/// Writes pretty JSON.
pub fn write_json(path: &Path, v: &Value) -> Result<()> {
    let text = serde_json::to_string_pretty(v).expect("JSON values serialize");
    std::fs::write(path, text + "\n").with_context(|| format!("cannot write {}", path.display()))
}

/// One planned run of `compare`: technique name, label, and its parameters.
type PlannedRun = (String, String, Vec<(String, String)>);

/// Expands `--techniques` and `--sweep` into labelled runs with their parameters.
fn plan_runs(a: &CompareArgs) -> Result<Vec<PlannedRun>> {
    let names: Vec<String> = if a.techniques.trim() == "all" {
        techniques::ALL.iter().map(|s| s.to_string()).collect()
    } else {
        a.techniques
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    };
    if names.is_empty() {
        bail!("--techniques {:?} names no technique", a.techniques);
    }
    let params = parse_prefixed_params(&a.params)?;
    for t in params.keys() {
        if !names.contains(t) {
            bail!(
                "--param names technique {t}, which is not among --techniques {}",
                names.join(",")
            );
        }
    }
    let mut sweeps: Vec<(String, String, Vec<String>)> = Vec::new();
    for s in &a.sweeps {
        let Some((tk, vals)) = s.split_once('=') else {
            bail!("--sweep {s:?} is not TECHNIQUE.KEY=V1,V2,...");
        };
        let Some((t, k)) = tk.split_once('.') else {
            bail!("--sweep {s:?} must name its technique: TECHNIQUE.KEY=V1,V2,...");
        };
        let vals: Vec<String> = vals
            .split(',')
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
            .collect();
        if vals.is_empty() {
            bail!("--sweep {s:?} lists no values");
        }
        if vals.len() > MAX_SWEEP_VALUES {
            bail!(
                "--sweep {tk} lists {} values, more than the limit of {MAX_SWEEP_VALUES}",
                vals.len()
            );
        }
        sweeps.push((t.trim().to_string(), k.trim().to_string(), vals));
    }
    let mut runs = Vec::new();
    for n in &names {
        let base = params.get(n).cloned().unwrap_or_default();
        let mine: Vec<_> = sweeps.iter().filter(|s| &s.0 == n).collect();
        if mine.is_empty() {
            runs.push((n.clone(), n.clone(), base));
            continue;
        }
        for (_, k, vals) in mine {
            for v in vals {
                let mut p = base.clone();
                p.push((k.clone(), v.clone()));
                runs.push((n.clone(), format!("{n}.{k}={v}"), p));
            }
        }
    }
    for (t, _, _) in &sweeps {
        if !names.contains(t) {
            bail!(
                "--sweep names technique {t}, which is not among --techniques {}",
                names.join(",")
            );
        }
    }
    if runs.len() > MAX_RUNS {
        bail!(
            "--techniques and --sweep plan {} runs, more than the limit of {MAX_RUNS}",
            runs.len()
        );
    }
    let mut files = std::collections::BTreeMap::new();
    for (_, label, _) in &runs {
        if let Some(other) = files.insert(slug(label), label) {
            bail!("runs {other} and {label} would write the same report files; give them distinct values");
        }
    }
    Ok(runs)
}

/// File-name-safe form of a run label.
pub fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `shadowlab compare` (and `shadowlab` with no arguments).
pub fn compare(a: &CompareArgs) -> Result<()> {
    let plan = plan_runs(a)?;
    let kind: PatternKind = a.reference_pattern.parse()?;
    let mut runs = Vec::new();
    for (name, label, params) in &plan {
        runs.push(Run {
            technique: make_technique(name, params)?,
            label: label.clone(),
            last: None,
            frames: Vec::new(),
        });
    }
    let (spps, sample_sets) = plan_references(&runs, a, kind)?;
    outputs::check_report_dir(&a.out, a.force)?;
    let pb = progress::step(format!("loading {}", a.scene.scene));
    let setup = a.scene.resolve()?;
    setup.check_pixel_budget(runs.len() + 1)?;
    pb.finish_and_clear();
    outputs::create_report_dir(&a.out)?;
    let dump = a.dump.then(|| a.out.join("dump"));
    if let Some(d) = &dump {
        std::fs::create_dir_all(d)?;
    }
    // A sequence writes DIR/frames/<run>-NNNN.png and an animated DIR/<run>.gif per run.
    let mut animations = Vec::new();
    if setup.frames > 1 {
        let fdir = a.out.join("frames");
        std::fs::create_dir_all(&fdir)
            .with_context(|| format!("cannot create {}", fdir.display()))?;
        for run in &runs {
            animations.push(report::Animation::create(
                &a.out.join(format!("{}.gif", slug(&run.label))),
            )?);
        }
    }
    let bar = progress::bar((setup.frames * runs.len()) as u64, "techniques");
    let mut last = None;
    for i in 0..setup.frames {
        bar.set_message(format!("frame {}/{} camera pass", i + 1, setup.frames));
        let (camera, view) = camera_pass(&setup, i)?;
        let layers = layers_of(&setup, &camera, &view, a.scene.layers)?;
        let mut frame = Frame::new(&setup.scene, &camera, &setup.light, &view);
        if let Some(l) = &layers {
            frame = frame.with_layers(l);
        }
        frame.index = i;
        let dump_sink = dump.as_deref().map(DumpDir::new);
        frame.dump = dump_sink.as_ref().map(|d| d as &dyn DumpSink);
        for (r, run) in runs.iter_mut().enumerate() {
            bar.set_message(format!("frame {}/{} {}", i + 1, setup.frames, run.label));
            if setup.frames == 1 {
                run_still(run, &frame)?;
            } else {
                run_frame(run, &frame)?;
            }
            if let Some(anim) = animations.get_mut(r) {
                let (s, _) = run.last.as_ref().expect("just rendered");
                let img = shade_shadows(&setup, &view, layers.as_ref(), s);
                shade::save_png(
                    &img,
                    &a.out
                        .join(format!("frames/{}-{i:04}.png", slug(&run.label))),
                )?;
                anim.push(&img)?;
            }
            bar.inc(1);
        }
        last = Some((camera, view, layers));
    }
    bar.finish_and_clear();
    for anim in animations {
        anim.finish()?;
    }
    let (camera, view, layers) = last.expect("at least one frame");
    let frame = Frame::new(&setup.scene, &camera, &setup.light, &view);
    let spp_text: Vec<String> = spps.iter().map(|n| format!("{n} spp")).collect();
    let pb = progress::step(format!("ray-traced reference ({})", spp_text.join(", ")));
    let t0 = Instant::now();
    let reference = Reference::build(&setup.scene);
    let bvh_ms = reference.build_ms;
    let refs = trace_references(&reference, &frame, &spps, &sample_sets);
    let ref_vis = &refs[0].1;
    let ref_ms = t0.elapsed().as_secs_f64() * 1e3;
    let ref_layers = layers
        .as_ref()
        .map(|l| reference.layer_visibility(&frame, l));
    pb.finish_and_clear();

    let mut results = Vec::new();
    let mut rows = Vec::new();
    let bar = progress::bar(runs.len() as u64 + 1, "writing images");
    let ref_img = shade_result(
        &setup,
        &view,
        layers.as_ref(),
        ref_vis,
        ref_layers.as_deref(),
    );
    shade::save_png(&ref_img, &a.out.join("reference.png"))?;
    let mut ref_json = Vec::new();
    for (i, (n, vis, ms)) in refs.iter().enumerate() {
        let image = if i == 0 {
            "reference.png".to_string()
        } else {
            let name = format!("reference-{n}spp.png");
            let img = shade_result(&setup, &view, layers.as_ref(), vis, ref_layers.as_deref());
            shade::save_png(&img, &a.out.join(&name))?;
            name
        };
        ref_json.push(json!({
            "samples_per_pixel": n, "trace_ms": ms, "image": image,
            "shadowed_share": shadowed_share(&view, vis),
        }));
    }
    bar.inc(1);
    for run in &runs {
        let (s, ms) = run.last.as_ref().expect("every run rendered");
        bar.set_message(format!("writing {}", run.label));
        let spp = reference_spp_for(run.technique.name(), a.reference_spp);
        let ref_vis = &refs.iter().find(|r| r.0 == spp).expect("made above").1;
        let m: Metrics = measure(&view, &s.visibility, ref_vis);
        let file = slug(&run.label);
        let shaded = shade_shadows(&setup, &view, layers.as_ref(), s);
        let error_img = shade::error_image(&view, &s.visibility, ref_vis);
        shade::save_png(&shaded, &a.out.join(format!("{file}.png")))?;
        shade::save_png(&error_img, &a.out.join(format!("{file}-error.png")))?;
        let mut r = serde_json::Map::new();
        r.insert("technique".into(), json!(run.technique.name()));
        r.insert("label".into(), json!(run.label));
        r.insert("params".into(), json!(run.technique.params()));
        r.extend(stats_json(s, *ms));
        r.insert("mismatch_rate".into(), json!(m.mismatch_rate));
        r.insert("mean_abs_error".into(), json!(m.mean_abs_error));
        r.insert("mean_abs_error_rgb".into(), json!(m.mean_abs_error_rgb));
        r.insert("reference_spp".into(), json!(spp));
        r.insert("frames_run".into(), json!(run.frames.len()));
        r.insert("converged".into(), json!(run.technique.converged()));
        if let (Some(ours), Some(truth)) = (&s.layers, &ref_layers) {
            let lm = shadowlab::compare::compare_samples(ours, truth);
            r.insert("layer_samples".into(), json!(ours.len()));
            r.insert("layer_mismatch_rate".into(), json!(lm.mismatch_rate));
            r.insert(
                "layer_mean_abs_error_rgb".into(),
                json!(lm.mean_abs_error_rgb),
            );
        }
        r.insert("image".into(), json!(format!("{file}.png")));
        r.insert("error_image".into(), json!(format!("{file}-error.png")));
        if setup.frames > 1 {
            r.insert("frames".into(), json!(run.frames));
            r.insert("animation".into(), json!(format!("{file}.gif")));
        }
        if let Some((k, v)) = run
            .label
            .strip_prefix(&format!("{}.", run.technique.name()))
            .and_then(|kv| kv.split_once('='))
        {
            r.insert("sweep".into(), json!({"key": k, "value": v}));
        }
        r.insert(
            "worst_region".into(),
            match report::worst_region(&view, &s.visibility, ref_vis) {
                Some(region) => region.to_json(&report::write_crop(
                    &a.out,
                    &file,
                    &region,
                    &[&ref_img, &shaded, &error_img],
                )?),
                None => Value::Null,
            },
        );
        let frames = match run.technique.converged() {
            None => String::new(),
            Some(c) => format!("{}{}", run.frames.len(), if c { "" } else { " (cap)" }),
        };
        rows.push((run.label.clone(), *ms, m, spp, frames));
        results.push(Value::Object(r));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let (cam_json, light_json) = provenance(&camera, &setup.light);
    let metrics = json!({
        "scene": setup.scene.name,
        "scene_source": a.scene.scene,
        "scene_params": parse_kvs(&a.scene.scene_params, "--scene-param")?,
        "triangles": setup.scene.len(),
        "warnings": setup.scene.warnings,
        "width": view.width, "height": view.height,
        "covered_pixels": view.covered_count(),
        "layer_samples": layers.as_ref().map(|l| l.len()),
        "camera_pass_ms": view.time_ms,
        "frames": setup.frames,
        "threads": rayon::current_num_threads(),
        "shadowlab_version": env!("CARGO_PKG_VERSION"),
        "camera": cam_json, "light": light_json,
        "reference": {
            "technique": "raytrace", "samples_per_pixel": spps[0],
            "pattern": a.reference_pattern,
            "time_ms": ref_ms, "bvh_build_ms": bvh_ms, "trace_ms": ref_ms - bvh_ms,
            "image": "reference.png",
            "shadowed_share": shadowed_share(&view, ref_vis),
        },
        "references": ref_json,
        "results": results,
        "dump": dump.as_ref().map(|_| "dump"),
    });
    let pb = progress::step("writing report");
    write_json(&a.out.join("metrics.json"), &metrics)?;
    report::write_html(&a.out, &metrics)?;
    pb.finish_and_clear();
    if !progress::quiet() {
        print_table(&setup, &view, (ref_ms, bvh_ms), &rows);
        println!("report: {}", a.out.join("index.html").display());
    }
    Ok(())
}

/// The reference sample counts the verdicts of `runs` ask for, the highest first, with
/// their sub-pixel patterns; a note on stderr when `--reference-spp 1` judges a filtering
/// technique.
fn plan_references(
    runs: &[Run],
    a: &CompareArgs,
    kind: PatternKind,
) -> Result<(Vec<u32>, Vec<Vec<shadowlab::math::Vec2>>)> {
    // One reference per sample count the verdicts ask for, the highest first.
    let mut spps: Vec<u32> = runs
        .iter()
        .map(|r| reference_spp_for(r.technique.name(), a.reference_spp))
        .collect();
    spps.sort_unstable_by(|x, y| y.cmp(x));
    spps.dedup();
    let sets = spps
        .iter()
        .map(|&n| pattern(kind, n))
        .collect::<shadowlab::error::Result<Vec<_>>>()?;
    if a.reference_spp == Some(1) && !progress::quiet() {
        let filtered = runs
            .iter()
            .map(|r| r.technique.name())
            .find(|t| FILTERED.contains(t));
        if let Some(t) = filtered {
            eprintln!(
                "note: {t} filters or anti-aliases its shadows, and --reference-spp 1 judges it against one sample per pixel; \
                 the default ({FILTERED_REFERENCE_SPP} samples) judges soft and sub-pixel edges fairly"
            );
        }
    }
    Ok((spps, sets))
}

/// One reference per sample count of `spps` (the highest first): samples per pixel, the
/// reference visibility, and its trace time in milliseconds.
fn trace_references(
    reference: &Reference,
    frame: &Frame,
    spps: &[u32],
    sample_sets: &[Vec<shadowlab::math::Vec2>],
) -> Vec<(u32, shadowlab::techniques::Visibility, f64)> {
    spps.iter()
        .zip(sample_sets)
        .map(|(&n, samples)| {
            let t = Instant::now();
            let vis = reference.visibility(frame, samples);
            (n, vis, t.elapsed().as_secs_f64() * 1e3)
        })
        .collect()
}

/// One verdict of the terminal table: label, time, metrics, reference samples, frames.
type TableRow = (String, f64, Metrics, u32, String);

/// The terminal table of `compare`: one line per run, with the reference each verdict used
/// and the frames of progressive techniques.
fn print_table(setup: &Setup, view: &ViewSamples, (ref_ms, bvh_ms): (f64, f64), rows: &[TableRow]) {
    println!(
        "{} — {} triangles, {}x{}, {} covered pixels; camera pass {:.1} ms; reference {:.1} ms (BVH {:.1} + trace {:.1})",
        setup.scene.name,
        setup.scene.len(),
        view.width,
        view.height,
        view.covered_count(),
        view.time_ms,
        ref_ms,
        bvh_ms,
        ref_ms - bvh_ms
    );
    println!(
        "{:<28} {:>10} {:>10} {:>10} {:>8} {:>8}",
        "technique", "time ms", "mismatch", "mean err", "ref spp", "frames"
    );
    for (label, ms, m, spp, frames) in rows {
        println!(
            "{:<28} {:>10.2} {:>9.4}% {:>10.5} {:>8} {:>8}",
            label,
            ms,
            m.mismatch_rate * 100.0,
            m.mean_abs_error,
            spp,
            frames
        );
    }
    println!(
        "each verdict is against the ray-traced reference at its \"ref spp\" samples per pixel; \
         \"frames\": the frames a progressive technique had on this still view (until converged, at most {MAX_STILL_FRAMES})"
    );
}

/// Share of a frame's covered pixels that the reference puts in shadow (term below 0.5).
fn shadowed_share(view: &ViewSamples, vis: &shadowlab::techniques::Visibility) -> f64 {
    let covered = view.covered_count().max(1);
    let dark = (0..vis.value.len())
        .filter(|&k| view.covered(k) && vis.value[k].max_element() < 0.5)
        .count();
    dark as f64 / covered as f64
}

/// `shadowlab scenes`.
pub fn scenes() -> Result<()> {
    for (name, desc) in shadowlab::scene::builtin::list() {
        let n = shadowlab::scene::builtin::generate(name, &Default::default())
            .map(|s| s.len().to_string())
            .unwrap_or_else(|e| format!("({e})"));
        println!("{name:<18} {n:>10}  {desc}");
    }
    Ok(())
}
