//! One frame of `gpu:afsm` on the device: the buffers, and the stages recorded, submitted
//! and timed in the paper's order (transform, bin, raster and test per batch of
//! triangles, resolve).

use super::buffers::{
    capacity, plane_init, Bufs, Caps, Sizes, CHUNK_WORDS, COUNTERS, PLANE_WORDS, RECORD_WORDS,
};
use super::kit::{dispatch, Kit, Scan};
use super::planes::Planes;
use super::{Resident, NAME};
use crate::transfer::{read_back, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::Light;
use shadowlab::techniques::Stats;
use wgpu::util::DeviceExt;

/// `AfsmParams` of `grid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct ParamsU {
    light: LightU,
    n_samples: u32,
    n_pixels: u32,
    identity: u32,
    n_planes: u32,
    tri_first: u32,
    tri_count: u32,
    leaf: u32,
    cell_cap: u32,
    cell_target: f32,
    masks: u32,
    ortho_scale: f32,
    far_corner: f32,
}

/// The most set-up records one batch of triangles makes (72 bytes each; a triangle makes
/// one a light plane).
const MAX_RECORDS: u64 = 1 << 21;

/// What the frame hands to the shaders: the samples and where each pixel's run starts.
pub(super) struct Input<'a> {
    pub(super) samples: &'a wgpu::Buffer,
    pub(super) pixel_start: &'a wgpu::Buffer,
    pub(super) n_samples: u32,
    pub(super) n_pixels: u32,
    /// True when sample `k` is pixel `k`.
    pub(super) identity: bool,
}

/// What a frame leaves: the shadow terms, counters, and the grid for `--dump`.
pub(super) struct Outcome {
    /// The shadow terms read back; empty when they stay on the device.
    pub(super) out: Vec<u8>,
    /// The shadow terms' buffer, when they stay on the device.
    pub(super) out_buffer: Option<wgpu::Buffer>,
    pub(super) counters: [u64; COUNTERS],
    pub(super) planes: Vec<u32>,
    pub(super) gpu_ms: Vec<(String, f64)>,
    pub(super) bytes: u64,
    pub(super) tri_batches: u32,
    /// Each cell's first sample (one more than cells), each chunk's record and how often
    /// it was culled as dark: read back only when dumping.
    pub(super) grid: Option<(Vec<u32>, Vec<u32>, Vec<u32>)>,
}

/// What one frame's recording needs.
struct Ctx<'a> {
    res: &'a Resident,
    input: &'a Input<'a>,
    b: Bufs,
    params: wgpu::Buffer,
    base: ParamsU,
    timer: Timer,
    n: u64,
    cells: u64,
    chunk_cap: u64,
}

