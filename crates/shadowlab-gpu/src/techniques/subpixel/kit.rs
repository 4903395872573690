//! `gpu:subpixel`'s shaders, its one bind-group layout and its pipelines (made once per
//! device), and the uniform and table structs mirrored from `bindings.wgsl`.

use crate::device::Gpu;
use crate::shader::{Common, PipelineKey, Stage, ALPHA_MASK, LIGHT, RAY_OFFSET, TRIANGLES};
use bytemuck::{Pod, Zeroable};

const fn common(name: &'static str, source: &'static str) -> Common {
    Common { name, source }
}

/// The files every stage is composed after, in order.
const COMMON: &[Common] = &[
    RAY_OFFSET,
    LIGHT,
    ALPHA_MASK,
    TRIANGLES,
    common("subpixel/bindings.wgsl", include_str!("bindings.wgsl")),
    common(
        "subpixel/rasterization.wgsl",
        include_str!("rasterization.wgsl"),
    ),
    common("subpixel/ray_plane.wgsl", include_str!("ray_plane.wgsl")),
    common(
        "subpixel/lookup_table.wgsl",
        include_str!("lookup_table.wgsl"),
    ),
];

const fn stage(name: &'static str, source: &'static str) -> Stage {
    Stage {
        name,
        common: COMMON,
        source,
    }
}

/// The stages, and the entry points each runs.
const STAGES: &[(Stage, &[&str])] = &[
    (
        stage(
            "silhouette_edges.wgsl",
            include_str!("silhouette_edges.wgsl"),
        ),
        &["main"],
    ),
    (
        stage(
            "silhouette_mask_map.wgsl",
            include_str!("silhouette_mask_map.wgsl"),
        ),
        &["hidden", "sat_rows", "sat_columns"],
    ),
    (stage("facets.wgsl", include_str!("facets.wgsl")), &["main"]),
    (
        stage("pairs.wgsl", include_str!("pairs.wgsl")),
        &[
            "pixel_texels",
            "slots",
            "triangle_texels_main",
            "list_mode",
            "big_blocks",
            "scan_blocks",
            "scan",
            "scan_slots",
        ],
    ),
    (
        stage(
            "visibility_evaluation.wgsl",
            include_str!("visibility_evaluation.wgsl"),
        ),
        &["count_items", "list_items", "main", "finish"],
    ),
];

/// Bindings of `bindings.wgsl`: 0 the frame's uniform, 3 the depth map, the rest storage.
pub const BINDINGS: u32 = 28;
const UNIFORM_BINDING: u32 = 0;
const MAP_BINDING: u32 = 3;

/// The pipelines, by `stage:entry`, all over one layout.
pub struct Pipelines {
    list: Vec<(String, wgpu::ComputePipeline)>,
}

impl Pipelines {
    /// Made once per device (kept in the device's pipeline cache).
    pub fn get(gpu: &Gpu) -> Pipelines {
        let mut made = gpu.compute.lock().unwrap_or_else(|e| e.into_inner());
        let have = |made: &[(PipelineKey, wgpu::ComputePipeline)], s: &Stage, e: &str| {
            made.iter()
                .find(|(k, _)| k.is(s, e))
                .map(|(_, p)| p.clone())
        };
        if have(&made, &STAGES[0].0, STAGES[0].1[0]).is_none() {
            let layout = pipeline_layout(&gpu.device);
            for (s, entries) in STAGES {
                let module = s.module(&gpu.device);
                for e in *entries {
                    let p = gpu
                        .device
                        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                            label: Some(s.name),
                            layout: Some(&layout),
                            module: &module,
                            entry_point: Some(e),
                            compilation_options: Default::default(),
                            cache: None,
                        });
                    made.push((PipelineKey::new(s, e), p));
                }
            }
        }
        let list = STAGES
            .iter()
            .flat_map(|(s, entries)| entries.iter().map(move |e| (s, *e)))
            .filter_map(|(s, e)| have(&made, s, e).map(|p| (format!("{}:{e}", s.name), p)))
            .collect();
        Pipelines { list }
    }

    /// The pipeline of `stage` (its file name) at `entry`.
    pub fn at(&self, stage: &str, entry: &str) -> &wgpu::ComputePipeline {
        let k = format!("{stage}:{entry}");
        &self
            .list
            .iter()
            .find(|(m, _)| *m == k)
            .unwrap_or_else(|| panic!("gpu:subpixel has no pipeline {k}"))
            .1
    }

    /// The layout every pipeline shares.
    pub fn layout(&self) -> wgpu::BindGroupLayout {
        self.list[0].1.get_bind_group_layout(0)
    }
}

fn pipeline_layout(device: &wgpu::Device) -> wgpu::PipelineLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..BINDINGS)
        .map(|b| wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: match b {
                UNIFORM_BINDING => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                MAP_BINDING => wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    multisampled: false,
                },
                _ => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            },
            count: None,
        })
        .collect();
    let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("gpu:subpixel"),
        entries: &entries,
    });
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gpu:subpixel"),
        bind_group_layouts: &[Some(&group)],
        immediate_size: 0,
    })
}

/// `FrameU` of `bindings.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameU {
    pub light: crate::upload::LightU,
    pub o0: [f32; 3],
    pub parallel: u32,
    pub ox: [f32; 3],
    pub width: u32,
    pub oy: [f32; 3],
    pub height: u32,
    pub d0: [f32; 3],
    pub res: u32,
    pub dx: [f32; 3],
    pub views: u32,
    pub dy: [f32; 3],
    pub samples: u32,
    pub screen: [f32; 16],
    pub centre: u32,
    pub bias: f32,
    pub slope_bias: f32,
    pub masks: u32,
    pub edges: u32,
    pub triangles: u32,
    pub pixels: u32,
    pub row: u32,
    pub toward: [f32; 3],
    pub toward_is_dir: u32,
}

/// `ViewS` of `bindings.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewS {
    pub clip_from_world: [f32; 16],
    pub light_from_world: [f32; 16],
    pub clip_from_light: [f32; 16],
    pub ortho: u32,
    pub near: f32,
    pub extent: f32,
    pub depth_scale: f32,
}

/// Bytes of `FacetU` in `bindings.wgsl`.
pub const FACET_BYTES: u64 = 288;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<FrameU>(), 256);
        assert_eq!(std::mem::size_of::<ViewS>(), 208);
    }
}
