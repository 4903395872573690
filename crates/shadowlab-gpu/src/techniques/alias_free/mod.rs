//! `gpu:afsm`: alias-free shadow maps (Aila & Laine, "Alias-Free Shadow Maps", EGSR 2004)
//! as the GPU's irregular z-buffer (Johnson et al. 2005; Sintorn et al. 2008; Wyman,
//! Hoetzlein & Lefohn, "Frustum-traced raster shadows", 2015): the view samples are the
//! shadow map's sampling points, binned into a light-space grid, and every caster triangle
//! is rasterized conservatively over the grid's cells in a compute shader, each sample
//! under it decided by the watertight test on its own shadow ray.
//!
//! Stages (one WGSL file each, run in this order, timed with timestamp queries):
//! - *transform* (`transform.wgsl`, Section 3): each lit sample's shadow ray, formed by
//!   the shared WGSL exactly as `gpu:raytrace` and the CPU reference form it (the same
//!   `illuminates`, error-bounded origin and shear), is projected to its light plane: the
//!   orthographic plane of a directional light, a spot light's own plane (a cube stands in
//!   for samples behind it), or the cube face of a point light its direction falls on.
//!   Each plane's count, rectangle and depth range are gathered with integer atomics.
//! - *bin* (`bin.wgsl`, the paper's light-space hierarchy, Section 5.1, as a uniform grid):
//!   each plane's grid holds about `leaf-size`/2 samples a cell; a counting sort (count,
//!   prefix sum in `scan.wgsl`, scatter) lays each cell's samples out contiguously — no
//!   linked lists, nothing unbounded. Each cell's list is cut into chunks of at most
//!   `leaf-size` samples, each with its samples' tight rectangle, greatest depth and count
//!   of samples still lit, and a summed-area table counts the chunks under any rectangle
//!   of cells.
//! - *raster* (`raster.wgsl`, "Rasterization of blockers", set-up): each triangle's
//!   footprint on each plane — rectangle, three edge functions, least depth — widened as
//!   the CPU `afsm`'s set-up widens it (the same constants: homogeneous edge planes on a
//!   perspective plane, the slab of a triangle nearly edge-on), and the number of chunks
//!   under its rectangle of cells: its share of the triangle–chunk work queue.
//! - *test* (`test.wgsl`): one thread per triangle–chunk pair (a prefix sum over the
//!   triangles' shares and two binary searches find both), so a large triangle spreads
//!   over as many threads as it has chunks under it and a dense cell over as many chunks as
//!   it has runs of `leaf-size` samples: no thread takes a whole large triangle or a whole
//!   dense cell (a triangle over at most 8 chunks is one item that visits them in turn,
//!   one search instead of one a chunk). The paper's occlusion culling: a chunk whose samples are all dark, or all
//!   in front of the triangle (its greatest depth below the triangle's least), or outside
//!   the footprint, is skipped whole; in the others each live sample inside the footprint
//!   takes the watertight test of `shaders/common/watertight.wgsl` on its own ray (own
//!   triangle skipped, alpha masks cut at the hit's barycentrics). `resolve` writes each
//!   pixel's shadow term: its sample's, or the mean of its sub-pixel samples.
//!
//! Multiple samples a pixel (`samples` = 4, 8, 16, 32): every covered pixel's primary rays
//! through the library's grid of sub-pixel positions are traced on the CPU to their
//! closest surface with the library's BVH, exactly as the N-spp reference traces them
//! (`samples.rs`), and every hit becomes a sample of the one grid: all of a frame's
//! samples share one transform, one bin and one pass over the triangles, which is why 32
//! samples cost far less than 32 frames. The pixel's value is the mean in the pattern's
//! order, as the reference's.
//!
//! Invariants:
//! - The decision of a sample is the shared watertight test on the same ray as
//!   `gpu:raytrace`'s: the grid, the chunks and the footprints only choose which pairs reach
//!   it, and every culling test is widened (by the CPU's `CULL_TOLERANCE` rules) so it
//!   never drops a pair the exact test would count.
//! - Opaque casters set a sample's dark flag (an integer `atomicMax`: order-independent).
//!   Semi-transparent casters add their transmittance's −log2 per channel, quantized on the
//!   CPU to 2⁻²⁰ and summed with saturating integer atomics: the sum of the same integers
//!   whatever order the threads meet the casters in, so the images are bit-identical over
//!   runs; the shadow term is 2^−sum.
//! - Which samples a chunk holds depends on the order the count's atomics ran, and so do
//!   the culling counters (a chunk goes dark sooner or later); no shadow term does: a
//!   sample's result depends only on the set of casters that hit it.
//!
//! Departures from the paper and from the CPU `afsm`:
//! - A uniform grid of chunked cells instead of the BSP: a GPU builds it with a counting
//!   sort and no recursion, and a triangle finds its chunks by arithmetic.
//! - Semi-transparent shadows are a product taken in log space: a transmittance of t
//!   becomes 2^−round(−log2(t)·2²⁰)/2²⁰ per caster (relative error below 4·10⁻⁷ per caster,
//!   exp2 rounding aside), not the CPU's product in triangle-index order; a product below
//!   2⁻¹⁵⁰ is 0, and a transmittance above 1 counts as 1.
//! - The sub-pixel samples' primary hits are traced on the CPU (the GPU traces shadows).
//! - The layers behind semi-transparent receivers are not shaded (`Shadows::layers` stays
//!   empty); area lights shade with their punctual stand-in, as the CPU `afsm` does.
//!
//! Counters: `samples` (lit samples binned), `light_planes`, `cells`,
//! `work_items` (the work queue's items), `cells_visited` (pairs whose samples were looped
//! over), `cells_occlusion_culled` (pairs skipped because every sample was dark),
//! `cells_depth_culled` (every sample in front of the triangle), `samples_tested` (samples
//! not yet dark in the chunks visited), `ray_tests` (samples under a footprint that took
//! the exact test), `triangle_batches`. `--dump` writes `gpu-afsm-load{i}.png` (samples a
//! cell of plane i) and `gpu-afsm-culled{i}.png` (cells skipped as dark, red).