impl Ctx<'_> {
    fn uniform(&self, p: &ParamsU) -> wgpu::Buffer {
        self.res
            .gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("afsm parameters"),
                contents: bytemuck::bytes_of(p),
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    /// Records `f`'s passes into one encoder, submits it, and waits, as stage `stage`.
    fn submit(
        &mut self,
        stage: &str,
        f: impl FnOnce(&mut Self, &mut wgpu::CommandEncoder),
    ) -> Result<()> {
        let gpu = self.res.gpu.clone();
        gpu.stage(NAME, stage, || {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            f(self, &mut enc);
            gpu.queue.submit([enc.finish()]);
        })
    }

    /// The test kit's bind group with parameters `p` (the test and the resolve share it).
    fn test_group(&self, p: &wgpu::Buffer) -> wgpu::BindGroup {
        let (b, s) = (&self.b, &self.res.scene);
        self.res.kits.test.bind(
            &self.res.gpu.device,
            &[
                p,
                &b.planes,
                &s.triangles,
                &s.material_of,
                &s.materials,
                &s.uvs,
                &s.texels,
                &self.res.mat_q,
                &b.records,
                &b.items,
                &b.sat,
                &b.chunk_start,
                &b.chunks,
                &b.chunk_live,
                &b.chunk_culled,
                &b.sorted_uvz,
                &b.sorted_ray,
                &b.dark,
                &b.logs,
                &b.counters,
                &b.s_cell,
                &b.s_rank,
                &b.cell_start,
                self.input.pixel_start,
                &b.out,
            ],
        )
    }

    fn transform(&mut self, enc: &mut wgpu::CommandEncoder) {
        let (b, k) = (&self.b, &self.res.kits);
        let group = k.transform.bind(
            &self.res.gpu.device,
            &[
                &self.params,
                self.input.samples,
                &b.projs,
                &b.planes,
                &b.s_uvz,
                &b.s_ray,
            ],
        );
        for buf in [
            &b.cell_start,
            &b.chunk_start,
            &b.dark,
            &b.logs,
            &b.counters,
            &b.chunk_culled,
            &b.overflow,
        ] {
            enc.clear_buffer(buf, 0, None);
        }
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("transform"),
            timestamp_writes: self.timer.pass("transform"),
        });
        dispatch(&mut pass, &k.transform, "main", &group, self.n);
    }

    fn bin(&mut self, enc: &mut wgpu::CommandEncoder) {
        let (b, k, dev) = (&self.b, &self.res.kits, &self.res.gpu.device);
        let group = k.bin.bind(
            dev,
            &[
                &self.params,
                &b.planes,
                &b.s_uvz,
                &b.s_ray,
                &b.s_cell,
                &b.s_rank,
                &b.cell_start,
                &b.chunk_start,
                &b.chunks,
                &b.chunk_live,
                &b.sat,
                &b.sorted_uvz,
                &b.sorted_ray,
                self.input.samples,
            ],
        );
        let (n, cells) = (self.n, self.cells);
        let scan_cells = Scan::new(dev, &k.scan, &b.cell_start, (cells + 1) as u32, &b.overflow);
        let scan_chunks = Scan::new(
            dev,
            &k.scan,
            &b.chunk_start,
            (cells + 1) as u32,
            &b.overflow,
        );
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bin"),
            timestamp_writes: self.timer.pass("bin"),
        });
        pass.set_pipeline(k.bin.pipe("plan"));
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        dispatch(&mut pass, &k.bin, "count", &group, n);
        scan_cells.record(&mut pass, &k.scan);
        dispatch(&mut pass, &k.bin, "scatter", &group, n);
        dispatch(&mut pass, &k.bin, "chunk_count", &group, cells);
        scan_chunks.record(&mut pass, &k.scan);
        dispatch(&mut pass, &k.bin, "chunk_cells", &group, cells);
        dispatch(&mut pass, &k.bin, "chunk_boxes", &group, self.chunk_cap);
        dispatch(&mut pass, &k.bin, "sat_columns", &group, cells + 8);
    }

    /// The set-up and the test of triangles `first..first + count`.
    fn raster_test(&mut self, enc: &mut wgpu::CommandEncoder, first: u32, count: u32) {
        let p = self.uniform(&ParamsU {
            tri_first: first,
            tri_count: count,
            ..self.base
        });
        let (b, k, dev) = (&self.b, &self.res.kits, &self.res.gpu.device);
        let records = u64::from(count) * u64::from(self.base.n_planes);
        let raster = k.raster.bind(
            dev,
            &[
                &p,
                &b.planes,
                &b.projs,
                &self.res.scene.triangles,
                &b.chunk_start,
                &b.sat,
                &b.records,
                &b.items,
                &b.args,
            ],
        );
        let test = self.test_group(&p);
        let scan = Scan::new(dev, &k.scan, &b.items, (records + 1) as u32, &b.overflow);
        enc.clear_buffer(&b.items, 0, None);
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("raster"),
                timestamp_writes: self.timer.pass("raster"),
            });
            dispatch(&mut pass, &k.raster, "setup", &raster, records);
            scan.record(&mut pass, &k.scan);
            pass.set_pipeline(k.raster.pipe("dispatch_args"));
            pass.set_bind_group(0, &raster, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("test"),
            timestamp_writes: self.timer.pass("test"),
        });
        pass.set_pipeline(k.test.pipe("main"));
        pass.set_bind_group(0, &test, &[]);
        pass.dispatch_workgroups_indirect(&b.args, 0);
    }

    fn resolve(&mut self, enc: &mut wgpu::CommandEncoder) {
        let group = self.test_group(&self.params);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("resolve"),
            timestamp_writes: self.timer.pass("resolve"),
        });
        let pixels = u64::from(self.input.n_pixels);
        dispatch(&mut pass, &self.res.kits.test, "resolve", &group, pixels);
    }

    fn read(&self, buf: &wgpu::Buffer, bytes: u64) -> Result<Vec<u32>> {
        let gpu = &*self.res.gpu;
        let raw = gpu.stage(NAME, "readback", || read_back(gpu, buf, bytes))??;
        Ok(bytemuck::pod_collect_to_vec(&raw))
    }

    /// The grid for `--dump`: each cell's first sample, each chunk's cell and cull count.
    fn read_grid(&self, total_cells: u64) -> Result<(Vec<u32>, Vec<u32>, Vec<u32>)> {
        let b = &self.b;
        let cs = self.read(&b.cell_start, (total_cells + 1) * 4)?;
        let ks = self.read(&b.chunk_start, (total_cells + 1) * 4)?;
        let n_chunks = u64::from(ks.last().copied().unwrap_or(0)).max(1);
        let ch = self.read(&b.chunks, n_chunks * CHUNK_WORDS * 4)?;
        let culled = self.read(&b.chunk_culled, n_chunks * 4)?;
        let cell_of_chunk = ch
            .chunks_exact(CHUNK_WORDS as usize)
            .map(|c| c[7])
            .collect();
        Ok((cs, cell_of_chunk, culled))
    }
}

