//! A drawn frame read back from the GPU: the screenshot's pixels.

use anyhow::{anyhow, Result};
use shadowlab::picture::RgbImage;
use shadowlab_gpu::device::Gpu;
use shadowlab_gpu::transfer::read_back;

/// The RGB pixels of `t` (RGBA8 or BGRA8, one mip).
pub fn read_rgb(gpu: &Gpu, t: &wgpu::Texture) -> Result<RgbImage> {
    let (w, h) = (t.width(), t.height());
    let row = w * 4;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let size = u64::from(padded) * u64::from(h);
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("screenshot read-back"),
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
    let bgra = matches!(
        t.format(),
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for r in raw.chunks_exact(padded as usize) {
        for p in r[..row as usize].chunks_exact(4) {
            if bgra {
                rgb.extend([p[2], p[1], p[0]]);
            } else {
                rgb.extend([p[0], p[1], p[2]]);
            }
        }
    }
    RgbImage::from_raw(w, h, rgb).ok_or_else(|| anyhow!("a screenshot of {w}x{h} came back short"))
}
