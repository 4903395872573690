//! `asm-walkthrough`: the adaptive shadow map paper's walkthrough (Section 5, Figure 4) —
//! the built-in `room` scene (bunny, teapot, rod sculpture; a 122° light on the ceiling)
//! along its camera path at the paper's 512×512, with adaptive shadow maps under 8 MB and
//! 16 MB budgets beside a conventional 2048² map (16 MB of 32-bit depths).
//!
//! Per frame: each technique's own time (the camera pass, shared by all, is excluded), the
//! bytes it holds, and its mismatch against the ray-traced reference. `asm` keeps its tree
//! along the path, with its default parameters (the per-frame time budget included), so
//! its frames are single runs; `sm` is stateless and its time is the median of `--repeat`
//! runs. The paper (1 GHz Pentium III, GeForce2 Ultra) measured 203 ms per ASM frame
//! against 117 ms for the 2048² map, a ratio of 1.74; the target is the same ratio or less.

use super::BenchReport;
use crate::config::BenchConfig;
use anyhow::{Context, Result};
use serde_json::json;
use shadowlab::camera::Camera;
use shadowlab::compare::compare;
use shadowlab::math::vec2;
use shadowlab::reference::Reference;
use shadowlab::techniques::{self, Frame, ShadowTechnique, Shadows, Visibility};
use shadowlab::view::ViewSamples;
use std::time::Instant;

/// The paper's image size.
const SIDE: u32 = 512;
/// Frames along the path (the quick run takes fewer).
const FRAMES: usize = 48;
const QUICK_FRAMES: usize = 12;
/// The budgets of the paper's Figure 4, in MB.
const BUDGETS: [u32; 2] = [8, 16];
/// The conventional map the paper compares with.
const SM_RESOLUTION: u32 = 2048;
/// The paper's per-frame times in ms: ASM (16 MB) and the 2048² map.
const PAPER_ASM_MS: f64 = 203.0;
const PAPER_SM_MS: f64 = 117.0;

