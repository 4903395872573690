//! The stages' GPU work for one pass of a frame: `analysis` (page requests and LRU
//! stamps, read back), `allocate` (the page table's updates and the new pages emptied),
//! `render` (the new pages drawn into their slots) and `lookup`.

use super::pool::{Layout, Request, Update};
use super::WORKGROUP;
use super::{Resident, State};
use crate::compute::bind;
use crate::transfer::{grid, output, read_back, storage, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::LightView;
use shadowlab::math::DMat4;

/// `VirtualU` of `pages.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct VirtualU {
    pub(super) light: LightU,
    pub(super) count: u32,
    pub(super) row: u32,
    pub(super) page: u32,
    pub(super) levels: u32,
    pub(super) side: u32,
    pub(super) faces: u32,
    pub(super) atlas_cols: u32,
    pub(super) now: u32,
    pub(super) oversampling: f32,
    pub(super) bias: f32,
    pub(super) slope_bias: f32,
    pub(super) pad: u32,
    pub(super) bases: [u32; 8],
}

/// `FaceV` of `pages.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct FaceV {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    ortho: u32,
    near: f32,
    extent: f32,
    pad: u32,
}

impl FaceV {
    pub(super) fn of(v: &LightView) -> Self {
        FaceV {
            clip_from_world: v.clip_from_world.to_cols_array(),
            light_from_world: v.light_from_world.to_cols_array(),
            ortho: u32::from(v.orthographic),
            near: v.near,
            extent: v.extent,
            pad: 0,
        }
    }
}

/// `PageU` of `render.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PageU {
    clip_from_world: [f32; 16],
    light_from_world: [f32; 16],
    depth_scale: f32,
    masks: u32,
    first: u32,
    pad: u32,
}

/// `AllocU` of `allocate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct AllocU {
    count: u32,
    row: u32,
    page: u32,
    atlas_cols: u32,
}

/// The depth a view's linear depths are divided by for the depth test: its far plane.
fn depth_scale(v: &LightView) -> f32 {
    if v.far.is_finite() && v.far > 0.0 {
        v.far
    } else {
        1.0
    }
}

/// The `clip_from_world` that maps `page`'s square of view `v` onto the whole viewport:
/// the view's, scaled by the page's share and shifted, composed in f64.
fn page_clip(v: &LightView, layout: &Layout, entry: u32) -> [f32; 16] {
    let p = layout.page(entry);
    let n = f64::from(layout.texels_across(p.level));
    let size = f64::from(layout.page) / n;
    let u0 = f64::from(p.x) * size;
    let v0 = f64::from(p.y) * size;
    // x' = x / size + w ((1 - 2 u0) / size - 1), y' = y / size + w (1 - (1 - 2 v0) / size).
    let t = DMat4::from_cols_array(&[
        1.0 / size,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0 / size,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        (1.0 - 2.0 * u0) / size - 1.0,
        1.0 - (1.0 - 2.0 * v0) / size,
        0.0,
        1.0,
    ]);
    (t * v.clip_from_world.as_dmat4()).as_mat4().to_cols_array()
}

/// A frame's buffers: the virtual map's uniform, the camera pass's samples and their
/// footprints, the request list and the shadow terms, for `count` pixels.
pub(super) struct FrameBuffers {
    pub(super) vu: wgpu::Buffer,
    pub(super) view: wgpu::Buffer,
    pub(super) footprints: wgpu::Buffer,
    pub(super) requests: wgpu::Buffer,
    pub(super) out: wgpu::Buffer,
    pub(super) count: u32,
}

