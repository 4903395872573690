//! `gpu:psm`: perspective shadow maps (Stamminger & Drettakis 2002) on the GPU, twin of
//! the library's `psm`: the same parameters, meanings and defaults, and every light case
//! the CPU handles (a post-space point light in front, an inverted one for lights behind
//! the viewer, a post-space directional light, a cube of post-space maps for a point
//! light that surrounds the body; casters outside the view enter through the body `H`).
//!
//! The post-perspective set-up is the library's own (`Perspective::plan`: the camera
//! pass's receivers push the near and far planes, the body `H`, the virtual camera shift,
//! the light in post-perspective space, the map frusta fitted to `H′`): a few matrices a
//! frame, computed on the CPU as the paper's implementation did (it read back the depth
//! buffer for the near plane). Stage `post_map` (`post_map.wgsl`): the hardware rasterizer
//! draws the scene into each post-perspective map, a layer of one depth array texture,
//! with the map's matrix applied to world points (so the hardware divides by the virtual
//! camera's `w` with the map's own), clipping to the virtual camera's front by discarding
//! fragments. Stage `lookup` (`lookup.wgsl`): a compute pass takes each receiver into
//! post-perspective space and compares, with the paper's offset in post-space texels.
//! When the light reaches no receiver every covered pixel is dark; when no post-space
//! map fits, `gpu:sm`'s map with the same resolution and biases stands in (counted as
//! `uniform_fallback`), as on the CPU.
//!
//! Departures from the CPU twin: the hardware rasterizer's coverage and interpolation
//! round differently from the library's (its fill rule is the same); the CPU clips each
//! triangle in world space at `CLIP_DEPTH_FRACTION` of the virtual near plane and
//! rasterizes the pieces, the GPU rasterizes the whole triangle and discards the
//! fragments nearer than that depth (the same surface kept, its edge on the clip plane
//! rounded per fragment instead of per vertex); depths are stored divided by the map's
//! span (mirrored, `1 − d`, for an inverted light, where the CPU negates them), a
//! monotonic rounding.

use super::maps::{self, MapScene};
use super::shadow_map::{Fallback, GpuShadowMap};
use crate::compute::render_pipeline;
use crate::resident::{self, DeviceView, ShadowTerm};
use crate::shader::{Stage, ALPHA_MASK, LIGHT, MAP_COMPARE, MAP_PIXELS, RAY_OFFSET, TRIANGLES};
use crate::transfer::{storage, uniform, Timer};
use crate::upload::LightU;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::techniques::perspective::{Perspective, Plan, PostLight, Setup};
use shadowlab::techniques::shadow_map::check_light_map_size;
use shadowlab::techniques::{Frame, Stats};

/// `gpu:psm`'s name.
pub const NAME: &str = "gpu:psm";

const POST_MAP: Stage = Stage {
    name: "perspective/post_map.wgsl",
    common: &[ALPHA_MASK, TRIANGLES],
    source: include_str!("post_map.wgsl"),
};

const LOOKUP: Stage = Stage {
    name: "perspective/lookup.wgsl",
    common: &[RAY_OFFSET, LIGHT, MAP_COMPARE, MAP_PIXELS],
    source: include_str!("lookup.wgsl"),
};

/// `PostFaceU` of `post_map.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PostFaceU {
    clip_from_world: [f32; 16],
    depth_world: [f32; 4],
    w_row: [f32; 4],
    clip_depth: f32,
    span: f32,
    inverted: u32,
    masks: u32,
}

/// `MapU` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MapU {
    clip_from_world: [f32; 16],
    depth_world: [f32; 4],
    texel: f32,
    near: f32,
    span: f32,
    ortho: u32,
}

/// `Params` of `lookup.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    post_from_world: [f32; 16],
    post_planes: [f32; 16],
    w_row: [f32; 4],
    q: [f32; 4],
    dir: [f32; 4],
    faces: [u32; 8],
    light: LightU,
    count: u32,
    row: u32,
    res: u32,
    kind: u32,
    bias: f32,
    slope_bias: f32,
    cube: u32,
    pad: u32,
}

/// The most negative finite clip depth: "clip nothing" (an orthographic view's −∞).
const NO_CLIP: f32 = -f32::MAX;

/// Perspective shadow maps on the GPU; the CPU `psm`'s parameters.
#[derive(Default)]
pub struct GpuPsm {
    cpu: Perspective,
    scene: Option<MapScene>,
    /// The last frame's post-perspective maps, for a viewer to show.
    last_maps: Option<wgpu::Texture>,
}

/// The stage's code for the post-space light's kind.
fn kind_code(kind: PostLight) -> u32 {
    match kind {
        PostLight::Point => 0,
        PostLight::Inverted => 1,
        PostLight::Directional => 2,
    }
}