mod buffers;
mod dump;
mod kit;
mod planes;
mod run;
mod samples;

use crate::compute::to_rgb;
use crate::device::{shared, Gpu};
use crate::resident::{DeviceShadows, DeviceView, OnDevice};
use crate::shader::{Common, Stage, ALPHA_MASK, LIGHT, RAY_OFFSET, TRIANGLES, WATERTIGHT};
use crate::transfer::storage;
use crate::upload::{view_buffer, SceneBuffers, SceneKey};
use buffers::{Bufs, COUNTERS};
use kit::Kit;
use run::{run, Input, Kits, Setting};
use shadowlab::error::{Error, Result};
use shadowlab::scene::Scene;
use shadowlab::techniques::{find_param, Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// The technique's name.
pub const NAME: &str = "gpu:afsm";

/// The sample counts a pixel may take.
pub const SAMPLE_COUNTS: &[&str] = &["1", "4", "8", "16", "32"];

/// The chunk size by default (measured: 4 to 8 test fastest on lavapipe).
pub const DEFAULT_LEAF_SIZE: u32 = 8;
/// The largest chunk size.
pub const MAX_LEAF_SIZE: u32 = 4096;

/// `grid.wgsl`: what every stage of the technique shares.
const GRID: Common = Common {
    name: "alias_free/grid.wgsl",
    source: include_str!("grid.wgsl"),
};

const TRANSFORM: Stage = Stage {
    name: "transform.wgsl",
    common: &[RAY_OFFSET, LIGHT, WATERTIGHT, GRID],
    source: include_str!("transform.wgsl"),
};
const BIN: Stage = Stage {
    name: "bin.wgsl",
    common: &[RAY_OFFSET, LIGHT, GRID],
    source: include_str!("bin.wgsl"),
};
const RASTER: Stage = Stage {
    name: "raster.wgsl",
    common: &[RAY_OFFSET, LIGHT, GRID],
    source: include_str!("raster.wgsl"),
};
const TEST: Stage = Stage {
    name: "test.wgsl",
    common: &[RAY_OFFSET, LIGHT, WATERTIGHT, ALPHA_MASK, TRIANGLES, GRID],
    source: include_str!("test.wgsl"),
};
const SCAN: Stage = Stage {
    name: "scan.wgsl",
    common: &[],
    source: include_str!("scan.wgsl"),
};

/// The largest −log2 a channel's transmittance contributes, in 2⁻²⁰ (`LOG_CAP`).
const LOG_CAP: u32 = 150 << 20;

/// Each material's channels as −log2 in units of 2⁻²⁰, saturating at [`LOG_CAP`], and
/// whether it is opaque: four words a material.
fn material_logs(scene: &Scene) -> Vec<u32> {
    let q = |t: f32| -> u32 {
        if t >= 1.0 {
            0
        } else if t > 0.0 {
            ((-f64::from(t).log2()) * f64::from(1u32 << 20))
                .round()
                .min(f64::from(LOG_CAP)) as u32
        } else {
            LOG_CAP
        }
    };
    scene
        .materials
        .iter()
        .flat_map(|m| {
            let t = m.transmittance;
            [q(t.x), q(t.y), q(t.z), u32::from(m.is_opaque())]
        })
        .collect()
}

/// The scene and pipelines of one scene revision on one device.
struct Resident {
    key: SceneKey,
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    mat_q: wgpu::Buffer,
    kits: Arc<Kits>,
    /// The last frame's buffers, for the next frame to reuse.
    spare: Mutex<Option<Bufs>>,
}

/// The kits, made once per process (the one shared device): lavapipe's LLVM takes
/// seconds to compile them.
static KITS: Mutex<Option<Arc<Kits>>> = Mutex::new(None);

fn kits(gpu: &Gpu) -> Arc<Kits> {
    let mut made = KITS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(k) = made.as_ref() {
        return k.clone();
    }
    let k = Arc::new(make_kits(gpu));
    *made = Some(k.clone());
    k
}

fn make_kits(gpu: &Gpu) -> Kits {
    let d = &gpu.device;
    Kits {
        transform: Kit::new(d, &TRANSFORM, &["main"]),
        bin: Kit::new(
            d,
            &BIN,
            &[
                "plan",
                "count",
                "scatter",
                "chunk_count",
                "chunk_cells",
                "chunk_boxes",
                "sat_columns",
            ],
        ),
        raster: Kit::new(d, &RASTER, &["setup", "dispatch_args"]),
        test: Kit::new(d, &TEST, &["main", "resolve"]),
        scan: Kit::new(d, &SCAN, &["scan_blocks", "scan_add"]),
    }
}

/// Alias-free shadow maps on the GPU.
pub struct GpuAliasFree {
    /// A cell's list is cut into chunks of at most this many samples.
    pub leaf_size: u32,
    /// Samples a pixel.
    pub samples: u32,
    resident: Option<Resident>,
}

impl Default for GpuAliasFree {
    fn default() -> Self {
        GpuAliasFree {
            leaf_size: DEFAULT_LEAF_SIZE,
            samples: 1,
            resident: None,
        }
    }
}

impl GpuAliasFree {
    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&Resident> {
        let key = SceneKey::of(frame.scene);
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            self.resident = None;
            let gpu = shared()?;
            let (scene, mat_q) = stats.stage("upload_scene", || {
                gpu.stage(NAME, "upload_scene", || -> Result<_> {
                    let logs = material_logs(frame.scene);
                    Ok((
                        SceneBuffers::new(&gpu, frame.scene)?,
                        storage(
                            &gpu,
                            "the materials' log transmittances",
                            bytemuck::cast_slice(&logs),
                        )?,
                    ))
                })?
            })?;
            let kits = gpu.stage(NAME, "pipelines", || kits(&gpu))?;
            self.resident = Some(Resident {
                key,
                gpu,
                scene,
                mat_q,
                kits,
                spare: Mutex::new(None),
            });
        }
        self.resident
            .as_ref()
            .ok_or_else(|| Error::Internal(format!("{NAME}: the scene was not uploaded")))
    }
}

