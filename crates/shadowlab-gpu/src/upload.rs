//! The library's data in GPU buffers: the scene (once per revision), its BVH, and the
//! camera pass's view samples (once per frame).
//!
//! One storage buffer per concern: vertices, each triangle's material, the material table,
//! texture coordinates, alpha texels, the BVH's children and primitive list, the view
//! samples. Every struct a shader reads is mirrored by a `#[repr(C)]` + `Pod` type here
//! whose size a test checks against the WGSL layout.

use crate::device::Gpu;
use crate::transfer::storage;
use bytemuck::{Pod, Zeroable};
use shadowlab::error::Result;
use shadowlab::light::Light;
use shadowlab::raster::NO_TRIANGLE;
use shadowlab::reference::Reference;
use shadowlab::scene::alpha_mask::Wrap;
use shadowlab::scene::Scene;
use shadowlab::view::ViewSamples;

/// `MaterialU` of `shaders/common/alpha_mask.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct MaterialU {
    /// RGB transmittance.
    pub transmittance: [f32; 3],
    /// 1 when opaque.
    pub opaque: u32,
    /// 1 when alpha-masked.
    pub masked: u32,
    /// First byte of the mask's texels.
    pub texel_offset: u32,
    /// Mask width.
    pub width: u32,
    /// Mask height.
    pub height: u32,
    /// Wrap mode along u (0 repeat, 1 mirrored, 2 clamp).
    pub wrap_u: u32,
    /// Wrap mode along v.
    pub wrap_v: u32,
    /// Alpha factor.
    pub factor: f32,
    /// Alpha cut-off.
    pub cutoff: f32,
}

/// `LightU` of `shaders/common/light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightU {
    /// Directional: unit vector towards the light; else its position.
    pub pos_or_dir: [f32; 3],
    /// 0 directional, 1 spot, 2 point.
    pub kind: u32,
    /// Spot: unit axis.
    pub axis: [f32; 3],
    /// Spot: cosine of half the opening angle.
    pub cos_half: f32,
    /// +infinity.
    pub far: f32,
    /// Padding to the WGSL struct's 16-byte size.
    pub pad: [f32; 3],
}

impl LightU {
    /// The light as the shaders read it; the spot's axis and cosine are formed exactly as
    /// the library's `Light::cone_contains` forms them.
    pub fn of(light: &Light) -> Self {
        let mut u = LightU {
            pos_or_dir: [0.0; 3],
            kind: 0,
            axis: [0.0; 3],
            cos_half: -1.0,
            far: f32::INFINITY,
            pad: [0.0; 3],
        };
        match *light {
            Light::Directional { to_light } => u.pos_or_dir = to_light.to_array(),
            Light::Spot {
                position,
                target,
                fov_deg,
            } => {
                u.kind = 1;
                u.pos_or_dir = position.to_array();
                u.axis = (target - position).normalize().to_array();
                u.cos_half = (fov_deg.to_radians() * 0.5).cos();
            }
            Light::Point { position } => {
                u.kind = 2;
                u.pos_or_dir = position.to_array();
            }
        }
        u
    }
}

/// `Child` of `techniques/raytrace/trace.wgsl`: one child slot of a wide BVH node.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ChildU {
    /// Box minimum, scene units, rounded outwards.
    pub lo: [f32; 3],
    /// 0 empty, 1 inner, 2 + 4·count leaf.
    pub kind: u32,
    /// Box maximum, scene units, rounded outwards.
    pub hi: [f32; 3],
    /// Node index (inner) or first primitive (leaf).
    pub index: u32,
}

/// What identifies a scene's upload: the scene's address, name, revision, size and
/// bounds, so an edit in place (which bumps the revision) or another scene re-uploads.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneKey {
    address: usize,
    name: String,
    revision: u64,
    len: usize,
    bounds: [u32; 6],
}

impl SceneKey {
    /// The key of `scene` now.
    pub fn of(scene: &Scene) -> Self {
        let b = scene.bounds;
        SceneKey {
            address: scene as *const Scene as usize,
            name: scene.name.clone(),
            revision: scene.revision,
            len: scene.len(),
            bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits),
        }
    }
}