/// The frame's settings: the light, its planes, the triangles and the chunk size.
pub(super) struct Setting<'a> {
    pub(super) light: &'a Light,
    pub(super) planes: &'a Planes,
    pub(super) n_tris: u32,
    pub(super) leaf: u32,
    pub(super) dumping: bool,
    /// Leave the shadow terms on the device (the counters are still read: a few words).
    pub(super) on_device: bool,
}

/// Runs one frame: with as many triangles a batch as the buffers allow, and again with
/// fewer when a batch's work count passed 32 bits (the same result, in more batches).
pub(super) fn run(
    res: &Resident,
    set: &Setting,
    input: &Input,
    stats: &mut Stats,
) -> Result<Outcome> {
    let gpu = &*res.gpu;
    let n_planes = u64::from(set.planes.projs.len() as u32);
    let per_batch = (MAX_RECORDS
        .min(gpu.limits.max_storage_buffer_binding_size / (RECORD_WORDS * 4))
        / n_planes)
        .max(1);
    let mut tri_batch = per_batch.min(u64::from(set.n_tris.max(1))) as u32;
    loop {
        let (o, overflowed) = run_once(res, set, input, stats, tri_batch)?;
        if !overflowed || tri_batch == 1 {
            return Ok(o);
        }
        tri_batch = (tri_batch / 64).max(1);
    }
}