/// Stage `analysis` over every pixel: returns the requested entries with their benefits
/// (in the order threads appended them) and every slot's last-read frame.
pub(super) fn analysis(
    res: &Resident,
    st: &State,
    fb: &FrameBuffers,
    timer: &mut Timer,
) -> Result<(Vec<Request>, Vec<u32>)> {
    let (vu, view, footprints, requests, count) =
        (&fb.vu, &fb.view, &fb.footprints, &fb.requests, fb.count);
    let gpu = &res.gpu;
    let (gx, gy, _) = grid(gpu, count, WORKGROUP);
    let id = st.id.create_view(&Default::default());
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.analysis.get_bind_group_layout(0),
        entries: &[
            entry(0, vu.as_entire_binding()),
            entry(1, st.faces.as_entire_binding()),
            entry(2, view.as_entire_binding()),
            entry(3, footprints.as_entire_binding()),
            entry(4, st.table.as_entire_binding()),
            entry(5, wgpu::BindingResource::TextureView(&id)),
            entry(6, res.scene.triangles.as_entire_binding()),
            entry(7, st.flags.as_entire_binding()),
            entry(8, requests.as_entire_binding()),
            entry(9, st.slot_used.as_entire_binding()),
        ],
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.clear_buffer(&st.flags, 0, None);
    encoder.clear_buffer(requests, 0, Some(4));
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("analysis"),
            timestamp_writes: timer.pass("analysis"),
        });
        pass.set_pipeline(&res.analysis);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    let words = |raw: Vec<u8>| -> Vec<u32> { bytemuck::pod_collect_to_vec(&raw) };
    let used = words(read_back(
        gpu,
        &st.slot_used,
        4 * u64::from(st.pool.slots()),
    )?);
    let n = words(read_back(gpu, requests, 4)?)[0];
    if n == 0 {
        return Ok((Vec::new(), used));
    }
    let benefits = output(gpu, "the requests' benefits", 4 * u64::from(n))?;
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.tally.get_bind_group_layout(0),
        entries: &[
            entry(0, vu.as_entire_binding()),
            entry(7, st.flags.as_entire_binding()),
            entry(8, requests.as_entire_binding()),
            entry(10, benefits.as_entire_binding()),
        ],
    });
    // The pixels' grid rows, so that `tally` indexes as `main` does.
    let groups = n.div_ceil(WORKGROUP);
    let x = groups.min(gx);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tally"),
            timestamp_writes: timer.pass("analysis"),
        });
        pass.set_pipeline(&res.tally);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
    }
    gpu.queue.submit([encoder.finish()]);
    let listed = words(read_back(gpu, requests, 4 * (u64::from(n) + 1))?);
    let benefit = words(read_back(gpu, &benefits, 4 * u64::from(n))?);
    Ok((listed[1..].iter().copied().zip(benefit).collect(), used))
}

fn entry(binding: u32, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource }
}

/// Stages `allocate` and `render` for `updates`: the page table written, the new pages
/// emptied and drawn into their slots.
pub(super) fn allocate_and_draw(
    res: &Resident,
    st: &State,
    updates: &[Update],
    timer: &mut Timer,
) -> Result<()> {
    if updates.is_empty() {
        return Ok(());
    }
    let gpu = &res.gpu;
    let n = updates.len() as u32;
    let page = st.layout.page;
    let list = storage(gpu, "the page updates", bytemuck::cast_slice(updates))?;
    let (gx, gy, row) = grid(gpu, n, WORKGROUP);
    let au = uniform(
        gpu,
        "allocation",
        &AllocU {
            count: n,
            row,
            page,
            atlas_cols: st.cols,
        },
    );
    let apply = bind(&gpu.device, &res.apply, &[&au, &list, &st.table]);
    let slots: Vec<u32> = updates.iter().map(|u| u.slot).collect();
    let slots = storage(gpu, "the new pages' slots", bytemuck::cast_slice(&slots))?;
    let (cx, cy, crow) = grid(gpu, n * page * page, WORKGROUP);
    let cu = uniform(
        gpu,
        "clear",
        &AllocU {
            count: n,
            row: crow,
            page,
            atlas_cols: st.cols,
        },
    );
    let id = st.id.create_view(&Default::default());
    let clear = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.clear.get_bind_group_layout(0),
        entries: &[
            entry(3, cu.as_entire_binding()),
            entry(4, slots.as_entire_binding()),
            entry(5, wgpu::BindingResource::TextureView(&id)),
        ],
    });
    let s = &res.scene;
    let lists: Vec<(u32, u32)> = updates
        .iter()
        .map(|u| st.culling.of(&st.layout, st.layout.page(u.entry)))
        .collect();
    let pages: Vec<PageU> = updates
        .iter()
        .zip(&lists)
        .map(|(u, &(first, _))| {
            let v = &st.views[st.layout.page(u.entry).face as usize];
            PageU {
                clip_from_world: page_clip(v, &st.layout, u.entry),
                light_from_world: v.light_from_world.to_cols_array(),
                depth_scale: depth_scale(v),
                masks: u32::from(s.masks),
                first,
                pad: 0,
            }
        })
        .collect();
    let pages = storage(gpu, "the new pages", bytemuck::cast_slice(&pages))?;
    let draw = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.render.get_bind_group_layout(0),
        entries: &crate::compute::bind_entries(&[
            &pages,
            &s.triangles,
            &s.material_of,
            &s.materials,
            &s.uvs,
            &s.texels,
            &st.cull,
        ]),
    });
    let scratch = st.scratch.create_view(&Default::default());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("allocate"),
            timestamp_writes: timer.pass("allocate"),
        });
        pass.set_pipeline(&res.apply);
        pass.set_bind_group(0, &apply, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
        pass.set_pipeline(&res.clear);
        pass.set_bind_group(0, &clear, &[]);
        pass.dispatch_workgroups(cx, cy, 1);
    }
    {
        let load = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let target = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: load,
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("render"),
            color_attachments: &[target(&id)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &scratch,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.render_pass("render"),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&res.render);
        pass.set_bind_group(0, &draw, &[]);
        for (i, (u, &(_, count))) in updates.iter().zip(&lists).enumerate() {
            if count == 0 {
                continue;
            }
            let x = (u.slot % st.cols) * page;
            let y = (u.slot / st.cols) * page;
            pass.set_viewport(x as f32, y as f32, page as f32, page as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, page, page);
            pass.draw(0..count * 3, i as u32..i as u32 + 1);
        }
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(())
}

