//! `shadowlab render`: one technique's shadows on one scene, as an image.
//!
//! The flow: render every frame (a still view until a progressive technique converges; a
//! sequence frame by frame, each frame's image and the animation written as it comes),
//! then write the last frame's outputs — the shaded image, the raw shadow term, the
//! exported scene, the stats file — and say what was done.

use crate::config::{RenderConfig, RenderOutputs, Setup};
use crate::frames::{GpuScene, Pass, Run};
use crate::metrics::{
    self, AreaRecord, CameraRecord, Figures, LightRecord, RenderStats, SceneRecord,
};
use crate::output::{self, Animation};
use crate::progress;
use anyhow::{Context, Result};
use shadowlab::frame::{DumpDir, DumpSink};
use shadowlab::{picture, shade};

/// Runs `render`.
pub fn run(cfg: RenderConfig) -> Result<()> {
    let (setup, out) = (&cfg.setup, &cfg.outputs);
    let mut run = Run::new(cfg.plan);
    if let Some(d) = &out.dump {
        std::fs::create_dir_all(d)
            .with_context(|| format!("cannot create --dump folder {}", d.display()))?;
    }
    let pass = render_frames(setup, out, &mut run, cfg.gpu_camera_pass)?;
    let pb = progress::step("writing outputs");
    let time_ms = write_outputs(setup, out, &run, &pass)?;
    pb.finish_and_clear();
    if !progress::quiet() {
        eprintln!(
            "{}: {} in {:.1} ms{}, wrote {}",
            setup.scene.name,
            run.label,
            time_ms,
            frames_note(run.frames.len(), run.technique.converged(), setup.frames),
            out.output.display()
        );
    }
    Ok(())
}

/// Renders every frame; a sequence writes `OUT-NNNN.png` per frame and the animated
/// `OUT.gif` as it goes; `gpu_pass` takes the GPU's camera pass. Returns the last frame's
/// camera pass.
fn render_frames(
    setup: &Setup,
    out: &RenderOutputs,
    run: &mut Run,
    gpu_pass: bool,
) -> Result<Pass> {
    let sequence = setup.frames > 1;
    let dump = out.dump.as_deref().map(DumpDir::new);
    let bar = progress::bar(setup.frames as u64, format!("rendering {}", run.label));
    let mut animation = if sequence {
        Some(Animation::create(&out.output.with_extension("gif"))?)
    } else {
        None
    };
    let gpu_scene = if gpu_pass {
        Some(GpuScene::new(setup)?)
    } else {
        None
    };
    let mut last = None;
    for i in 0..setup.frames {
        let pass = if let Some(g) = &gpu_scene {
            Pass::render_on_gpu(setup, i, g)?
        } else {
            Pass::render(setup, i, last.take())?
        };
        let sink = dump.as_ref().map(|d| d as &dyn DumpSink);
        run.render(&pass.frame(setup, i, sink), !sequence)?;
        if let Some(anim) = animation.as_mut() {
            let img = pass.shade(setup, &run.result().0);
            picture::save_png(&img, &output::frame_file(&out.output, i))?;
            anim.push(&img)?;
        }
        bar.inc(1);
        last = Some(pass);
    }
    bar.finish_and_clear();
    if let Some(anim) = animation {
        anim.finish()?;
    }
    Ok(last.expect("at least one frame"))
}

/// Writes the last frame's image, shadow term, scene and stats; returns its time.
fn write_outputs(setup: &Setup, out: &RenderOutputs, run: &Run, pass: &Pass) -> Result<f64> {
    let (shadows, time_ms) = run.result();
    let img = pass.shade(setup, shadows);
    picture::save_png(&img, &out.output)?;
    if let Some(p) = &out.visibility {
        shade::write_visibility_exr(p, &pass.view, &shadows.visibility)?;
    }
    if let Some(p) = &out.export_scene {
        shadowlab::scene::export::write_obj(&setup.scene, p)?;
    }
    if let Some(p) = &out.stats {
        output::write_json(p, &stats(setup, run, pass))?;
    }
    Ok(*time_ms)
}

/// The stats file: the last frame's figures, the scene, camera and light it was
/// rendered from, and every parameter in effect.
fn stats(setup: &Setup, run: &Run, pass: &Pass) -> RenderStats {
    let (shadows, time_ms) = run.result();
    let layers = pass.layers.as_ref();
    RenderStats {
        figures: Figures::of(&shadows.stats, *time_ms),
        technique: run.label.clone(),
        params: run.technique.params(),
        scene: SceneRecord::from(setup),
        shadowlab_version: metrics::VERSION.to_string(),
        camera: CameraRecord::from(&pass.camera),
        light: LightRecord::from(&setup.light),
        area_light: AreaRecord::of(setup),
        camera_pass_ms: pass.view.time_ms,
        covered_pixels: pass.view.covered_count(),
        layer_samples: layers.map(|l| l.len()),
        layers_ms: layers.map(|l| l.time_ms),
        layers_shaded: layers.map(|_| shadows.layers.is_some()),
        frames: (setup.frames > 1).then(|| run.frames.clone()),
        frames_run: run.frames.len(),
        converged: run.technique.converged(),
    }
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
