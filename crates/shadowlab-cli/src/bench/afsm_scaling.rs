//! `afsm-scaling`: the alias-free shadow map paper's Table 1 — 1K, 10K, 100K and 1M random
//! triangles of constant total area (the built-in `random-triangles` scene), 1024×768, its
//! own camera and light — with the ray-traced reference timed in the same run on the same
//! view samples: BVH build and shadow-ray trace reported separately. Built with the cargo
//! feature `embree`, Intel Embree 3's BVH build and occlusion rays (`rtcOccluded1`) over the
//! same scene and samples are timed too, with their agreement with the reference.
//!
//! With a GPU adapter, `gpu:afsm` and `gpu:raytrace` are timed on the same scene at
//! 1920×1080 (`--quick`: 480×270) too (see
//! [`super::afsm_scaling_gpu`]), with the target that `gpu:afsm`'s GPU time is at most
//! `gpu:raytrace`'s at every size.
//!
//! `afsm` times are the technique's own frame (transform, BSP, rasterization); the camera
//! pass, shared by every technique, is excluded, as the paper's table excludes it. Each
//! figure is the median of `--repeat` runs after one untimed warm-up frame. The paper ran on
//! a 1.6 GHz Mobile Pentium 4; the targets, printed with whether each is met: at least 30×
//! its total at every size, and no slower than Embree tracing the same shadow rays through
//! its prebuilt BVH at every size (the trace alone; measured when built with `embree`).

use super::afsm_scaling_gpu::{self as gpu, GpuTimes};
use super::{verdict, BenchReport};
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::json;
use shadowlab::compare::compare;
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;
use std::time::Instant;

/// Triangle counts of the paper's columns.
const COUNTS: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];
/// The paper's Table 1, per column: BSP nodes, nodes visited, nodes occlusion culled,
/// sampling points tested, transformation, BSP construction, rasterization and total (ms).
/// The transformation was reported once (130 ms) for all four scenes.
const PAPER: [[f64; 8]; 4] = [
    [16e3, 91e3, 5.3e3, 458e3, 130.0, 400.0, 145.0, 675.0],
    [16e3, 471e3, 5.4e3, 513e3, 130.0, 402.0, 381.0, 913.0],
    [16e3, 3.2e6, 5.8e3, 506e3, 130.0, 391.0, 1568.0, 2089.0],
    [16e3, 23e6, 6.8e3, 501e3, 130.0, 408.0, 8102.0, 8640.0],
];
/// Speed-up over the paper's total that the implementation aims for at every size.
const TARGET_SPEEDUP: f64 = 30.0;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn stage(s: &Shadows, name: &str) -> f64 {
    s.stats
        .stages_ms
        .iter()
        .find(|(n, _)| n == name)
        .map_or(0.0, |(_, t)| *t)
}

fn counter(s: &Shadows, name: &str) -> f64 {
    s.stats.counters.get(name).copied().unwrap_or(0.0)
}

/// A count in the paper's style: 91K, 3.2M.
fn short(x: f64) -> String {
    if x >= 1e6 {
        format!("{:.1}M", x / 1e6)
    } else if x >= 1e3 {
        format!("{:.1}K", x / 1e3)
    } else {
        format!("{x:.0}")
    }
}

/// One column of the table.
struct Column {
    triangles: usize,
    afsm_ms: f64,
    transform_ms: f64,
    bsp_ms: f64,
    raster_ms: f64,
    bvh_build_ms: f64,
    trace_ms: f64,
    mismatch_rate: f64,
    covered: usize,
    last: Shadows,
    embree: Option<EmbreeTimes>,
    gpu: Option<GpuTimes>,
}

/// Intel Embree's BVH build and occlusion rays over the same scene and samples.
struct EmbreeTimes {
    build_ms: f64,
    trace_ms: f64,
    /// Share of covered pixels where Embree's answer differs from the reference.
    mismatch_rate: f64,
}

#[cfg(feature = "embree")]
fn measure_embree(
    scene: &shadowlab::scene::Scene,
    frame: &Frame,
    truth: &shadowlab::techniques::Visibility,
    repeat: usize,
) -> Result<Option<EmbreeTimes>> {
    use shadowlab::embree::EmbreeScene;
    let mut builds = Vec::new();
    let mut traces = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let e = EmbreeScene::build(scene, rayon::current_num_threads())?;
        builds.push(e.build_ms);
        let t0 = Instant::now();
        let v = e.visibility(frame);
        traces.push(t0.elapsed().as_secs_f64() * 1e3);
        last = Some(v);
    }
    let v = last.expect("at least one trace");
    let m = compare(frame.view, &v, truth);
    Ok(Some(EmbreeTimes {
        build_ms: median(builds),
        trace_ms: median(traces),
        mismatch_rate: m.mismatch_rate,
    }))
}

