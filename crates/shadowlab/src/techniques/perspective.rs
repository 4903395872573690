//! `psm`: perspective shadow maps (Stamminger & Drettakis 2002, "Perspective Shadow Maps").
//!
//! The idea: map the scene and the light into the camera's post-perspective space (normalized
//! device coordinates), where the view is an orthographic look at a cube, and render an
//! ordinary shadow map there. Texels are then spread evenly over the *image* rather than over
//! the world, so shadows near the viewer get many texels and distant ones few.
//!
//! # One frame
//! 1. Near plane (Section 6): the camera pass is the read-back depth buffer. The near and
//!    far planes of the post-perspective transform are pushed to the nearest and farthest
//!    depth of the visible receivers that the light can reach.
//! 2. The body `H` (Section 4.1): `B` = view frustum ∩ box of those receivers ∩ light frustum
//!    (a spot light's pyramid), then `H = hull(B ∪ l) ∩ S` with `S` the scene bounds, built as
//!    an exact convex polyhedron (face planes of `B` that the light sees from inside, plus
//!    planes through `B`'s silhouette edges and the light; for a directional light the light
//!    is the point at infinity along `to_light`). Every caster between a receiver and the
//!    light lies in `H`.
//! 3. Virtual camera shift (Section 4.2): when `H` reaches nearer than the near plane, the
//!    camera is moved back along its axis until it does not; near stays, far grows by the
//!    shift. The post-perspective transform `post_from_world` is the OpenGL-style projection
//!    (the paper's unit cube, infinity plane at `z = (f+n)/(f−n)`) of this virtual camera.
//! 4. The light in post-perspective space (Sections 3.1–3.2) is the homogeneous point
//!    `l' = post_from_world · l` (`l = (to_light, 0)` for directional lights, `(position, 1)`
//!    for point and spot lights). `l'.w = 0` (a directional light parallel to the image
//!    plane, a point light on the camera plane): directional, an orthographic map along
//!    `l'.xyz`. `l'.w > 0` (directional from the front, point light in front): a point light
//!    at `q = l'.xyz / l'.w`. `l'.w < 0` (directional from behind, point light behind the
//!    viewer): an *inverted* point light at `q` whose rays converge, so the depth test is
//!    reversed and the surface farthest from `q` is the one the light reaches first.
//! 5. The map frustum is fitted to the transformed body `H'`: the tangent-plane window of
//!    its vertices seen from `q` (off-centre, so no texel is spent outside `H'`), or their
//!    window across the light direction for an orthographic map.
//! 6. Every triangle is clipped in world space to the virtual camera's depths beyond
//!    [`CLIP_DEPTH_FRACTION`] of its near plane (`H` lies beyond the near plane), divided
//!    into post-perspective space and rasterized by the shared rasterizer with
//!    `clip_from_post · post_from_world` (one matrix, then the division by the virtual
//!    camera's `w`); receivers take the same path and compare depths.
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

use super::shadow_map::{
    check_resolution, receiver_bias, DEFAULT_CONSTANT_BIAS, DEFAULT_RESOLUTION, DEFAULT_SLOPE_BIAS,
};
use super::{
    check_range, parse_value, unknown_param, Frame, ShadowTechnique, Shadows, Stats, Visibility,
};
use crate::error::Result;
use crate::light::{cube_face, Light, CUBE_FACES};
use crate::math::{Aabb, Mat4, Vec3, Vec4};
use crate::raster::{self, DepthBuffer, SetupTriangle, NO_TRIANGLE};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;
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
/// The pushed near plane sits this fraction of the nearest visible depth in front of it
/// (and the far plane as much beyond the farthest), so receivers at exactly those depths
/// stay strictly inside. Larger values give away a little of the perspective gain.
pub const DEPTH_FIT_PAD: f64 = 1e-3;
/// The box of visible receivers is widened by this fraction of the scene's diagonal on
/// each side: it covers the floating-point error of the receiver positions and keeps the
/// body solid when every receiver lies on one plane. Larger values waste texels.
pub const RECEIVER_PAD: f64 = 1e-4;
/// The camera is shifted back only when the body reaches nearer than this fraction of the
/// near distance in front of the near plane; smaller shifts are not worth the lost
/// perspective, and the few points nearer than the near plane still map to finite points.
pub const SHIFT_SLACK: f64 = 1e-3;
/// Triangles are clipped to depths beyond this fraction of the virtual near plane before
/// the perspective division. The body lies beyond the near plane, so anything nearer
/// cannot matter; smaller values keep more irrelevant geometry with huge post-space images.
pub const CLIP_DEPTH_FRACTION: f32 = 0.5;
/// A post-perspective light farther than this many body diameters away is treated as
/// directional: its rays across the body then diverge by less than 1e-7 rad, far below a
/// texel, while a perspective frustum that far away would lose f32 precision.
pub const DIRECTIONAL_DISTANCE_RATIO: f64 = 1e7;
/// Largest tangent of the angle between the map axis and a body vertex for which a point
/// light keeps a single post-perspective map; beyond it six cube faces cover the body (a
/// single map spread over a wider cone would give its centre coarser texels than a cube
/// face). Directional lights always keep one map: their wide cones are the uniform case.
pub const MAX_POINT_TANGENT: f64 = 2.0;
/// The map window is widened by this fraction of its span on each side, so the body's
/// boundary never falls on the last texel. Larger values waste texels.
pub const WINDOW_PAD: f64 = 0.01;
/// The map's depth range is widened by this fraction on each side, so the nearest and
/// farthest casters are never clipped by rounding.
pub const DEPTH_PAD: f64 = 0.01;
/// Polyhedron clipping treats points within this fraction of the scene's coordinate
/// magnitude as lying on a plane; planes of the body are pushed out by as much, so
/// rounding can only make the body larger.
const GEOMETRY_TOLERANCE: f64 = 1e-9;

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

