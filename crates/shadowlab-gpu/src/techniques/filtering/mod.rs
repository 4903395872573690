//! The filtered shadow maps on the GPU, shared by `gpu:vsm`, `gpu:evsm`, `gpu:msm` and
//! `gpu:csm` (and their `-soft` variants), as the library's `filtering` module is shared by
//! their CPU twins: the pre-filtering chain of the convolution shadow map paper (Annen et
//! al. 2007, Section 4.1), which the moment maps reuse. Each technique gives its encoder
//! and its test as WGSL (in `techniques/{variance, moments, convolution}/`) and a
//! [`Codec`]: channels, storage format, parameters; everything else is here.
//!
//! Stages, in the order a frame runs them:
//! - `depth` (`depth.wgsl`, `maps.rs`): the hardware rasterizer draws each light view's map
//!   (the library's `light_views`; six cube faces as layers for a point light), keeping
//!   each texel's linear depth and triangle.
//! - `fit` (`fit.wgsl`, `fit.rs`): each map's min-depth pyramid (`pyramid.wgsl`), and the
//!   depth range each map is normalized over, fitted to the receivers that may be shadowed
//!   as the library's `ReceiverDepths` and `DepthRange::fitted` fit it (minima, maxima and
//!   counts through integer atomics, so independent of the threads' order).
//! - `blocker_search` (`blocker_search.wgsl`, the soft variants under an area light): each
//!   pixel's penumbra footprint, as the library's `SoftSearch` finds it over the pyramid.
//! - `encode` (`encode.wgsl` + the technique's encoder): a compute pass per view and group
//!   of four channels writes the stored values, rounded to the storage format.
//! - `blur` (`blur.wgsl`): the separable binomial blur as two compute passes, each written
//!   back in the storage format.
//! - `mipmap` (`mip.wgsl`): the full mip chain by compute passes (2×2 averages, box taps for
//!   odd sides), each level rounded to the format, then packed into the bytes of the
//!   sampled texture's format and copied into its mip levels.
//! - `lookup` (`lookup.wgsl` + the technique's test): per pixel the footprint from the
//!   camera pass's screen-space derivatives (widened to the penumbra for the soft
//!   variants), the level of detail and the anisotropic probes along its major axis placed
//!   as the library places them (`EXT_texture_filter_anisotropic`'s rule), each probe a
//!   hardware tri-linear sample of the mip chain.
//!
//! Departures from the CPU twins: the maps are drawn by the hardware rasterizer (its
//! rounding differs from the library's on edge texels, as for `gpu:sm`); the texture unit
//! filters within and between levels (bilinear weights at the adapter's sub-texel
//! precision, often 8 bits; 8-bit and 16-bit texels filtered at its internal precision);
//! storage is in the GPU formats the library emulates (`Rgba8Unorm`, `Rgba16Float`,
//! `Rgba16Unorm`, 32-bit floats), rounded by the shaders exactly as the library rounds
//! them, save half floats (`quantizeToF16`, the adapter's rounding); on an adapter without
//! 16-bit normalized textures the 16-bit codes are kept in 32-bit floats (the same values,
//! filtered at higher precision); 32-bit float maps need an adapter that filters them
//! (`FLOAT32_FILTERABLE`), else the render is refused in one sentence. The anisotropic
//! probes are placed by the shader rather than left to the texture unit's anisotropic
//! mode, whose footprints are vendor-specific approximations (on Mesa's lavapipe 22 that
//! mode gave look-ups as blurry as tri-linear ones, doubling `gpu:vsm`'s error on the
//! bunny): so a map looks the same on every adapter, and as the library's, at the cost of up to
//! `max-aniso` samples a look-up, as the texture unit would take. The fit and the blocker
//! search compute in f32 where the library sums blocker depths in f64 and multiplies by
//! reciprocals; nothing is read back before the look-up. The work buffers (every mip
//! level of one view's group as `vec4<f32>`s, every view's min pyramid) are single storage
//! bindings, so a map side whose buffers pass the adapter's largest binding is refused in
//! one sentence (lavapipe's 128 MiB holds a point light's six 2048² faces, not 4096²).

mod fit;
pub use fit::VIEWS;
mod lookup;
mod maps;
mod prefilter;