#[cfg(not(feature = "embree"))]
fn measure_embree(
    _: &shadowlab::scene::Scene,
    _: &Frame,
    _: &shadowlab::techniques::Visibility,
    _: usize,
) -> Result<Option<EmbreeTimes>> {
    Ok(None)
}

fn measure(count: usize, repeat: usize, quick: bool) -> Result<Column> {
    let params = BTreeMap::from([("count".to_string(), count.to_string())]);
    let scene = shadowlab::scene::load("random-triangles", &params)
        .context("generating random-triangles")?;
    let mut camera = scene.camera.context("random-triangles has no camera")?;
    camera.width = 1024;
    camera.height = 768;
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.context("random-triangles has no light")?;
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);

    let mut afsm = techniques::create("afsm")?;
    afsm.render(&frame)?;
    let mut runs = Vec::new();
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        let s = afsm.render(&frame)?;
        runs.push((t0.elapsed().as_secs_f64() * 1e3, s));
    }
    let afsm_ms = median(runs.iter().map(|r| r.0).collect());
    let transform_ms = median(runs.iter().map(|r| stage(&r.1, "transform")).collect());
    let bsp_ms = median(runs.iter().map(|r| stage(&r.1, "bsp")).collect());
    let raster_ms = median(runs.iter().map(|r| stage(&r.1, "raster")).collect());
    let last = runs.pop().expect("at least one run").1;

    // The reference: the same shadow rays from the same samples, through a BVH built for
    // this frame.
    let centre = [vec2(0.5, 0.5)];
    let mut builds = Vec::new();
    let mut traces = Vec::new();
    let mut truth = None;
    for _ in 0..repeat.max(1) {
        let reference = Reference::build(&scene);
        builds.push(reference.build_ms);
        let t0 = Instant::now();
        let v = reference.visibility(&frame, &centre);
        traces.push(t0.elapsed().as_secs_f64() * 1e3);
        truth = Some(v);
    }
    let truth = truth.expect("at least one trace");
    let m = compare(&view, &last.visibility, &truth);
    let embree = measure_embree(&scene, &frame, &truth, repeat)?;
    let gpu = gpu::measure(&scene, &camera, &light, repeat, quick);
    Ok(Column {
        triangles: count,
        afsm_ms,
        transform_ms,
        bsp_ms,
        raster_ms,
        bvh_build_ms: median(builds),
        trace_ms: median(traces),
        mismatch_rate: m.mismatch_rate,
        covered: m.covered_pixels,
        last,
        embree,
        gpu,
    })
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let repeat = if a.quick { 1 } else { a.repeat };
    let mut cols = Vec::new();
    for &n in &COUNTS {
        let p = crate::progress::step(format!("afsm-scaling: {} triangles", short(n as f64)));
        cols.push(measure(n, repeat, a.quick)?);
        p.finish_and_clear();
    }
    println!(
        "afsm-scaling: random-triangles, 1024x768, {} threads, median of {} run(s); paper: 1.6 GHz Mobile Pentium 4",
        rayon::current_num_threads(),
        repeat
    );
    let table = Table {
        cols: &cols,
        quick: a.quick,
    };
    table.head();
    table.paper_rows();
    table.reference_rows();
    table.embree_rows();
    table.gpu_rows();
    table.footer_rows();
    print_targets(&cols);
    Ok(BenchReport {
        rows: cols.iter().map(row).collect(),
    })
}

/// The paper's column for a measured one.
fn paper_of(c: &Column) -> [f64; 8] {
    PAPER[COUNTS.iter().position(|&n| n == c.triangles).unwrap_or(0)]
}

fn ms(x: f64) -> String {
    format!("{x:.1}")
}

/// The printed table: a line per measure, a pair of cells (paper, ours) per column.
struct Table<'c> {
    cols: &'c [Column],
    quick: bool,
}

