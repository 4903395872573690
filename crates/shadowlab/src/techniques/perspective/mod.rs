//! `psm`: perspective shadow maps (Stamminger & Drettakis 2002, "Perspective Shadow Maps").
//!
//! The idea: map the scene and the light into the camera's post-perspective space (normalized
//! device coordinates), where the view is an orthographic look at a cube, and render an
//! ordinary shadow map there. Texels are then spread evenly over the *image* rather than over
//! the world, so shadows near the viewer get many texels and distant ones few.
//!
//! # One frame
//! 1. Near plane (Section 6, [`near_plane`]): the camera pass is the read-back depth
//!    buffer. The near and far planes of the post-perspective transform are pushed to the
//!    nearest and farthest depth of the visible receivers that the light can reach.
//! 2. The body `H` (Section 4.1, [`body`]): `B` = view frustum ∩ box of those receivers ∩
//!    light frustum (a spot light's pyramid), then `H = hull(B ∪ l) ∩ S` with `S` the scene
//!    bounds, built as an exact convex polyhedron (face planes of `B` that the light sees
//!    from inside, plus planes through `B`'s silhouette edges and the light; for a
//!    directional light the light is the point at infinity along `to_light`). Every caster
//!    between a receiver and the light lies in `H`.
//! 3. Virtual camera shift (Section 4.2, [`post_space`]): when `H` reaches nearer than the
//!    near plane, the camera is moved back along its axis until it does not; near stays,
//!    far grows by the shift. The post-perspective transform `post_from_world` is the
//!    OpenGL-style projection (the paper's unit cube, infinity plane at `z = (f+n)/(f−n)`)
//!    of this virtual camera.
//! 4. The light in post-perspective space (Sections 3.1–3.2, [`post_space`]) is the
//!    homogeneous point `l' = post_from_world · l` (`l = (to_light, 0)` for directional
//!    lights, `(position, 1)` for point and spot lights). `l'.w = 0` (a directional light
//!    parallel to the image plane, a point light on the camera plane): directional, an
//!    orthographic map along `l'.xyz`. `l'.w > 0` (directional from the front, point light
//!    in front): a point light at `q = l'.xyz / l'.w`. `l'.w < 0` (directional from behind,
//!    point light behind the viewer): an *inverted* point light at `q` whose rays converge,
//!    so the depth test is reversed and the surface farthest from `q` is the one the light
//!    reaches first.
//! 5. The map frustum ([`fit`]) is fitted to the transformed body `H'`: the tangent-plane
//!    window of its vertices seen from `q` (off-centre, so no texel is spent outside `H'`),
//!    or their window across the light direction for an orthographic map.
//! 6. The map ([`post_map`]): every triangle is clipped in world space to the virtual
//!    camera's depths beyond [`CLIP_DEPTH_FRACTION`] of its near plane (`H` lies beyond the
//!    near plane), divided into post-perspective space and rasterized by the shared
//!    rasterizer with `clip_from_post · post_from_world` (one matrix, then the division by
//!    the virtual camera's `w`).
//! 7. The look-up ([`lookup`]): receivers take the same path and compare depths.
//!
//! # Orthographic views
//! With an orthographic camera the post-perspective transform is the camera's orthographic
//! projection: an affine map, so post-perspective space is the world itself, scaled into
//! the cube, and there is no perspective aliasing to redistribute. A directional light
//! stays directional there (`l'.w = 0`), a point light stays a point light in front
//! (`l'.w = 1`), and `psm` degenerates to a uniform shadow map fitted to the view's body
//! `H` — `sm` fitted to what the view needs. Nothing needs the virtual shift or the
//! clipping of step 6 (every point has a finite image), so neither is applied.
//!
//! # Depth and bias
//! The stored depth is the *linear* depth in post-perspective space from the map's near
//! plane (along the map axis from `q`, or along the light direction for orthographic
//! maps), negated for inverted lights so the shared min-test keeps the surface farthest
//! from `q`. Since post-perspective space is reached by a projective map, planes stay
//! planes and that depth is affine on every post-space triangle, so the rasterizer's
//! perspective-correct interpolation is exact. The depth offset is applied in shadow map
//! space, as the paper does, in units of the map's own texel: `texel' · (bias + slope_bias ·
//! tan θ')` with `texel'` the post-space texel size at the receiver and `θ'` the
//! post-space angle between the receiver's plane and the light; the parameters are `sm`'s
//! and so are the defaults ([`DEFAULT_DEPTH_OFFSET`], [`DEFAULT_SLOPE_OFFSET`]).
//!
//! # Invariants
//! - Every receiver the light can reach lies inside the map's frustum, and so does every
//!   point of `H` (the frustum is fitted to `H'`'s vertices and `H'` is convex).
//! - Nothing behind the virtual camera's eye plane is rasterized (it has no finite,
//!   order-preserving post-perspective image); `H` lies in front of it by construction.
//! - Results do not depend on the thread count: rayon with ordered collection only.
//!
//! # Departures from the paper, and why
//! - `B` uses the box of the *visible* receivers (the paper intersects the whole view
//!   frustum with the scene box): a tighter body, the same guarantee, since only visible
//!   receivers are ever looked up.
//! - The far plane is pulled in to the farthest visible receiver, as the near plane is
//!   pushed out (the paper mentions only the near plane).
//! - The virtual shift only brings `H` beyond the near plane (every point of `H` at least
//!   the near distance from the virtual eye); the paper shifts until `H` lies inside the
//!   whole frustum. Points of `H` outside the side planes still have a finite,
//!   order-preserving image, and a smaller shift keeps more of the perspective gain.
//! - The bias is in texel units with a slope term, like `sm`, instead of the paper's bare
//!   constant offset in shadow map space, so that one default fits every scene.
//! - A point light whose post-perspective image sees `H'` over more than
//!   [`MAX_POINT_TANGENT`] (or surrounds it) gets a cube of six post-perspective maps, as an
//!   omnidirectional light needs; the paper treats spot lights only.
//! - Triangles are clipped to the virtual camera's front half-space in world space before
//!   the perspective division (a GPU clips in clip space; our rasterizer must interpolate
//!   post-space depth, which needs the divided positions).
//!
//! # Known artifacts
//! - When the light is nearly parallel to the view direction the parameterization falls
//!   back to that of a uniform map (Section 3.3) and so do its artifacts; a light far
//!   behind the viewer forces a large virtual shift with the same effect.
//! - Projection aliasing (light grazing a surface) is not reduced, as the paper says.
//! - A surface lit at grazing incidence can shadow itself: a light perpendicular to the
//!   view is exactly edge-on, in post-perspective space, to every face that looks straight
//!   at the camera, and the slope term is clamped as in `sm` (raising the clamp fixes such
//!   faces but lets shadows leak onto curved receivers near their terminator).
//! - On a CPU the map costs more than a uniform one of the same size: near geometry is
//!   magnified, so more triangles cover texel centres and the map is filled where a
//!   uniform map fitted to the whole view leaves much of it empty. The paper's "almost no
//!   overhead" holds on a GPU, where rasterization is not the bottleneck.
//! - Post-perspective space compresses depth far from the viewer; a texel-scaled bias is
//!   large there in world units, which can detach distant contact shadows (peter-panning).

