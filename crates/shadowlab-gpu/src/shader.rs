//! Shader composition: the shared WGSL of `shaders/common/` is written once and placed
//! before each stage's own file.
//!
//! The include step is plain concatenation of `include_str!`ed files, in the order a
//! stage's [`Stage::common`] lists them (a common file may use the ones listed before
//! it). It needs no preprocessor and no extra crate, so the crate builds as fast as wgpu
//! allows; the price is one namespace for every stage's functions, so common files name
//! their items distinctly. A stage file starts with a comment naming the common files it
//! is composed after.

/// One common WGSL file.
#[derive(Clone, Copy, Debug)]
pub struct Common {
    /// Its name under `shaders/common/`.
    pub name: &'static str,
    /// Its text.
    pub source: &'static str,
}

/// `shaders/common/ray_offset.wgsl`: the error-bounded ray origin, `next_up`, `dot3`.
pub const RAY_OFFSET: Common = Common {
    name: "ray_offset.wgsl",
    source: include_str!("shaders/common/ray_offset.wgsl"),
};
/// `shaders/common/camera_rays.wgsl`: the library's camera rays (`RaysU`, `camera_ray`)
/// and error-bounded surface points (`surface_point`).
pub const CAMERA_RAYS: Common = Common {
    name: "camera_rays.wgsl",
    source: include_str!("shaders/common/camera_rays.wgsl"),
};
/// `shaders/common/order_key.wgsl`: `order_key`, a float as an unsigned key of the same
/// order, for reductions by integer atomics ([`order_key`] and [`float_of_key`] on the
/// CPU).
pub const ORDER_KEY: Common = Common {
    name: "order_key.wgsl",
    source: include_str!("shaders/common/order_key.wgsl"),
};

/// `order_key.wgsl`'s `order_key` on the CPU: keys compare as the floats do.
pub fn order_key(f: f32) -> u32 {
    let b = f.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

/// The float an [`order_key`] stands for.
pub fn float_of_key(key: u32) -> f32 {
    if key & 0x8000_0000 != 0 {
        f32::from_bits(key & 0x7fff_ffff)
    } else {
        f32::from_bits(!key)
    }
}

/// `shaders/common/light.wgsl`: the light, its shadow ray and `illuminates` (after
/// [`RAY_OFFSET`]).
pub const LIGHT: Common = Common {
    name: "light.wgsl",
    source: include_str!("shaders/common/light.wgsl"),
};
/// `shaders/common/watertight.wgsl`: the watertight ray–triangle test.
pub const WATERTIGHT: Common = Common {
    name: "watertight.wgsl",
    source: include_str!("shaders/common/watertight.wgsl"),
};
/// `shaders/common/alpha_mask.wgsl`: materials and alpha-mask texel look-ups.
pub const ALPHA_MASK: Common = Common {
    name: "alpha_mask.wgsl",
    source: include_str!("shaders/common/alpha_mask.wgsl"),
};

/// `shaders/common/triangles.wgsl`: a triangle's vertices and the alpha-mask cut-out of a
/// point on it (after [`ALPHA_MASK`]; the stage declares the scene's buffers).
pub const TRIANGLES: Common = Common {
    name: "triangles.wgsl",
    source: include_str!("shaders/common/triangles.wgsl"),
};

/// `shaders/common/light_depth.wgsl`: a light view's uniform, the scene's buffers and the
/// vertex shader of every hardware-rasterized map (after [`TRIANGLES`]).
pub const LIGHT_DEPTH: Common = Common {
    name: "light_depth.wgsl",
    source: include_str!("shaders/common/light_depth.wgsl"),
};

/// `shaders/common/map_compare.wgsl`: the receiver bias, texel size, cube face,
/// nearest-texel and PCF comparisons the map look-ups share (after [`RAY_OFFSET`]).
pub const MAP_COMPARE: Common = Common {
    name: "map_compare.wgsl",
    source: include_str!("shaders/common/map_compare.wgsl"),
};

/// `shaders/common/map_pixels.wgsl`: the map look-ups' entry point over the camera pass's
/// pixels, calling the stage's `shadow_term` (after [`LIGHT`]).
pub const MAP_PIXELS: Common = Common {
    name: "map_pixels.wgsl",
    source: include_str!("shaders/common/map_pixels.wgsl"),
};

/// One pipeline stage's shader: the common files it needs and its own file.
#[derive(Clone, Copy, Debug)]
pub struct Stage {
    /// The stage's file name, such as `trace.wgsl`.
    pub name: &'static str,
    /// The common files, in order.
    pub common: &'static [Common],
    /// The stage's own text.
    pub source: &'static str,
}

impl Stage {
    /// The composed WGSL: each common file, then the stage's own, each headed by its name.
    pub fn compose(&self) -> String {
        let mut out = String::new();
        for c in self.common {
            out.push_str(&format!("// ---- common/{} ----\n", c.name));
            out.push_str(c.source);
            out.push('\n');
        }
        out.push_str(&format!("// ---- {} ----\n", self.name));
        out.push_str(self.source);
        out
    }

    /// A render pipeline of the stage's `vs` and `fragment` over no vertex buffers (the stage
    /// reads its triangles from storage by vertex index), both faces drawn, a 32-bit float
    /// depth tested `Less` and written, and the colour `targets`: the light's depth map
    /// (none) and the camera's G-buffer share it.
    pub fn depth_tested_pipeline(
        &self,
        device: &wgpu::Device,
        fragment: &str,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> wgpu::RenderPipeline {
        let module = self.module(device);
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.name),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(fragment),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// The stage's shader module on `device`.
    pub fn module(&self, device: &wgpu::Device) -> wgpu::ShaderModule {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(self.name),
            source: wgpu::ShaderSource::Wgsl(self.compose().into()),
        })
    }
}

/// What the pipeline caches find a pipeline by: its stage's text (its own file and its
/// common files, compared by content, so two stages may share a file name) and its entry
/// point (`""` for a render pipeline's `vs` and `fs`).
pub(crate) struct PipelineKey {
    source: &'static str,
    common: &'static [Common],
    entry: String,
}

impl PipelineKey {
    pub(crate) fn new(stage: &Stage, entry: &str) -> Self {
        PipelineKey {
            source: stage.source,
            common: stage.common,
            entry: entry.to_string(),
        }
    }

    pub(crate) fn is(&self, stage: &Stage, entry: &str) -> bool {
        self.entry == entry
            && self.source == stage.source
            && self.common.len() == stage.common.len()
            && self
                .common
                .iter()
                .zip(stage.common)
                .all(|(a, b)| a.source == b.source)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_order_as_their_floats() {
        let zs = [
            f32::NEG_INFINITY,
            -3.5,
            -1e-30,
            0.0,
            1e-30,
            0.25,
            7.0,
            f32::INFINITY,
        ];
        for w in zs.windows(2) {
            assert!(order_key(w[0]) < order_key(w[1]), "{} {}", w[0], w[1]);
        }
        for z in zs {
            assert_eq!(float_of_key(order_key(z)), z);
        }
    }

    #[test]
    fn keys_keep_the_floats_order_and_come_back() {
        let xs = [-1e30f32, -2.5, -0.0, 0.0, 1e-30, 3.0, 1e30];
        for w in xs.windows(2) {
            assert!(order_key(w[0]) <= order_key(w[1]), "{w:?}");
        }
        for x in xs {
            assert_eq!(float_of_key(order_key(x)).to_bits(), x.to_bits());
        }
    }
}