impl Table<'_> {
    fn line(&self, label: &str, f: &dyn Fn(&Column) -> (String, String)) {
        let mut s = format!("{label:<30}");
        for c in self.cols {
            let (p, o) = f(c);
            s.push_str(&format!(" | {p:>10} {o:>10}"));
        }
        println!("{s}");
    }

    /// The column heads: triangle counts, then paper and ours.
    fn head(&self) {
        let mut head = format!("{:<30}", "");
        for c in self.cols {
            head.push_str(&format!(
                " | {:>21}",
                format!("{} triangles", short(c.triangles as f64))
            ));
        }
        println!("{head}");
        let mut sub = format!("{:<30}", "");
        for _ in self.cols {
            sub.push_str(&format!(" | {:>10} {:>10}", "paper", "ours"));
        }
        println!("{sub}");
    }

    /// The paper's rows: its counters and stage times beside ours.
    fn paper_rows(&self) {
        let counts_row = |label: &str, i: usize, name: &'static str| {
            self.line(label, &|c| {
                (short(paper_of(c)[i]), short(counter(&c.last, name)))
            });
        };
        counts_row("#2D BSP nodes", 0, "bsp_nodes");
        counts_row("#2D BSP nodes visited", 1, "nodes_visited");
        counts_row("#nodes occlusion culled", 2, "nodes_occlusion_culled");
        counts_row("#sampling points tested", 3, "samples_tested");
        self.line("#shadow-ray tests in leaves", &|c| {
            ("-".into(), short(counter(&c.last, "ray_tests")))
        });
        self.line("#samples (lit, visible)", &|c| {
            ("-".into(), short(counter(&c.last, "samples")))
        });
        self.line("Transformation of samples ms", &|c| {
            (ms(paper_of(c)[4]), ms(c.transform_ms))
        });
        self.line("BSP construction ms", &|c| {
            (ms(paper_of(c)[5]), ms(c.bsp_ms))
        });
        self.line("Rasterization of blockers ms", &|c| {
            (ms(paper_of(c)[6]), ms(c.raster_ms))
        });
        self.line("Total time ms", &|c| (ms(paper_of(c)[7]), ms(c.afsm_ms)));
        self.line("Speed-up over the paper", &|c| {
            ("1".into(), format!("{:.1}x", paper_of(c)[7] / c.afsm_ms))
        });
    }

    /// The ray-traced reference's times and afsm's ratios to them.
    fn reference_rows(&self) {
        self.line("Reference BVH build ms", &|c| {
            ("-".into(), ms(c.bvh_build_ms))
        });
        self.line("Reference trace ms", &|c| ("-".into(), ms(c.trace_ms)));
        self.line("afsm / trace", &|c| {
            ("-".into(), format!("{:.2}", c.afsm_ms / c.trace_ms))
        });
        self.line("afsm / (build + trace)", &|c| {
            (
                "-".into(),
                format!("{:.2}", c.afsm_ms / (c.bvh_build_ms + c.trace_ms)),
            )
        });
    }

    /// Embree's times and agreement, when it was timed.
    fn embree_rows(&self) {
        if self.cols.iter().all(|c| c.embree.is_none()) {
            return;
        }
        let embree = |c: &Column, f: &dyn Fn(&EmbreeTimes) -> String| {
            ("-".to_string(), c.embree.as_ref().map_or("-".into(), f))
        };
        self.line("Embree BVH build ms", &|c| embree(c, &|e| ms(e.build_ms)));
        self.line("Embree trace ms", &|c| embree(c, &|e| ms(e.trace_ms)));
        self.line("afsm / Embree trace", &|c| {
            embree(c, &|e| format!("{:.2}", c.afsm_ms / e.trace_ms))
        });
        self.line("afsm / Embree (build + trace)", &|c| {
            embree(c, &|e| {
                format!("{:.2}", c.afsm_ms / (e.build_ms + e.trace_ms))
            })
        });
        self.line("Embree mismatch vs reference", &|c| {
            embree(c, &|e| format!("{:.5}%", e.mismatch_rate * 100.0))
        });
    }

    /// The GPU techniques' times, when an adapter was there.
    fn gpu_rows(&self) {
        let Some(adapter) = self.cols.iter().find_map(|c| c.gpu.as_ref()) else {
            return;
        };
        let (w, h) = gpu::size(self.quick);
        println!("GPU rows at {w}x{h}: {}", adapter.adapter);
        let gpu = |c: &Column, f: &dyn Fn(&GpuTimes) -> String| {
            ("-".to_string(), c.gpu.as_ref().map_or("-".into(), f))
        };
        self.line("gpu:afsm ms (wall)", &|c| gpu(c, &|g| ms(g.afsm.wall_ms)));
        self.line("gpu:afsm ms (GPU)", &|c| {
            gpu(c, &|g| format!("{:.2}", g.afsm.gpu_ms))
        });
        self.line("gpu:raytrace ms (wall)", &|c| {
            gpu(c, &|g| ms(g.raytrace.wall_ms))
        });
        self.line("gpu:raytrace ms (GPU)", &|c| {
            gpu(c, &|g| format!("{:.2}", g.raytrace.gpu_ms))
        });
        self.line("gpu:afsm / gpu:raytrace (GPU)", &|c| {
            gpu(c, &|g| format!("{:.2}", g.afsm.gpu_ms / g.raytrace.gpu_ms))
        });
        self.line("gpu:afsm/raytrace mismatch", &|c| {
            gpu(c, &|g| format!("{:.5}%", g.mismatch_rate * 100.0))
        });
    }

    /// Mismatch and memory, and whether Embree was timed.
    fn footer_rows(&self) {
        self.line("Mismatch vs reference", &|c| {
            ("-".into(), format!("{:.5}%", c.mismatch_rate * 100.0))
        });
        self.line("Memory MB", &|c| {
            (
                "-".into(),
                format!("{:.1}", c.last.stats.memory_bytes as f64 / 1e6),
            )
        });
        if self.cols.iter().all(|c| c.embree.is_none()) {
            println!(
                "Embree: not timed (build with `--features embree`, which needs Debian's libembree-dev)"
            );
        }
    }
}

