//! The buffers of one `gpu:afsm` frame, sized from its sample count: per sample (light
//! position, shadow ray, cell and rank, binned copies, dark flag, transmittance sums), per
//! cell and chunk of the grid, per triangle record of a batch, and the few words of
//! counters, dispatch arguments and flags.
//!
//! They are sized with room to spare ([`capacity`]) and kept for the next frame, which
//! clears and reuses them when it needs the same sizes: a turning camera's sample count
//! moves a little every frame, and allocating some twenty buffers of up to 64 MiB anew
//! took 5 ms a frame at 1920×1080 on an H200, more than the GPU's own stages.

use super::planes::Planes;
use crate::device::Gpu;
use shadowlab::error::Result;
use wgpu::util::DeviceExt;

/// Counters the test keeps, two words each.
pub(super) const COUNTERS: usize = 6;
/// Words a chunk record holds (`CHUNK_STRIDE`).
pub(super) const CHUNK_WORDS: u64 = 8;
/// Words a triangle's set-up record holds (`RECORD_STRIDE`).
pub(super) const RECORD_WORDS: u64 = 18;
/// Words of the planes' records (`PLANE_STRIDE` × 7, then the total cells and padding).
pub(super) const PLANE_WORDS: usize = 7 * 16 + 4;
/// The frame's buffers.
pub(super) struct Bufs {
    pub(super) planes: wgpu::Buffer,
    pub(super) projs: wgpu::Buffer,
    pub(super) s_uvz: wgpu::Buffer,
    pub(super) s_ray: wgpu::Buffer,
    pub(super) s_cell: wgpu::Buffer,
    pub(super) s_rank: wgpu::Buffer,
    pub(super) cell_start: wgpu::Buffer,
    pub(super) chunk_start: wgpu::Buffer,
    pub(super) chunks: wgpu::Buffer,
    pub(super) chunk_live: wgpu::Buffer,
    pub(super) chunk_culled: wgpu::Buffer,
    pub(super) sat: wgpu::Buffer,
    pub(super) sorted_uvz: wgpu::Buffer,
    pub(super) sorted_ray: wgpu::Buffer,
    pub(super) dark: wgpu::Buffer,
    pub(super) logs: wgpu::Buffer,
    pub(super) records: wgpu::Buffer,
    pub(super) items: wgpu::Buffer,
    pub(super) counters: wgpu::Buffer,
    pub(super) args: wgpu::Buffer,
    pub(super) out: wgpu::Buffer,
    pub(super) overflow: wgpu::Buffer,
    pub(super) bytes: u64,
    /// What they were sized for.
    sizes: Sizes,
}

/// What a frame's buffers are sized by.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) struct Sizes {
    /// Samples.
    pub(super) n: u64,
    /// Pixels (the shadow terms).
    pub(super) pixels: u64,
    /// The grid's and the batches' capacities.
    pub(super) caps: Caps,
    /// Whether the scene has semi-transparent casters.
    pub(super) transparency: bool,
}

/// The samples the buffers of a frame of `n` samples hold: `n` rounded up to a sixteenth
/// of its power of two (at most 1/8 more), so that nearby counts share one size.
pub(super) fn capacity(n: u64) -> u64 {
    let step = (n.next_power_of_two() / 16).max(1);
    n.div_ceil(step) * step
}

/// The frame's capacities.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) struct Caps {
    pub(super) cells: u64,
    pub(super) chunks: u64,
    pub(super) sat: u64,
    pub(super) records: u64,
}

fn buffer(
    gpu: &Gpu,
    bytes: &mut u64,
    what: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let size = size.max(4).div_ceil(4) * 4;
    gpu.check_binding(what, size)?;
    *bytes += size;
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC
            | extra,
        mapped_at_creation: false,
    }))
}

