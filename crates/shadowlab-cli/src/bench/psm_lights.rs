//! `psm-lights`: perspective against uniform shadow maps at equal resolution as the light
//! turns from perpendicular to the view direction (90°) to parallel to it (0°), from in
//! front of the viewer and from behind (the perspective shadow map paper's Section 3.3).
//!
//! The light is directional and turns in the plane of the view direction and the scene's
//! 90° light (its own sun made perpendicular to the view, else the direction above the
//! view): "front" lights shine towards the camera, "behind" lights shine along the view.
//! A light below [`MIN_ELEVATION_DEG`] would leave the scene in grazing light, so angles
//! the camera's pitch makes unreachable from one side are measured from the other only.
//! (A sweep in the vertical plane down the street would light every facade at grazing
//! incidence, where every map-based technique fails alike.) Each
//! row renders the ray-traced reference once and times `psm` and `sm` (their own frame
//! time: light maps and look-ups; the shared camera pass is excluded), interleaved, as the
//! median of `--repeat` runs after one untimed run.
//!
//! The paper gives no table for this; its statements, printed beside ours: the benefit is
//! largest at 90° and vanishes at 0°, where the parameterization becomes that of a uniform
//! map, and the overhead is a depth read-back (10 ms at 640×480 on their machine) plus the
//! set-up of one projection matrix.