/// How the light looks from post-perspective space (Sections 3.1–3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PostLight {
    /// A point light: rays leave `q`.
    Point,
    /// An inverted point light: rays converge towards `q`; the depth test is reversed.
    Inverted,
    /// A directional light (the world light lies on the virtual camera plane).
    Directional,
}

/// What one frame's perspective shadow map was built from (for tests, dumps and reports).
#[derive(Clone, Debug)]
pub struct PostSpace {
    /// World to post-perspective space of the (virtually shifted) camera.
    pub post_from_world: Mat4,
    /// The light's case in post-perspective space.
    pub light: PostLight,
    /// The light in post-perspective space as a homogeneous point.
    pub light_post: DVec4,
    /// How far the camera was moved back along its view direction (world units).
    pub virtual_shift: f64,
    /// Near plane distance of the virtual camera (the pushed near plane).
    pub near: f64,
    /// Far plane distance of the virtual camera.
    pub far: f64,
    /// Vertices of the body `H` in world space.
    pub body: Vec<DVec3>,
    /// Number of maps (1, or up to 6 for a cube around a post-perspective point light).
    pub maps: usize,
}

/// A map frustum in post-perspective space, in f64, before it is joined to the world.
struct MapFit {
    /// Post-perspective space to the map's clip space.
    clip_from_post: DMat4,
    /// Post-space linear depth beyond the near plane: `depth_row · (p', 1)`.
    depth_row: DVec4,
    /// Texel size in post units: absolute (orthographic) or per unit distance from `q`.
    texel: f64,
    /// Distance of the near plane from `q` (0 for orthographic maps).
    near: f64,
    orthographic: bool,
}

/// One post-perspective shadow map.
#[derive(Clone, Debug)]
struct PostMap {
    /// World to the map's clip space up to the positive factor `w_p` (the virtual camera's
    /// clip `w`): `clip_from_post · post_from_world`, composed in f64.
    clip_from_world: Mat4,
    /// The post-space linear depth beyond the near plane times `w_p`, as a row on
    /// homogeneous world points.
    depth_world: Vec4,
    /// Texel size in post units: absolute (orthographic) or per unit distance from `q`.
    texel: f32,
    /// Distance of the near plane from `q` (0 for orthographic maps).
    near: f32,
    orthographic: bool,
    /// Stored depths (negated for inverted lights), `+inf` where empty.
    depth: Vec<f32>,
}

impl PostMap {
    fn new(fit: MapFit, post_from_world: &DMat4) -> PostMap {
        PostMap {
            clip_from_world: (fit.clip_from_post * *post_from_world).as_mat4(),
            depth_world: (post_from_world.transpose() * fit.depth_row).as_vec4(),
            texel: fit.texel as f32,
            near: fit.near as f32,
            orthographic: fit.orthographic,
            depth: Vec::new(),
        }
    }

    /// Clip coordinates (divided by `w_p`) and linear depth of a world point whose
    /// virtual-camera `w` has reciprocal `inv_wp`: the one formula for map vertices and
    /// receivers alike.
    #[inline]
    fn transform(&self, p: Vec4, inv_wp: f32) -> (Vec4, f32) {
        (
            self.clip_from_world * p * inv_wp,
            self.depth_world.dot(p) * inv_wp,
        )
    }

    /// Post-space size of one texel at linear depth `depth` (beyond the near plane).
    #[inline]
    fn texel_size(&self, depth: f32) -> f32 {
        if self.orthographic {
            self.texel
        } else {
            self.texel * (depth + self.near).max(self.near)
        }
    }
}

/// The frame's geometry, ready to rasterize.
struct Setup {
    post: PostSpace,
    /// The post-space light position `q` (unused for directional lights).
    q: Vec3,
    /// Unit direction towards a directional post-space light.
    dir: Vec3,
    /// Transposed inverse of `post_from_world`: maps world planes to post planes.
    post_planes: Mat4,
    /// The virtual camera's clip `w` (its view depth) as a row on world points.
    w_row: Vec4,
    /// Depth (along the view axis from the virtual eye) below which triangles are clipped.
    clip_depth: f32,
    maps: Vec<PostMap>,
    /// For a cube: map index of each of the six faces (`usize::MAX` when skipped).
    cube: Option<[usize; 6]>,
}

impl ShadowTechnique for Perspective {
    fn name(&self) -> &'static str {
        "psm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([
            ("resolution".to_string(), self.resolution.into()),
            ("bias".to_string(), self.bias.into()),
            ("slope-bias".to_string(), self.slope_bias.into()),
        ])
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        let t = "psm";
        match key {
            "resolution" => self.resolution = check_resolution(t, parse_value(t, key, value)?)?,
            "bias" => self.bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?,
            "slope-bias" => {
                self.slope_bias = check_range(t, key, parse_value(t, key, value)?, 0.0, 1000.0)?
            }
            _ => return Err(unknown_param(t, key, &["resolution", "bias", "slope-bias"])),
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
            return Ok(Shadows {
                visibility: Visibility {
                    width: w,
                    height: h,
                    value,
                },
                stats,
                layers: None,
            });
        };
        let Some(mut setup) = stats.stage("body", || build_setup(frame, &receivers, res))? else {
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
            let pieces = clipped_pieces(frame, &setup);
            for i in 0..setup.maps.len() {
                let depth = render_post_map(frame, &setup, &setup.maps[i], &pieces, res);
                setup.maps[i].depth = depth;
            }
        });
        let (bias, slope) = (self.bias, self.slope_bias);
        let value = stats.stage("lookup", || {
            lookup(frame, &setup, &receivers.lit, res, bias, slope)
        });
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
        if frame.dumping() {
            dump(frame, &setup, res)?;
        }
        Ok(Shadows {
            visibility: Visibility {
                width: w,
                height: h,
                value,
            },
            stats,
            layers: None,
        })
    }
}