pub mod body;
pub mod fit;
pub mod lookup;
pub mod near_plane;
pub mod post_map;
pub mod post_space;

pub use body::RECEIVER_PAD;
pub use fit::{DEPTH_PAD, MAX_POINT_TANGENT, WINDOW_PAD};
pub use near_plane::DEPTH_FIT_PAD;
pub use post_map::CLIP_DEPTH_FRACTION;
pub use post_space::{PostLight, PostSpace, DIRECTIONAL_DISTANCE_RATIO, SHIFT_SLACK};

use super::shadow_map::{
    check_resolution, DEFAULT_CONSTANT_BIAS, DEFAULT_RESOLUTION, DEFAULT_SLOPE_BIAS,
};
use super::{
    find_param, not_read, param_value, parse_value, Frame, ParamSpec, ShadowTechnique, Shadows,
    Stats, BIAS, RESOLUTION, SLOPE_BIAS,
};
use crate::error::Result;
use crate::light::Light;
use crate::math::{Mat4, Vec3, Vec4};
use crate::raster::{DepthBuffer, NO_TRIANGLE};
use near_plane::Receivers;
pub use post_map::PostMap;
use post_space::{PostBody, PostLightSource, VirtualCamera};
use std::collections::BTreeMap;

/// Default constant depth offset in post-perspective texels — the paper's "constant offset
/// in depth in shadow map space", in units of the map's own texel so that one value fits
/// every scene (the same value as `sm`'s): half a texel covers the depth error of looking
/// up a texel centre up to half a texel from a receiver that faces the light. Larger values
/// detach contact shadows (peter-panning); since post-perspective texels grow with the
/// distance from the viewer, so does the world size of the offset, as it should.
pub const DEFAULT_DEPTH_OFFSET: f32 = DEFAULT_CONSTANT_BIAS;
/// Default slope-scaled depth offset in post-perspective texels per unit of tan θ' (θ' the
/// post-space angle between the receiver's normal and the light): a receiver's own depth
/// changes by tan θ' per texel. Smaller values give acne on surfaces the light grazes.
pub const DEFAULT_SLOPE_OFFSET: f32 = DEFAULT_SLOPE_BIAS;