use super::{median_ms, verdict, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::json;
use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::math::{vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;

/// Map side for both techniques (the paper's street and ecosystem figures use 1024²).
const RESOLUTION: u32 = 1024;
/// Angles between the light and the view direction, in the order measured.
const ANGLES: [f32; 7] = [90.0, 75.0, 60.0, 45.0, 30.0, 15.0, 0.0];
/// The fewer angles of `--quick`.
const QUICK_ANGLES: [f32; 4] = [90.0, 60.0, 30.0, 0.0];
/// Lights lower than this above the horizon are skipped: most of the scene would be lit at
/// grazing angles or not at all.
const MIN_ELEVATION_DEG: f32 = 10.0;
/// The targets: `psm` at most this multiple of `sm`'s mismatch, and of its time.
const MISMATCH_TARGET: f64 = 1.25;
const TIME_TARGET: f64 = 1.15;

/// One light of the sweep.
struct Sweep {
    angle: f32,
    behind: bool,
    elevation: f32,
    to_light: Vec3,
}

/// The lights of the sweep for a camera looking along `forward`. They turn in the plane
/// spanned by the view direction and `perpendicular` (a unit vector perpendicular to it,
/// with an upward component): at 90° the light is `perpendicular`, at 0° it shines along
/// the view (behind) or against it (front).
fn sweep(forward: Vec3, perpendicular: Vec3, angles: &[f32]) -> Vec<Sweep> {
    let min_y = MIN_ELEVATION_DEG.to_radians().sin();
    let mut out = Vec::new();
    for &angle in angles {
        let (s, c) = angle.to_radians().sin_cos();
        for behind in [false, true] {
            if angle >= 90.0 && behind {
                continue;
            }
            // A light behind the viewer lies opposite the view direction.
            let to_light = (perpendicular * s + forward * if behind { -c } else { c }).normalize();
            if to_light.y >= min_y {
                out.push(Sweep {
                    angle,
                    behind,
                    elevation: to_light.y.clamp(-1.0, 1.0).asin().to_degrees(),
                    to_light,
                });
            }
        }
    }
    out
}

/// The 90° light of a scene: its own directional light made perpendicular to the view (the
/// street's sun), or else the direction in the plane of the view and the up axis (the
/// paper's Fig. 3).
fn perpendicular_light(light: Option<Light>, forward: Vec3) -> Vec3 {
    let reject = |v: Vec3| (v - forward * v.dot(forward)).normalize_or_zero();
    match light {
        Some(Light::Directional { to_light }) if reject(to_light).y > 0.1 => reject(to_light),
        _ => reject(Vec3::Y),
    }
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let (scenes, angles, size, repeat): (&[&str], &[f32], (u32, u32), usize) = if a.quick {
        (&["chessboard"], &QUICK_ANGLES, (512, 384), a.repeat.min(3))
    } else {
        (&["chessboard", "street"], &ANGLES, (1024, 768), a.repeat)
    };
    println!(
        "psm-lights: psm vs sm at {RESOLUTION}², directional light at an angle to the view direction; {} threads; times are medians of {repeat} runs",
        rayon::current_num_threads()
    );
    println!("paper (Sect. 3.3): the gain is largest at 90° and vanishes at 0° (uniform map); overhead: a depth read-back (10 ms at 640x480) and one matrix");
    let mut rows = Vec::new();
    let mut worst_mismatch = 0.0f64;
    let mut per_scene = Vec::new();
    for &name in scenes {
        let mut scene_time = 0.0f64;
        let scene = shadowlab::scene::load(name, &Default::default())
            .with_context(|| format!("loading the {name} scene"))?;
        let mut camera = scene
            .camera
            .with_context(|| format!("{name} has no camera"))?;
        (camera.width, camera.height) = size;
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let bvh = Reference::build(&scene);
        let lights = sweep(
            camera.forward(),
            perpendicular_light(scene.light, camera.forward()),
            angles,
        );
        println!(
            "\n{name}: {} triangles, {}x{}, {} covered pixels",
            scene.len(),
            size.0,
            size.1,
            view.covered_count()
        );
        println!(
            "{:>6} {:>7} {:>6} | {:>9} {:>9} {:>6} | {:>8} {:>8} {:>5} | {:>9} {:>7}",
            "angle",
            "light",
            "elev",
            "psm miss",
            "sm miss",
            "ratio",
            "psm ms",
            "sm ms",
            "ratio",
            "psm case",
            "shift"
        );
        let pb = crate::progress::bar(lights.len() as u64, name.to_string());
        for l in &lights {
            let light = Light::Directional {
                to_light: l.to_light,
            };
            let frame = Frame::new(&scene, &camera, &light, &view);
            let reference = bvh.visibility(&frame, &[vec2(0.5, 0.5)]);
            let mut psm = techniques::create("psm")?;
            let mut sm = techniques::create("sm")?;
            for t in [&mut psm, &mut sm] {
                t.set_param("resolution", &RESOLUTION.to_string())?;
                // One untimed frame first, so page faults of fresh buffers are not timed.
                t.render(&frame)?;
            }
            // Interleave the two so that a change of machine load hits both alike.
            let (mut psm_times, mut sm_times) = (Vec::new(), Vec::new());
            let (mut psm_out, mut sm_out): (Option<Shadows>, Option<Shadows>) = (None, None);
            for _ in 0..repeat.max(1) {
                let (ms, r) = median_ms(1, || psm.render(&frame));
                psm_times.push(ms);
                psm_out = Some(r?);
                let (ms, r) = median_ms(1, || sm.render(&frame));
                sm_times.push(ms);
                sm_out = Some(r?);
            }
            let (psm_out, sm_out) = (psm_out.expect("ran once"), sm_out.expect("ran once"));
            let (psm_ms, sm_ms) = (median(&mut psm_times), median(&mut sm_times));
            let pm = compare(&view, &psm_out.visibility, &reference).mismatch_rate;
            let smm = compare(&view, &sm_out.visibility, &reference).mismatch_rate;
            let c = |k: &str| psm_out.stats.counters.get(k).copied().unwrap_or(0.0);
            let case = match (c("inverted") > 0.0, c("post_directional") > 0.0) {
                (true, _) => "inverted",
                (_, true) => "directional",
                _ => "point",
            };
            let mratio = if smm > 0.0 {
                pm / smm
            } else if pm > 0.0 {
                f64::INFINITY
            } else {
                1.0
            };
            let tratio = psm_ms / sm_ms;
            worst_mismatch = worst_mismatch.max(mratio);
            scene_time = scene_time.max(tratio);
            pb.suspend(|| {
                println!(
                    "{:>5.0}° {:>7} {:>5.0}° | {:>8.4}% {:>8.4}% {:>6.2} | {:>8.1} {:>8.1} {:>5.2} | {:>9} {:>7.2}",
                    l.angle,
                    if l.behind { "behind" } else { "front" },
                    l.elevation,
                    pm * 100.0,
                    smm * 100.0,
                    mratio,
                    psm_ms,
                    sm_ms,
                    tratio,
                    case,
                    c("virtual_shift"),
                )
            });
            rows.push(json!({
                "scene": name,
                "angle_deg": l.angle,
                "behind_viewer": l.behind,
                "elevation_deg": l.elevation,
                "to_light": l.to_light.to_array(),
                "resolution": RESOLUTION,
                "psm_mismatch": pm,
                "sm_mismatch": smm,
                "mismatch_ratio": mratio,
                "psm_ms": psm_ms,
                "sm_ms": sm_ms,
                "time_ratio": tratio,
                "psm_stages_ms": psm_out.stats.stages_ms.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
                "sm_stages_ms": sm_out.stats.stages_ms.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
                "psm_light_case": case,
                "psm_virtual_shift": c("virtual_shift"),
                "psm_maps": c("maps"),
            }));
            pb.inc(1);
        }
        pb.finish_and_clear();
        per_scene.push((name, scene_time));
    }
    println!("\ntargets:");
    println!(
        "  worst psm/sm mismatch ratio {worst_mismatch:.2} (target at most {MISMATCH_TARGET}): {}",
        verdict(worst_mismatch <= MISMATCH_TARGET)
    );
    for (name, t) in per_scene {
        println!(
            "  {name}: worst psm/sm time ratio {t:.2} (target at most {TIME_TARGET}): {}",
            verdict(t <= TIME_TARGET)
        );
    }
    Ok(BenchReport { rows })
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
