//! One frame of `gpu:subpixel`: the buffers, the stages' dispatches in the paper's order,
//! and the two counts read back between them (facets, then triangle–texel pairs), which
//! size the later dispatches and the pair list.

use super::kit::{FrameU, Pipelines, ViewS, BINDINGS, FACET_BYTES};
use super::{Resident, NAME};
use crate::compute::to_rgb;
use crate::device::Gpu;
use crate::techniques::maps::{self, depth_scale};
use crate::transfer::{output, read_back, storage, uniform, Timer};
use crate::upload::{view_buffer, LightU};
use shadowlab::camera::Projection;
use shadowlab::error::{Error, Result};
use shadowlab::light::{light_views, Light, LightView};
use shadowlab::math::Vec3;
use shadowlab::scene::Scene;
use shadowlab::techniques::shadow_map::DIRECTIONAL_PAD;
use shadowlab::techniques::subpixel::{edge_adjacency, LookupTable, Subpixel};
use shadowlab::techniques::{Frame, Stats};

const WORKGROUP: u32 = 64;

/// The scene's edges as `silhouette_edges.wgsl` reads them (ends; faces), and their
/// number.
pub fn upload_edges(gpu: &Gpu, scene: &Scene) -> Result<([wgpu::Buffer; 2], u32)> {
    let adj = edge_adjacency(scene);
    let mut ends: Vec<f32> = Vec::with_capacity(adj.a.len() * 6);
    let mut faces: Vec<f32> = Vec::with_capacity(adj.a.len() * 7);
    for e in 0..adj.a.len() {
        ends.extend_from_slice(&adj.a[e].to_array());
        ends.extend_from_slice(&adj.b[e].to_array());
        let (two, f) = match adj.faces[e] {
            Some(f) => (1.0, f),
            None => (0.0, [Vec3::ZERO; 2]),
        };
        faces.push(two);
        faces.extend_from_slice(&f[0].to_array());
        faces.extend_from_slice(&f[1].to_array());
    }
    Ok((
        [
            storage(gpu, "the scene's edges", bytemuck::cast_slice(&ends))?,
            storage(gpu, "the scene's edge faces", bytemuck::cast_slice(&faces))?,
        ],
        adj.a.len() as u32,
    ))
}

/// The camera's rays as `RayPlane` forms them: (o0, ox, oy, d0, dx, dy, parallel).
fn ray_plane(frame: &Frame) -> ([Vec3; 6], bool) {
    let c = frame.camera;
    let (r, u, f) = c.basis();
    let (w, h) = (c.width as f32, c.height as f32);
    match c.projection {
        Projection::Perspective => {
            let th = (c.fov_y_deg.to_radians() * 0.5).tan();
            let asp = c.aspect();
            (
                [
                    c.eye,
                    Vec3::ZERO,
                    Vec3::ZERO,
                    f - r * (th * asp) + u * th,
                    r * (2.0 * th * asp / w),
                    -u * (2.0 * th / h),
                ],
                false,
            )
        }
        Projection::Orthographic { xmag, ymag } => (
            [
                c.eye - r * xmag + u * ymag,
                r * (2.0 * xmag / w),
                -u * (2.0 * ymag / h),
                f,
                Vec3::ZERO,
                Vec3::ZERO,
            ],
            true,
        ),
    }
}

/// Dispatch size for `count` threads with the frame's fixed row of threads.
fn groups(count: u32, row: u32) -> (u32, u32) {
    let g = count.div_ceil(WORKGROUP).max(1);
    let x = row / WORKGROUP;
    (g.min(x), g.div_ceil(x))
}

/// The frame's uniform.
fn frame_uniform(
    frame: &Frame,
    cpu: &Subpixel,
    res: u32,
    views: u32,
    lut: &LookupTable,
    edges: u32,
    row: u32,
) -> FrameU {
    let ([o0, ox, oy, d0, dx, dy], parallel) = ray_plane(frame);
    let (toward, is_dir) = match *frame.light {
        Light::Directional { to_light } => (to_light.normalize(), 1),
        Light::Spot { position, .. } | Light::Point { position } => (position, 0),
    };
    FrameU {
        light: LightU::of(frame.light),
        o0: o0.to_array(),
        parallel: u32::from(parallel),
        ox: ox.to_array(),
        width: frame.view.width,
        oy: oy.to_array(),
        height: frame.view.height,
        d0: d0.to_array(),
        res,
        dx: dx.to_array(),
        views,
        dy: dy.to_array(),
        samples: lut.samples.len() as u32,
        screen: frame.camera.clip_from_world().to_cols_array(),
        centre: lut.centre as u32,
        bias: cpu.bias,
        slope_bias: cpu.slope_bias,
        masks: u32::from(frame.scene.has_alpha_masks()),
        edges,
        triangles: frame.scene.len() as u32,
        pixels: frame.view.triangle.len() as u32,
        row,
        toward: toward.to_array(),
        toward_is_dir: is_dir,
    }
}