impl GpuPsm {
    /// Draws the post-perspective maps of `setup` and looks every pixel of the uploaded
    /// `view` up.
    fn draw(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        setup: &Setup,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let cpu = self.cpu.clone();
        let res = cpu.resolution;
        let layers = setup.maps.len() as u32;
        check_light_map_size(NAME, setup.maps.len(), res)?;
        let ms = MapScene::keep(&mut self.scene, NAME, frame, stats)?;
        let gpu = ms.gpu.clone();
        let texture = maps::depth_array(&gpu, NAME, &format!("{NAME}.resolution"), res, layers)?;
        let mut timer = Timer::new(&gpu, layers + 1);
        let inverted = setup.post.light == PostLight::Inverted;
        let clip_depth = if setup.clip_depth.is_finite() {
            setup.clip_depth
        } else {
            NO_CLIP
        };
        let faces: Vec<wgpu::Buffer> = setup
            .maps
            .iter()
            .map(|m| {
                let face = PostFaceU {
                    clip_from_world: m.clip_from_world.to_cols_array(),
                    depth_world: m.depth_world.to_array(),
                    w_row: setup.w_row.to_array(),
                    clip_depth,
                    span: m.span,
                    inverted: u32::from(inverted),
                    masks: u32::from(ms.scene.masks),
                };
                uniform(&gpu, "post-perspective map", &face)
            })
            .collect();
        let pipeline = gpu.stage(NAME, "pipeline", || render_pipeline(&gpu, &POST_MAP, &[]))?;
        stats.stage("shadow_map", || {
            gpu.stage(NAME, "shadow_map", || {
                maps::draw_layers(ms, &pipeline, &texture, &faces, frame, &mut timer)
            })
        })?;
        let table: Vec<MapU> = setup
            .maps
            .iter()
            .map(|m| MapU {
                clip_from_world: m.clip_from_world.to_cols_array(),
                depth_world: m.depth_world.to_array(),
                texel: m.texel,
                near: m.near,
                span: m.span,
                ortho: u32::from(m.orthographic),
            })
            .collect();
        let table = storage(
            &gpu,
            "the post-perspective maps",
            bytemuck::cast_slice(&table),
        )?;
        let (count, row, _) = maps::lookup_grid(&gpu, view);
        let mut faces = [u32::MAX; 8];
        if let Some(cube) = setup.cube {
            for (f, m) in faces.iter_mut().zip(cube) {
                *f = u32::try_from(m).unwrap_or(u32::MAX);
            }
        }
        let params = Params {
            post_from_world: setup.post.post_from_world.to_cols_array(),
            post_planes: setup.post_planes.to_cols_array(),
            w_row: setup.w_row.to_array(),
            q: setup.q.extend(0.0).to_array(),
            dir: setup.dir.extend(0.0).to_array(),
            faces,
            light: LightU::of(frame.light),
            count,
            row,
            res,
            kind: kind_code(setup.post.light),
            bias: cpu.bias,
            slope_bias: cpu.slope_bias,
            cube: u32::from(setup.cube.is_some()),
            pad: 0,
        };
        let params = uniform(&gpu, "look-up parameters", &params);
        let array = maps::array_view(&texture);
        let value = maps::look_up(
            ms,
            NAME,
            &LOOKUP,
            &[
                params.as_entire_binding(),
                table.as_entire_binding(),
                wgpu::BindingResource::TextureView(&array),
            ],
            view,
            &mut timer,
            stats,
        )?;
        maps::count_maps(stats, &texture);
        stats.count("maps", f64::from(layers));
        stats.count("inverted", f64::from(u8::from(inverted)));
        stats.count(
            "post_directional",
            f64::from(u8::from(setup.post.light == PostLight::Directional)),
        );
        stats.count("virtual_shift", setup.post.virtual_shift);
        stats.count("near", setup.post.near);
        stats.count("far", setup.post.far);
        stats.count("body_vertices", setup.post.body.len() as f64);
        self.last_maps = Some(texture);
        Ok(value)
    }
}

resident::device_twin!(GpuPsm, NAME);

impl ShadowTerm for GpuPsm {
    /// The light's fit reads every visible point on the CPU.
    fn cpu_samples(&self) -> bool {
        true
    }

    fn shadow_term(
        &mut self,
        frame: &Frame,
        view: &DeviceView,
        stats: &mut Stats,
    ) -> Result<wgpu::Buffer> {
        let plan = stats.stage("body", || self.cpu.plan(frame))?;
        match plan {
            Plan::NoReceivers => {
                stats.count("maps", 0.0);
                maps::unreached(frame)
            }
            Plan::Uniform => {
                let c = &self.cpu;
                GpuShadowMap::fallback(
                    frame,
                    view,
                    stats,
                    (&mut self.scene, &mut self.last_maps),
                    &Fallback {
                        kernel: 0,
                        resolution: c.resolution,
                        bias: c.bias,
                        slope_bias: c.slope_bias,
                        counter: "uniform_fallback",
                    },
                )
            }
            Plan::Maps(setup) => self.draw(frame, view, &setup, stats),
        }
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
        assert_eq!(std::mem::size_of::<PostFaceU>(), 112);
        assert_eq!(std::mem::size_of::<MapU>(), 96);
        assert_eq!(std::mem::size_of::<Params>(), 288);
    }
}
