//! The pipelines of one stage file: every entry point it exports shares one bind-group
//! layout, read from the file's own `@binding` declarations, so a stage binds its buffers
//! once per frame whatever subset each entry point uses. Also the dispatch shapes, and
//! the prefix sum the counting sorts run.

use crate::shader::Stage;

/// Threads along x of every two-dimensional dispatch (the shaders' `ROW`), in workgroups.
pub(super) const ROW_GROUPS: u32 = 32768;

/// What a binding holds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Uniform,
    Storage { read_only: bool },
}

/// The bindings a WGSL source declares, in binding order.
fn bindings(source: &str) -> Vec<Kind> {
    let mut out: Vec<(u32, Kind)> = Vec::new();
    for line in source.lines() {
        let Some(at) = line.find("@binding(") else {
            continue;
        };
        let rest = &line[at + 9..];
        let Some(end) = rest.find(')') else {
            continue;
        };
        let Ok(n) = rest[..end].trim().parse::<u32>() else {
            continue;
        };
        let kind = if rest.contains("var<uniform>") {
            Kind::Uniform
        } else {
            Kind::Storage {
                read_only: !rest.contains("read_write"),
            }
        };
        out.push((n, kind));
    }
    out.sort_by_key(|b| b.0);
    out.into_iter().map(|b| b.1).collect()
}

/// A stage file's pipelines over one shared layout.
pub(super) struct Kit {
    layout: wgpu::BindGroupLayout,
    pipes: Vec<(&'static str, wgpu::ComputePipeline)>,
}

impl Kit {
    /// The pipelines of `entries` of `stage`.
    pub(super) fn new(device: &wgpu::Device, stage: &Stage, entries: &[&'static str]) -> Kit {
        let entries_layout: Vec<wgpu::BindGroupLayoutEntry> = bindings(stage.source)
            .into_iter()
            .enumerate()
            .map(|(i, k)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: match k {
                        Kind::Uniform => wgpu::BufferBindingType::Uniform,
                        Kind::Storage { read_only } => {
                            wgpu::BufferBindingType::Storage { read_only }
                        }
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(stage.name),
            entries: &entries_layout,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(stage.name),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = stage.module(device);
        let pipes = entries
            .iter()
            .map(|&e| {
                let p = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(e),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(e),
                    compilation_options: Default::default(),
                    cache: None,
                });
                (e, p)
            })
            .collect();
        Kit { layout, pipes }
    }

    /// The pipeline of entry point `entry` (one of those the kit was made with).
    pub(super) fn pipe(&self, entry: &str) -> &wgpu::ComputePipeline {
        match self.pipes.iter().find(|p| p.0 == entry) {
            Some(p) => &p.1,
            None => &self.pipes[0].1,
        }
    }

    /// A bind group with `buffers` at bindings 0, 1, … of the kit's layout.
    pub(super) fn bind(&self, device: &wgpu::Device, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// The workgroup grid `(x, y)` of `groups` workgroups in rows of [`ROW_GROUPS`].
pub(super) fn groups_2d(groups: u32) -> (u32, u32) {
    let x = groups.clamp(1, ROW_GROUPS);
    (x, groups.div_ceil(x).max(1))
}

/// Dispatches `entry` of `kit` over `threads` threads, 64 a workgroup.
pub(super) fn dispatch(
    pass: &mut wgpu::ComputePass,
    kit: &Kit,
    entry: &str,
    group: &wgpu::BindGroup,
    threads: u64,
) {
    let groups = threads.div_ceil(64).clamp(1, u64::from(u32::MAX)) as u32;
    let (x, y) = groups_2d(groups);
    pass.set_pipeline(kit.pipe(entry));
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(x, y, 1);
}

/// Words a scan workgroup sums.
const SCAN_BLOCK: u32 = 1024;

/// An exclusive prefix sum over the first `n` words of a buffer, with the bind groups of
/// every level (the blocks' totals summed the same way until one block remains).
pub(super) struct Scan {
    levels: Vec<(wgpu::BindGroup, u32)>,
}

impl Scan {
    /// The scan of the first `n` words of `data`; a sum past 32 bits sets word 0 of
    /// `overflow`.
    pub(super) fn new(
        device: &wgpu::Device,
        kit: &Kit,
        data: &wgpu::Buffer,
        n: u32,
        overflow: &wgpu::Buffer,
    ) -> Scan {
        let mut levels = Vec::new();
        let mut cur = data.clone();
        let mut len = n.max(1);
        loop {
            let blocks = len.div_ceil(SCAN_BLOCK);
            let sums = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scan sums"),
                size: u64::from(blocks) * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            let n_buf = wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some("scan length"),
                    contents: bytemuck::cast_slice(&[len, 0, 0, 0]),
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            );
            levels.push((kit.bind(device, &[&n_buf, &cur, &sums, overflow]), blocks));
            if blocks <= 1 {
                break;
            }
            cur = sums;
            len = blocks;
        }
        Scan { levels }
    }

    /// Records the scan into `pass`.
    pub(super) fn record(&self, pass: &mut wgpu::ComputePass, kit: &Kit) {
        pass.set_pipeline(kit.pipe("scan_blocks"));
        for (group, blocks) in &self.levels {
            let (x, y) = groups_2d(*blocks);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        pass.set_pipeline(kit.pipe("scan_add"));
        for (group, blocks) in self.levels.iter().rev() {
            if *blocks > 1 {
                let (x, y) = groups_2d(*blocks);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_read_from_the_declarations() {
        let src = "@group(0) @binding(1) var<storage, read> a: array<u32>;\n\
                   @group(0) @binding(0) var<uniform> p: P;\n\
                   @group(0) @binding(2) var<storage, read_write> b: array<u32>;";
        assert_eq!(
            bindings(src),
            vec![
                Kind::Uniform,
                Kind::Storage { read_only: true },
                Kind::Storage { read_only: false }
            ]
        );
    }
}