impl ShadowTechnique for GpuAliasFree {
    fn name(&self) -> &'static str {
        NAME
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("leaf-size".to_string(), self.leaf_size.into()),
            ("samples".to_string(), self.samples.into()),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::int(
                "leaf-size",
                1,
                MAX_LEAF_SIZE as i64,
                "a grid cell's samples are tested in chunks of at most this many (the BSP leaf size's counterpart); only the speed changes",
            ),
            ParamSpec::choice(
                "samples",
                SAMPLE_COUNTS,
                "samples a pixel, at the sub-pixel positions of the reference with as many samples",
            ),
        ]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let spec = find_param(NAME, &self.param_specs(), key)?;
        match key {
            "leaf-size" => self.leaf_size = spec.u32(NAME, value)?,
            "samples" => {
                let w = spec.word(NAME, value)?;
                self.samples = w.parse().map_err(|_| {
                    Error::Internal(format!("{NAME}: sample count {w} is not a number"))
                })?;
            }
            _ => return Err(shadowlab::techniques::not_read(NAME, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let mut stats = Stats::default();
        let o = self.frame(frame, None, &mut stats)?;
        Ok(Shadows::of_frame(frame, to_rgb(&o.out), stats))
    }
}

impl OnDevice for GpuAliasFree {
    fn render_on_device(&mut self, frame: &Frame, view: &DeviceView) -> Result<DeviceShadows> {
        let mut stats = Stats::default();
        let o = self.frame(frame, Some(view), &mut stats)?;
        let visibility = o
            .out_buffer
            .ok_or_else(|| Error::Internal(format!("{NAME}: the shadow terms left no buffer")))?;
        Ok(DeviceShadows { visibility, stats })
    }

    /// More than one sample a pixel traces sub-pixel rays from the pixels on the CPU.
    fn needs_cpu_samples(&self) -> bool {
        self.samples > 1
    }
}

impl GpuAliasFree {
    /// One frame over the camera pass's samples (`view` when uploaded already: then the
    /// shadow terms stay on the device).
    fn frame(
        &mut self,
        frame: &Frame,
        uploaded: Option<&DeviceView>,
        stats: &mut Stats,
    ) -> Result<run::Outcome> {
        frame.light.validate()?;
        let (leaf, spp) = (self.leaf_size.clamp(1, MAX_LEAF_SIZE), self.samples);
        let res = self.resident(frame, stats)?;
        let gpu = res.gpu.clone();
        let view = frame.view;
        let n_pixels = uploaded.map_or(view.triangle.len() as u32, DeviceView::pixels);
        let planes = planes::planes(frame.light, frame.scene);
        let (samples, pixel_start, n_samples) = if spp <= 1 {
            let v = match uploaded {
                Some(v) => v.samples.clone(),
                None => stats.stage("upload_view", || view_buffer(&gpu, view))?,
            };
            (v, storage(&gpu, "no pixel runs", &[0; 4])?, n_pixels)
        } else {
            let sub = stats.stage("subpixel_hits", || samples::sub_samples(frame, spp))?;
            let n = (sub.words.len() / crate::upload::VIEW_STRIDE) as u32;
            stats.stage("upload_view", || -> Result<_> {
                Ok((
                    storage(
                        &gpu,
                        "the sub-pixel samples",
                        bytemuck::cast_slice(&sub.words),
                    )?,
                    storage(
                        &gpu,
                        "the pixels' sample runs",
                        bytemuck::cast_slice(&sub.start),
                    )?,
                    n,
                ))
            })?
        };
        let input = Input {
            samples: &samples,
            pixel_start: &pixel_start,
            n_samples,
            n_pixels,
            identity: spp <= 1,
        };
        let n_tris = u32::try_from(frame.scene.len()).map_err(|_| {
            Error::Limit(format!(
                "{NAME}: the scene has more triangles than 32-bit indices reach"
            ))
        })?;
        let setting = Setting {
            light: frame.light,
            planes: &planes,
            n_tris,
            leaf,
            dumping: frame.dumping(),
            on_device: uploaded.is_some(),
        };
        let o = run(res, &setting, &input, stats)?;
        record(stats, &o);
        if let Some((starts, chunk_cell, culled)) = &o.grid {
            for (i, g) in dump::plane_grids(&o.planes, starts, chunk_cell, culled)
                .iter()
                .enumerate()
            {
                frame.dump_image(&format!("gpu-afsm-load{i}.png"), || dump::load_picture(g))?;
                frame.dump_image(&format!("gpu-afsm-culled{i}.png"), || {
                    dump::culled_picture(g)
                })?;
            }
        }
        stats.memory_bytes = o.bytes + res.scene.bytes;
        stats.device = Some(gpu.adapter.label());
        Ok(o)
    }
}

/// The counters and GPU stage times of a frame into `stats`.
fn record(stats: &mut Stats, o: &run::Outcome) {
    let p = &o.planes;
    let samples: u64 = (0..7).map(|pl| u64::from(p[pl * 16])).sum();
    let planes = (0..7).filter(|pl| p[pl * 16] > 0).count();
    stats.count("samples", samples as f64);
    stats.count("light_planes", planes as f64);
    stats.count("cells", f64::from(p[7 * 16]));
    let names = [
        "cells_visited",
        "cells_occlusion_culled",
        "cells_depth_culled",
        "samples_tested",
        "ray_tests",
        "work_items",
    ];
    for (name, v) in names.iter().zip(o.counters.iter().take(COUNTERS)) {
        stats.count(name, *v as f64);
    }
    stats.count("triangle_batches", f64::from(o.tri_batches));
    let mut sums: Vec<(String, f64)> = Vec::new();
    for (name, ms) in &o.gpu_ms {
        match sums.iter_mut().find(|s| &s.0 == name) {
            Some(s) => s.1 += ms,
            None => sums.push((name.clone(), *ms)),
        }
    }
    for (name, ms) in sums {
        stats.count(&format!("gpu_{name}_ms"), ms);
    }
}
