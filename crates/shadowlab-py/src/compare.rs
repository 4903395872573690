//! `Scene.compare`: every technique against the ray-traced reference on one frame (the
//! soft-shadow reference under an area light), as a dict shaped like `metrics.json`.

use serde_json::{json, Value};
use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::compare::compare as measure;
use shadowlab::light::Light;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::scene::Scene;
use shadowlab::soft_reference::soft_visibility;
use shadowlab::techniques::{self, Frame, ShadowTechnique};
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;

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

/// What `Scene.compare` runs: techniques with their parameters, and the reference's
/// sub-pixel samples.
pub(crate) struct CompareSpec {
    pub(crate) names: Vec<String>,
    pub(crate) params: BTreeMap<String, Vec<(String, String)>>,
    pub(crate) kind: PatternKind,
    pub(crate) spp: u32,
    pub(crate) pattern_name: String,
    pub(crate) area: Option<AreaLight>,
    pub(crate) light_samples: u32,
}

/// The `metrics.json` of one frame (without the report's image files).
pub(crate) fn compare_frame(
    scene: &Scene,
    camera: &Camera,
    light: &Light,
    spec: &CompareSpec,
) -> shadowlab::Result<Value> {
    let CompareSpec {
        names,
        params,
        kind,
        spp,
        pattern_name,
        area,
        light_samples,
    } = spec;
    let (kind, spp) = (*kind, *spp);
    let samples = pattern(kind, spp)?;
    let mut runs = Vec::new();
    for n in names {
        runs.push(make(n, params.get(n).map_or(&[][..], |p| p))?);
    }
    let view = ViewSamples::render(scene, camera);
    let frame = Frame::new(scene, camera, light, &view).with_area(area.as_ref(), *light_samples);
    let t0 = std::time::Instant::now();
    let reference = Reference::build(scene);
    let bvh_ms = reference.build_ms;
    let (truth, std_error) = match area {
        Some(a) => {
            let soft = soft_visibility(&reference, &frame, a, *light_samples, &samples);
            let e = soft.mean_std_error(&frame);
            (soft.visibility, Some(e))
        }
        None => (reference.visibility(&frame, &samples), None),
    };
    let ref_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut results = Vec::new();
    for (name, t) in names.iter().zip(runs.iter_mut()) {
        let t0 = std::time::Instant::now();
        let s = t.render(&frame).map_err(|e| in_technique(name, e))?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let m = measure(&view, &s.visibility, &truth);
        let stages: serde_json::Map<String, Value> = s
            .stats
            .stages_ms
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        results.push(json!({
            "technique": t.name(), "label": name, "params": t.params(),
            "time_ms": ms, "stages_ms": stages, "memory_bytes": s.stats.memory_bytes,
            "counters": s.stats.counters,
            "mismatch_rate": m.mismatch_rate, "mean_abs_error": m.mean_abs_error,
            "mean_abs_error_rgb": m.mean_abs_error_rgb,
        }));
    }
    Ok(json!({
        "scene": scene.name, "triangles": scene.len(),
        "width": view.width, "height": view.height,
        "covered_pixels": view.covered_count(), "camera_pass_ms": view.time_ms,
        "frames": 1, "threads": rayon::current_num_threads(),
        "shadowlab_version": env!("CARGO_PKG_VERSION"),
        "camera": serde_json::to_value(camera).expect("cameras serialize"),
        "light": serde_json::to_value(light).expect("lights serialize"),
        "area_light": area.map(|a| {
            let mut v = serde_json::to_value(a).expect("area lights serialize");
            v["light_samples"] = json!(light_samples);
            v
        }),
        "reference": {
            "technique": "raytrace", "samples_per_pixel": spp, "pattern": pattern_name,
            "time_ms": ref_ms, "bvh_build_ms": bvh_ms, "trace_ms": ref_ms - bvh_ms,
            "mean_std_error": std_error,
        },
        "results": results,
    }))
}
