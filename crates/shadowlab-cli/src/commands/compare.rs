//! `shadowlab compare` (and `shadowlab` with no arguments): several techniques on one
//! frame, each measured against the ray-traced reference, written up as a report.
//!
//! The flow, one stage per function below: create the report folder; render every frame
//! with every technique (a still view until the progressive ones converge) and trace its
//! references (a sequence measures every frame against its own, with the temporal error,
//! and writes each frame's images and the animations as they come); measure each run's
//! last frame against its reference and write its images; gather everything into
//! [`Metrics`]; write `metrics.json` and the report from it; print the terminal table.

use crate::config::{CompareConfig, ReferencePlan, Setup};
use crate::frames::{Pass, Run, MAX_STILL_FRAMES};
use crate::metrics::{
    self, AreaRecord, CameraRecord, Figures, LightRecord, Metrics, ReferenceImage,
    ReferenceSummary, RunResult, SceneRecord, Sweep,
};
use crate::output::{self, slug};
use crate::sequence::{mean_temporal_error, walkthrough_file, References, Sequence};
use crate::{progress, report};
use anyhow::Result;
use shadowlab::compare::{compare as measure, compare_samples};
use shadowlab::frame::{DumpDir, DumpSink, Visibility};
use shadowlab::picture::{self, RgbImage};
use shadowlab::reference::Reference;
use shadowlab::shade;
use shadowlab::view::ViewSamples;
use std::path::{Path, PathBuf};

