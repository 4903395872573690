//! Stage `fit` (`fit.wgsl`) and the soft variants' stage `blocker_search`
//! (`blocker_search.wgsl`), both over the maps' min-depth pyramids on the GPU: the depth
//! range each map is normalized over, as the library's `ReceiverDepths` and
//! `DepthRange::fitted` fit it, and each pixel's penumbra footprint, as the library's
//! `SoftSearch` finds it. Nothing is read back before the look-up; the counts behind
//! `shadowable_share` are read with the frame's timestamps.

use super::Codec;
use crate::device::Gpu;
use crate::shader::{order_key, Common, Stage, LIGHT, ORDER_KEY, RAY_OFFSET};
use crate::transfer::{grid, output, read_back, storage, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::LightView;
use shadowlab::techniques::filtering::{Filter, MAX_ANISOTROPY};
use shadowlab::techniques::shadow_map::{DEFAULT_CONSTANT_BIAS, DEFAULT_SLOPE_BIAS};
use shadowlab::techniques::Frame;

/// `filtering/views.wgsl`: the light views, their projections and footprints, the ranges.
pub const VIEWS: Common = Common {
    name: "filtering/views.wgsl",
    source: include_str!("views.wgsl"),
};
const PYRAMID: Common = Common {
    name: "filtering/pyramid.wgsl",
    source: include_str!("pyramid.wgsl"),
};
const FIT: Stage = Stage {
    name: "filtering/fit.wgsl",
    common: &[RAY_OFFSET, LIGHT, ORDER_KEY, VIEWS, PYRAMID],
    source: include_str!("fit.wgsl"),
};
const BLOCKER_SEARCH: Stage = Stage {
    name: "filtering/blocker_search.wgsl",
    common: &[RAY_OFFSET, LIGHT, ORDER_KEY, VIEWS, PYRAMID],
    source: include_str!("blocker_search.wgsl"),
};

/// Numbers `fit.wgsl` keeps per view (see its `acc`).
const ACC: usize = 8;

/// `ViewU` of `views.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct ViewU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    ortho: u32,
    near: f32,
    far: f32,
    extent: f32,
}

/// `FitU` of `pyramid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct FitU {
    light: LightU,
    count: u32,
    row: u32,
    side: u32,
    views: u32,
    levels: u32,
    filtering: u32,
    max_aniso: u32,
    blur_pad: u32,
    stride: u32,
    level: u32,
    pad: [u32; 2],
    span: f32,
    light_width: f32,
    bias: f32,
    slope_bias: f32,
}

/// The light views as the shaders read them.
pub(super) fn view_table(gpu: &Gpu, views: &[LightView]) -> Result<wgpu::Buffer> {
    let table: Vec<ViewU> = views
        .iter()
        .map(|v| ViewU {
            clip_from_world: v.clip_from_world.to_cols_array(),
            light_from_world: v.light_from_world.to_cols_array(),
            ortho: u32::from(v.orthographic),
            near: v.near,
            far: v.far,
            extent: v.extent,
        })
        .collect();
    storage(gpu, "the light views", bytemuck::cast_slice(&table))
}

/// The code `lookup.wgsl` and `fit.wgsl` name a filter by.
pub(super) fn filter_code(f: Filter) -> u32 {
    match f {
        Filter::Bilinear => 0,
        Filter::Trilinear => 1,
        Filter::Anisotropic => 2,
    }
}

/// What the fit leaves on the GPU for the later stages.
pub(super) struct Fitted {
    /// Each view's depth range (`RangeU`).
    pub ranges: wgpu::Buffer,
    /// Each pixel's penumbra footprint, for the soft variants under an area light.
    pub widths: Option<wgpu::Buffer>,
    /// The per-view sums (`acc`), read for the counters.
    acc: wgpu::Buffer,
    views: usize,
}