impl Perspective {
    /// The post-perspective space this technique would build for `frame` (the body, the
    /// virtual shift and the light's case), without rendering a map; `None` when no receiver
    /// can be lit or no post-space map fits (the technique then falls back to a uniform map).
    pub fn post_space(&self, frame: &Frame) -> Result<Option<PostSpace>> {
        let res = check_resolution("psm", self.resolution)?;
        frame.light.validate()?;
        match Receivers::gather(frame) {
            None => Ok(None),
            Some(r) => Ok(build_setup(frame, &r, res)?.map(|s| s.post)),
        }
    }
}

/// The visible receivers the light can reach: the camera-pass read-back of Section 6.
struct Receivers {
    /// Per pixel: covered and reachable by the light.
    lit: Vec<bool>,
    /// Their bounds.
    bounds: Aabb,
    /// Nearest and farthest view depth among them.
    depth: (f32, f32),
}

impl Receivers {
    fn gather(frame: &Frame) -> Option<Receivers> {
        let view = frame.view;
        let n = view.triangle.len();
        const CHUNK: usize = 8192;
        let mut lit = vec![false; n];
        let parts: Vec<(Aabb, f32, f32)> = lit
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, out)| {
                let base = c * CHUNK;
                let pos = &view.position[base..base + out.len()];
                let depth = &view.depth[base..base + out.len()];
                let mut b = Aabb::EMPTY;
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for (i, l) in out.iter_mut().enumerate() {
                    *l = frame.receiver_lit(base + i);
                    if *l {
                        b.grow(pos[i]);
                        lo = lo.min(depth[i]);
                        hi = hi.max(depth[i]);
                    }
                }
                (b, lo, hi)
            })
            .collect();
        let mut bounds = Aabb::EMPTY;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (b, a, z) in parts {
            bounds = bounds.union(&b);
            lo = lo.min(a);
            hi = hi.max(z);
        }
        if bounds.is_empty() || lo.is_nan() || lo <= 0.0 {
            return None;
        }
        Some(Receivers {
            lit,
            bounds,
            depth: (lo, hi),
        })
    }
}

// ---------------------------------------------------------------------------------------
// Convex bodies (Section 4.1), in f64.

/// A half-space `n · x <= d`.
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: DVec3,
    d: f64,
}

impl Plane {
    #[inline]
    fn dist(&self, p: DVec3) -> f64 {
        self.n.dot(p) - self.d
    }
}

/// A convex polyhedron as its face polygons.
#[derive(Clone, Debug, Default)]
struct Body {
    faces: Vec<Vec<DVec3>>,
}

/// Faces of a hexahedron whose corners are indexed like [`Aabb::corners`] (bit 0: +x,
/// bit 1: +y, bit 2: +z).
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 2, 6, 4],
    [1, 5, 7, 3],
    [0, 4, 5, 1],
    [2, 3, 7, 6],
    [0, 1, 3, 2],
    [4, 6, 7, 5],
];

impl Body {
    fn hexahedron(c: [DVec3; 8]) -> Body {
        Body {
            faces: HEX_FACES
                .iter()
                .map(|f| f.iter().map(|&i| c[i]).collect())
                .collect(),
        }
    }