use crate::device::{shared, Gpu};
use crate::shader::{Common, Stage};
use crate::transfer::{storage, Timer};
use crate::upload::{view_buffer, SceneBuffers, SceneKey};
use shadowlab::error::{Error, Result};
use shadowlab::light::light_views;
use shadowlab::techniques::filtering::{check_map_size, FilterSettings};
use shadowlab::techniques::shadow_map::DIRECTIONAL_PAD;
use shadowlab::techniques::{Frame, ParamSpec, ShadowTechnique, Shadows, Stats};
use std::collections::BTreeMap;
use std::sync::Arc;

/// `filtering/filtered.wgsl`: the technique's parameters and the storage formats.
pub const FILTERED: Common = Common {
    name: "filtering/filtered.wgsl",
    source: include_str!("filtered.wgsl"),
};
/// The text of stage `encode`, composed after [`FILTERED`] and a technique's encoder.
pub const ENCODE_SOURCE: &str = include_str!("encode.wgsl");
/// The text of stage `lookup`, composed after the light's files, [`FILTERED`] and a
/// technique's encoder and test.
pub const LOOKUP_SOURCE: &str = include_str!("lookup.wgsl");

/// The view samples' screen-space derivatives, six floats a pixel.
fn derivatives(frame: &Frame) -> Vec<f32> {
    let v = frame.view;
    v.dpdx
        .iter()
        .zip(&v.dpdy)
        .flat_map(|(a, b)| [a.x, a.y, a.z, b.x, b.y, b.z])
        .collect()
}

/// Numbers a technique's parameter block holds (`TechU` of `filtered.wgsl`).
pub const TECH_PARAMS: usize = 40;

/// The format a filtered map's values are stored in, as the library's `Channel`s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Store {
    /// 32-bit float.
    F32,
    /// Half float.
    F16,
    /// 16-bit unsigned normalized (held as codes 0..=65535).
    Unorm16,
    /// 8-bit unsigned normalized (held as codes 0..=255).
    U8,
}

impl Store {
    /// The code `filtered.wgsl` names it by.
    pub fn code(self) -> u32 {
        match self {
            Store::F32 => 0,
            Store::F16 => 1,
            Store::Unorm16 => 2,
            Store::U8 => 3,
        }
    }

    /// Bytes the library counts a stored value as.
    pub fn bytes(self) -> usize {
        match self {
            Store::F32 => 4,
            Store::F16 | Store::Unorm16 => 2,
            Store::U8 => 1,
        }
    }
}

/// What a filtered technique gives the shared chain.
#[derive(Clone, Debug)]
pub struct Codec {
    /// The CPU twin's name (for errors and the library's limits).
    pub technique: &'static str,
    /// Map side in texels (checked).
    pub resolution: u32,
    /// Values per texel.
    pub channels: u32,
    /// Their storage.
    pub store: Store,
    /// The normalized depth of the farthest texel (the library's `MapLayout::span`).
    pub span: f32,
    /// The technique's parameters, as its WGSL reads them.
    pub tech: [f32; TECH_PARAMS],
    /// Stage `encode` with the technique's encoder.
    pub encode: Stage,
    /// Stage `lookup` with the technique's test.
    pub lookup: Stage,
    /// Blur, filter, anisotropy, soft.
    pub settings: FilterSettings,
}

impl Codec {
    /// Texture layers (groups of four channels) a light view takes.
    pub fn groups(&self) -> u32 {
        self.channels.div_ceil(4)
    }
}

/// The CPU twin of a filtered GPU technique: it keeps the parameters, and says what they
/// make of the shared chain (each technique's folder implements it for its twin).
pub trait FilteredTwin: ShadowTechnique {
    /// The codec of the parameters set now (their checks are the twin's).
    fn codec(&self) -> Result<Codec>;
}

/// The scene on one device, with the depth stage's pipeline.
struct Resident {
    key: SceneKey,
    gpu: Arc<Gpu>,
    scene: SceneBuffers,
    depth: wgpu::RenderPipeline,
}

/// A pre-filtered shadow map on the GPU with its CPU twin's parameters.
pub struct GpuFiltered {
    name: &'static str,
    twin: Box<dyn FilteredTwin>,
    resident: Option<Resident>,
}

impl GpuFiltered {
    /// The technique `name` over `twin`'s parameters; `soft` sets the twin's `soft` (the
    /// `-soft` variants).
    pub fn new(name: &'static str, mut twin: Box<dyn FilteredTwin>, soft: bool) -> Self {
        if soft {
            // `soft` is a flag of every filtered twin; setting it cannot fail.
            let _ = twin.set_param("soft", "true");
        }
        GpuFiltered {
            name,
            twin,
            resident: None,
        }
    }