/// One frame in batches of `tri_batch` triangles; true when a work count overflowed.
fn run_once(
    res: &Resident,
    set: &Setting,
    input: &Input,
    stats: &mut Stats,
    tri_batch: u32,
) -> Result<(Outcome, bool)> {
    let gpu = &*res.gpu;
    let (leaf, n_tris) = (set.leaf, set.n_tris);
    let n = u64::from(input.n_samples.max(1));
    let n_planes = set.planes.projs.len() as u32;
    let cell_target = (leaf / 2).max(1);
    let cells = n / u64::from(cell_target) + 8;
    let chunk_cap = n.div_ceil(u64::from(leaf)) + cells;
    // The buffers hold `capacity(n)` samples (and the grid for as many), so that the next
    // frame can reuse them; the passes are given the frame's own counts.
    let (n_cap, records) = (capacity(n), u64::from(tri_batch) * u64::from(n_planes));
    let cells_cap = n_cap / u64::from(cell_target) + 8;
    let pixels = u64::from(input.n_pixels);
    let sizes = Sizes {
        n: n_cap,
        pixels,
        caps: Caps {
            cells: cells_cap,
            chunks: n_cap.div_ceil(u64::from(leaf)) + cells_cap,
            sat: 2 * cells_cap + 16,
            records,
        },
        transparency: res.scene.transparency,
    };
    let spare = res.spare.lock().unwrap_or_else(|e| e.into_inner()).take();
    let b = stats.stage("buffers", || Bufs::for_frame(gpu, spare, sizes, set.planes))?;
    let base = ParamsU {
        light: LightU::of(set.light),
        n_samples: input.n_samples,
        n_pixels: input.n_pixels,
        identity: u32::from(input.identity),
        n_planes,
        tri_first: 0,
        tri_count: 0,
        leaf,
        cell_cap: cells as u32,
        cell_target: cell_target as f32,
        masks: u32::from(res.scene.masks),
        ortho_scale: set.planes.ortho_scale,
        far_corner: set.planes.far_corner,
    };
    let batches = n_tris.div_ceil(tri_batch).max(1);
    gpu.queue
        .write_buffer(&b.planes, 0, bytemuck::cast_slice(&plane_init()));
    let mut cx = Ctx {
        res,
        input,
        params: gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("afsm parameters"),
                contents: bytemuck::bytes_of(&base),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
        b,
        base,
        timer: Timer::new(gpu, 3 + 2 * batches.min(1000)),
        n,
        cells,
        chunk_cap,
    };
    stats.stage("transform", || {
        cx.submit("transform", |c, e| c.transform(e))
    })?;
    stats.stage("bin", || cx.submit("bin", |c, e| c.bin(e)))?;
    stats.stage("raster_test", || -> Result<()> {
        for batch in 0..batches {
            let first = batch * tri_batch;
            let count = tri_batch.min(n_tris - first);
            cx.submit("raster", |c, e| c.raster_test(e, first, count))?;
        }
        Ok(())
    })?;
    stats.stage("resolve", || cx.submit("resolve", |c, e| c.resolve(e)))?;
    let (out, out_buffer) = match set.on_device {
        true => (Vec::new(), Some(cx.b.out.clone())),
        false => (
            stats.stage("readback", || cx.read(&cx.b.out, pixels * 12))?,
            None,
        ),
    };
    let words = cx.read(&cx.b.counters, COUNTERS as u64 * 8)?;
    let mut counters = [0u64; COUNTERS];
    for (i, c) in counters.iter_mut().enumerate() {
        *c = u64::from(words[2 * i]) | (u64::from(words[2 * i + 1]) << 32);
    }
    let planes = cx.read(&cx.b.planes, PLANE_WORDS as u64 * 4)?;
    let overflowed = cx.read(&cx.b.overflow, 4)?[0] != 0;
    let grid = match set.dumping {
        true => Some(cx.read_grid(u64::from(planes[7 * 16]))?),
        false => None,
    };
    let o = Outcome {
        out: bytemuck::cast_slice(&out).to_vec(),
        out_buffer,
        counters,
        planes,
        gpu_ms: cx.timer.read(gpu)?,
        bytes: cx.b.bytes,
        tri_batches: batches,
        grid,
    };
    *res.spare.lock().unwrap_or_else(|e| e.into_inner()) = Some(cx.b);
    Ok((o, overflowed))
}

/// The kits of every stage.
pub(super) struct Kits {
    pub(super) transform: Kit,
    pub(super) bin: Kit,
    pub(super) raster: Kit,
    pub(super) test: Kit,
    pub(super) scan: Kit,
}
