//! The frames of a view as `compare` measures them: every frame's references traced
//! through one BVH and, in a sequence (`--frames N > 1`), each run measured frame by frame
//! against that frame's own reference — mismatch, mean error, and the temporal error from
//! the frame before by reprojection (`shadowlab::temporal`) — with its frames written as
//! they come: `DIR/frames/<run>-NNNN.png`, the animation `DIR/<run>.gif`, and
//! `DIR/<run>-walkthrough.gif`, the reference and the technique side by side.
//!
//! Cost: a sequence traces every planned reference (1 and, for the filtering techniques,
//! 16 samples per pixel) in every frame, not once, and keeps the frame before — its camera
//! pass, references and every run's shadow term — for the reprojection.

use crate::config::{ReferencePlan, Setup};
use crate::frames::{Pass, Run};
use crate::metrics::FrameVerdict;
use crate::output::{self, slug, Animation};
use anyhow::Result;
use shadowlab::compare::compare as measure;
use shadowlab::frame::{Frame, Visibility};
use shadowlab::math::Vec3;
use shadowlab::picture::{self, RgbImage};
use shadowlab::reference::Reference;
use shadowlab::soft_reference::soft_visibility;
use shadowlab::temporal::Reprojection;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One traced reference: samples per pixel, the shadow term, the trace time and, under an
/// area light, its per-pixel standard error and their mean.
pub struct Traced {
    /// Primary rays per pixel.
    pub spp: u32,
    /// The shadow term.
    pub vis: Visibility,
    /// Its trace time in milliseconds.
    pub ms: f64,
    /// Under an area light: each pixel's standard error, and their mean over covered pixels.
    pub std_error: Option<(Vec<f32>, f64)>,
}

/// The references of one frame, the most samples first, with the BVH build time, their
/// trace time and, with `--layers`, the layer samples' shadow terms.
pub struct References {
    /// Each reference.
    pub each: Vec<Traced>,
    /// The BVH build (once for every frame).
    pub bvh_ms: f64,
    /// This frame's traces together.
    pub trace_ms: f64,
    /// With `--layers`, the shadow terms of the layer samples.
    pub layers: Option<Vec<Vec3>>,
}

impl References {
    /// Traces every planned reference on the frame of `pass` through `reference`.
    pub fn trace(reference: &Reference, setup: &Setup, pass: &Pass, plan: &ReferencePlan) -> Self {
        let frame = Frame::new(&setup.scene, &pass.camera, &setup.light, &pass.view)
            .with_area(setup.area.as_ref(), setup.light_samples);
        let t0 = Instant::now();
        let each = plan
            .spps
            .iter()
            .zip(&plan.samples)
            .map(|(&spp, samples)| {
                let t = Instant::now();
                let (vis, std_error) = match &setup.area {
                    Some(area) => {
                        let n = setup.light_samples;
                        let soft = soft_visibility(reference, &frame, area, n, samples);
                        let mean = soft.mean_std_error(&frame);
                        (soft.visibility, Some((soft.std_error, mean)))
                    }
                    None => (reference.visibility(&frame, samples), None),
                };
                Traced {
                    spp,
                    vis,
                    ms: t.elapsed().as_secs_f64() * 1e3,
                    std_error,
                }
            })
            .collect();
        let trace_ms = t0.elapsed().as_secs_f64() * 1e3;
        let layers = pass
            .layers
            .as_ref()
            .map(|l| reference.layer_visibility(&frame, l));
        References {
            each,
            bvh_ms: reference.build_ms,
            trace_ms,
            layers,
        }
    }

    /// The reference traced with `spp` samples per pixel.
    pub fn traced(&self, spp: u32) -> &Traced {
        self.each
            .iter()
            .find(|r| r.spp == spp)
            .expect("every planned reference is traced")
    }

    /// The shadow term of the reference traced with `spp` samples per pixel.
    pub fn with_spp(&self, spp: u32) -> &Visibility {
        &self.traced(spp).vis
    }

    /// The shaded image of the reference with `spp` samples per pixel.
    pub fn shade(&self, setup: &Setup, pass: &Pass, spp: u32) -> RgbImage {
        pass.shade_result(setup, self.with_spp(spp), self.layers.as_deref())
    }
}