    fn resident(&mut self, frame: &Frame, stats: &mut Stats) -> Result<&mut Resident> {
        let key = SceneKey::of(frame.scene);
        if self.resident.as_ref().is_none_or(|r| r.key != key) {
            self.resident = None;
            let gpu = shared()?;
            let name = self.name;
            let scene = stats.stage("upload_scene", || {
                gpu.stage(name, "upload_scene", || {
                    SceneBuffers::new(&gpu, frame.scene)
                })
            })??;
            let depth = gpu.stage(name, "pipeline", || maps::depth_pipeline(&gpu))?;
            self.resident = Some(Resident {
                key,
                gpu,
                scene,
                depth,
            });
        }
        self.resident
            .as_mut()
            .ok_or_else(|| Error::Internal(format!("{}: the scene was not uploaded", self.name)))
    }
}

impl ShadowTechnique for GpuFiltered {
    fn name(&self) -> &'static str {
        self.name
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        self.twin.params()
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        self.twin.param_specs()
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        crate::twin::set_twin_param(self.name, &mut *self.twin, key, value)
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let name = self.name;
        let codec = self.twin.codec()?;
        let views = light_views(
            frame.light,
            &frame.view.receiver_bounds(),
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        let side = codec.resolution;
        check_map_size(
            name,
            views.len(),
            side,
            codec.channels as usize,
            codec.store.bytes(),
        )?;
        let mut stats = Stats::default();
        let res = self.resident(frame, &mut stats)?;
        let gpu = res.gpu.clone();
        gpu.check_texture_side(&format!("{name}.resolution"), side)?;
        let layers = views.len() as u32 * codec.groups();
        if layers > gpu.limits.max_texture_array_layers {
            return Err(Error::Limit(format!(
                "{name}: {layers} map layers are more than the adapter's {}",
                gpu.limits.max_texture_array_layers
            )));
        }
        let format = maps::Format::of(&gpu, name, &codec)?;
        let view = stats.stage("upload_view", || view_buffer(&gpu, frame.view))?;
        let mut timer = Timer::new(&gpu, 4 * layers + views.len() as u32 + 2);
        let depth = stats.stage("shadow_map", || {
            gpu.stage(name, "shadow_map", || {
                maps::draw(
                    &gpu, &res.depth, &res.scene, frame, &views, side, &mut timer,
                )
            })
        })?;
        let table = fit::view_table(&gpu, &views)?;
        let derivs = storage(
            &gpu,
            "the camera pass's derivatives",
            bytemuck::cast_slice(&derivatives(frame)),
        )?;
        let fitted = stats.stage("fit", || {
            gpu.stage(name, "fit", || {
                fit::run(
                    &gpu, frame, &codec, &views, &table, &depth, &view, &derivs, &mut timer,
                )
            })
        })??;
        let texture = stats.stage("prefilter", || {
            gpu.stage(name, "prefilter", || {
                let n = views.len() as u32;
                prefilter::prefilter(&gpu, &codec, &format, &depth, n, &fitted.ranges, &mut timer)
            })
        })??;
        let raw = lookup::run(
            &gpu,
            name,
            frame,
            &codec,
            &table,
            &fitted,
            &texture,
            format.levels,
            &view,
            &derivs,
            &mut timer,
            &mut stats,
        )?;
        stats.count("shadowable_share", fitted.shadowable_share(&gpu)?);
        for (stage, ms) in timer.read(&gpu)? {
            stats.count(&format!("gpu_{stage}_ms"), ms);
        }
        // The depth maps (linear depth and triangle a texel) the soft variants keep for
        // the blocker search, as the library counts them.
        let kept: u64 = if codec.settings.soft {
            views.len() as u64 * u64::from(side).pow(2) * 8
        } else {
            0
        };
        stats.memory_bytes = format.bytes(views.len() as u32 * codec.groups()) + kept;
        stats.count(
            "depth_map_bytes",
            (views.len() as u64 * u64::from(side).pow(2) * 8) as f64,
        );
        stats.count("mip_levels", format.levels as f64);
        stats.count("hardware_raster", 1.0);
        stats.count("hardware_filtering", 1.0);
        stats.device = Some(gpu.adapter.label());
        Ok(Shadows::of_frame(
            frame,
            crate::compute::to_rgb(&raw),
            stats,
        ))
    }
}