    fn from_box(b: &Aabb, pad: f64) -> Body {
        let lo = b.min.as_dvec3() - DVec3::splat(pad);
        let hi = b.max.as_dvec3() + DVec3::splat(pad);
        Body::hexahedron(std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 != 0 { hi.x } else { lo.x },
                if i & 2 != 0 { hi.y } else { lo.y },
                if i & 4 != 0 { hi.z } else { lo.z },
            )
        }))
    }

    fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The distinct vertices.
    fn vertices(&self, tol: f64) -> Vec<DVec3> {
        let mut out: Vec<DVec3> = Vec::new();
        for f in &self.faces {
            for &p in f {
                if !out.iter().any(|q| (*q - p).abs().max_element() <= tol) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The part of the body with `plane.dist(x) <= tol`.
    fn clip(&self, plane: Plane, tol: f64) -> Body {
        let mut faces = Vec::with_capacity(self.faces.len() + 1);
        let mut cap: Vec<DVec3> = Vec::new();
        for f in &self.faces {
            let mut out: Vec<DVec3> = Vec::with_capacity(f.len() + 2);
            for i in 0..f.len() {
                let (a, b) = (f[i], f[(i + 1) % f.len()]);
                let (da, db) = (plane.dist(a), plane.dist(b));
                if da <= tol {
                    out.push(a);
                    if da >= -tol {
                        cap.push(a);
                    }
                }
                if (da < -tol && db > tol) || (da > tol && db < -tol) {
                    // From the inside vertex towards the outside one, so the two faces that
                    // share the edge get the same point.
                    let (pi, di, po, dout) = if da < 0.0 {
                        (a, da, b, db)
                    } else {
                        (b, db, a, da)
                    };
                    let p = pi + (po - pi) * (di / (di - dout));
                    out.push(p);
                    cap.push(p);
                }
            }
            out.dedup_by(|x, y| (*x - *y).abs().max_element() <= tol);
            if out.len() >= 3 {
                faces.push(out);
            }
        }
        let mut pts: Vec<DVec3> = Vec::new();
        for p in cap {
            if !pts.iter().any(|q| (*q - p).abs().max_element() <= tol) {
                pts.push(p);
            }
        }
        if pts.len() >= 3 && !faces.is_empty() {
            // Order the cap polygon by angle around its centroid in the plane.
            let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
            let u = plane.n.any_orthonormal_vector();
            let v = plane.n.cross(u);
            pts.sort_by(|a, b| {
                let aa = (*a - c).dot(v).atan2((*a - c).dot(u));
                let ab = (*b - c).dot(v).atan2((*b - c).dot(u));
                aa.total_cmp(&ab)
            });
            faces.push(pts);
        }
        Body { faces }
    }

    fn clip_all(&self, planes: &[Plane], tol: f64) -> Body {
        let mut b = self.clone();
        for p in planes {
            if b.is_empty() {
                break;
            }
            b = b.clip(*p, tol);
        }
        b
    }
}

/// The outward plane of a face of a body whose interior contains `inside`.
fn face_plane(face: &[DVec3], inside: DVec3) -> Option<Plane> {
    // Newell's method: robust for any planar polygon.
    let mut n = DVec3::ZERO;
    for i in 0..face.len() {
        let (a, b) = (face[i], face[(i + 1) % face.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let n = n.try_normalize()?;
    let c = face.iter().copied().sum::<DVec3>() / face.len() as f64;
    let n = if n.dot(inside - c) > 0.0 { -n } else { n };
    Some(Plane { n, d: n.dot(c) })
}

/// The light as a point, possibly at infinity.
#[derive(Clone, Copy, Debug)]
enum LightPoint {
    At(DVec3),
    /// At infinity in this (unit) direction.
    Towards(DVec3),
}

/// Half-spaces whose intersection is `hull(B ∪ l)`: the faces of `B` that do not face the
/// light, and the planes through the light and each silhouette edge of `B`. Each is
/// pushed out by `tol`, so the hull can only grow.
fn hull_planes(b: &Body, light: LightPoint, tol: f64) -> Vec<Plane> {
    let verts = b.vertices(tol);
    let inside = verts.iter().copied().sum::<DVec3>() / verts.len().max(1) as f64;
    let mut planes = Vec::new();
    for f in &b.faces {
        if let Some(pl) = face_plane(f, inside) {
            let keep = match light {
                LightPoint::At(l) => pl.dist(l) <= tol,
                LightPoint::Towards(d) => pl.n.dot(d) <= 1e-12,
            };
            if keep {
                planes.push(Plane {
                    n: pl.n,
                    d: pl.d + tol,
                });
            }
        }
        for i in 0..f.len() {
            let (a, e) = (f[i], f[(i + 1) % f.len()]);
            if (e - a).length() <= tol {
                continue;
            }
            let m = match light {
                LightPoint::At(l) => (e - a).cross(l - a),
                LightPoint::Towards(d) => (e - a).cross(d),
            };
            let Some(m) = m.try_normalize() else { continue };
            let d = m.dot(a);
            let (lo, hi) = verts
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    let s = m.dot(*v) - d;
                    (lo.min(s), hi.max(s))
                });
            if hi <= tol {
                planes.push(Plane { n: m, d: d + tol });
            } else if lo >= -tol {
                planes.push(Plane { n: -m, d: -d + tol });
            }
        }
    }
    planes
}

/// The four side planes of the square pyramid around a spot light's cone.
fn spot_planes(position: Vec3, target: Vec3, fov_deg: f32) -> [Plane; 4] {
    let l = position.as_dvec3();
    let axis = (target.as_dvec3() - l).normalize();
    let up = pick_up(axis);
    let right = axis.cross(up).normalize();
    let up = right.cross(axis);
    // Slightly wider than the cone, so rounding never cuts a lit receiver off.
    let half = ((fov_deg as f64).to_radians() * 0.5).tan() * (1.0 + 1e-6) + 1e-9;
    [right, -right, up, -up].map(|s| {
        let n = (s - axis * half).normalize();
        Plane { n, d: n.dot(l) }
    })
}

/// An up vector not parallel to `dir`.
fn pick_up(dir: DVec3) -> DVec3 {
    if dir.normalize().y.abs() > 0.99 {
        DVec3::Z
    } else {
        DVec3::Y
    }
}

// ---------------------------------------------------------------------------------------
// Post-perspective space (Sections 3 and 4.2).

/// Right-handed view matrix (looking down −Z) in f64.
fn look_at(eye: DVec3, forward: DVec3, up: DVec3) -> DMat4 {
    let f = forward.normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    DMat4::from_cols(
        DVec4::new(s.x, u.x, -f.x, 0.0),
        DVec4::new(s.y, u.y, -f.y, 0.0),
        DVec4::new(s.z, u.z, -f.z, 0.0),
        DVec4::new(-eye.dot(s), -eye.dot(u), eye.dot(f), 1.0),
    )
}

/// The OpenGL perspective projection (NDC cube `[-1, 1]³`), as the paper uses: the
/// infinity plane lies at `z = (f + n) / (f − n)`.
fn perspective_gl(fov_y: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    DMat4::from_cols(
        DVec4::new(h / aspect, 0.0, 0.0, 0.0),
        DVec4::new(0.0, h, 0.0, 0.0),
        DVec4::new(0.0, 0.0, (far + near) / (near - far), -1.0),
        DVec4::new(0.0, 0.0, 2.0 * far * near / (near - far), 0.0),
    )
}

/// A matrix from its four rows.
fn from_rows(r: [DVec4; 4]) -> DMat4 {
    DMat4::from_cols(r[0], r[1], r[2], r[3]).transpose()
}

/// Builds the post-perspective set-up; `None` when no post-space map can be fitted around
/// the body (degenerate bodies, e.g. every lit receiver in a sliver the post-space light
/// sees edge-on).
fn build_setup(frame: &Frame, rec: &Receivers, res: u32) -> Result<Option<Setup>> {
    let cam = frame.camera;
    let scene = &frame.scene.bounds;
    let scale = scene
        .min
        .abs()
        .max(scene.max.abs())
        .max_element()
        .max(cam.eye.abs().max_element())
        .max(1e-30) as f64;
    let tol = scale * GEOMETRY_TOLERANCE;
    let (right, up, fwd) = cam.basis();
    let (right, up, fwd) = (right.as_dvec3(), up.as_dvec3(), fwd.as_dvec3());
    let eye = cam.eye.as_dvec3();

    // The near plane pushed to the nearest visible receiver, the far plane pulled in.
    let near = rec.depth.0 as f64 * (1.0 - DEPTH_FIT_PAD);
    let far = (rec.depth.1 as f64 * (1.0 + DEPTH_FIT_PAD)).max(near * (1.0 + 1e-3));
    let th = ((cam.fov_y_deg as f64).to_radians() * 0.5).tan() * (1.0 + 1e-6);
    let tw = th * cam.aspect() as f64;
    let frustum = Body::hexahedron(std::array::from_fn(|i| {
        let d = if i & 4 != 0 { far } else { near };
        let x = if i & 1 != 0 { tw } else { -tw };
        let y = if i & 2 != 0 { th } else { -th };
        eye + fwd * d + right * (x * d) + up * (y * d)
    }));

    // B: the part of the view frustum that holds the lit receivers.
    let diag = scene.diagonal() as f64;
    let rpad = diag * RECEIVER_PAD + tol;
    let mut b = frustum.clip_all(&box_planes(&rec.bounds, rpad), tol);
    let light_point = match *frame.light {
        Light::Directional { to_light } => LightPoint::Towards(to_light.as_dvec3().normalize()),
        Light::Point { position } => LightPoint::At(position.as_dvec3()),
        Light::Spot {
            position,
            target,
            fov_deg,
        } => {
            b = b.clip_all(&spot_planes(position, target, fov_deg), tol);
            LightPoint::At(position.as_dvec3())
        }
    };
    if b.is_empty() {
        // Rounding removed a body that holds receivers: fall back to their box.
        b = Body::from_box(&rec.bounds, rpad);
    }
    // H = hull(B ∪ l) ∩ S.
    let sbox = Body::from_box(scene, rpad);
    let mut hbody = sbox.clip_all(&hull_planes(&b, light_point, tol), tol);
    if hbody.is_empty() {
        hbody = b.clone();
    }
    let body = hbody.vertices(tol);

    // Virtual camera shift: bring H behind the near plane (Section 4.2).
    let min_depth = body
        .iter()
        .map(|p| (*p - eye).dot(fwd))
        .fold(f64::INFINITY, f64::min);
    let shift = if min_depth < near * (1.0 - SHIFT_SLACK) {
        near - min_depth
    } else {
        0.0
    };
    let veye = eye - fwd * shift;
    // Near stays, far grows to hold the whole previous frustum.
    let vfar = far + shift;
    let post_from_world = perspective_gl(
        (cam.fov_y_deg as f64).to_radians(),
        cam.aspect() as f64,
        near,
        vfar,
    ) * look_at(veye, fwd, cam.up.as_dvec3());

    // The light in post-perspective space.
    let lh = match *frame.light {
        Light::Directional { to_light } => to_light.as_dvec3().normalize().extend(0.0),
        Light::Point { position } | Light::Spot { position, .. } => position.as_dvec3().extend(1.0),
    };
    let lp = post_from_world * lh;
    let pts: Vec<DVec3> = body
        .iter()
        .map(|p| {
            let h = post_from_world * p.extend(1.0);
            h.truncate() / h.w
        })
        .collect();
    let (lo, hi) = pts
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let size = (hi - lo).length().max(1e-12);
    let centre = (lo + hi) * 0.5;
    let xyz = lp.truncate();
    let directional = lp.w == 0.0 || xyz.length() / lp.w.abs() > DIRECTIONAL_DISTANCE_RATIO * size;
    let world_directional = matches!(frame.light, Light::Directional { .. });

    let mut maps: Vec<MapFit> = Vec::new();
    let mut cube = None;
    let (kind, q, dir) = if directional {
        let dir = xyz.normalize();
        maps.push(fit_orthographic(dir, centre, &pts, res));
        (PostLight::Directional, DVec3::ZERO, dir)
    } else {
        let q = xyz / lp.w;
        let kind = if lp.w > 0.0 {
            PostLight::Point
        } else {
            PostLight::Inverted
        };
        let limit = if world_directional || kind == PostLight::Inverted {
            f64::INFINITY
        } else {
            MAX_POINT_TANGENT
        };
        match fit_perspective(q, &pts, res, limit) {
            Some(m) => maps.push(m),
            None => {
                let mut faces = [usize::MAX; 6];
                for (i, (axis, up)) in CUBE_FACES.iter().enumerate() {
                    if let Some(m) = fit_cube_face(q, axis.as_dvec3(), up.as_dvec3(), &pts, res) {
                        faces[i] = maps.len();
                        maps.push(m);
                    }
                }
                cube = Some(faces);
            }
        }
        (kind, q, DVec3::ZERO)
    };
    if maps.is_empty() {
        return Ok(None);
    }
    let post_from_world_f = post_from_world.as_mat4();
    let maps: Vec<PostMap> = maps
        .into_iter()
        .map(|m| PostMap::new(m, &post_from_world))
        .collect();
    let post = PostSpace {
        post_from_world: post_from_world_f,
        light: kind,
        light_post: lp,
        virtual_shift: shift,
        near,
        far: vfar,
        body,
        maps: maps.len(),
    };
    Ok(Some(Setup {
        post,
        q: q.as_vec3(),
        dir: dir.as_vec3(),
        post_planes: post_from_world.inverse().transpose().as_mat4(),
        w_row: post_from_world.row(3).as_vec4(),
        clip_depth: (near * CLIP_DEPTH_FRACTION as f64) as f32,
        maps,
        cube,
    }))
}

/// The six planes of a box, pushed out by `pad`.
fn box_planes(b: &Aabb, pad: f64) -> [Plane; 6] {
    let (lo, hi) = (b.min.as_dvec3() - pad, b.max.as_dvec3() + pad);
    [
        Plane {
            n: DVec3::X,
            d: hi.x,
        },
        Plane {
            n: -DVec3::X,
            d: -lo.x,
        },
        Plane {
            n: DVec3::Y,
            d: hi.y,
        },
        Plane {
            n: -DVec3::Y,
            d: -lo.y,
        },
        Plane {
            n: DVec3::Z,
            d: hi.z,
        },
        Plane {
            n: -DVec3::Z,
            d: -lo.z,
        },
    ]
}

/// Orthographic map along the post-space light direction `dir` (towards the light).
fn fit_orthographic(dir: DVec3, centre: DVec3, pts: &[DVec3], res: u32) -> MapFit {
    let up0 = pick_up(dir);
    let right = up0.cross(dir).normalize();
    let up = dir.cross(right);
    // Light view: x = right, y = up, z = towards the light; depth = −z grows away from it.
    let (mut x0, mut x1, mut y0, mut y1, mut d0, mut d1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts {
        let r = *p - centre;
        let (x, y, d) = (r.dot(right), r.dot(up), -r.dot(dir));
        (x0, x1, y0, y1, d0, d1) = (
            x0.min(x),
            x1.max(x),
            y0.min(y),
            y1.max(y),
            d0.min(d),
            d1.max(d),
        );
    }
    let span = (x1 - x0).max(y1 - y0).max(1e-12);
    let (hx, hy) = (window_half(x1 - x0, span), window_half(y1 - y0, span));
    let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
    let pad = (d1 - d0).max(span * 1e-3) * DEPTH_PAD;
    let (near, far) = (d0 - pad, d1 + pad);
    // Rows in post space, constants taken relative to the centre in f64.
    let rx = DVec4::from((right / hx, -(right.dot(centre) + cx) / hx));
    let ry = DVec4::from((up / hy, -(up.dot(centre) + cy) / hy));
    // depth beyond near = −dir·(p − centre) − near
    let depth = DVec4::from((-dir, dir.dot(centre) - near));
    let rz = depth / (far - near);
    let rw = DVec4::new(0.0, 0.0, 0.0, 1.0);
    MapFit {
        clip_from_post: from_rows([rx, ry, rz, rw]),
        depth_row: depth,
        texel: 2.0 * hx.max(hy) / res as f64,
        near: 0.0,
        orthographic: true,
    }
}

/// Half the window for a span of `s`, padded, and at least a sliver of the larger span so a
/// flat body still gets a non-degenerate window.
fn window_half(s: f64, span: f64) -> f64 {
    (s.max(span * 1e-3) * 0.5) * (1.0 + 2.0 * WINDOW_PAD)
}

/// An orthonormal light frame looking along `axis`: (right, up).
fn frame_of(axis: DVec3, up_hint: DVec3) -> (DVec3, DVec3) {
    let right = axis.cross(up_hint).normalize();
    (right, right.cross(axis))
}

/// A perspective map from `q` that sees every point of `pts` in front of it, its window
/// off-centre in the tangent plane. `None` when no axis sees them all in front, or the
/// window would need tangents beyond `max_tangent`.
fn fit_perspective(q: DVec3, pts: &[DVec3], res: u32, max_tangent: f64) -> Option<MapFit> {
    let mut axis = pts
        .iter()
        .filter_map(|p| (*p - q).try_normalize())
        .sum::<DVec3>()
        .try_normalize()?;
    if pts.iter().any(|p| (*p - q).length() == 0.0) {
        return None;
    }
    // Two passes: the second recentres the axis on the first window.
    let mut window = None;
    for _ in 0..2 {
        let (right, up) = frame_of(axis, pick_up(axis));
        let (mut x0, mut x1, mut y0, mut y1, mut t0, mut t1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in pts {
            let r = *p - q;
            let t = r.dot(axis);
            if t.is_nan() || t <= 1e-9 * r.length() {
                return None;
            }
            let (x, y) = (r.dot(right) / t, r.dot(up) / t);
            (x0, x1, y0, y1, t0, t1) = (
                x0.min(x),
                x1.max(x),
                y0.min(y),
                y1.max(y),
                t0.min(t),
                t1.max(t),
            );
        }
        window = Some((axis, right, up, x0, x1, y0, y1, t0, t1));
        let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
        axis = (axis + right * cx + up * cy).normalize();
    }
    let (axis, right, up, x0, x1, y0, y1, t0, t1) = window?;
    if [x0, x1, y0, y1].iter().any(|x| x.abs() > max_tangent) {
        return None;
    }
    let span = (x1 - x0).max(y1 - y0).max(1e-12);
    let (hx, hy) = (window_half(x1 - x0, span), window_half(y1 - y0, span));
    let (cx, cy) = ((x0 + x1) * 0.5, (y0 + y1) * 0.5);
    let (near, far) = depth_range(t0, t1);
    Some(perspective_map(
        q,
        (axis, right, up),
        (cx, cy, hx, hy),
        (near, far),
        res,
    ))
}

/// The near and far distances of a perspective map whose body spans `t0..t1` from `q`,
/// padded by a fraction of the span (not of the distance: for a far `q` that would push the
/// near plane far off and leave the stored depths, measured from it, without f32 digits).
fn depth_range(t0: f64, t1: f64) -> (f64, f64) {
    let span = (t1 - t0).max(t1 * 1e-6);
    (
        (t0 - DEPTH_PAD * span).max(t0 * (1.0 - DEPTH_PAD)),
        t1 + DEPTH_PAD * span,
    )
}

/// One 90° cube face around `q`, or `None` when every point of `pts` lies outside it.
fn fit_cube_face(q: DVec3, axis: DVec3, up_hint: DVec3, pts: &[DVec3], res: u32) -> Option<MapFit> {
    let (right, up) = frame_of(axis, up_hint);
    // Skip the face when one of its side planes separates it from the convex body.
    for s in [right, -right, up, -up] {
        if pts.iter().all(|p| (*p - q).dot(s) > (*p - q).dot(axis)) {
            return None;
        }
    }
    let t1 = pts
        .iter()
        .map(|p| (*p - q).dot(axis))
        .fold(f64::NEG_INFINITY, f64::max);
    if t1.is_nan() || t1 <= 0.0 {
        return None;
    }
    let t0 = pts
        .iter()
        .map(|p| (*p - q).dot(axis))
        .fold(f64::INFINITY, f64::min);
    // When q lies inside the body the near plane goes down to a small fraction of far.
    let (near, far) = if t0 > 0.0 {
        depth_range(t0, t1)
    } else {
        (t1 * 1e-4, t1 * (1.0 + DEPTH_PAD))
    };
    Some(perspective_map(
        q,
        (axis, right, up),
        (0.0, 0.0, 1.0, 1.0),
        (near, far),
        res,
    ))
}

/// A perspective map from `q` along `axis` (with image axes `right`, `up`) whose window is
/// `cx ± hx, cy ± hy` in tangent coordinates, depth range `near..far` along the axis.
fn perspective_map(
    q: DVec3,
    (axis, right, up): (DVec3, DVec3, DVec3),
    (cx, cy, hx, hy): (f64, f64, f64, f64),
    (near, far): (f64, f64),
    res: u32,
) -> MapFit {
    // With t = axis·(p − q): x_ndc = (right·(p − q) / t − cx) / hx, and likewise y; clip
    // w = t; clip z = far (t − near) / (far − near) so that 0 ≤ z ≤ w spans near..far.
    // Each row keeps its constant in f64 before rounding, so a distant q loses no precision
    // in the depth row.
    let ax = (right - axis * cx) / hx;
    let ay = (up - axis * cy) / hy;
    let rx = DVec4::from((ax, -ax.dot(q)));
    let ry = DVec4::from((ay, -ay.dot(q)));
    let depth = DVec4::from((axis, -axis.dot(q) - near));
    let rz = depth * (far / (far - near));
    let rw = DVec4::from((axis, -axis.dot(q)));
    MapFit {
        clip_from_post: from_rows([rx, ry, rz, rw]),
        depth_row: depth,
        texel: 2.0 * hx.max(hy) / res as f64,
        near,
        orthographic: false,
    }
}

// ---------------------------------------------------------------------------------------
// Rasterization and look-ups.

/// Clips a world triangle to `depth >= clip` (depth = `w_row · (p, 1)`), returning 0, 1 or
/// 2 triangles.
fn clip_triangle(t: [Vec3; 3], w_row: Vec4, clip: f32, out: &mut Vec<[Vec3; 3]>) {
    let d = t.map(|p| w_row.dot(p.extend(1.0)) - clip);
    let mut poly: Vec<Vec3> = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (t[i], t[(i + 1) % 3]);
        let (da, db) = (d[i], d[(i + 1) % 3]);
        if da >= 0.0 {
            poly.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let (pi, di, po, dout) = if da >= 0.0 {
                (a, da, b, db)
            } else {
                (b, db, a, da)
            };
            poly.push(pi + (po - pi) * (di / (di - dout)));
        }
    }
    for k in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}

/// The pieces of the triangles that cross the clip plane `w_row · p = clip`, cut in world
/// space (the whole ones go to the rasterizer as they are).
fn clipped_pieces(frame: &Frame, setup: &Setup) -> Vec<[Vec3; 3]> {
    let scene = frame.scene;
    let (w_row, clip) = (setup.w_row, setup.clip_depth);
    if scene
        .bounds
        .corners()
        .iter()
        .all(|p| w_row.dot(p.extend(1.0)) >= clip)
    {
        return Vec::new();
    }
    const CHUNK: usize = 8192;
    let parts: Vec<Vec<[Vec3; 3]>> = (0..scene.len().div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            for i in c * CHUNK..((c + 1) * CHUNK).min(scene.len()) {
                let t = scene.triangle(i);
                let d = t.map(|p| w_row.dot(p.extend(1.0)));
                let lo = d[0].min(d[1]).min(d[2]);
                let hi = d[0].max(d[1]).max(d[2]);
                if lo < clip && hi >= clip {
                    clip_triangle(t, w_row, clip, &mut out);
                }
            }
            out
        })
        .collect();
    parts.concat()
}

/// Rasterizes the scene (whole triangles in front of the clip plane, and `pieces`) into
/// one post-perspective map.
fn render_post_map(
    frame: &Frame,
    setup: &Setup,
    map: &PostMap,
    pieces: &[[Vec3; 3]],
    res: u32,
) -> Vec<f32> {
    let scene = frame.scene;
    let (w_row, clip) = (setup.w_row, setup.clip_depth);
    let sign = if setup.post.light == PostLight::Inverted {
        -1.0f32
    } else {
        1.0
    };
    let n = scene.len();
    let setups: Vec<SetupTriangle> = raster::setup(n + pieces.len(), res, res, |i| {
        let t = if i < n {
            scene.triangle(i)
        } else {
            pieces[i - n]
        };
        let h = t.map(|p| p.extend(1.0));
        let wp = h.map(|h| w_row.dot(h));
        if i < n && wp.iter().any(|&w| w < clip) {
            // Behind the clip plane, or cut into `pieces`.
            return ([Vec4::NAN; 3], [0.0; 3]);
        }
        let v: [(Vec4, f32); 3] = std::array::from_fn(|k| map.transform(h[k], 1.0 / wp[k]));
        (
            [v[0].0, v[1].0, v[2].0],
            [sign * v[0].1, sign * v[1].1, sign * v[2].1],
        )
    });
    let tiles = raster::rasterize(
        &setups,
        res,
        res,
        |r| vec![f32::INFINITY; (r.width() * r.height()) as usize],
        |d: &mut Vec<f32>, r, f| {
            let k = ((f.y - r.y0) * r.width() + (f.x - r.x0)) as usize;
            if f.depth < d[k] {
                d[k] = f.depth;
            }
        },
    );
    let mut out = vec![f32::INFINITY; res as usize * res as usize];
    for (r, d) in tiles {
        for y in r.y0..r.y1 {
            let src = ((y - r.y0) * r.width()) as usize;
            let dst = (y * res + r.x0) as usize;
            out[dst..dst + r.width() as usize].copy_from_slice(&d[src..src + r.width() as usize]);
        }
    }
    out
}

/// Per-pixel shadow test against the post-perspective maps.
fn lookup(
    frame: &Frame,
    setup: &Setup,
    lit: &[bool],
    res: u32,
    bias: f32,
    slope: f32,
) -> Vec<Vec3> {
    let view = frame.view;
    let pfw = setup.post.post_from_world;
    let planes = setup.post_planes;
    let sign = if setup.post.light == PostLight::Inverted {
        -1.0f32
    } else {
        1.0
    };
    let kind = setup.post.light;
    let (fres, ires) = (res as f32, res as i64 - 1);
    let shadow = |p: Vec3, nw: Vec3| -> f32 {
        let h = p.extend(1.0);
        let inv_wp = 1.0 / setup.w_row.dot(h);
        // The post-space position is needed only towards a post-space point light.
        let pp = if kind == PostLight::Directional {
            Vec3::ZERO
        } else {
            (pfw * h).truncate() * inv_wp
        };
        let map = match setup.cube {
            None => &setup.maps[0],
            Some(faces) => match faces[cube_face(pp - setup.q)] {
                usize::MAX => return 1.0,
                i => &setup.maps[i],
            },
        };
        let (c, depth) = map.transform(h, inv_wp);
        let inv_cw = 1.0 / c.w;
        let (u, v) = (c.x * inv_cw * 0.5 + 0.5, 0.5 - c.y * inv_cw * 0.5);
        // The receiver's plane and the light direction in post-perspective space.
        let np = (planes * nw.extend(-nw.dot(p)))
            .truncate()
            .normalize_or_zero();
        let l = match kind {
            PostLight::Directional => setup.dir,
            PostLight::Point => (setup.q - pp).normalize_or_zero(),
            PostLight::Inverted => (pp - setup.q).normalize_or_zero(),
        };
        let offset = receiver_bias(map.texel_size(depth), np, l, bias, slope);
        let x = ((u * fres).floor() as i64).clamp(0, ires) as usize;
        let y = ((v * fres).floor() as i64).clamp(0, ires) as usize;
        if sign * depth - offset > map.depth[y * res as usize + x] {
            0.0
        } else {
            1.0
        }
    };
    const CHUNK: usize = 4096;
    let mut value = vec![Vec3::ONE; lit.len()];
    value
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let base = c * CHUNK;
            let range = base..base + out.len();
            let (lit, pos, nrm) = (
                &lit[range.clone()],
                &view.position[range.clone()],
                &view.normal[range],
            );
            for (i, o) in out.iter_mut().enumerate() {
                *o = if lit[i] {
                    Vec3::splat(shadow(pos[i], nrm[i]))
                } else if view.covered(base + i) {
                    Vec3::ZERO
                } else {
                    Vec3::ONE
                };
            }
        });
    value
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