fn view_table(gpu: &Gpu, views: &[LightView]) -> Result<wgpu::Buffer> {
    let t: Vec<ViewS> = views
        .iter()
        .map(|v| ViewS {
            clip_from_world: v.clip_from_world.to_cols_array(),
            light_from_world: v.light_from_world.to_cols_array(),
            clip_from_light: v.clip_from_light.to_cols_array(),
            ortho: u32::from(v.orthographic),
            near: v.near,
            extent: v.extent,
            depth_scale: depth_scale(v),
        })
        .collect();
    storage(gpu, "the light views", bytemuck::cast_slice(&t))
}

/// Records one dispatch of `stage:entry` over `count` threads.
fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    p: &Pipelines,
    group: &wgpu::BindGroup,
    (stage, entry, count): (&str, &str, u32),
    row: u32,
    timer: &mut Timer,
) {
    let name = stage.trim_end_matches(".wgsl");
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(name),
        timestamp_writes: timer.pass(name),
    });
    pass.set_pipeline(p.at(stage, entry));
    pass.set_bind_group(0, group, &[]);
    let (gx, gy) = if entry == "scan" {
        (1, 1)
    } else {
        groups(count, row)
    };
    pass.dispatch_workgroups(gx, gy, 1);
}

/// The counters' words: facets, slots, pairs, the pairs pass's mode, blocks of large
/// triangles, blocks listed, evaluation items, items listed.
const COUNTERS: usize = 8;

/// Records `steps` (stage, entry, threads) over `group` in one command buffer and submits
/// it.
fn submit(
    gpu: &Gpu,
    pipes: &Pipelines,
    group: &wgpu::BindGroup,
    steps: &[(&str, &str, u32)],
    row: u32,
    timer: &mut Timer,
) {
    let mut e = gpu.device.create_command_encoder(&Default::default());
    for step in steps {
        dispatch(&mut e, pipes, group, *step, row, timer);
    }
    gpu.queue.submit([e.finish()]);
}

/// Reads back the counters.
fn counters(gpu: &Gpu, b: &wgpu::Buffer) -> Result<[u32; COUNTERS]> {
    let raw = read_back(gpu, b, 4 * COUNTERS as u64)?;
    let mut c = [0u32; COUNTERS];
    for (i, w) in raw.chunks_exact(4).enumerate() {
        c[i] = u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
    }
    Ok(c)
}

/// The frame's buffers, by binding: the uniform, views and samples (0–2); the look-up
/// table, the pattern and the per-texel, per-pixel and counter buffers (10–21); the
/// camera depths (23); the edges (9, 24) are the scene's.
struct Buffers {
    fixed: [wgpu::Buffer; 3],
    rest: [wgpu::Buffer; 12],
    cam_depth: wgpu::Buffer,
    /// Per facet, its occlusion and validity masks (binding 27).
    masks: wgpu::Buffer,
}

fn frame_buffers(
    gpu: &Gpu,
    frame: &Frame,
    views: &[LightView],
    lut: &LookupTable,
    fu: &FrameU,
    texels: u64,
    stats: &mut Stats,
) -> Result<Buffers> {
    let (n, nv) = (frame.view.triangle.len() as u64, views.len() as u64);
    let sat_side = u64::from(fu.res) + 1;
    let lut_words: Vec<u32> = lut
        .masks
        .iter()
        .zip(&lut.uncertain)
        .flat_map(|(m, u)| [*m, *u])
        .flat_map(|m| (0..4).map(move |w| (m >> (32 * w)) as u32))
        .collect();
    let samples: Vec<f32> = lut.samples.iter().flat_map(|s| [s.x, s.y]).collect();
    let depth: Vec<f32> = frame.view.depth.clone();
    let buf = |what: &str, bytes: u64| output(gpu, what, bytes);
    let fixed = [
        uniform(gpu, "gpu:subpixel frame", fu),
        view_table(gpu, views)?,
        stats.stage("upload_view", || view_buffer(gpu, frame.view))?,
    ];
    let rest = [
        storage(gpu, "the look-up table", bytemuck::cast_slice(&lut_words))?,
        storage(gpu, "the sample pattern", bytemuck::cast_slice(&samples))?,
        buf("the silhouette edges' depths", texels * 4)?,
        buf("the silhouette mask map", texels * 4)?,
        buf("the summed-area table", sat_side * sat_side * nv * 4)?,
        buf("the shadow terms", n * 12)?,
        buf("the facets", n * FACET_BYTES)?,
        buf("the counters", 4 * COUNTERS as u64)?,
        buf("the facets' texel depths", texels * 4)?,
        buf("the texel slots", texels * 4)?,
        buf("the slots' triangle counts", texels * 4)?,
        buf("the slots' starts", (texels + 1) * 4)?,
    ];
    let cam_depth = storage(gpu, "the camera depths", bytemuck::cast_slice(&depth))?;
    Ok(Buffers {
        fixed,
        rest,
        cam_depth,
        masks: buf("the facets' masks", n * 32)?,
    })
}