/// Whether each column meets its targets: at least [`TARGET_SPEEDUP`]× the paper's total,
/// and no slower than Embree's occlusion rays through its prebuilt BVH (when Embree was
/// timed; the reference's own trace is printed beside it).
fn print_targets(cols: &[Column]) {
    println!("\ntargets:");
    for c in cols {
        let speedup = paper_of(c)[7] / c.afsm_ms;
        let mut notes = vec![format!(
            "{speedup:.1}x the paper (target {TARGET_SPEEDUP}x): {}",
            verdict(speedup >= TARGET_SPEEDUP)
        )];
        notes.push(match &c.embree {
            Some(e) => format!(
                "afsm {:.1} ms vs Embree trace {:.1} ms (target at most 1.00x, {:.2}x): {}",
                c.afsm_ms,
                e.trace_ms,
                c.afsm_ms / e.trace_ms,
                verdict(c.afsm_ms <= e.trace_ms)
            ),
            None => "afsm vs Embree trace: not measured (build with `--features embree`)".into(),
        });
        if let Some(g) = &c.gpu {
            notes.push(gpu::target(g));
        }
        notes.push(format!(
            "vs reference trace {:.1} ms: {:.2}x",
            c.trace_ms,
            c.afsm_ms / c.trace_ms
        ));
        println!(
            "  {:>5} triangles: {}",
            short(c.triangles as f64),
            notes.join("; ")
        );
    }
}

/// A column as its JSON row.
fn row(c: &Column) -> serde_json::Value {
    let p = paper_of(c);
    json!({
        "triangles": c.triangles,
        "afsm_ms": c.afsm_ms,
        "transform_ms": c.transform_ms,
        "bsp_ms": c.bsp_ms,
        "raster_ms": c.raster_ms,
        "bvh_build_ms": c.bvh_build_ms,
        "trace_ms": c.trace_ms,
        "embree_build_ms": c.embree.as_ref().map(|e| e.build_ms),
        "embree_trace_ms": c.embree.as_ref().map(|e| e.trace_ms),
        "embree_mismatch_rate": c.embree.as_ref().map(|e| e.mismatch_rate),
        "paper_total_ms": p[7],
        "paper_transform_ms": p[4],
        "paper_bsp_ms": p[5],
        "paper_raster_ms": p[6],
        "speedup_vs_paper": p[7] / c.afsm_ms,
        "bsp_nodes": counter(&c.last, "bsp_nodes"),
        "nodes_visited": counter(&c.last, "nodes_visited"),
        "nodes_occlusion_culled": counter(&c.last, "nodes_occlusion_culled"),
        "samples_tested": counter(&c.last, "samples_tested"),
        "ray_tests": counter(&c.last, "ray_tests"),
        "samples": counter(&c.last, "samples"),
        "paper_bsp_nodes": p[0],
        "paper_nodes_visited": p[1],
        "paper_nodes_occlusion_culled": p[2],
        "paper_samples_tested": p[3],
        "covered_pixels": c.covered,
        "mismatch_rate": c.mismatch_rate,
        "memory_bytes": c.last.stats.memory_bytes,
        "gpu_adapter": c.gpu.as_ref().map(|g| g.adapter.clone()),
        "gpu_afsm_wall_ms": c.gpu.as_ref().map(|g| g.afsm.wall_ms),
        "gpu_afsm_gpu_ms": c.gpu.as_ref().map(|g| g.afsm.gpu_ms),
        "gpu_afsm_vs_raytrace_mismatch_rate": c.gpu.as_ref().map(|g| g.mismatch_rate),
        "gpu_raytrace_wall_ms": c.gpu.as_ref().map(|g| g.raytrace.wall_ms),
        "gpu_raytrace_gpu_ms": c.gpu.as_ref().map(|g| g.raytrace.gpu_ms),
    })
}
