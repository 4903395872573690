//! `gpu:asm`'s frame: the scene and pipelines on the device, the virtual map made or kept,
//! the passes of analysis, allocation and drawing, the look-up and the counters.

use super::culling::Culling;
use super::passes::{self, FaceV, FrameBuffers, VirtualU};
use super::pool::{Pool, NO_ENTRY};
use super::*;
use shadowlab::scene::Scene;

impl GpuAdaptive {
    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&mut Resident> {
        let key = SceneKey::of(frame.scene);
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            self.resident = None;
            self.state = None;
            let gpu = shared()?;
            let scene = stats.stage("upload_scene", || {
                gpu.stage(NAME, "upload_scene", || {
                    SceneBuffers::new(&gpu, frame.scene)
                })
            })??;
            let targets = [Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::R32Uint,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })];
            let r = gpu.stage(NAME, "pipeline", || Resident {
                key,
                gpu: gpu.clone(),
                scene,
                analysis: pipeline(&gpu, &ANALYSIS, "main"),
                tally: pipeline(&gpu, &ANALYSIS, "tally"),
                apply: pipeline(&gpu, &ALLOCATE, "apply"),
                clear: pipeline(&gpu, &ALLOCATE, "clear"),
                render: render_pipeline(&gpu, &RENDER, &targets),
                lookup: pipeline(&gpu, &LOOKUP, "main"),
            })?;
            self.resident = Some(r);
        }
        self.resident
            .as_mut()
            .ok_or_else(|| Error::Internal(format!("{NAME}: the scene was not uploaded")))
    }
}

/// A buffer of `bytes` zeros the stages read and write, refused past the adapter's largest
/// binding.
fn zeroed(gpu: &Gpu, what: &str, bytes: u64, read: bool) -> Result<wgpu::Buffer> {
    gpu.check_binding(what, bytes)?;
    let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    if read {
        usage |= wgpu::BufferUsages::COPY_SRC;
    }
    Ok(gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes.max(4),
        usage,
        mapped_at_creation: false,
    }))
}

fn pool_texture(gpu: &Gpu, what: &str, w: u32, h: u32, f: wgpu::TextureFormat) -> wgpu::Texture {
    let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    if f != wgpu::TextureFormat::Depth32Float {
        usage |= wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING;
    }
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(what),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: f,
        usage,
        view_formats: &[],
    })
}

/// A new, empty virtual map of `shape` on `gpu`: the budget checked against the coarsest
/// level and the adapter's largest texture.
fn new_state(gpu: &Gpu, scene: &Scene, p: &Params, shape: Shape) -> Result<State> {
    let layout = shape.layout;
    let pinned = layout.coarsest().len() as u32;
    if shape.slots < pinned {
        let page = u64::from(layout.page).pow(2) * TEXEL_BYTES;
        return Err(Error::Limit(format!(
            "{NAME}.budget-mb = {} cannot hold the coarsest level: {} light view(s) of {}² texels \
             need {:.2} MiB; raise {NAME}.budget-mb or lower {NAME}.root-resolution",
            p.budget_mb,
            layout.faces,
            layout.texels_across(layout.levels - 1),
            (u64::from(pinned) * page) as f64 / (1024.0 * 1024.0)
        )));
    }
    let max = gpu.limits.max_texture_dimension_2d;
    let cols = shape.slots.min(max / layout.page).max(1);
    let rows = shape.slots.div_ceil(cols);
    if rows * layout.page > max {
        return Err(Error::Limit(format!(
            "{NAME}.budget-mb = {} needs a pool of {} pages of {}² texels, more than the \
             adapter's largest texture ({max}² texels) holds; lower {NAME}.budget-mb",
            p.budget_mb, shape.slots, layout.page
        )));
    }
    let (w, h) = (cols * layout.page, rows * layout.page);
    let entries = u64::from(layout.entries());
    let faces: Vec<FaceV> = shape.views.iter().map(FaceV::of).collect();
    let culling = Culling::new(scene, &shape.views, &layout);
    let cull = storage(
        gpu,
        "the culling lists",
        bytemuck::cast_slice(&culling.triangles),
    )?;
    Ok(State {
        culling,
        cull,
        layout,
        views: shape.views.clone(),
        pool: Pool::new(shape.slots, pinned),
        cols,
        faces: storage(gpu, "the light views", bytemuck::cast_slice(&faces))?,
        table: zeroed(gpu, "the page table", 4 * entries, false)?,
        flags: zeroed(gpu, "the page requests' flags", 4 * entries, false)?,
        slot_used: zeroed(gpu, "the slots' stamps", 4 * u64::from(shape.slots), true)?,
        id: pool_texture(gpu, "pool ids", w, h, wgpu::TextureFormat::R32Uint),
        scratch: pool_texture(
            gpu,
            "page depth test",
            w,
            h,
            wgpu::TextureFormat::Depth32Float,
        ),
        table_bytes: 4 * 2 * entries,
        shape,
    })
}

/// The camera pass's derivatives, six floats a pixel.
fn footprints(frame: &Frame) -> Vec<f32> {
    let v = frame.view;
    let mut out = Vec::with_capacity(v.dpdx.len() * 6);
    for (dx, dy) in v.dpdx.iter().zip(&v.dpdy) {
        out.extend_from_slice(&dx.to_array());
        out.extend_from_slice(&dy.to_array());
    }
    out
}

/// What a frame did, for its counters.
#[derive(Default)]
struct Tally {
    requested: usize,
    drawn: usize,
    evicted: usize,
    passes: u32,
}