fn counter(s: &Shadows, name: &str) -> f64 {
    s.stats.counters.get(name).copied().unwrap_or(0.0)
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// One technique's figures on one frame.
#[derive(Clone, Copy)]
struct Cell {
    ms: f64,
    memory: u64,
    tree: u64,
    mismatch: f64,
    nodes: f64,
    effective: f64,
    refined: f64,
    evicted: f64,
}

/// The walkthrough's measurements: per frame, `sm`'s cell and one cell per budget.
struct Walk {
    triangles: usize,
    frames: usize,
    sm: Vec<Cell>,
    asm: Vec<Vec<Cell>>,
}

/// Runs the suite.
pub fn run(a: &BenchConfig) -> Result<BenchReport> {
    let frames = if a.quick { QUICK_FRAMES } else { FRAMES };
    let repeat = if a.quick { 1 } else { a.repeat.max(1) };
    let walk = walk(frames, repeat)?;
    let rows = print_frames(&walk);
    print_means(&walk);
    Ok(BenchReport { rows })
}

/// Renders the room along its path with `sm` and `asm` at each budget, measuring every
/// frame against the reference.
fn walk(frames: usize, repeat: usize) -> Result<Walk> {
    let scene =
        shadowlab::scene::load("room", &Default::default()).context("generating the room scene")?;
    let light = scene.light.context("the room scene has no light")?;
    let path = scene
        .camera_path
        .clone()
        .context("the room scene has no camera path")?;
    let mut base: Camera = scene.camera.context("the room scene has no camera")?;
    base.width = SIDE;
    base.height = SIDE;

    let mut sm = techniques::create("sm")?;
    sm.set_param("resolution", &SM_RESOLUTION.to_string())?;
    let mut asms: Vec<Box<dyn ShadowTechnique>> = Vec::new();
    for b in BUDGETS {
        let mut t = techniques::create("asm")?;
        t.set_param("budget-mb", &b.to_string())?;
        asms.push(t);
    }
    let reference = Reference::build(&scene);

    let mut walk = Walk {
        triangles: scene.len(),
        frames,
        sm: Vec::new(),
        asm: vec![Vec::new(); BUDGETS.len()],
    };
    let bar = crate::progress::bar(frames as u64, "asm-walkthrough");
    for i in 0..frames {
        let mut camera = path.camera_along(&base, i, frames);
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let mut frame = Frame::new(&scene, &camera, &light, &view);
        frame.index = i;
        let truth = reference.visibility(&frame, &[vec2(0.5, 0.5)]);
        walk.sm.push(sm_cell(sm.as_mut(), &frame, &truth, repeat)?);
        for (t, cells) in asms.iter_mut().zip(walk.asm.iter_mut()) {
            cells.push(asm_cell(t.as_mut(), &frame, &truth)?);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(walk)
}

/// The standard map on one frame: the median time of `repeat` runs.
fn sm_cell(
    sm: &mut dyn ShadowTechnique,
    frame: &Frame,
    truth: &Visibility,
    repeat: usize,
) -> Result<Cell> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat {
        let t0 = Instant::now();
        let s = sm.render(frame)?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        last = Some(s);
    }
    times.sort_by(f64::total_cmp);
    let s = last.expect("at least one run");
    Ok(Cell {
        ms: times[times.len() / 2],
        memory: s.stats.memory_bytes,
        tree: s.stats.memory_bytes,
        mismatch: compare(frame.view, &s.visibility, truth).mismatch_rate,
        nodes: 0.0,
        effective: SM_RESOLUTION as f64,
        refined: 0.0,
        evicted: 0.0,
    })
}

/// The adaptive map on one frame: a single run, its tree kept along the path.
fn asm_cell(t: &mut dyn ShadowTechnique, frame: &Frame, truth: &Visibility) -> Result<Cell> {
    let t0 = Instant::now();
    let s = t.render(frame)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    Ok(Cell {
        ms,
        memory: s.stats.memory_bytes,
        tree: counter(&s, "tree_bytes") as u64,
        mismatch: compare(frame.view, &s.visibility, truth).mismatch_rate,
        nodes: counter(&s, "nodes"),
        effective: counter(&s, "effective_resolution_used"),
        refined: counter(&s, "cells_refined"),
        evicted: counter(&s, "nodes_evicted"),
    })
}

fn mb(b: u64) -> f64 {
    b as f64 / (1024.0 * 1024.0)
}

/// Prints the per-frame table; returns its rows, one per frame and budget.
fn print_frames(walk: &Walk) -> Vec<serde_json::Value> {
    println!(
        "asm-walkthrough: room, {} triangles, {SIDE}×{SIDE}, {} frames along its path; times in ms \
         (camera pass excluded), MB = the adaptive tree's MiB (what the budget bounds), mismatch in % of covered pixels",
        walk.triangles, walk.frames
    );
    println!(
        "{:>5} {:>8} {:>7} {:>7} | {:>8} {:>6} {:>7} {:>6} {:>9} | {:>8} {:>6} {:>7} {:>6} {:>9}",
        "frame",
        "sm ms",
        "sm MB",
        "sm %",
        "8MB ms",
        "MB",
        "%",
        "nodes",
        "eff",
        "16MB ms",
        "MB",
        "%",
        "nodes",
        "eff"
    );
    let mut rows = Vec::new();
    for i in 0..walk.frames {
        let s = walk.sm[i];
        let (x, y) = (walk.asm[0][i], walk.asm[1][i]);
        println!(
            "{i:>5} {:>8.1} {:>7.1} {:>7.4} | {:>8.1} {:>6.2} {:>7.4} {:>6.0} {:>9.0} | {:>8.1} {:>6.2} {:>7.4} {:>6.0} {:>9.0}",
            s.ms,
            mb(s.memory),
            s.mismatch * 100.0,
            x.ms,
            mb(x.tree),
            x.mismatch * 100.0,
            x.nodes,
            x.effective,
            y.ms,
            mb(y.tree),
            y.mismatch * 100.0,
            y.nodes,
            y.effective
        );
        for (b, c) in BUDGETS.iter().zip([x, y]) {
            rows.push(json!({
                "frame": i,
                "budget_mb": b,
                "asm_ms": c.ms,
                "sm_ms": s.ms,
                "asm_memory_bytes": c.memory,
                "asm_tree_bytes": c.tree,
                "sm_memory_bytes": s.memory,
                "asm_mismatch": c.mismatch,
                "sm_mismatch": s.mismatch,
                "asm_nodes": c.nodes,
                "asm_effective_resolution": c.effective,
                "asm_cells_refined": c.refined,
                "asm_nodes_evicted": c.evicted,
            }));
        }
    }
    rows
}

/// Prints the means over the walkthrough beside the paper's times.
fn print_means(walk: &Walk) {
    let sm_ms = mean(walk.sm.iter().map(|c| c.ms));
    let sm_mis = mean(walk.sm.iter().map(|c| c.mismatch));
    println!();
    println!(
        "means over the walkthrough (frame 0, which builds the root and calibrates, in brackets):"
    );
    println!(
        "  sm 2048²: {sm_ms:.1} ms, {:.1} MB, mismatch {:.4}%   | paper: {PAPER_SM_MS:.0} ms, 16 MB",
        mb(walk.sm[0].memory),
        sm_mis * 100.0
    );
    for (b, cells) in BUDGETS.iter().zip(&walk.asm) {
        let ms = mean(cells.iter().map(|c| c.ms));
        let later = mean(cells.iter().skip(1).map(|c| c.ms));
        let most = cells.iter().map(|c| c.tree).max().unwrap_or(0);
        let culling = cells.iter().map(|c| c.memory - c.tree).max().unwrap_or(0);
        let paper = if *b == 16 {
            format!(
                "paper: {PAPER_ASM_MS:.0} ms, ratio {:.2}",
                PAPER_ASM_MS / PAPER_SM_MS
            )
        } else {
            "paper: no time given".to_string()
        };
        println!(
            "  asm {b:>2} MB: {ms:.1} ms [{:.1}], frames 1.. {later:.1} ms, ratio to sm {:.2} (target ≤ {:.2}), \
             tree at most {:.2} MB (+ {:.2} MB of culling lists), mismatch {:.4}%   | {paper}",
            cells[0].ms,
            ms / sm_ms,
            PAPER_ASM_MS / PAPER_SM_MS,
            mb(most),
            mb(culling),
            mean(cells.iter().map(|c| c.mismatch)) * 100.0,
        );
    }
}