/// Perspective shadow maps.
#[derive(Clone, Debug)]
pub struct Perspective {
    /// Map side in texels.
    pub resolution: u32,
    /// Constant depth offset in post-perspective texels.
    pub bias: f32,
    /// Slope-scaled depth offset in post-perspective texels per unit of tan θ'.
    pub slope_bias: f32,
}

impl Default for Perspective {
    fn default() -> Self {
        Perspective {
            resolution: DEFAULT_RESOLUTION,
            bias: DEFAULT_DEPTH_OFFSET,
            slope_bias: DEFAULT_SLOPE_OFFSET,
        }
    }
}

/// The frame's geometry, ready to rasterize.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The post-perspective space.
    pub post: PostSpace,
    /// The post-space light position `q` (unused for directional lights).
    pub q: Vec3,
    /// Unit direction towards a directional post-space light.
    pub dir: Vec3,
    /// Transposed inverse of `post_from_world`: maps world planes to post planes.
    pub post_planes: Mat4,
    /// The virtual camera's clip `w` (its view depth) as a row on world points.
    pub w_row: Vec4,
    /// Depth (along the view axis from the virtual eye) below which triangles are clipped
    /// (−∞ for an orthographic view: nothing is).
    pub clip_depth: f32,
    /// The maps, their depths still empty until the map is drawn.
    pub maps: Vec<PostMap>,
    /// For a cube: map index of each of the six faces (`usize::MAX` when skipped).
    pub cube: Option<[usize; 6]>,
}

/// What one frame of `psm` is drawn from ([`Perspective::plan`]).
#[derive(Clone, Debug)]
pub enum Plan {
    /// The light reaches no receiver: every covered pixel is dark.
    NoReceivers,
    /// No post-space map fits the frame: a uniform shadow map with the same resolution
    /// and biases stands in.
    Uniform,
    /// The post-perspective maps.
    Maps(Box<Setup>),
}

impl ShadowTechnique for Perspective {
    fn name(&self) -> &'static str {
        "psm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), param_value(self.bias)),
            ("slope-bias".to_string(), param_value(self.slope_bias)),
        ])
    }

    fn param_specs(&self) -> Vec<ParamSpec> {
        vec![BIAS, RESOLUTION, SLOPE_BIAS]
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "psm";
        let spec = find_param(t, &self.param_specs(), key)?;
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = spec.f32(t, value)?,
            "slope-bias" => self.slope_bias = spec.f32(t, value)?,
            _ => return Err(not_read(t, key)),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        let mut stats = Stats::default();
        let res = check_resolution("psm", self.resolution)?;
        frame.light.validate()?;
        let view = frame.view;
        let (w, h) = (view.width, view.height);
        let n = (w * h) as usize;
        let receivers = stats.stage("near_plane", || Receivers::gather(frame));
        let Some(receivers) = receivers else {
            // No receiver can be lit: the shared illumination test decides every pixel.
            let value = (0..n)
                .map(|k| {
                    if view.covered(k) {
                        Vec3::ZERO
                    } else {
                        Vec3::ONE
                    }
                })
                .collect();
            stats.count("maps", 0.0);
            return Ok(Shadows::of_frame(frame, value, stats));
        };
        let Some(mut setup) = stats.stage("body", || build_setup(frame, &receivers, res)) else {
            // No post-space map fits this frame: fall back to a uniform shadow map with the
            // same resolution and bias rather than fail the frame.
            let mut sm = super::shadow_map::ShadowMap::standard();
            sm.resolution = res;
            sm.bias = self.bias;
            sm.slope_bias = self.slope_bias;
            let mut out = sm.render(frame)?;
            out.stats.count("uniform_fallback", 1.0);
            return Ok(out);
        };
        super::shadow_map::check_light_map_size("psm", setup.maps.len(), res)?;
        stats.stage("shadow_map", || {
            let pieces = post_map::clipped_pieces(frame, &setup);
            for i in 0..setup.maps.len() {
                let depth = post_map::render_post_map(frame, &setup, &setup.maps[i], &pieces, res);
                setup.maps[i].depth = depth;
            }
        });
        let (bias, slope) = (self.bias, self.slope_bias);
        let value = stats.stage("lookup", || {
            lookup::lookup(frame, &setup, &receivers.lit, res, bias, slope)
        });
        count_stats(&mut stats, &setup, res);
        if frame.dumping() {
            dump(frame, &setup, res)?;
        }
        Ok(Shadows::of_frame(frame, value, stats))
    }
}

impl Perspective {
    /// What this frame's maps are drawn from, before any is drawn (the GPU twin draws them
    /// itself): the same receivers, body, virtual camera, post-space light and fits as
    /// [`ShadowTechnique::render`].
    pub fn plan(&self, frame: &Frame) -> Result<Plan> {
        let res = check_resolution("psm", self.resolution)?;
        frame.light.validate()?;
        let Some(receivers) = Receivers::gather(frame) else {
            return Ok(Plan::NoReceivers);
        };
        Ok(match build_setup(frame, &receivers, res) {
            Some(s) => Plan::Maps(Box::new(s)),
            None => Plan::Uniform,
        })
    }