/// A scene's triangles and materials on the GPU.
pub struct SceneBuffers {
    /// Nine floats a triangle (three vertices).
    pub triangles: wgpu::Buffer,
    /// Each triangle's material index.
    pub material_of: wgpu::Buffer,
    /// The materials ([`MaterialU`]).
    pub materials: wgpu::Buffer,
    /// Six floats a triangle (three texture coordinates), or one word when no material is
    /// masked.
    pub uvs: wgpu::Buffer,
    /// Every mask's alpha bytes, four to a word.
    pub texels: wgpu::Buffer,
    /// True when some material lets light through.
    pub transparency: bool,
    /// True when some material is alpha-masked.
    pub masks: bool,
    /// Bytes uploaded.
    pub bytes: u64,
}

fn wrap_code(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    }
}

impl SceneBuffers {
    /// Uploads `scene`.
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        let mut verts = Vec::with_capacity(scene.len() * 9);
        for i in 0..scene.len() {
            for v in scene.triangle(i) {
                verts.extend_from_slice(&v.to_array());
            }
        }
        let mut texels: Vec<u8> = Vec::new();
        let mut seen: Vec<(usize, u32)> = Vec::new();
        let mut materials = Vec::with_capacity(scene.materials.len());
        for m in &scene.materials {
            let mut u = MaterialU {
                transmittance: m.transmittance.to_array(),
                opaque: u32::from(m.is_opaque()),
                masked: 0,
                texel_offset: 0,
                width: 1,
                height: 1,
                wrap_u: 0,
                wrap_v: 0,
                factor: 1.0,
                cutoff: 0.0,
            };
            if let Some(mask) = &m.alpha_mask {
                // Textures shared between materials are uploaded once.
                let key = std::sync::Arc::as_ptr(&mask.texture) as usize;
                let offset = match seen.iter().find(|s| s.0 == key) {
                    Some(&(_, o)) => o,
                    None => {
                        let o = texels.len() as u32;
                        texels.extend_from_slice(&mask.texture.alpha);
                        seen.push((key, o));
                        o
                    }
                };
                u.masked = 1;
                u.texel_offset = offset;
                u.width = mask.texture.width;
                u.height = mask.texture.height;
                u.wrap_u = wrap_code(mask.wrap_u);
                u.wrap_v = wrap_code(mask.wrap_v);
                u.factor = mask.factor;
                u.cutoff = mask.cutoff;
            }
            materials.push(u);
        }
        texels.resize(texels.len().div_ceil(4).max(1) * 4, 0);
        let masks = scene.has_alpha_masks();
        let uvs: Vec<f32> = if masks {
            (0..scene.len())
                .flat_map(|i| {
                    let uv = scene.uv.get(i).copied().unwrap_or_default();
                    [uv[0].x, uv[0].y, uv[1].x, uv[1].y, uv[2].x, uv[2].y]
                })
                .collect()
        } else {
            vec![0.0]
        };
        let bufs = SceneBuffers {
            triangles: storage(gpu, "the scene's triangles", bytemuck::cast_slice(&verts))?,
            material_of: storage(
                gpu,
                "the scene's material indices",
                bytemuck::cast_slice(&scene.material),
            )?,
            materials: storage(
                gpu,
                "the scene's materials",
                bytemuck::cast_slice(&materials),
            )?,
            uvs: storage(
                gpu,
                "the scene's texture coordinates",
                bytemuck::cast_slice(&uvs),
            )?,
            texels: storage(gpu, "the scene's alpha masks", &texels)?,
            transparency: scene.has_transparency(),
            masks,
            bytes: (verts.len() * 4
                + scene.material.len() * 4
                + materials.len() * std::mem::size_of::<MaterialU>()
                + uvs.len() * 4
                + texels.len()) as u64,
        };
        Ok(bufs)
    }
}

/// The library's BVH of a scene, flattened to eight [`ChildU`] a node, on the GPU.
pub struct BvhBuffers {
    /// The child records.
    pub children: wgpu::Buffer,
    /// The primitive list leaves index into.
    pub primitives: wgpu::Buffer,
    /// Bytes uploaded.
    pub bytes: u64,
}

