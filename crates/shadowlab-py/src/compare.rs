//! `Scene.compare`: every technique (and every value of a swept parameter) against the
//! ray-traced reference on one frame or along the camera path (the soft-shadow reference
//! under an area light), as a dict shaped like `metrics.json`.

use serde_json::{json, Value};
use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::compare::compare as measure;
use shadowlab::light::Light;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::scene::Scene;
use shadowlab::soft_reference::soft_visibility;
use shadowlab::techniques::{self, Frame, ShadowTechnique, Shadows};
use shadowlab::view::ViewSamples;

/// The technique `name` with `params` set.
pub(crate) fn make(
    name: &str,
    params: &[(String, String)],
) -> shadowlab::Result<Box<dyn ShadowTechnique>> {
    let mut t = techniques::create(name)?;
    for (k, v) in params {
        t.set_param(k, v)?;
    }
    Ok(t)
}

/// A technique's failure with the technique named, as the command line reports it.
pub(crate) fn in_technique(name: &str, e: shadowlab::Error) -> shadowlab::Error {
    let msg = format!("technique {name}: {e}");
    if e.is_bad_input() {
        shadowlab::Error::Param(msg)
    } else {
        shadowlab::Error::Output {
            path: Default::default(),
            what: msg,
        }
    }
}

/// The most frames a still view gives a progressive technique to converge in, as the
/// command line's `compare` gives it.
const MAX_STILL_FRAMES: usize = 64;

/// One run of `Scene.compare`: a technique with its parameters and its label (`sm`, or
/// `sm.resolution=512` for one value of a sweep, as the command line labels it).
pub(crate) struct RunSpec {
    pub(crate) name: String,
    pub(crate) label: String,
    pub(crate) params: Vec<(String, String)>,
    /// The swept key and value, for a run of a sweep.
    pub(crate) sweep: Option<(String, String)>,
}

/// What `Scene.compare` runs: the runs, the reference's sub-pixel samples and the frames.
pub(crate) struct CompareSpec {
    pub(crate) runs: Vec<RunSpec>,
    pub(crate) kind: PatternKind,
    pub(crate) spp: u32,
    pub(crate) pattern_name: String,
    pub(crate) area: Option<AreaLight>,
    pub(crate) light_samples: u32,
    /// Frames along the scene's camera path (a still camera without one); 1 is a still view.
    pub(crate) frames: usize,
}

/// A run while its frames come: the technique, its last result and time, its per-frame
/// figures and how many frames it rendered.
struct Run<'a> {
    spec: &'a RunSpec,
    technique: Box<dyn ShadowTechnique>,
    last: Option<(Shadows, f64)>,
    frames: Vec<Value>,
    frames_run: usize,
}

impl Run<'_> {
    /// Renders one frame; on a still view a progressive technique renders it again until it
    /// converges or has had [`MAX_STILL_FRAMES`] frames, as the command line does.
    fn render(&mut self, frame: &Frame, still: bool) -> shadowlab::Result<()> {
        loop {
            let t0 = std::time::Instant::now();
            let s = self
                .technique
                .render(frame)
                .map_err(|e| in_technique(&self.spec.label, e))?;
            self.last = Some((s, t0.elapsed().as_secs_f64() * 1e3));
            self.frames_run += 1;
            if !(still
                && self.technique.converged() == Some(false)
                && self.frames_run < MAX_STILL_FRAMES)
            {
                return Ok(());
            }
        }
    }
}

/// The camera of frame `i` of `n`: along the scene's camera path when it has one and
/// `n > 1`, else `camera`; its depth range fitted to the scene.
fn camera_at(scene: &Scene, camera: &Camera, i: usize, n: usize) -> Camera {
    let mut c = match &scene.camera_path {
        Some(path) if n > 1 => path.camera_at(camera, i, n),
        _ => *camera,
    };
    c.fit_depth_range(&scene.bounds);
    c
}