/// The frame before, as the temporal error needs it.
struct Previous {
    pass: Pass,
    references: References,
    runs: Vec<Visibility>,
}

/// A sequence while its frames come: the files being written and the frame before.
pub struct Sequence {
    dir: PathBuf,
    animations: Vec<Animation>,
    walkthroughs: Vec<Animation>,
    spps: Vec<u32>,
    previous: Option<Previous>,
}

/// The side-by-side animation of a run labelled `label`, relative to the report folder.
pub fn walkthrough_file(label: &str) -> String {
    format!("{}-walkthrough.gif", slug(label))
}

impl Sequence {
    /// Creates `DIR/frames/` and every run's animations; `spps[r]` is the reference
    /// samples per pixel that run `r` is judged against.
    pub fn create(dir: &Path, runs: &[Run], spps: Vec<u32>) -> Result<Self> {
        output::create_dir(&dir.join("frames"))?;
        let mut animations = Vec::new();
        let mut walkthroughs = Vec::new();
        for run in runs {
            let file = format!("{}.gif", slug(&run.label));
            animations.push(Animation::create(&dir.join(file))?);
            walkthroughs.push(Animation::create_pair(
                &dir.join(walkthrough_file(&run.label)),
            )?);
        }
        Ok(Sequence {
            dir: dir.to_path_buf(),
            animations,
            walkthroughs,
            spps,
            previous: None,
        })
    }

    /// Measures frame `i` of every run (just rendered on `pass`) against `references`,
    /// with the temporal error from the frame before; records the verdict in the run's
    /// last frame figures and writes the frame's images.
    pub fn frame(
        &mut self,
        setup: &Setup,
        i: usize,
        pass: Pass,
        references: References,
        runs: &mut [Run],
    ) -> Result<()> {
        let reprojection = self
            .previous
            .as_ref()
            .map(|p| Reprojection::between(&p.pass.view, &pass.view));
        let mut shaded_refs: Vec<(u32, RgbImage)> = Vec::new();
        for (r, run) in runs.iter_mut().enumerate() {
            let spp = self.spps[r];
            let vis = &run.result().0.visibility;
            let truth = references.with_spp(spp);
            let m = measure(&pass.view, vis, truth);
            let temporal = match (&self.previous, &reprojection) {
                (Some(p), Some(rp)) => {
                    rp.temporal_error([&p.runs[r], vis], [p.references.with_spp(spp), truth])
                }
                _ => None,
            };
            let figures = run.frames.last_mut().expect("the frame was rendered");
            figures.verdict = Some(FrameVerdict {
                mismatch_rate: m.mismatch_rate,
                mean_abs_error: m.mean_abs_error,
                temporal_error: temporal,
                reprojected_pixels: reprojection.as_ref().map(|rp| rp.pixels),
            });
            let img = pass.shade(setup, &run.result().0);
            let file = format!("frames/{}-{i:04}.png", slug(&run.label));
            picture::save_png(&img, &self.dir.join(file))?;
            self.animations[r].push(&img)?;
            if !shaded_refs.iter().any(|(s, _)| *s == spp) {
                shaded_refs.push((spp, references.shade(setup, &pass, spp)));
            }
            let (_, ref_img) = shaded_refs
                .iter()
                .find(|(s, _)| *s == spp)
                .expect("shaded above");
            self.walkthroughs[r].push_pair(ref_img, &img)?;
        }
        self.previous = Some(Previous {
            runs: runs
                .iter()
                .map(|run| run.result().0.visibility.clone())
                .collect(),
            pass,
            references,
        });
        Ok(())
    }

    /// Finishes the animations; returns the last frame's camera pass and references.
    pub fn finish(self) -> Result<(Pass, References)> {
        for anim in self.animations.into_iter().chain(self.walkthroughs) {
            anim.finish()?;
        }
        let last = self.previous.expect("a sequence has frames");
        Ok((last.pass, last.references))
    }
}

/// The mean of a run's per-frame temporal errors, over the frames that have one.
pub fn mean_temporal_error(run: &Run) -> Option<f64> {
    let each: Vec<f64> = run
        .frames
        .iter()
        .filter_map(|f| f.verdict?.temporal_error)
        .collect();
    (!each.is_empty()).then(|| each.iter().sum::<f64>() / each.len() as f64)
}