/// The child records of `reference`'s wide BVH in scene units, each box rounded outwards
/// by an ulp after decompression and after the exact power-of-two rescaling, so the GPU's
/// boxes hold the library's.
pub fn flatten_bvh(reference: &Reference) -> (Vec<ChildU>, Vec<u32>) {
    let bvh = reference.bvh();
    let inv_scale = 1.0 / reference.bvh_scale();
    let mut out = Vec::with_capacity(bvh.nodes.len().max(1) * 8);
    for node in &bvh.nodes {
        for c in 0..8 {
            if node.is_child_empty(c) {
                out.push(ChildU::zeroed());
                continue;
            }
            let b = node.child_aabb(c);
            let lo = [b.min.x, b.min.y, b.min.z].map(|v| (v.next_down() * inv_scale).next_down());
            let hi = [b.max.x, b.max.y, b.max.z].map(|v| (v.next_up() * inv_scale).next_up());
            let (kind, index) = if node.is_leaf(c) {
                let (first, count) = node.child_primitives(c);
                (2 + 4 * count, first)
            } else {
                (1, node.child_node_index(c))
            };
            out.push(ChildU {
                lo,
                kind,
                hi,
                index,
            });
        }
    }
    if out.is_empty() {
        // An empty scene: a root whose children are all empty.
        out.resize(8, ChildU::zeroed());
    }
    (out, bvh.primitive_indices.clone())
}

impl BvhBuffers {
    /// Builds the library's BVH over `scene` and uploads it.
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<Self> {
        let reference = Reference::build(scene);
        let (children, prims) = flatten_bvh(&reference);
        Ok(BvhBuffers {
            children: storage(gpu, "the BVH's nodes", bytemuck::cast_slice(&children))?,
            primitives: storage(
                gpu,
                "the BVH's primitive list",
                bytemuck::cast_slice(&prims),
            )?,
            bytes: (children.len() * std::mem::size_of::<ChildU>() + prims.len() * 4) as u64,
        })
    }
}

/// `RaysU` of `shaders/common/camera_rays.wgsl`: the camera's primary-ray generator.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct RaysU {
    eye: [f32; 3],
    parallel: u32,
    forward: [f32; 3],
    inv_width: f32,
    right: [f32; 3],
    inv_height: f32,
    up: [f32; 3],
    width: u32,
}

impl RaysU {
    /// The primary rays of `camera` ([`shadowlab::camera::RayGenerator`]).
    pub fn of(camera: &shadowlab::camera::Camera) -> Self {
        let (eye, forward, right, up, inv_width, inv_height, parallel) = camera.rays().parts();
        RaysU {
            eye: eye.to_array(),
            parallel: u32::from(parallel),
            forward: forward.to_array(),
            inv_width,
            right: right.to_array(),
            inv_height,
            up: up.to_array(),
            width: camera.width,
        }
    }
}

/// Floats a view sample takes on the GPU: position, its error bound, normal, triangle id
/// (its bits).
pub const VIEW_STRIDE: usize = 10;

/// The camera pass's samples as the shaders read them: [`VIEW_STRIDE`] floats a pixel.
pub fn view_floats(view: &ViewSamples) -> Vec<f32> {
    let n = view.triangle.len();
    let mut out = Vec::with_capacity(n * VIEW_STRIDE);
    for k in 0..n {
        let tri = view.triangle[k];
        if tri == NO_TRIANGLE {
            out.extend_from_slice(&[0.0; 9]);
        } else {
            out.extend_from_slice(&view.position[k].to_array());
            out.extend_from_slice(&view.position_error[k].to_array());
            out.extend_from_slice(&view.normal[k].to_array());
        }
        out.push(f32::from_bits(tri));
    }
    out
}

/// Uploads the camera pass's samples.
pub fn view_buffer(gpu: &Gpu, view: &ViewSamples) -> Result<wgpu::Buffer> {
    storage(
        gpu,
        "the camera pass's samples",
        bytemuck::cast_slice(&view_floats(view)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The WGSL structs' sizes (std430/uniform layout, by hand from the WGSL rules): a
    /// mismatch would make every field after it read garbage.
    #[test]
    fn mirrored_structs_have_the_wgsl_sizes() {
        assert_eq!(std::mem::size_of::<MaterialU>(), 48);
        assert_eq!(std::mem::size_of::<LightU>(), 48);
        assert_eq!(std::mem::size_of::<ChildU>(), 32);
        assert_eq!(std::mem::size_of::<RaysU>(), 64);
    }
}