impl ShadowTechnique for GpuAdaptive {
    fn name(&self) -> &'static str {
        NAME
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        self.cpu.params()
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        self.cpu.param_specs()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        crate::twin::set_twin_param(NAME, &mut self.cpu, key, value)
    }

    /// Converged once a frame allocated and evicted no page: the next would repeat it.
    fn converged(&self) -> Option<bool> {
        Some(self.state.is_some() && self.quiet)
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let p = Params::of(&self.cpu)?;
        let views = light_views(
            frame.light,
            &frame.scene.bounds,
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        let layout = p.layout(views.len() as u32)?;
        let page_bytes = u64::from(layout.page).pow(2) * TEXEL_BYTES;
        let slots =
            ((p.budget_mb * 1024.0 * 1024.0) as u64 / page_bytes).min(u64::from(u32::MAX >> 1));
        let shape = Shape {
            light: *frame.light,
            views,
            layout,
            slots: slots as u32,
        };
        let mut stats = Stats::default();
        self.resident(frame, &mut stats)?;
        self.now += 1;
        let now = self.now;
        let res = self.resident.as_ref().expect("made above");
        let gpu = res.gpu.clone();
        if self.state.as_ref().is_none_or(|s| s.shape != shape) {
            self.state = None;
            self.state =
                Some(stats.stage("allocate_pool", || new_state(&gpu, frame.scene, &p, shape))?);
        }
        let st = self.state.as_mut().expect("made above");
        let n = frame.view.triangle.len() as u32;
        let view = stats.stage("upload_view", || view_buffer(&gpu, frame.view))?;
        let fp = storage(
            &gpu,
            "the pixels' footprints",
            bytemuck::cast_slice(&footprints(frame)),
        )?;
        let out = output(&gpu, "the shadow terms", u64::from(n) * 12)?;
        // A pixel requests one page a pass at most.
        let requests = zeroed(&gpu, "the page requests", 4 * (u64::from(n) + 1), true)?;
        let (_, _, row) = crate::transfer::grid(&gpu, n, WORKGROUP);
        let vu = crate::transfer::uniform(
            &gpu,
            "the virtual map",
            &VirtualU {
                light: LightU::of(frame.light),
                count: n,
                row,
                page: layout.page,
                levels: layout.levels,
                side: layout.side,
                faces: layout.faces,
                atlas_cols: st.cols,
                now,
                oversampling: p.oversampling,
                bias: p.bias,
                slope_bias: p.slope_bias,
                pad: 0,
                bases: std::array::from_fn(|l| layout.level_base(l as u32)),
            },
        );
        let fb = FrameBuffers {
            vu,
            view,
            footprints: fp,
            requests,
            out,
            count: n,
        };
        let mut timer = Timer::new(&gpu, 3 * (p.passes + 1) + 2);
        let mut tally = Tally::default();
        if st.pool.resident() == 0 {
            // The coarsest level of every view, drawn once.
            let pins = st.pool.pin(layout.coarsest(), now);
            tally.drawn += pins.len();
            stats.stage("render", || {
                gpu.stage(NAME, "render", || {
                    passes::allocate_and_draw(res, st, &pins, &mut timer)
                })
            })??;
        }
        let mut budget = p.max_new as usize;
        for _ in 0..p.passes {
            tally.passes += 1;
            let (requests, used) = stats.stage("analysis", || {
                gpu.stage(NAME, "analysis", || {
                    passes::analysis(res, st, &fb, &mut timer)
                })
            })??;
            st.pool.stamp(&used);
            tally.requested += requests.len();
            let updates = st.pool.assign(&requests, now, budget);
            if updates.is_empty() {
                break;
            }
            budget -= updates.len();
            tally.drawn += updates.len();
            tally.evicted += updates.iter().filter(|u| u.evicted != NO_ENTRY).count();
            stats.stage("render", || {
                gpu.stage(NAME, "render", || {
                    passes::allocate_and_draw(res, st, &updates, &mut timer)
                })
            })??;
        }
        stats.stage("lookup", || {
            gpu.stage(NAME, "lookup", || passes::lookup(res, st, &fb, &mut timer))
        })??;
        let raw = stats.stage("readback", || {
            gpu.stage(NAME, "readback", || {
                read_back(&gpu, &fb.out, u64::from(n) * 12)
            })
        })??;
        for (stage, ms) in timer.read(&gpu)? {
            stats.count(&format!("gpu_{stage}_ms"), ms);
        }
        self.quiet = tally.drawn == 0 && tally.evicted == 0;
        let slots = u64::from(st.pool.slots());
        stats.memory_bytes = slots * page_bytes;
        stats.count("pages_requested", tally.requested as f64);
        stats.count("pages_drawn", tally.drawn as f64);
        stats.count("pages_evicted", tally.evicted as f64);
        stats.count("pages_resident", st.pool.resident() as f64);
        stats.count("pool_pages", slots as f64);
        stats.count("analysis_passes", f64::from(tally.passes));
        stats.count("page_table_bytes", st.table_bytes as f64);
        stats.count("culling_bytes", st.culling.bytes() as f64);
        stats.count("scratch_bytes", (slots * page_bytes) as f64);
        stats.count("virtual_resolution", f64::from(layout.side));
        stats.count("levels", f64::from(layout.levels));
        stats.count("hardware_raster", 1.0);
        stats.device = Some(gpu.adapter.label());
        if frame.dumping() {
            super::dump::write_dump(&layout, &st.pool, frame)?;
        }
        Ok(Shadows::of_frame(frame, to_rgb(&raw), stats))
    }
}
