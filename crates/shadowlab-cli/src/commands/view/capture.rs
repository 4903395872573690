//! A drawn frame read back from the GPU: the screenshot's pixels.

use anyhow::{anyhow, Result};
use shadowlab::picture::RgbImage;
use shadowlab_gpu::device::Gpu;
use shadowlab_gpu::transfer::read_texture;

/// The RGB pixels of `t` (RGBA8 or BGRA8, one mip).
pub fn read_rgb(gpu: &Gpu, t: &wgpu::Texture) -> Result<RgbImage> {
    let (w, h) = (t.width(), t.height());
    let raw = read_texture(gpu, t)?;
    let bgra = matches!(
        t.format(),
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for p in raw.chunks_exact(4) {
        if bgra {
            rgb.extend([p[2], p[1], p[0]]);
        } else {
            rgb.extend([p[0], p[1], p[2]]);
        }
    }
    RgbImage::from_raw(w, h, rgb).ok_or_else(|| anyhow!("a screenshot of {w}x{h} came back short"))
}
