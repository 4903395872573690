//! The min-depth pyramid of `gpu:pcss`'s maps (the library's `MinPyramid`), reduced on
//! the GPU a level at a time from the map array (`min_pyramid.wgsl`).

use crate::compute::pipeline;
use crate::device::Gpu;
use crate::shader::Stage;
use crate::transfer::{grid, output, storage, uniform, Timer};
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;

const MIN_PYRAMID: Stage = Stage {
    name: "min_pyramid.wgsl",
    common: &[],
    source: include_str!("min_pyramid.wgsl"),
};

const WORKGROUP: u32 = 64;

/// `Reduce` of `min_pyramid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Reduce {
    side_in: u32,
    side_out: u32,
    offset_in: u32,
    offset_out: u32,
    layer_stride: u32,
    layers: u32,
    row: u32,
    from_map: u32,
}

/// The levels of the pyramid of a `side`-texel map, level 0 (the map) first: each level's
/// side (`⌈previous / 2⌉`, down to 1) and its offset in a layer's part of the buffer
/// (level 0 is the map itself and has none), and the floats of one layer's levels.
pub fn levels(side: u32) -> (Vec<[u32; 2]>, u32) {
    let mut out = vec![[side, 0]];
    let mut offset = 0;
    let mut s = side;
    while s > 1 {
        s = s.div_ceil(2);
        out.push([s, offset]);
        offset += s * s;
    }
    (out, offset)
}

/// The pyramid above `map` (`layers` layers of `side²` texels) in one buffer, layer by
/// layer, and its level table (`levels`) in another.
pub struct Pyramid {
    /// Levels 1 and on of every layer.
    pub buffer: wgpu::Buffer,
    /// `(side, offset)` of each level, level 0 first.
    pub table: wgpu::Buffer,
    /// Number of levels, level 0 included.
    pub count: u32,
    /// Floats of one layer's levels.
    pub layer_stride: u32,
}

impl Pyramid {
    /// Bytes the pyramid's levels take.
    pub fn bytes(&self, layers: u32) -> u64 {
        u64::from(self.layer_stride) * u64::from(layers) * 4
    }
}

/// Reduces `map` into its pyramid: one compute pass a level, each reading the last.
pub fn build(
    gpu: &Gpu,
    map: &wgpu::Texture,
    side: u32,
    layers: u32,
    timer: &mut Timer,
) -> Result<Pyramid> {
    let (table, stride) = levels(side);
    let bytes = u64::from(stride) * u64::from(layers) * 4;
    let buffer = output(gpu, "the min-depth pyramid", bytes)?;
    let reduce = pipeline(gpu, &MIN_PYRAMID, "main");
    let map_view = map.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    for (i, w) in table.windows(2).enumerate() {
        let (from, to) = (w[0], w[1]);
        let count = to[0] * to[0] * layers;
        let (gx, gy, row) = grid(gpu, count, WORKGROUP);
        let r = Reduce {
            side_in: from[0],
            side_out: to[0],
            offset_in: from[1],
            offset_out: to[1],
            layer_stride: stride,
            layers,
            row,
            from_map: u32::from(i == 0),
        };
        let r = uniform(gpu, "pyramid level", &r);
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &reduce.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: r.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&map_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: buffer.as_entire_binding(),
                },
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("min_pyramid"),
            timestamp_writes: timer.pass("min_pyramid"),
        });
        pass.set_pipeline(&reduce);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    let flat: Vec<u32> = table.iter().flatten().copied().collect();
    Ok(Pyramid {
        buffer,
        table: storage(gpu, "the pyramid's levels", bytemuck::cast_slice(&flat))?,
        count: table.len() as u32,
        layer_stride: stride,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_rounding_up_down_to_one() {
        let (t, stride) = levels(5);
        assert_eq!(t, vec![[5, 0], [3, 0], [2, 9], [1, 13]]);
        assert_eq!(stride, 14);
        assert_eq!(levels(1), (vec![[1, 0]], 0));
        assert_eq!(std::mem::size_of::<Reduce>(), 32);
    }
}
