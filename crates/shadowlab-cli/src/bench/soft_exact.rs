//! `soft-exact`: exact soft shadows from the alias-free structure (`afsm-soft`) against
//! the brute-force way to the same result, the hard alias-free shadow map (`afsm`) run
//! once per light sample with a punctual light at the sample's position, on the same view
//! samples, in one run. Both give every view sample the visibility of the same light
//! samples (the soft reference's); the target is a speed-up of at least 10× at 256 light
//! samples.
//!
//! The scene is `penumbra` (its rectangular light's samples are the same points from every
//! receiver, so each is a punctual light). With `--quick` 160×120, else 320×240.

use super::{median_ms, BenchReport};
use crate::config::BenchConfig;
use crate::progress;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use shadowlab::area_light::light_samples;
use shadowlab::light::Light;
use shadowlab::math::Vec3;
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;

/// The speed-up the exact soft technique is to reach over one hard frame per light
/// sample, at 256 light samples.
const TARGET_SPEEDUP: f64 = 10.0;

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let (width, height, counts): (u32, u32, &[u32]) = if a.quick {
        (160, 120, &[64, 256])
    } else {
        (320, 240, &[16, 64, 256])
    };
    let repeat = if a.quick { 1 } else { a.repeat.max(1) };
    let mut scene = shadowlab::scene::load("penumbra", &Default::default())
        .context("loading the penumbra scene")?;
    let mut camera = scene.camera.take().context("penumbra has no camera")?;
    camera.width = width;
    camera.height = height;
    camera.fit_depth_range(&scene.bounds);
    let area = scene.area_light.context("penumbra has no area light")?;
    let light = scene.light.context("penumbra has no light")?;
    let view = ViewSamples::render(&scene, &camera);
    let total: u64 = counts.iter().map(|&n| n as u64).sum();
    let bar = progress::bar(total, "soft-exact");
    let mut rows = Vec::new();
    let mut soft = techniques::create("afsm-soft")?;
    let mut hard = techniques::create("afsm")?;
    for &n in counts {
        bar.set_message(format!("{n} light samples"));
        let frame = Frame::new(&scene, &camera, &light, &view).with_area(Some(&area), n);
        soft.render(&frame)?; // warms the buffers
        let (soft_ms, shadows) = median_ms(repeat, || soft.render(&frame));
        let shadows = shadows?;
        // Brute force: one hard frame per light sample, a point light at its position.
        let mut hard_ms = 0.0;
        let mut sum = vec![Vec3::ZERO; view.triangle.len()];
        for uv in light_samples(n) {
            let point = Light::Point {
                position: area.position(Vec3::ZERO, uv),
            };
            let f = Frame::new(&scene, &camera, &point, &view);
            let t0 = std::time::Instant::now();
            let s = hard.render(&f)?;
            hard_ms += t0.elapsed().as_secs_f64() * 1e3;
            for (acc, v) in sum.iter_mut().zip(&s.visibility.value) {
                *acc += *v;
            }
            bar.inc(1);
        }
        // The two agree wherever every light sample is in front of the surface (the hard
        // frames light a point facing away from a sample as unlit too).
        let differ = (0..sum.len())
            .filter(|&k| view.covered(k))
            .filter(|&k| {
                (sum[k] / n as f32 - shadows.visibility.value[k])
                    .abs()
                    .max_element()
                    > 1e-6
            })
            .count();
        let c = &shadows.stats.counters;
        rows.push(json!({
            "light_samples": n,
            "soft_ms": soft_ms,
            "hard_per_sample_ms": hard_ms,
            "speedup": hard_ms / soft_ms,
            "pixels_differing": differ,
            "pairs": c.get("pairs"),
            "pairs_masked": c.get("pairs_masked"),
            "ray_tests": c.get("ray_tests"),
            "stages_ms": shadows.stats.stages_ms,
            "width": width, "height": height, "triangles": scene.len(),
        }));
    }
    bar.finish_and_clear();
    print_table(&rows, width, height, scene.len());
    Ok(BenchReport { rows })
}

fn print_table(rows: &[Value], width: u32, height: u32, triangles: usize) {
    let f = |r: &Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    println!(
        "soft-exact: penumbra ({triangles} triangles), {width}x{height}, {} threads; brute force = afsm once per light sample",
        rayon::current_num_threads()
    );
    println!(
        "{:>13} {:>12} {:>14} {:>9} {:>12} {:>12} {:>10}",
        "light samples",
        "afsm-soft ms",
        "afsm x N ms",
        "speed-up",
        "pairs",
        "ray tests",
        "differing"
    );
    for r in rows {
        println!(
            "{:>13} {:>12.1} {:>14.1} {:>9.1} {:>12} {:>12} {:>10}",
            r["light_samples"],
            f(r, "soft_ms"),
            f(r, "hard_per_sample_ms"),
            f(r, "speedup"),
            f(r, "pairs"),
            f(r, "ray_tests"),
            r["pixels_differing"],
        );
    }
    if let Some(r) = rows.iter().find(|r| r["light_samples"] == 256) {
        let s = f(r, "speedup");
        println!(
            "target: >= {TARGET_SPEEDUP}x hard afsm once per light sample at 256 samples: {s:.1}x, {}",
            if s >= TARGET_SPEEDUP { "met" } else { "NOT met" }
        );
    }
}