/// Stage `lookup` over every pixel into the frame's shadow terms.
pub(super) fn lookup(
    res: &Resident,
    st: &State,
    fb: &FrameBuffers,
    timer: &mut Timer,
) -> Result<()> {
    let (vu, view, out, count) = (&fb.vu, &fb.view, &fb.out, fb.count);
    let gpu = &res.gpu;
    let (gx, gy, _) = grid(gpu, count, WORKGROUP);
    let id = st.id.create_view(&Default::default());
    let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &res.lookup.get_bind_group_layout(0),
        entries: &[
            entry(0, vu.as_entire_binding()),
            entry(1, st.faces.as_entire_binding()),
            entry(2, view.as_entire_binding()),
            entry(3, st.table.as_entire_binding()),
            entry(4, wgpu::BindingResource::TextureView(&id)),
            entry(5, res.scene.triangles.as_entire_binding()),
            entry(6, out.as_entire_binding()),
        ],
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("lookup"),
            timestamp_writes: timer.pass("lookup"),
        });
        pass.set_pipeline(&res.lookup);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([encoder.finish()]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab::math::{vec3, vec4, Aabb, Vec3};

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<VirtualU>(), 128);
        assert_eq!(std::mem::size_of::<FaceV>(), 144);
        assert_eq!(std::mem::size_of::<PageU>(), 144);
        assert_eq!(std::mem::size_of::<AllocU>(), 16);
        assert_eq!(std::mem::size_of::<Update>(), 16);
    }

    /// A page's clip space puts the page's square of the view on [-1, 1]².
    #[test]
    fn a_page_clip_maps_its_square_onto_the_viewport() {
        let scene = Aabb {
            min: vec3(-1.0, 0.0, -1.0),
            max: vec3(1.0, 1.0, 1.0),
        };
        let v = LightView::perspective(
            vec3(0.0, 4.0, 0.0),
            Vec3::ZERO,
            90.0,
            vec3(0.0, 0.0, 1.0),
            &scene,
        );
        let layout = Layout {
            page: 32,
            levels: 3,
            side: 512,
            faces: 1,
        };
        // Level 1 (256 texels, 8 pages across), page (5, 2).
        let e = layout.level_base(1) + 2 * 8 + 5;
        let m = shadowlab::math::Mat4::from_cols_array(&page_clip(&v, &layout, e));
        // The texel centre (5·32 + 3.5, 2·32 + 30.5) of level 1, in view coordinates.
        let (u, w) = ((5.0 * 32.0 + 3.5) / 256.0, (2.0 * 32.0 + 30.5) / 256.0);
        let s = v.clip_from_world.inverse() * vec4(2.0 * u - 1.0, 1.0 - 2.0 * w, 0.5, 1.0);
        let c = m * s;
        let (x, y) = (c.x / c.w, c.y / c.w);
        // In the page's viewport: column 3.5 of 32, row 30.5 of 32.
        assert!((x - (3.5 / 16.0 - 1.0)).abs() < 1e-4, "{x}");
        assert!((y - (1.0 - 30.5 / 16.0)).abs() < 1e-4, "{y}");
    }
}