/// The frame's bind group, with `pairs` at binding 22, the large triangles' blocks `big`
/// at 25 and the evaluation's `items` at 26.
fn bind_group(
    gpu: &Gpu,
    pipes: &Pipelines,
    r: &Resident,
    map_view: &wgpu::TextureView,
    b: &Buffers,
    [pairs, big, items]: [&wgpu::Buffer; 3],
) -> wgpu::BindGroup {
    let s = &r.ms.scene;
    let mut list: Vec<wgpu::BindingResource> = vec![
        b.fixed[0].as_entire_binding(),
        b.fixed[1].as_entire_binding(),
        b.fixed[2].as_entire_binding(),
        wgpu::BindingResource::TextureView(map_view),
        s.triangles.as_entire_binding(),
        s.material_of.as_entire_binding(),
        s.materials.as_entire_binding(),
        s.uvs.as_entire_binding(),
        s.texels.as_entire_binding(),
        r.edges[0].as_entire_binding(),
    ];
    list.extend(b.rest.iter().map(|b| b.as_entire_binding()));
    list.push(pairs.as_entire_binding());
    list.push(b.cam_depth.as_entire_binding());
    list.push(r.edges[1].as_entire_binding());
    list.push(big.as_entire_binding());
    list.push(items.as_entire_binding());
    list.push(b.masks.as_entire_binding());
    debug_assert_eq!(list.len(), BINDINGS as usize);
    let entries: Vec<wgpu::BindGroupEntry> = list
        .into_iter()
        .enumerate()
        .map(|(i, resource)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource,
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gpu:subpixel"),
        layout: &pipes.layout(),
        entries: &entries,
    })
}