/// Runs `compare`.
pub fn run(cfg: CompareConfig) -> Result<()> {
    let CompareConfig {
        runs,
        references,
        setup,
        out,
        dump,
    } = cfg;
    let mut runs: Vec<Run> = runs.into_iter().map(Run::new).collect();
    let folder = Folder::create(&out, dump)?;
    let (pass, traced) = render_frames(&setup, &mut runs, &references, &folder)?;
    let bar = progress::bar(runs.len() as u64 + 1, "writing images");
    let (ref_img, reference_images) = write_references(&setup, &pass, &folder, &traced)?;
    bar.inc(1);
    let mut results = Vec::new();
    for run in &runs {
        bar.set_message(format!("writing {}", run.label));
        let measured = Measured {
            setup: &setup,
            pass: &pass,
            traced: &traced,
            reference_image: &ref_img,
            dir: &out,
        };
        results.push(measured.result(run, references.spp_for(run.technique.name()))?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let metrics = gather(
        &setup,
        &pass,
        &references,
        &traced,
        &folder,
        reference_images,
        results,
    );
    let pb = progress::step("writing report");
    output::write_json(&out.join("metrics.json"), &metrics)?;
    report::write(&out, &metrics)?;
    pb.finish_and_clear();
    if !progress::quiet() {
        print_table(&metrics);
        println!("report: {}", out.join("index.html").display());
    }
    Ok(())
}

/// The report folder while the runs fill it, and where the techniques dump.
struct Folder {
    dir: PathBuf,
    dump: Option<DumpDir>,
}

impl Folder {
    /// Creates the folder with its marker and the dump folder when asked for.
    fn create(dir: &Path, dump: bool) -> Result<Self> {
        output::create_report_dir(dir)?;
        let dump = dump.then(|| DumpDir::new(&dir.join("dump")));
        if let Some(d) = &dump {
            output::create_dir(&d.0)?;
        }
        Ok(Folder {
            dir: dir.to_path_buf(),
            dump,
        })
    }
}

/// Renders every frame with every run and traces its references through one BVH; a
/// sequence measures each frame and writes its images as it goes (see [`Sequence`]).
/// Returns the last frame's camera pass and references.
fn render_frames(
    setup: &Setup,
    runs: &mut [Run],
    plan: &ReferencePlan,
    folder: &Folder,
) -> Result<(Pass, References)> {
    let frames = setup.frames;
    let mut sequence = if frames > 1 {
        let spps = runs
            .iter()
            .map(|r| plan.spp_for(r.technique.name()))
            .collect();
        Some(Sequence::create(&folder.dir, runs, spps)?)
    } else {
        None
    };
    let pb = progress::step("ray-traced reference: BVH");
    let reference = Reference::build(&setup.scene);
    pb.finish_and_clear();
    let spp_text: Vec<String> = plan.spps.iter().map(|n| format!("{n} spp")).collect();
    let bar = progress::bar((frames * (runs.len() + 1)) as u64, "techniques");
    let mut last = None;
    for i in 0..frames {
        bar.set_message(format!("frame {}/{frames} camera pass", i + 1));
        let pass = Pass::render(setup, i, last.take().map(|(p, _)| p))?;
        let sink = folder.dump.as_ref().map(|d| d as &dyn DumpSink);
        let frame = pass.frame(setup, i, sink);
        for run in runs.iter_mut() {
            bar.set_message(format!("frame {}/{frames} {}", i + 1, run.label));
            run.render(&frame, frames == 1)?;
            bar.inc(1);
        }
        bar.set_message(format!(
            "frame {}/{frames} reference ({})",
            i + 1,
            spp_text.join(", ")
        ));
        let traced = References::trace(&reference, setup, &pass, plan);
        match &mut sequence {
            Some(s) => s.frame(setup, i, pass, traced, runs)?,
            None => last = Some((pass, traced)),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    match sequence {
        Some(s) => s.finish(),
        None => Ok(last.expect("at least one frame")),
    }
}

/// Writes each reference's shaded image: `reference.png` for the most samples,
/// `reference-Nspp.png` for the others. Returns the first and their records.
fn write_references(
    setup: &Setup,
    pass: &Pass,
    folder: &Folder,
    traced: &References,
) -> Result<(RgbImage, Vec<ReferenceImage>)> {
    let layers = traced.layers.as_deref();
    let first = pass.shade_result(setup, &traced.each[0].vis, layers);
    picture::save_png(&first, &folder.dir.join("reference.png"))?;
    let mut records = Vec::new();
    for (i, r) in traced.each.iter().enumerate() {
        let image = if i == 0 {
            "reference.png".to_string()
        } else {
            let name = format!("reference-{}spp.png", r.spp);
            let img = pass.shade_result(setup, &r.vis, layers);
            picture::save_png(&img, &folder.dir.join(&name))?;
            name
        };
        let std_error_image = match &r.std_error {
            Some((se, _)) => {
                let name = format!("reference-{}spp-std-error.png", r.spp);
                let img = shade::std_error_image(&pass.view, se);
                picture::save_png(&img, &folder.dir.join(&name))?;
                Some(name)
            }
            None => None,
        };
        records.push(ReferenceImage {
            samples_per_pixel: r.spp,
            trace_ms: r.ms,
            image,
            shadowed_share: shadowed_share(&pass.view, &r.vis),
            mean_std_error: r.std_error.as_ref().map(|s| s.1),
            std_error_image,
        });
    }
    Ok((first, records))
}

/// What measuring a run needs: the frame, the references and the report folder.
struct Measured<'a> {
    setup: &'a Setup,
    pass: &'a Pass,
    traced: &'a References,
    reference_image: &'a RgbImage,
    dir: &'a Path,
}

impl Measured<'_> {
    /// Measures `run` against the reference with `spp` samples, writes its shaded, error
    /// and worst-region images, and returns its record.
    fn result(&self, run: &Run, spp: u32) -> Result<RunResult> {
        let (s, ms) = run.result();
        let view = &self.pass.view;
        let traced = self.traced.traced(spp);
        let ref_vis = &traced.vis;
        let m = measure(view, &s.visibility, ref_vis);
        let file = slug(&run.label);
        let shaded = self.pass.shade(self.setup, s);
        let error_img = shade::error_image(view, &s.visibility, ref_vis);
        picture::save_png(&shaded, &self.dir.join(format!("{file}.png")))?;
        picture::save_png(&error_img, &self.dir.join(format!("{file}-error.png")))?;
        let layers = match (&s.layers, &self.traced.layers) {
            (Some(ours), Some(truth)) => Some((ours.len(), compare_samples(ours, truth))),
            _ => None,
        };
        let worst_region = match report::crops::worst_region(view, &s.visibility, ref_vis) {
            Some(region) => {
                let panels = [self.reference_image, &shaded, &error_img];
                let crop = report::crops::write_crop(self.dir, &file, &region, &panels)?;
                Some(region.record(crop))
            }
            None => None,
        };
        let technique = run.technique.name();
        let sequence = self.setup.frames > 1;
        Ok(RunResult {
            technique: technique.to_string(),
            label: run.label.clone(),
            params: run.technique.params(),
            figures: Figures::of(&s.stats, *ms),
            mismatch_rate: m.mismatch_rate,
            mean_abs_error: m.mean_abs_error,
            mean_abs_error_rgb: m.mean_abs_error_rgb,
            reference_spp: spp,
            reference_std_error: traced.std_error.as_ref().map(|s| s.1),
            frames_run: run.frames.len(),
            converged: run.technique.converged(),
            layer_samples: layers.as_ref().map(|l| l.0),
            layer_mismatch_rate: layers.as_ref().map(|l| l.1.mismatch_rate),
            layer_mean_abs_error_rgb: layers.as_ref().map(|l| l.1.mean_abs_error_rgb),
            image: format!("{file}.png"),
            error_image: format!("{file}-error.png"),
            frames: sequence.then(|| run.frames.clone()),
            animation: sequence.then(|| format!("{file}.gif")),
            temporal_error: mean_temporal_error(run),
            walkthrough: sequence.then(|| walkthrough_file(&run.label)),
            sweep: swept(technique, &run.label),
            worst_region,
        })
    }
}

/// The swept parameter of a run labelled `technique.key=value`.
fn swept(technique: &str, label: &str) -> Option<Sweep> {
    let (key, value) = label
        .strip_prefix(&format!("{technique}."))?
        .split_once('=')?;
    Some(Sweep {
        key: key.to_string(),
        value: value.to_string(),
    })
}

/// Everything measured, as `metrics.json` records it.
fn gather(
    setup: &Setup,
    pass: &Pass,
    plan: &ReferencePlan,
    traced: &References,
    folder: &Folder,
    references: Vec<ReferenceImage>,
    results: Vec<RunResult>,
) -> Metrics {
    let view = &pass.view;
    Metrics {
        scene: SceneRecord::from(setup),
        width: view.width,
        height: view.height,
        covered_pixels: view.covered_count(),
        layer_samples: pass.layers.as_ref().map(|l| l.len()),
        camera_pass_ms: view.time_ms,
        frames: setup.frames,
        threads: rayon::current_num_threads(),
        shadowlab_version: metrics::VERSION.to_string(),
        camera: CameraRecord::from(&pass.camera),
        light: LightRecord::from(&setup.light),
        area_light: AreaRecord::of(setup),
        reference: ReferenceSummary {
            technique: "raytrace".to_string(),
            samples_per_pixel: plan.spps[0],
            pattern: plan.pattern.clone(),
            time_ms: traced.bvh_ms + traced.trace_ms,
            bvh_build_ms: traced.bvh_ms,
            trace_ms: traced.trace_ms,
            image: "reference.png".to_string(),
            shadowed_share: shadowed_share(view, &traced.each[0].vis),
        },
        references,
        results,
        dump: folder.dump.as_ref().map(|_| "dump".to_string()),
    }
}

/// Share of a frame's covered pixels that the reference puts in shadow (term below 0.5).
fn shadowed_share(view: &ViewSamples, vis: &Visibility) -> f64 {
    let covered = view.covered_count().max(1);
    let dark = (0..vis.value.len())
        .filter(|&k| view.covered(k) && vis.value[k].max_element() < 0.5)
        .count();
    dark as f64 / covered as f64
}

/// The terminal table of `compare`: one line per run, with the reference each verdict used
/// and the frames of progressive techniques.
fn print_table(m: &Metrics) {
    let r = &m.reference;
    println!(
        "{} — {} triangles, {}x{}, {} covered pixels; camera pass {:.1} ms; reference {:.1} ms (BVH {:.1} + trace {:.1})",
        m.scene.scene, m.scene.triangles, m.width, m.height, m.covered_pixels, m.camera_pass_ms, r.time_ms, r.bvh_build_ms, r.trace_ms
    );
    println!(
        "{:<28} {:>10} {:>10} {:>10} {:>8} {:>8} {:>8}",
        "technique", "time ms", "mismatch", "mean err", "ref spp", "ref σ", "frames"
    );
    for run in &m.results {
        let frames = match run.converged {
            None => String::new(),
            Some(c) => format!("{}{}", run.frames_run, if c { "" } else { " (cap)" }),
        };
        let sigma = run
            .reference_std_error
            .map_or("—".to_string(), |s| format!("{s:.5}"));
        println!(
            "{:<28} {:>10.2} {:>9.4}% {:>10.5} {:>8} {:>8} {:>8}",
            run.label,
            run.figures.time_ms,
            run.mismatch_rate * 100.0,
            run.mean_abs_error,
            run.reference_spp,
            sigma,
            frames
        );
    }
    print_devices(m);
    if let Some(a) = &m.area_light {
        println!(
            "area light ({}, {} light samples per pixel): the reference is the fraction of the light each point sees; \
             \"ref σ\" is its mean standard error; hard techniques see the light's centre as a point light",
            a.light.kind(),
            a.light_samples
        );
    }
    println!(
        "each verdict is against the ray-traced reference at its \"ref spp\" samples per pixel; \
         \"frames\": the frames a progressive technique had on this still view (until converged, at most {MAX_STILL_FRAMES})"
    );
    if m.frames > 1 {
        print_sequence(m);
    }
}

/// The GPU adapters the `gpu:` runs used, one line each (a software adapter's says its
/// times are CPU-emulated).
fn print_devices(m: &Metrics) {
    let mut seen: Vec<&str> = Vec::new();
    for run in &m.results {
        if let Some(d) = run.figures.device.as_deref() {
            if !seen.contains(&d) {
                seen.push(d);
                println!("GPU runs on {d}");
            }
        }
    }
}

/// The per-frame verdicts of a sequence: each run's mean error per frame and its temporal
/// error.
fn print_sequence(m: &Metrics) {
    println!(
        "{} frames, each against its own reference; temporal error: mean |Δ technique − Δ reference| between consecutive frames",
        m.frames
    );
    for run in &m.results {
        let per_frame: Vec<String> = run
            .frames
            .iter()
            .flatten()
            .filter_map(|f| f.verdict.map(|v| format!("{:.5}", v.mean_abs_error)))
            .collect();
        let temporal = run
            .temporal_error
            .map_or_else(|| "—".to_string(), |t| format!("{t:.5}"));
        println!(
            "{:<28} temporal {temporal:>8}  mean err per frame {}",
            run.label,
            per_frame.join(" ")
        );
    }
}
