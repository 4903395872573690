//! Moving bytes between the CPU and the GPU, and timing GPU passes.
//!
//! [`storage`] makes a storage buffer from bytes after checking the adapter's largest
//! binding; [`read_back`] copies a buffer into memory. [`Timer`] writes a timestamp at the
//! start and end of each timed pass, resolves them once per frame and scales the ticks by
//! the queue's period; on an adapter without timestamp queries it records nothing.

use crate::device::Gpu;
use shadowlab::error::{Error, Result};
use wgpu::util::DeviceExt;

/// A read-only storage buffer holding `bytes` (at least 4 bytes, as a binding cannot be
/// empty), refused in one sentence naming `what` when past the adapter's largest binding.
pub fn storage(gpu: &Gpu, what: &str, bytes: &[u8]) -> Result<wgpu::Buffer> {
    gpu.check_binding(what, bytes.len() as u64)?;
    let padded;
    let contents = if bytes.len() < 4 {
        padded = [bytes, &[0u8; 4][..4 - bytes.len()]].concat();
        &padded[..]
    } else {
        bytes
    };
    Ok(gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        }))
}

/// A storage buffer of `bytes` bytes the GPU writes and the CPU reads back.
pub fn output(gpu: &Gpu, what: &str, bytes: u64) -> Result<wgpu::Buffer> {
    gpu.check_binding(what, bytes)?;
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes.max(4),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    }))
}

/// A uniform buffer holding `value`.
pub fn uniform<T: bytemuck::Pod>(gpu: &Gpu, what: &str, value: &T) -> wgpu::Buffer {
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents: bytemuck::bytes_of(value),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// The texture `t` (one mip, one layer) read back row by row, without the copy's padding.
pub fn read_texture(gpu: &Gpu, t: &wgpu::Texture) -> Result<Vec<u8>> {
    let texel = t.format().block_copy_size(None).unwrap_or(4);
    let (w, h) = (t.width(), t.height());
    let row = w * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let size = u64::from(padded) * u64::from(h);
    gpu.check_binding("a texture's read-back", size)?;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture read-back"),
        size,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        t.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        t.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    let raw = read_back(gpu, &buffer, size)?;
    Ok(raw
        .chunks_exact(padded as usize)
        .flat_map(|r| r[..row as usize].iter().copied())
        .collect())
}

/// The first `bytes` bytes of `buffer` (which has `COPY_SRC` usage), copied to memory.
pub fn read_back(gpu: &Gpu, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>> {
    let size = bytes.max(4).div_ceil(4) * 4;
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Internal(format!("waiting for a GPU read-back failed: {e}")))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(Error::Internal(format!("a GPU read-back failed: {e}"))),
        Err(_) => return Err(Error::Internal("a GPU read-back never finished".into())),
    }
    let data = staging
        .get_mapped_range(..)
        .map_err(|e| Error::Internal(format!("a GPU read-back could not be mapped: {e}")))?
        .to_vec();
    staging.unmap();
    data.get(..bytes as usize)
        .map(<[u8]>::to_vec)
        .ok_or_else(|| Error::Internal("a GPU read-back came back short".into()))
}

/// Timestamps at the start and end of each timed pass of one frame.
pub struct Timer {
    set: Option<wgpu::QuerySet>,
    names: Vec<String>,
    capacity: u32,
}

impl Timer {
    /// A timer for at most `passes` passes.
    pub fn new(gpu: &Gpu, passes: u32) -> Self {
        let set = gpu.timestamps.then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            })
        });
        Timer {
            set,
            names: Vec::new(),
            capacity: passes,
        }
    }

    /// The timestamp writes of the next pass, named `name`; `None` when the adapter has no
    /// timestamp queries or every slot is taken.
    pub fn pass(&mut self, name: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let set = self.set.as_ref()?;
        let i = self.names.len() as u32;
        if i >= self.capacity {
            return None;
        }
        self.names.push(name.to_string());
        Some(wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// The timestamp writes of the next render pass, named `name` (see [`Timer::pass`]).
    pub fn render_pass(&mut self, name: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let w = self.pass(name)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        })
    }

    /// Every timed stage's GPU time in milliseconds (the passes of one name summed), in the
    /// order the stages were first met (empty without timestamp queries).
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<(String, f64)>> {
        let Some(set) = self.set.as_ref() else {
            return Ok(Vec::new());
        };
        let n = self.names.len() as u32;
        if n == 0 {
            return Ok(Vec::new());
        }
        let bytes = u64::from(2 * n) * 8;
        let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(set, 0..2 * n, &resolve, 0);
        gpu.queue.submit([encoder.finish()]);
        let raw = read_back(gpu, &resolve, bytes)?;
        let ticks: Vec<u64> = raw
            .chunks_exact(8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
            .collect();
        let ns = gpu.timestamp_period_ns();
        // Passes of one name (a cube's six faces) add up to one stage.
        let mut out: Vec<(String, f64)> = Vec::new();
        for (i, name) in self.names.iter().enumerate() {
            let ms = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * ns / 1e6;
            match out.iter_mut().find(|(n, _)| n == name) {
                Some((_, t)) => *t += ms,
                None => out.push((name.clone(), ms)),
            }
        }
        Ok(out)
    }
}

/// Workgroups of `size` threads covering `count` items in a grid no wider than the
/// adapter allows: `(x, y, threads per row)`.
pub fn grid(gpu: &Gpu, count: u32, size: u32) -> (u32, u32, u32) {
    let groups = count.div_ceil(size).max(1);
    let x = groups.min(gpu.limits.max_compute_workgroups_per_dimension.max(1));
    (x, groups.div_ceil(x), x * size)
}