/// The `metrics.json` of a comparison (without the report's image files): every run
/// measured against the reference of each frame, through one BVH; the run's own fields
/// describe the last frame, and with `frames > 1` `results[].frames` holds every frame's.
pub(crate) fn compare_frame(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    spec: &CompareSpec,
) -> shadowlab::Result<Value> {
    let (kind, spp, frames) = (spec.kind, spec.spp, spec.frames.max(1));
    let samples = pattern(kind, spp)?;
    let mut runs = Vec::new();
    for r in &spec.runs {
        runs.push(Run {
            spec: r,
            technique: make(&r.name, &r.params)?,
            last: None,
            frames: Vec::new(),
            frames_run: 0,
        });
    }
    let reference = Reference::build(scene);
    let mut last = None;
    for i in 0..frames {
        let cam = camera_at(scene, camera, i, frames);
        cam.validate()?;
        let view = ViewSamples::try_render(scene, &cam)?;
        let mut frame =
            Frame::new(scene, &cam, light, &view).with_area(spec.area.as_ref(), spec.light_samples);
        frame.index = i;
        for run in runs.iter_mut() {
            run.render(&frame, frames == 1)?;
        }
        let t0 = std::time::Instant::now();
        let (truth, std_error) = match &spec.area {
            Some(a) => {
                let soft = soft_visibility(&reference, &frame, a, spec.light_samples, &samples);
                let e = soft.mean_std_error(&frame);
                (soft.visibility, Some(e))
            }
            None => (reference.visibility(&frame, &samples), None),
        };
        let trace_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut measured = Vec::new();
        for run in runs.iter_mut() {
            let (s, ms) = run.last.as_ref().expect("every run renders each frame");
            let m = measure(&view, &s.visibility, &truth);
            run.frames.push(json!({
                "frame": i, "time_ms": ms, "memory_bytes": s.stats.memory_bytes,
                "mismatch_rate": m.mismatch_rate, "mean_abs_error": m.mean_abs_error,
            }));
            measured.push(m);
        }
        last = Some((cam, view, trace_ms, std_error, measured));
    }
    let (cam, view, trace_ms, std_error, measured) = last.expect("at least one frame");
    let bvh_ms = reference.build_ms;
    let mut results = Vec::new();
    for (run, m) in runs.iter().zip(measured) {
        let (s, ms) = run.last.as_ref().expect("every run renders each frame");
        let t = &run.technique;
        let stages: serde_json::Map<String, Value> = s
            .stats
            .stages_ms
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        let mut r = json!({
            "technique": t.name(), "label": run.spec.label, "params": t.params(),
            "time_ms": ms, "stages_ms": stages, "memory_bytes": s.stats.memory_bytes,
            "counters": s.stats.counters,
            "mismatch_rate": m.mismatch_rate, "mean_abs_error": m.mean_abs_error,
            "mean_abs_error_rgb": m.mean_abs_error_rgb,
            "reference_spp": spp, "reference_std_error": std_error,
            "frames_run": run.frames_run, "converged": t.converged(),
        });
        if let Some((key, value)) = &run.spec.sweep {
            r["sweep"] = json!({ "key": key, "value": value });
        }
        if frames > 1 {
            r["frames"] = json!(run.frames);
        }
        results.push(r);
    }
    Ok(json!({
        "scene": scene.name, "triangles": scene.len(),
        "width": view.width, "height": view.height,
        "covered_pixels": view.covered_count(), "camera_pass_ms": view.time_ms,
        "frames": frames, "threads": rayon::current_num_threads(),
        "shadowlab_version": env!("CARGO_PKG_VERSION"),
        "camera": serde_json::to_value(cam).expect("cameras serialize"),
        "light": serde_json::to_value(light).expect("lights serialize"),
        "area_light": spec.area.map(|a| {
            let mut v = serde_json::to_value(a).expect("area lights serialize");
            v["light_samples"] = json!(spec.light_samples);
            v
        }),
        "reference": {
            "technique": "raytrace", "samples_per_pixel": spp, "pattern": spec.pattern_name,
            "time_ms": bvh_ms + trace_ms, "bvh_build_ms": bvh_ms, "trace_ms": trace_ms,
            "mean_std_error": std_error,
        },
        "results": results,
    }))
}
