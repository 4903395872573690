//! `gpu:sm` and `gpu:pcf`: the standard shadow map (Williams 1978) and percentage-closer
//! filtering (Reeves et al. 1987) on the GPU, twins of the library's `sm` and `pcf`.
//!
//! Stage `depth` (`depth.wgsl`): the hardware rasterizer draws the scene into a depth map
//! per light view (one for directional and spot lights, six cube faces for a point light:
//! the layers of one array texture), over the CPU's own light views (the library's
//! `light_views`, fitted to the same receivers). Each fragment writes the library's linear
//! depth over the view's far plane, so the hardware depth test keeps the nearest caster
//! and the look-up compares linear depths; alpha-masked casters are discarded where cut.
//! Stage `lookup` (`lookup.wgsl`): a compute pass over the camera pass's samples applies
//! the CPU's bias (constant plus slope-scaled, in texels at the receiver; PCF's slope term
//! scaled by its reach) and compares: `gpu:sm` with the nearest texel, `gpu:pcf` with
//! `kernel × kernel` hardware bilinear 2×2 comparisons through a comparison sampler.
//!
//! Departures from the CPU twin: the hardware rasterizer's coverage and depth
//! interpolation differ from the library's rasterizer by rounding (its fill rule is the
//! same top-left rule), depths are stored divided by the far plane (a monotonic rounding),
//! and the hardware's bilinear weights have the adapter's sub-texel precision (8 bits on
//! many GPUs) where the CPU's are exact: so the two differ on a few edge pixels, which
//! the verdict tests bound. The map is drawn by the hardware rasterizer on every adapter
//! (`counters.hardware_raster = 1`); a compute rasterizer is not offered yet.

use super::maps::{self, MapScene};
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{Stage, LIGHT, MAP_COMPARE, MAP_PIXELS, RAY_OFFSET};
use crate::transfer::{uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::light_views;
use shadowlab::techniques::shadow_map::{
    check_resolution, pcf_slope_bias, ShadowMap, DIRECTIONAL_PAD,
};
use shadowlab::techniques::{Frame, ShadowTechnique, Shadows, Stats};

/// `gpu:sm`'s name.
pub const SM: &str = "gpu:sm";
/// `gpu:pcf`'s name.
pub const PCF: &str = "gpu:pcf";

const LOOKUP: Stage = Stage {
    name: "shadow_map/lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT, MAP_COMPARE, MAP_PIXELS],
    source: include_str!("lookup.wgsl"),
};

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LookupParams {
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    kernel: u32,
    bias: f32,
    slope_bias: f32,
    pad: [u32; 2],
}

/// A shadow map drawn by the hardware rasterizer; the CPU `sm`'s or `pcf`'s parameters.
pub struct GpuShadowMap {
    name: &'static str,
    cpu: ShadowMap,
    scene: Option<MapScene>,
    /// The last frame's maps, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

impl GpuShadowMap {
    /// `gpu:sm`.
    pub fn standard() -> Self {
        GpuShadowMap {
            name: SM,
            cpu: ShadowMap::standard(),
            scene: None,
            last_maps: None,
        }
    }

    /// `gpu:pcf`.
    pub fn pcf() -> Self {
        GpuShadowMap {
            name: PCF,
            cpu: ShadowMap::pcf(),
            scene: None,
            last_maps: None,
        }
    }

    /// The single map a warped or split map falls back to where its CPU twin does: `gpu:sm`
    /// (kernel 0) or `gpu:pcf` with `f`'s parameters, rendering `frame` over the uploaded
    /// `view` into `stats` and counting `f.counter`. It draws from the caller's own scene
    /// on the device (`scene`, uploaded there when missing, so a fallback frame after frame
    /// uploads it once) and leaves its map in `maps` (for a viewer).
    pub(crate) fn fallback(
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
        (scene, maps): (&mut Option<MapScene>, &mut Option<wgpu::Texture>),
        f: &Fallback,
    ) -> Result<wgpu::Buffer> {
        let (name, mut cpu) = if f.kernel > 0 {
            (PCF, ShadowMap::pcf())
        } else {
            (SM, ShadowMap::standard())
        };
        (cpu.resolution, cpu.bias, cpu.slope_bias) = (f.resolution, f.bias, f.slope_bias);
        cpu.kernel = f.kernel;
        let mut sm = GpuShadowMap {
            name,
            cpu,
            scene: scene.take(),
            last_maps: None,
        };
        let terms = sm.shadow_term(frame, view, stats);
        *scene = sm.scene.take();
        *maps = sm.last_maps.take();
        stats.count(f.counter, 1.0);
        terms
    }
}

/// The parameters of a single-map fallback ([`GpuShadowMap::fallback`]): the twin's map,
/// and the counter that says the frame fell back.
pub(crate) struct Fallback {
    pub(crate) kernel: u32,
    pub(crate) resolution: u32,
    pub(crate) bias: f32,
    pub(crate) slope_bias: f32,
    pub(crate) counter: &'static str,
}

impl ShadowTechnique for GpuShadowMap {
    fn name(&self) -> &'static str {
        self.name
    }

    crate::twin::twin_params!(cpu);

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        resident::read_back(self, frame)
    }
}

impl ShadowTerm for GpuShadowMap {
    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let name = self.name;
        let res = check_resolution(name, self.cpu.resolution)?;
        let cpu = self.cpu.clone();
        let ms = MapScene::keep(&mut self.scene, name, frame, stats)?;
        let gpu = ms.gpu.clone();
        let views = light_views(
            frame.light,
            &view.receivers,
            &frame.scene.bounds,
            DIRECTIONAL_PAD,
        );
        let layers = views.len() as u32;
        let texture = maps::depth_array(&gpu, name, &format!("{name}.resolution"), res, layers)?;
        let mut timer = Timer::new(&gpu, layers + 1);
        stats.stage("shadow_map", || {
            gpu.stage(name, "shadow_map", || {
                maps::draw_views(ms, &texture, &views, frame, &mut timer)
            })
        })?;
        let (count, row, _) = maps::lookup_grid(&gpu, view);
        let params = LookupParams {
            light: LightU::of(frame.light),
            count,
            row,
            res: cpu.resolution,
            kernel: cpu.kernel,
            bias: cpu.bias,
            slope_bias: pcf_slope_bias(cpu.slope_bias, cpu.kernel),
            pad: [0; 2],
        };
        let params = uniform(&gpu, "look-up parameters", &params);
        let table = maps::view_table(&gpu, &views)?;
        let sampler = maps::comparison_sampler(&gpu);
        let array = maps::array_view(&texture);
        let value = maps::look_up(
            ms,
            name,
            &LOOKUP,
            &[
                params.as_entire_binding(),
                table.as_entire_binding(),
                wgpu::BindingResource::TextureView(&array),
                wgpu::BindingResource::Sampler(&sampler),
            ],
            view,
            &mut timer,
            stats,
        )?;
        maps::count_maps(stats, &texture);
        self.last_maps = Some(texture);
        Ok(value)
    }

    fn last_maps(&self) -> Option<&wgpu::Texture> {
        self.last_maps.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<maps::FaceU>(), 144);
        assert_eq!(std::mem::size_of::<maps::ViewU>(), 144);
        assert_eq!(std::mem::size_of::<LookupParams>(), 80);
    }
}