/// The frame's shadow terms.
pub fn run(
    r: &Resident,
    frame: &Frame,
    cpu: &Subpixel,
    res: u32,
    lut: &LookupTable,
    stats: &mut Stats,
) -> Result<Vec<Vec3>> {
    let gpu = r.ms.gpu.clone();
    gpu.check_texture_side(&format!("{NAME}.resolution"), res)?;
    let views = light_views(
        frame.light,
        &frame.view.receiver_bounds(),
        &frame.scene.bounds,
        DIRECTIONAL_PAD,
    );
    let nv = views.len() as u32;
    if nv > gpu.limits.max_texture_array_layers {
        return Err(Error::Limit(format!(
            "{NAME}: {nv} light views need more array layers than the adapter's {}",
            gpu.limits.max_texture_array_layers
        )));
    }
    let pipes = gpu.stage(NAME, "pipeline", || Pipelines::get(&gpu))?;
    let row = gpu
        .limits
        .max_compute_workgroups_per_dimension
        .clamp(1, 65535)
        * WORKGROUP;
    let n = frame.view.triangle.len() as u32;
    let texels = u64::from(res) * u64::from(res) * u64::from(nv);
    let mut timer = Timer::new(&gpu, 32);
    let map = maps::depth_array(&gpu, NAME, &format!("{NAME}.resolution"), res, nv)?;
    stats.stage("shadow_map", || {
        gpu.stage(NAME, "shadow_map", || {
            maps::draw_views(&r.ms, &map, &views, frame, &mut timer)
        })
    })?;
    let fu = frame_uniform(frame, cpu, res, nv, lut, r.edge_count, row);
    let map_view = maps::array_view(&map);
    let bufs = frame_buffers(&gpu, frame, &views, lut, &fu, texels, stats)?;
    let rest = &bufs.rest;
    let buf = |what: &str, bytes: u64| output(&gpu, what, bytes);
    let group = |pairs: &wgpu::Buffer, big: &wgpu::Buffer, items: &wgpu::Buffer| {
        bind_group(&gpu, &pipes, r, &map_view, &bufs, [pairs, big, items])
    };
    let none = buf("no triangle-texel pairs yet", 4)?;
    let no_blocks = buf("no blocks yet", 8)?;
    let no_items = buf("no evaluation items yet", 16)?;
    let first = group(&none, &no_blocks, &no_items);
    let counter_buf = &rest[7];
    let t = texels as u32;
    let edges = r.edge_count;
    // Silhouette edges, mask map, facets.
    let found = stats.stage("silhouette_mask_map", || {
        gpu.stage(NAME, "silhouette_mask_map", || {
            let steps = [
                ("silhouette_edges.wgsl", "main", edges),
                ("silhouette_mask_map.wgsl", "hidden", t),
                ("silhouette_mask_map.wgsl", "sat_rows", res * nv),
                ("silhouette_mask_map.wgsl", "sat_columns", res * nv),
                ("facets.wgsl", "main", n),
            ];
            submit(&gpu, &pipes, &first, &steps, row, &mut timer);
            counters(&gpu, counter_buf)
        })
    })??;
    let facets = found[0];
    let tris = frame.scene.len() as u32 * nv;
    // Pixel–texel pairs, slots, and the triangle–texel pairs counted: those of the
    // triangles within one block of rows first, the blocks of the others once listed.
    let (paired, blocks) = stats.stage("pt_tt_pairs", || {
        gpu.stage(NAME, "pt_tt_pairs", || -> Result<_> {
            let steps = [
                ("pairs.wgsl", "pixel_texels", n),
                ("pairs.wgsl", "slots", t),
                ("pairs.wgsl", "triangle_texels_main", tris),
            ];
            submit(&gpu, &pipes, &first, &steps, row, &mut timer);
            let nb = counters(&gpu, counter_buf)?[4];
            let blocks = buf("the large triangles' blocks", u64::from(nb).max(1) * 8)?;
            let listing = group(&none, &blocks, &no_items);
            let steps = [
                ("pairs.wgsl", "list_mode", 1),
                ("pairs.wgsl", "triangle_texels_main", tris),
                ("pairs.wgsl", "big_blocks", nb),
                ("pairs.wgsl", "scan_blocks", t.div_ceil(256)),
                ("pairs.wgsl", "scan", 1),
                ("pairs.wgsl", "scan_slots", t.div_ceil(256)),
            ];
            submit(&gpu, &pipes, &listing, &steps, row, &mut timer);
            Ok((counters(&gpu, counter_buf)?, (blocks, nb)))
        })
    })??;
    let pairs = buf("the triangle-texel pairs", u64::from(paired[2]).max(1) * 4)?;
    let second = group(&pairs, &blocks.0, &no_items);
    // The pairs filled, the evaluation's items counted, listed and evaluated,
    // and each facet's term.
    let items = stats.stage("shadow_calculation", || {
        gpu.stage(NAME, "shadow_calculation", || -> Result<_> {
            let steps = [
                ("pairs.wgsl", "triangle_texels_main", tris),
                ("pairs.wgsl", "big_blocks", blocks.1),
                ("visibility_evaluation.wgsl", "count_items", n),
            ];
            submit(&gpu, &pipes, &second, &steps, row, &mut timer);
            let ni = counters(&gpu, counter_buf)?[6];
            let items = buf("the evaluation's items", u64::from(ni).max(1) * 16)?;
            let third = group(&pairs, &blocks.0, &items);
            let steps = [
                ("visibility_evaluation.wgsl", "list_items", n),
                ("visibility_evaluation.wgsl", "main", ni),
                ("visibility_evaluation.wgsl", "finish", n),
            ];
            submit(&gpu, &pipes, &third, &steps, row, &mut timer);
            Ok(ni)
        })
    })??;
    let raw = stats.stage("readback", || {
        gpu.stage(NAME, "readback", || {
            read_back(&gpu, &rest[5], u64::from(n) * 12)
        })
    })??;
    for (stage, ms) in timer.read(&gpu)? {
        stats.count(&format!("gpu_{stage}_ms"), ms);
    }
    let sizes = [facets, paired[2], blocks.1, items];
    count_stats(stats, lut, res, nv, n, sizes);
    stats.device = Some(gpu.adapter.label());
    Ok(to_rgb(&raw))
}

/// The frame's counters and memory: `sizes` are the facets built, the triangle–texel
/// pairs, the large triangles' blocks and the evaluation's items.
fn count_stats(stats: &mut Stats, lut: &LookupTable, res: u32, nv: u32, n: u32, sizes: [u32; 4]) {
    let [facets, pairs, blocks, items] = sizes;
    stats.count("samples", lut.samples.len() as f64);
    stats.count("silhouette_pixels", f64::from(facets));
    stats.count("tt_pairs", f64::from(pairs));
    stats.count("large_triangle_blocks", f64::from(blocks));
    stats.count("evaluation_items", f64::from(items));
    stats.count("hardware_raster", 1.0);
    let texels = u64::from(res) * u64::from(res) * u64::from(nv);
    stats.memory_bytes = texels * 4 * 7
        + (u64::from(res) + 1).pow(2) * u64::from(nv) * 4
        + u64::from(n) * FACET_BYTES
        + u64::from(pairs) * 4
        + u64::from(n) * 32
        + u64::from(blocks) * 8
        + u64::from(items) * 16;
}