fn projections(gpu: &Gpu, planes: &Planes) -> wgpu::Buffer {
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("light planes"),
            contents: bytemuck::cast_slice(&planes.projs),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

impl Bufs {
    /// The buffers of a frame of `sizes` with light `planes`: `spare` (the last frame's)
    /// cleared to zero, as new buffers start, when it was sized alike; else new ones. The
    /// shadow terms' buffer is always new, since the last frame's may still be shown.
    pub(super) fn for_frame(
        gpu: &Gpu,
        spare: Option<Bufs>,
        sizes: Sizes,
        planes: &Planes,
    ) -> Result<Bufs> {
        let Some(mut b) = spare.filter(|b| b.sizes == sizes) else {
            return Bufs::new(gpu, sizes, planes);
        };
        let mut e = gpu.device.create_command_encoder(&Default::default());
        for buf in [
            &b.planes,
            &b.s_uvz,
            &b.s_ray,
            &b.s_cell,
            &b.s_rank,
            &b.cell_start,
            &b.chunk_start,
            &b.chunks,
            &b.chunk_live,
            &b.chunk_culled,
            &b.sat,
            &b.sorted_uvz,
            &b.sorted_ray,
            &b.dark,
            &b.logs,
            &b.records,
            &b.items,
            &b.counters,
            &b.args,
            &b.overflow,
        ] {
            e.clear_buffer(buf, 0, None);
        }
        gpu.queue.submit([e.finish()]);
        b.projs = projections(gpu, planes);
        let mut bytes = 0;
        b.out = buffer(
            gpu,
            &mut bytes,
            "the shadow terms",
            sizes.pixels * 12,
            wgpu::BufferUsages::empty(),
        )?;
        Ok(b)
    }

    fn new(gpu: &Gpu, sizes: Sizes, planes: &Planes) -> Result<Bufs> {
        let Sizes {
            n,
            pixels,
            caps,
            transparency,
        } = sizes;
        let mut b = 0u64;
        let none = wgpu::BufferUsages::empty();
        let g = gpu;
        let projs = projections(g, planes);
        Ok(Bufs {
            planes: buffer(
                g,
                &mut b,
                "the light planes' grids",
                PLANE_WORDS as u64 * 4,
                none,
            )?,
            projs,
            s_uvz: buffer(
                g,
                &mut b,
                "the samples' light-space positions",
                n * 16,
                none,
            )?,
            s_ray: buffer(g, &mut b, "the samples' shadow rays", n * 32, none)?,
            s_cell: buffer(g, &mut b, "the samples' cells", n * 4, none)?,
            s_rank: buffer(g, &mut b, "the samples' ranks", n * 4, none)?,
            cell_start: buffer(g, &mut b, "the grid's cells", (caps.cells + 1) * 4, none)?,
            chunk_start: buffer(g, &mut b, "the cells' chunks", (caps.cells + 1) * 4, none)?,
            chunks: buffer(g, &mut b, "the chunks", caps.chunks * CHUNK_WORDS * 4, none)?,
            chunk_live: buffer(g, &mut b, "the chunks' live counts", caps.chunks * 4, none)?,
            chunk_culled: buffer(g, &mut b, "the chunks' cull counts", caps.chunks * 4, none)?,
            sat: buffer(g, &mut b, "the summed-area table", caps.sat * 4, none)?,
            sorted_uvz: buffer(g, &mut b, "the binned samples", n * 16, none)?,
            sorted_ray: buffer(g, &mut b, "the binned shadow rays", n * 32, none)?,
            dark: buffer(g, &mut b, "the samples' dark flags", n * 4, none)?,
            logs: buffer(
                g,
                &mut b,
                "the samples' transmittance sums",
                if transparency { n * 12 } else { 4 },
                none,
            )?,
            records: buffer(
                g,
                &mut b,
                "the triangles' set-up",
                caps.records * RECORD_WORDS * 4,
                none,
            )?,
            items: buffer(
                g,
                &mut b,
                "the triangles' work counts",
                (caps.records + 1) * 4,
                none,
            )?,
            counters: buffer(g, &mut b, "the counters", COUNTERS as u64 * 8, none)?,
            args: buffer(
                g,
                &mut b,
                "the test's dispatch",
                16,
                wgpu::BufferUsages::INDIRECT,
            )?,
            out: buffer(g, &mut b, "the shadow terms", pixels * 12, none)?,
            overflow: buffer(g, &mut b, "the work counts' overflow flag", 4, none)?,
            bytes: b,
            sizes,
        })
    }
}

/// The planes' records before the transform: counts zero, bounds empty.
pub(super) fn plane_init() -> Vec<u32> {
    let mut v = vec![0u32; PLANE_WORDS];
    for pl in 0..7 {
        v[pl * 16 + 1] = u32::MAX;
        v[pl * 16 + 2] = u32::MAX;
    }
    v
}