impl Fitted {
    /// The share of receivers that may be shadowed (the counter `shadowable_share`).
    pub fn shadowable_share(&self, gpu: &Gpu) -> Result<f64> {
        let raw = read_back(gpu, &self.acc, (self.views * ACC * 4) as u64)?;
        let word = |i: usize| u32::from_le_bytes([raw[i], raw[i + 1], raw[i + 2], raw[i + 3]]);
        let (mut count, mut shadowable) = (0u64, 0u64);
        for v in 0..self.views {
            count += u64::from(word((v * ACC + 4) * 4));
            shadowable += u64::from(word((v * ACC + 5) * 4));
        }
        Ok(shadowable as f64 / count.max(1) as f64)
    }
}

/// The sides and first texels of a view's pyramid levels (`⌈side / 2⌉` each, to 1×1), and
/// the texels of all of them.
fn pyramid_levels(side: u32) -> (Vec<[u32; 4]>, u32) {
    let (mut out, mut at, mut s) = (Vec::new(), 0u32, side);
    loop {
        out.push([s, s, at, 0]);
        at += s * s;
        if s <= 1 {
            return (out, at);
        }
        s = s.div_ceil(2);
    }
}

/// A whole buffer as a binding.
fn res(b: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    b.as_entire_binding()
}

/// A bind group of `p`'s group 0 with `entries` (binding, buffer).
fn bind(
    gpu: &Gpu,
    p: &wgpu::ComputePipeline,
    entries: &[(u32, wgpu::BindingResource)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|(b, r)| wgpu::BindGroupEntry {
            binding: *b,
            resource: r.clone(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &p.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// The fit's parameters for `frame` (the area light's width where the soft variants
/// widen their filters, else 0).
fn parameters(
    frame: &Frame,
    codec: &Codec,
    levels: &[[u32; 4]],
    stride: u32,
    views: usize,
    row: u32,
) -> FitU {
    let s = &codec.settings;
    let light_width = match frame.area {
        Some(a) if s.soft => a.equivalent_width(),
        _ => 0.0,
    };
    FitU {
        light: LightU::of(frame.light),
        count: frame.view.triangle.len() as u32,
        row,
        side: codec.resolution,
        views: views as u32,
        levels: levels.len() as u32,
        filtering: filter_code(s.filter),
        max_aniso: s.max_aniso.clamp(1, MAX_ANISOTROPY),
        blur_pad: s.blur / 2 + 1,
        stride,
        level: 0,
        pad: [0; 2],
        span: codec.span,
        light_width,
        bias: DEFAULT_CONSTANT_BIAS,
        slope_bias: DEFAULT_SLOPE_BIAS,
    }
}

/// The fit's per-view sums (`acc` of `fit.wgsl`), emptied: minima at +inf, maxima at
/// −inf, counts at 0.
fn accumulators(gpu: &Gpu, views: usize) -> wgpu::Buffer {
    let empty = [
        order_key(f32::INFINITY),
        order_key(f32::NEG_INFINITY),
        order_key(f32::INFINITY),
        order_key(f32::NEG_INFINITY),
        0,
        0,
        order_key(f32::INFINITY),
        order_key(f32::NEG_INFINITY),
    ];
    let init: Vec<u32> = (0..views).flat_map(|_| empty).collect();
    let acc = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("receiver depths"),
        size: (init.len() * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    gpu.queue.write_buffer(&acc, 0, bytemuck::cast_slice(&init));
    acc
}

/// Records and submits the fit (and, for the soft variants under an area light, the
/// blocker search) over the maps in `texels`.
#[allow(clippy::too_many_arguments)]
pub(super) fn run(
    gpu: &Gpu,
    frame: &Frame,
    codec: &Codec,
    views: &[LightView],
    table: &wgpu::Buffer,
    texels: &wgpu::Texture,
    view: &wgpu::Buffer,
    derivs: &wgpu::Buffer,
    timer: &mut Timer,
) -> Result<Fitted> {
    let side = codec.resolution;
    let (levels, stride) = pyramid_levels(side);
    let nv = views.len();
    let n = frame.view.triangle.len() as u32;
    let (gx, gy, row) = grid(gpu, n, 64);
    let base = parameters(frame, codec, &levels, stride, nv, row);
    let soft = base.light_width > 0.0;
    let pyramid = output(
        gpu,
        "the maps' min pyramids",
        u64::from(stride) * nv as u64 * 4,
    )?;
    let level_table = storage(gpu, "the pyramid levels", bytemuck::cast_slice(&levels))?;
    let acc = accumulators(gpu, nv);
    let ranges = output(gpu, "the fitted depth ranges", nv as u64 * 16)?;
    let widths = if soft {
        Some(output(
            gpu,
            "the penumbra footprints",
            u64::from(n).max(1) * 4,
        )?)
    } else {
        None
    };
    let depth_view = texels.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let fit_u = uniform(gpu, "fit parameters", &base);
    let tex = wgpu::BindingResource::TextureView(&depth_view);
    let mut steps: Vec<(wgpu::ComputePipeline, wgpu::BindGroup, [u32; 3])> = Vec::new();
    let p = crate::compute::pipeline(gpu, &FIT, "base");
    let g = bind(
        gpu,
        &p,
        &[
            (0, res(&fit_u)),
            (2, tex),
            (3, res(&pyramid)),
            (5, res(&acc)),
        ],
    );
    steps.push((p, g, [side.div_ceil(8), side.div_ceil(8), nv as u32]));
    let p = crate::compute::pipeline(gpu, &FIT, "reduce");
    for (l, lv) in levels.iter().enumerate().skip(1) {
        let u = uniform(
            gpu,
            "pyramid level",
            &FitU {
                level: l as u32,
                ..base
            },
        );
        let g = bind(
            gpu,
            &p,
            &[(0, res(&u)), (3, res(&pyramid)), (4, res(&level_table))],
        );
        steps.push((
            p.clone(),
            g,
            [lv[0].div_ceil(8), lv[1].div_ceil(8), nv as u32],
        ));
    }
    let p = crate::compute::pipeline(gpu, &FIT, "receivers");
    let g = bind(
        gpu,
        &p,
        &[
            (0, res(&fit_u)),
            (1, res(table)),
            (3, res(&pyramid)),
            (4, res(&level_table)),
            (5, res(&acc)),
            (6, res(view)),
            (7, res(derivs)),
        ],
    );
    steps.push((p, g, [gx, gy, 1]));
    let p = crate::compute::pipeline(gpu, &FIT, "fitted");
    let g = bind(
        gpu,
        &p,
        &[
            (0, res(&fit_u)),
            (1, res(table)),
            (5, res(&acc)),
            (8, res(&ranges)),
        ],
    );
    steps.push((p, g, [nv as u32, 1, 1]));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("fit"),
            timestamp_writes: timer.pass("fit"),
        });
        for (p, g, [x, y, z]) in &steps {
            pass.set_pipeline(p);
            pass.set_bind_group(0, g, &[]);
            pass.dispatch_workgroups(*x, *y, *z);
        }
    }
    if let Some(w) = &widths {
        let p = crate::compute::pipeline(gpu, &BLOCKER_SEARCH, "search");
        let g = bind(
            gpu,
            &p,
            &[
                (0, res(&fit_u)),
                (1, res(table)),
                (3, res(&pyramid)),
                (4, res(&level_table)),
                (6, res(view)),
                (9, res(w)),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("blocker_search"),
            timestamp_writes: timer.pass("blocker_search"),
        });
        pass.set_pipeline(&p);
        pass.set_bind_group(0, &g, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(Fitted {
        ranges,
        widths,
        acc,
        views: nv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<ViewU>(), 144);
        assert_eq!(std::mem::size_of::<FitU>(), 112);
    }

    #[test]
    fn pyramid_levels_halve_rounding_up() {
        let (l, total) = pyramid_levels(5);
        assert_eq!(l.iter().map(|v| v[0]).collect::<Vec<_>>(), vec![5, 3, 2, 1]);
        assert_eq!(total, 25 + 9 + 4 + 1);
    }
}