    /// The post-perspective space this technique would build for `frame` (the body, the
    /// virtual shift and the light's case), without rendering a map; `None` when no receiver
    /// can be lit or no post-space map fits (the technique then falls back to a uniform map).
    pub fn post_space(&self, frame: &Frame) -> Result<Option<PostSpace>> {
        let res = check_resolution("psm", self.resolution)?;
        frame.light.validate()?;
        Ok(Receivers::gather(frame)
            .and_then(|r| build_setup(frame, &r, res))
            .map(|s| s.post))
    }
}

/// Builds the post-perspective set-up, one stage of the paper after the other; `None` when
/// no post-space map can be fitted around the body (degenerate bodies, e.g. every lit
/// receiver in a sliver the post-space light sees edge-on).
fn build_setup(frame: &Frame, rec: &Receivers, res: u32) -> Option<Setup> {
    let tol = body::geometry_tolerance(frame);
    // Section 6: the near and far planes pushed to the visible receivers.
    let near_far = rec.near_far();
    // Section 4.1: the body H of everything the map must hold.
    let body = body::shadow_body(frame, rec, near_far, tol);
    // Section 4.2: the virtual camera, shifted until H lies beyond its near plane.
    let camera = VirtualCamera::shifted(frame.camera, &body, near_far);
    // Sections 3.1–3.2: H and the light in post-perspective space.
    let post_body = PostBody::of(&camera, &body);
    let light = PostLightSource::of(frame.light, &camera, post_body.size);
    // The map frustum (or a cube of them) fitted to H'.
    let world_directional = matches!(frame.light, Light::Directional { .. });
    let (maps, cube) = fit::fit_maps(&light, world_directional, &post_body, res);
    if maps.is_empty() {
        return None;
    }
    let post_from_world = camera.post_from_world;
    let maps: Vec<PostMap> = maps
        .into_iter()
        .map(|m| PostMap::new(m, &post_from_world))
        .collect();
    let post = PostSpace {
        post_from_world: post_from_world.as_mat4(),
        light: light.kind,
        light_post: light.light_post,
        virtual_shift: camera.shift,
        near: camera.near,
        far: camera.far,
        body,
        maps: maps.len(),
    };
    Some(Setup {
        post,
        q: light.q.as_vec3(),
        dir: light.dir.as_vec3(),
        post_planes: post_from_world.inverse().transpose().as_mat4(),
        w_row: post_from_world.row(3).as_vec4(),
        // An orthographic view's post-perspective map is affine: every point has a finite
        // image and nothing is clipped.
        clip_depth: if frame.camera.is_orthographic() {
            f32::NEG_INFINITY
        } else {
            (camera.near * CLIP_DEPTH_FRACTION as f64) as f32
        },
        maps,
        cube,
    })
}

/// The counters of one rendered frame.
fn count_stats(stats: &mut Stats, setup: &Setup, res: u32) {
    stats.memory_bytes = setup.maps.iter().map(|m| m.depth.len() as u64 * 4).sum();
    stats.count("map_texels", (res as f64).powi(2) * setup.maps.len() as f64);
    stats.count("maps", setup.maps.len() as f64);
    stats.count(
        "inverted",
        (setup.post.light == PostLight::Inverted) as u8 as f64,
    );
    stats.count(
        "post_directional",
        (setup.post.light == PostLight::Directional) as u8 as f64,
    );
    stats.count("virtual_shift", setup.post.virtual_shift);
    stats.count("near", setup.post.near);
    stats.count("far", setup.post.far);
    stats.count("body_vertices", setup.post.body.len() as f64);
}

/// Writes each post-perspective map (white = the first surface the light reaches) and a
/// description of the post-perspective space.
fn dump(frame: &Frame, setup: &Setup, res: u32) -> Result<()> {
    for (i, m) in setup.maps.iter().enumerate() {
        let buf = DepthBuffer {
            width: res,
            height: res,
            depth: m.depth.clone(),
            id: vec![NO_TRIANGLE; m.depth.len()],
        };
        frame.dump_depth(&format!("psm-post-map{i}.png"), &buf)?;
    }
    let p = &setup.post;
    let text = serde_json::json!({
        "light": format!("{:?}", p.light).to_lowercase(),
        "light_post": p.light_post.to_array(),
        "virtual_shift": p.virtual_shift,
        "near": p.near,
        "far": p.far,
        "maps": p.maps,
        "body": p.body.iter().map(|v| v.to_array()).collect::<Vec<_>>(),
    });
    frame.dump_text("psm-post-space.json", || {
        serde_json::to_string_pretty(&text).unwrap_or_default()
    })
}
