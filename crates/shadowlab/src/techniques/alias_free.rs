//! `afsm`: alias-free shadow maps (Aila & Laine, "Alias-Free Shadow Maps", EGSR 2004).
//!
//! Idea: the visible samples of the camera pass are transformed to the light's image plane
//! and used as the sampling points of the shadow map, so every sample gets the shadow term
//! of its own shadow ray and there is no map resolution to alias. The samples are organised
//! in an axis-aligned 2D BSP tree and every caster triangle is rasterized hierarchically
//! into it: the traversal descends only into nodes the triangle's light-space footprint
//! overlaps, and in the leaves each sample is tested for coverage and depth, the shadow term
//! going straight to the sample's screen pixel.
//!
//! Steps of a frame, named as the paper names them and timed as its Table 1:
//! - *transform*: each lit sample's shadow ray (origin offset by the position's error bound,
//!   exactly as the reference offsets it) is projected to the light's image plane: an
//!   orthographic plane for a directional light, the spot light's own perspective plane, or,
//!   for a point light, the cube face its direction falls on (one BSP per face).
//! - *bsp*: alternating x/y splits at the median (quickselect, expected linear time) until a
//!   leaf holds at most `leaf-size` samples (64, as in the paper). Every node keeps the tight
//!   bounding rectangle of its samples and their maximum light depth.
//! - *raster*: each triangle's footprint (bounding rectangle and three edge functions) and
//!   minimum depth cull nodes; a leaf tests its samples one by one.
//!   The paper's occlusion culling: a node whose samples are all in shadow is skipped by every
//!   later triangle, and a triangle beyond a node's maximum depth skips the node.
//!
//! The counters follow the paper's Table 1: `bsp_nodes`, `nodes_visited`,
//! `nodes_occlusion_culled`, `samples_tested` (samples not yet dark in the leaves visited),
//! plus `ray_tests` (samples inside a triangle's footprint that took the exact test).
//!
//! Invariants:
//! - The final per-sample decision is the watertight ray–triangle test of
//!   [`crate::math::intersect_triangle`] on the very ray the reference traces (same origin,
//!   direction and length, the sample's own triangle skipped), evaluated with the same
//!   floating-point operations: the answer equals the reference's bit for bit. The
//!   hierarchy only decides which pairs reach that test; every culling test is widened by
//!   [`CULL_TOLERANCE`] so it can never drop a pair the exact test would count.
//! - Semi-transparent casters modulate the sample's RGB transmittance in triangle-index
//!   order and an opaque one sets it to black: the product equals the reference's.
//! - Semi-transparent receivers (Section 4): when the frame carries the layers behind its
//!   semi-transparent surfaces ([`Frame::layers`], every visible surface of each pixel down
//!   to the first opaque one), their samples join the pixels' samples in the same BSP,
//!   each with its own shadow ray and its own shadow term ([`Shadows::layers`]); the image
//!   composites them (`shade::shade_layers`).
//! - The work is split over the subtrees of the BSP (each owns its samples), and each
//!   subtree takes its triangles in index order: results and counters are identical for
//!   any thread count.
//!
//! Departures from the paper:
//! - Coverage in the leaves is decided by the shadow ray's watertight test (the light-space
//!   projection along that very ray) instead of edge functions on the projected image plane,
//!   and the depth comparison by the ray parameter: the paper notes the remaining difference
//!   to shadow rays is only floating-point error; doing the final test on the ray removes it,
//!   so shadows agree with ray tracing exactly and shared edges never leak.
//! - Edge functions are homogeneous (the planes through the light and each triangle edge), so
//!   triangles that cross the plane of a perspective view need no clipping.
//! - This technique does not use the shared rasterizer: its sampling points are irregular,
//!   which is the paper's point; the regular-grid rasterizer cannot sample them.
//! - Point lights get six BSPs (one per cube face); the paper mentions several maps.
//! - A triangle's traversal starts at the deepest node whose subtree holds every sample its
//!   rectangle can contain (found through a uniform grid over the root), not at the root:
//!   small triangles skip the top levels, so fewer nodes are visited than in a root-first
//!   traversal for the same result.
//! - A triangle nearly edge-on from the light, whose orientation rounding could flip, is
//!   bounded by the slab along its longest edge instead of its three edge functions.
//!
//! Known artifacts: none beyond those of the reference (hard shadows only). A triangle
//! lying in the plane of a light ray (edge-on, or a point light on a surface) is decided by
//! floating-point ties exactly as the reference decides it. Cost grows with the number of
//! nodes each triangle visits; large numbers of tiny triangles dominate.

use super::{
    check_range, parse_value, unknown_param, Frame, ShadowTechnique, Shadows, Stats, Visibility,
};
use crate::error::Result;
use crate::light::{cube_face, pick_up, Light, CUBE_FACES};
use crate::math::{Aabb, Vec3};
use crate::scene::Scene;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};

/// The paper's leaf size: a leaf holds at most this many samples.
pub const DEFAULT_LEAF_SIZE: u32 = 64;
/// The largest leaf size accepted.
pub const MAX_LEAF_SIZE: u32 = 1 << 20;

/// Widening of every hierarchical culling test, in relative floating-point error: vertices
/// and samples are treated as uncertain by 64 ulps of the scene's size (directional light)
/// or of the distances to the light (point and spot lights), several times what the
/// shadow-ray test's rounding can move them. Larger values only send more samples to the
/// exact per-sample test (slower, never wrong); a value below the rounding error of the
/// shadow-ray test would let the hierarchy skip a sample the ray test counts as shadowed.
pub const CULL_TOLERANCE: f32 = 64.0 * f32::EPSILON;

/// BSP depth of the subtrees that are the units of parallel work (up to 2⁶ = 64 units):
/// enough for load balance on a few cores while the binning above them stays cheap.
const UNIT_DEPTH: u32 = 6;
/// Below this many samples a BSP subtree is built on one thread.
const PARALLEL_BUILD_MIN: usize = 32 * 1024;
/// Triangles per chunk of the binning pass (a fixed size keeps counters independent of the
/// thread count).
const BIN_CHUNK: usize = 8 * 1024;
/// Alias-free shadow maps: exact hard shadows by irregular rasterization.
#[derive(Clone, Debug)]
pub struct AliasFree {
    /// A BSP leaf holds at most this many samples.
    pub leaf_size: u32,
    /// The per-sample buffers of the last frame, kept so the next frame writes into memory
    /// that is already mapped instead of page-faulting tens of megabytes in again.
    buffers: Buffers,
}

impl Default for AliasFree {
    fn default() -> Self {
        AliasFree {
            leaf_size: DEFAULT_LEAF_SIZE,
            buffers: Buffers::default(),
        }
    }
}

/// Spare vectors of one element type, handed out emptied and taken back after the frame.
#[derive(Clone, Debug)]
struct Pool<T>(Vec<Vec<T>>);

impl<T> Default for Pool<T> {
    fn default() -> Self {
        Pool(Vec::new())
    }
}

impl<T> Pool<T> {
    /// An empty vector, with the capacity of one given back earlier when there is one.
    fn take(&mut self) -> Vec<T> {
        let mut v = self.0.pop().unwrap_or_default();
        v.clear();
        v
    }

    fn give(&mut self, v: Vec<T>) {
        self.0.push(v);
    }
}

/// The per-frame buffers, one pool per element type.
#[derive(Clone, Debug, Default)]
struct Buffers {
    rays: Pool<ShadowRay>,
    pts: Pool<Pt>,
    bytes: Pool<u8>,
    coords: Pool<f32>,
    vis: Pool<Vec3>,
    flags: Pool<bool>,
}

impl ShadowTechnique for AliasFree {
    fn name(&self) -> &'static str {
        "afsm"
    }

    fn params(&self) -> BTreeMap<String, serde_json::Value> {
        BTreeMap::from([("leaf-size".to_string(), self.leaf_size.into())])
    }

    fn set_param(&mut self, key: &str, value: &str) -> Result<()> {
        match key {
            "leaf-size" => {
                self.leaf_size = check_range(
                    "afsm",
                    key,
                    parse_value("afsm", key, value)?,
                    1,
                    MAX_LEAF_SIZE,
                )?
            }
            _ => return Err(unknown_param("afsm", key, &["leaf-size"])),
        }
        Ok(())
    }

    fn render(&mut self, frame: &Frame) -> Result<Shadows> {
        frame.light.validate()?;
        let mut stats = Stats::default();
        let leaf = self.leaf_size.max(1) as usize;
        let buf = &mut self.buffers;
        let planes = stats.stage("transform", || transform(frame, buf));
        let trees: Vec<Bsp> = stats.stage("bsp", || {
            planes
                .into_iter()
                .map(|p| Bsp::build(p, leaf, buf))
                .collect()
        });
        let (visibility, layers, counters) =
            stats.stage("raster", || rasterize(frame, &trees, buf));
        let nodes: usize = trees.iter().map(|t| t.nodes.len()).sum();
        let samples: usize = trees.iter().map(|t| t.su.len()).sum();
        stats.count("samples", samples as f64);
        stats.count("bsp_nodes", nodes as f64);
        stats.count("light_planes", trees.len() as f64);
        stats.count("nodes_visited", counters.nodes_visited as f64);
        stats.count("nodes_occlusion_culled", counters.occlusion_culled as f64);
        stats.count("samples_tested", counters.samples_tested as f64);
        stats.count("ray_tests", counters.ray_tests as f64);
        stats.count("triangles_binned", counters.triangles_binned as f64);
        // Coordinates, shadow ray, transmittance and flag of every sample.
        let per_sample = 3 * 4 + std::mem::size_of::<ShadowRay>() + std::mem::size_of::<Vec3>() + 1;
        stats.memory_bytes = (samples * per_sample
            + nodes * std::mem::size_of::<Node>()
            + counters.setup_bytes) as u64;
        for (i, t) in trees.iter().enumerate() {
            frame.dump_image(&format!("afsm-bsp{i}.png"), || bsp_picture(t))?;
        }
        for t in trees {
            t.recycle(&mut self.buffers);
        }
        Ok(Shadows {
            layers,
            ..Shadows::new(visibility, stats)
        })
    }
}

/// Side of the BSP picture written by `--dump`.
const DUMP_SIDE: u32 = 1024;

/// Draws one light plane's sample points (grey, brighter where denser) and the rectangles
/// of the BSP leaves (blue) over the root's rectangle.
fn bsp_picture(t: &Bsp) -> crate::picture::RgbImage {
    let side = DUMP_SIDE;
    let mut img = crate::picture::RgbImage::new(side, side);
    let Some(root) = t.nodes.first() else {
        return img;
    };
    let (lo, hi) = (root.lo, root.hi);
    let span = [
        (hi[0] - lo[0]).max(f32::MIN_POSITIVE),
        (hi[1] - lo[1]).max(f32::MIN_POSITIVE),
    ];
    let to_px = |u: f32, v: f32| {
        let x = ((u - lo[0]) / span[0] * (side - 1) as f32).clamp(0.0, (side - 1) as f32) as u32;
        let y = ((v - lo[1]) / span[1] * (side - 1) as f32).clamp(0.0, (side - 1) as f32) as u32;
        (x, y)
    };
    for (&u, &v) in t.su.iter().zip(&t.sv) {
        let (x, y) = to_px(u, v);
        let p = img.get_pixel_mut(x, y);
        p.0 = p.0.map(|c| c.saturating_add(48));
    }
    for n in t.nodes.iter().filter(|n| n.is_leaf() && n.len > 0) {
        let (x0, y0) = to_px(n.lo[0], n.lo[1]);
        let (x1, y1) = to_px(n.hi[0], n.hi[1]);
        crate::picture::outline_rect(&mut img, x0, y0, x1, y1, [40, 110, 255]);
    }
    img
}

// ---------------------------------------------------------------------------------------
// The exact per-sample test.

/// A sample's shadow ray, pre-sheared for the watertight test.
#[derive(Clone, Copy, Debug)]
struct ShadowRay {
    /// Ray origin (the offset surface point).
    o: [f32; 3],
    /// Shear constants `sx, sy, sz` of the watertight test.
    s: [f32; 3],
    /// Length of the segment to the light (infinite for a directional light).
    t_max: f32,
    /// Axis permutation `kx, ky, kz`.
    k: [u8; 3],
    /// The triangle the sample lies on (never its own occluder).
    own: u32,
    /// Where the sample's shadow term goes: its screen pixel, or, past the last pixel,
    /// its layer sample (`pixels + i` for layer sample `i`).
    pixel: u32,
}

impl ShadowRay {
    /// The ray `o + t·dir`, `t ∈ (0, t_max)`. The set-up repeats
    /// [`crate::math::intersect_triangle`]'s operations exactly.
    fn new(o: Vec3, dir: Vec3, t_max: f32, own: u32, pixel: u32) -> Self {
        let kz = dir.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        let sx = dir[kx] * sz;
        let sy = dir[ky] * sz;
        ShadowRay {
            o: o.to_array(),
            s: [sx, sy, sz],
            t_max,
            k: [kx as u8, ky as u8, kz as u8],
            own,
            pixel,
        }
    }

    /// True when the ray hits triangle `v` strictly between its ends: the same answer, from
    /// the same floating-point operations, as `intersect_triangle(o, dir, 0, t_max, v)`.
    #[inline]
    fn hits(&self, v: &[[f32; 3]; 3]) -> bool {
        let [kx, ky, kz] = self.k.map(|k| k as usize);
        let [sx, sy, sz] = self.s;
        let o = self.o;
        let a = [v[0][0] - o[0], v[0][1] - o[1], v[0][2] - o[2]];
        let b = [v[1][0] - o[0], v[1][1] - o[1], v[1][2] - o[2]];
        let c = [v[2][0] - o[0], v[2][1] - o[1], v[2][2] - o[2]];
        // Shear the vertices into the ray's space.
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut w = ax * cy - ay * cx;
        let mut x = bx * ay - by * ax;
        // Double precision on the edges, where f32 cannot decide the sign.
        if u == 0.0 || w == 0.0 || x == 0.0 {
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            w = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            x = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || w < 0.0 || x < 0.0) && (u > 0.0 || w > 0.0 || x > 0.0) {
            return false;
        }
        let det = u + w + x;
        if det == 0.0 {
            return false;
        }
        let az = sz * a[kz];
        let bz = sz * b[kz];
        let cz = sz * c[kz];
        let t_scaled = u * az + w * bz + x * cz;
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        t > 0.0 && t < self.t_max
    }
}

// ---------------------------------------------------------------------------------------
// Transform: samples to light image planes.

/// How world points map to one light image plane.
#[derive(Clone, Copy, Debug)]
enum Projection {
    /// Orthographic along a directional light: `(u, v, depth) = ((p − c)·s, (p − c)·t, (p − c)·w)`
    /// with `w` pointing away from the light.
    Ortho { c: Vec3, s: Vec3, t: Vec3, w: Vec3 },
    /// Perspective from a light position `l` looking along `f`: with `q = p − l`,
    /// `(x, y, z) = (q·s, q·t, q·f)` and `(u, v) = (x/z, y/z)`, depth `z`.
    Persp { l: Vec3, s: Vec3, t: Vec3, f: Vec3 },
}

impl Projection {
    /// Where `p` falls on the plane; `None` where a perspective projection is undefined
    /// (at or behind the light's plane).
    #[inline]
    fn project(&self, p: Vec3, id: u32) -> Option<Pt> {
        match *self {
            Projection::Ortho { c, s, t, w } => {
                let q = p - c;
                Some(Pt {
                    u: q.dot(s),
                    v: q.dot(t),
                    z: q.dot(w),
                    id,
                })
            }
            Projection::Persp { l, s, t, f } => {
                let q = p - l;
                let z = q.dot(f);
                let (u, v) = (q.dot(s) / z, q.dot(t) / z);
                (z > 0.0 && u.is_finite() && v.is_finite()).then_some(Pt { u, v, z, id })
            }
        }
    }
}

/// A sample projected to a light image plane.
#[derive(Clone, Copy, Debug)]
struct Pt {
    u: f32,
    v: f32,
    /// Light depth (distance along the plane's axis).
    z: f32,
    /// Index into the plane's shadow rays.
    id: u32,
}

/// The samples of one light image plane, before the BSP is built.
struct Plane {
    proj: Projection,
    pts: Vec<Pt>,
    rays: Vec<ShadowRay>,
    /// Scale of the culling tolerance: the scene's diagonal (orthographic), or the farthest
    /// sample plus the farthest scene corner from the light (perspective).
    scale: f32,
}

/// Pixels per block of the transform pass.
const TRANSFORM_BLOCK: usize = 4096;

/// The lit samples' shadow rays, exactly as the reference forms them, each projected by
/// `proj` (or by the cube face of its direction when `proj` is `None`).
fn shadow_rays(
    frame: &Frame,
    proj: Option<&Projection>,
    cube: &[Projection; 6],
    buf: &mut Buffers,
) -> (Vec<ShadowRay>, Vec<Pt>, Vec<u8>) {
    let view = frame.view;
    let light = frame.light;
    let pixels = view.triangle.len();
    let layers = frame.layers;
    // Receivers: the pixels' nearest surfaces, then the layer samples behind them.
    let n = pixels + layers.map_or(0, |l| l.len());
    let lit = |k: usize| match layers {
        Some(l) if k >= pixels => frame.layer_lit(l, k - pixels),
        _ => frame.receiver_lit(k),
    };
    let receiver = |k: usize| match layers {
        Some(l) if k >= pixels => {
            let i = k - pixels;
            (l.surface_point(i), l.normal[i], l.triangle[i])
        }
        _ => (view.surface_point(k), view.normal[k], view.triangle[k]),
    };
    // Count the lit samples of each block, so every block writes its own slice.
    let counts: Vec<usize> = (0..n.div_ceil(TRANSFORM_BLOCK))
        .into_par_iter()
        .map(|b| {
            (b * TRANSFORM_BLOCK..((b + 1) * TRANSFORM_BLOCK).min(n))
                .filter(|&k| lit(k))
                .count()
        })
        .collect();
    let total: usize = counts.iter().sum();
    let placeholder = ShadowRay::new(Vec3::ZERO, Vec3::Z, 0.0, 0, 0);
    let mut rays = buf.rays.take();
    rays.resize(total, placeholder);
    let mut pts = buf.pts.take();
    let origin = Pt {
        u: 0.0,
        v: 0.0,
        z: 0.0,
        id: 0,
    };
    pts.resize(total, origin);
    let mut face = buf.bytes.take();
    face.resize(total, 0);
    let mut jobs = Vec::with_capacity(counts.len());
    {
        let (mut r, mut p, mut f) = (&mut rays[..], &mut pts[..], &mut face[..]);
        let mut first = 0;
        for (b, &c) in counts.iter().enumerate() {
            let (r0, r1) = r.split_at_mut(c);
            let (p0, p1) = p.split_at_mut(c);
            let (f0, f1) = f.split_at_mut(c);
            jobs.push((b, first, r0, p0, f0));
            (r, p, f) = (r1, p1, f1);
            first += c;
        }
    }
    let position = match *light {
        Light::Point { position } | Light::Spot { position, .. } => position,
        Light::Directional { .. } => Vec3::ZERO,
    };
    jobs.into_par_iter().for_each(|(b, first, r, p, f)| {
        let mut j = 0;
        for k in b * TRANSFORM_BLOCK..((b + 1) * TRANSFORM_BLOCK).min(n) {
            if !lit(k) {
                continue;
            }
            let (sp, normal, own) = receiver(k);
            let (l, _) = light.shadow_ray(sp.p);
            let o = sp.offset_origin(normal, l);
            let (dir, t_max) = light.shadow_ray(o);
            r[j] = ShadowRay::new(o, dir, t_max, own, k as u32);
            let id = (first + j) as u32;
            let (pt, fc) = match proj {
                Some(proj) => (proj.project(o, id), 0),
                None => {
                    let fc = cube_face(o - position);
                    (cube[fc].project(o, id), fc as u8)
                }
            };
            // A sample the projection cannot place (behind a spot light's plane, or on the
            // light itself) is marked with a non-finite depth for the caller to handle.
            p[j] = pt.unwrap_or(Pt {
                u: 0.0,
                v: 0.0,
                z: f32::NAN,
                id,
            });
            f[j] = fc;
            j += 1;
        }
    });
    (rays, pts, face)
}

/// The cube faces of a point light at `l`, in [`CUBE_FACES`] order. The face axes are signed
/// coordinate axes, so the projection to a face is exact.
fn cube_projections(l: Vec3) -> [Projection; 6] {
    CUBE_FACES.map(|(dir, up)| Projection::Persp {
        l,
        s: dir.cross(up),
        t: up,
        f: dir,
    })
}

/// The lit samples grouped into light image planes.
fn transform(frame: &Frame, buf: &mut Buffers) -> Vec<Plane> {
    let light = frame.light;
    let scene_bounds = frame.scene.bounds;
    match *light {
        Light::Directional { to_light } => {
            let w = -to_light.normalize();
            let s = w.cross(pick_up(w)).normalize();
            let t = s.cross(w);
            let c = scene_bounds.center();
            let proj = Projection::Ortho { c, s, t, w };
            let (rays, pts, face) =
                shadow_rays(frame, Some(&proj), &cube_projections(Vec3::ZERO), buf);
            buf.bytes.give(face);
            vec![Plane {
                proj,
                pts,
                rays,
                scale: scene_bounds.diagonal().max(f32::MIN_POSITIVE),
            }]
        }
        Light::Spot {
            position, target, ..
        } => {
            let f = (target - position).normalize();
            let s = f.cross(pick_up(f)).normalize();
            let t = s.cross(f);
            let proj = Projection::Persp {
                l: position,
                s,
                t,
                f,
            };
            let cube = cube_projections(position);
            let (rays, pts, face) = shadow_rays(frame, Some(&proj), &cube, buf);
            buf.bytes.give(face);
            if pts.iter().all(|p| p.z.is_finite()) {
                let scale = perspective_scale(position, &rays, &scene_bounds);
                vec![Plane {
                    proj,
                    pts,
                    rays,
                    scale,
                }]
            } else {
                // A sample at or behind the spot's own plane (impossible inside its cone,
                // but cheap to be sure of): use the cube of a point light instead.
                buf.rays.give(rays);
                buf.pts.give(pts);
                let (rays, pts, face) = shadow_rays(frame, None, &cube, buf);
                cube_planes(position, rays, pts, face, &scene_bounds, buf)
            }
        }
        Light::Point { position } => {
            let cube = cube_projections(position);
            let (rays, pts, face) = shadow_rays(frame, None, &cube, buf);
            cube_planes(position, rays, pts, face, &scene_bounds, buf)
        }
    }
}

fn perspective_scale(l: Vec3, rays: &[ShadowRay], scene: &Aabb) -> f32 {
    let far_sample = rays
        .par_iter()
        .with_min_len(4096)
        .map(|r| (Vec3::from_array(r.o) - l).length())
        .reduce(|| 0.0f32, f32::max);
    let far_corner = scene
        .corners()
        .iter()
        .map(|c| (*c - l).length())
        .fold(0.0f32, f32::max);
    (far_sample + far_corner).max(f32::MIN_POSITIVE)
}

/// Splits a point light's samples by cube face (faces without samples are left out).
fn cube_planes(
    l: Vec3,
    rays: Vec<ShadowRay>,
    pts: Vec<Pt>,
    face: Vec<u8>,
    scene: &Aabb,
    buf: &mut Buffers,
) -> Vec<Plane> {
    let scale = perspective_scale(l, &rays, scene);
    let cube = cube_projections(l);
    let mut count = [0usize; 6];
    for &f in &face {
        count[f as usize] += 1;
    }
    let mut planes: Vec<Plane> = (0..6)
        .map(|f| {
            let (mut pts, mut rays) = (buf.pts.take(), buf.rays.take());
            pts.reserve(count[f]);
            rays.reserve(count[f]);
            Plane {
                proj: cube[f],
                pts,
                rays,
                scale,
            }
        })
        .collect();
    for ((r, p), &f) in rays.iter().zip(&pts).zip(&face) {
        let (r, mut p) = (*r, *p);
        let plane = &mut planes[f as usize];
        p.id = plane.rays.len() as u32;
        if !p.z.is_finite() {
            // The sample sits on the light itself: any point of the face will do, the
            // tolerance and the exact test decide.
            p = Pt {
                u: 0.0,
                v: 0.0,
                z: 0.0,
                id: p.id,
            };
        }
        plane.rays.push(r);
        plane.pts.push(p);
    }
    buf.rays.give(rays);
    buf.pts.give(pts);
    buf.bytes.give(face);
    let (kept, empty): (Vec<Plane>, Vec<Plane>) =
        planes.into_iter().partition(|p| !p.pts.is_empty());
    for p in empty {
        buf.rays.give(p.rays);
        buf.pts.give(p.pts);
    }
    kept
}

// ---------------------------------------------------------------------------------------
// The 2D BSP tree.

/// A BSP node: the tight rectangle and maximum depth of its samples. Internal nodes have
/// their left child right after them (preorder) and `right` further on; leaves have
/// `right == 0` and own the samples `start .. start + len`.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    lo: [f32; 2],
    hi: [f32; 2],
    zmax: f32,
    start: u32,
    len: u32,
    right: u32,
}

impl Node {
    #[inline]
    fn is_leaf(&self) -> bool {
        self.right == 0
    }
}

/// Marks nodes above the units of parallel work.
const NO_UNIT: u32 = u32::MAX;

/// The BSP of one light image plane, with its samples in leaf order.
struct Bsp {
    proj: Projection,
    scale: f32,
    nodes: Vec<Node>,
    /// Parent of each node (the root's is itself).
    parent: Vec<u32>,
    /// Depth of each node (the root's is 0).
    depth: Vec<u8>,
    /// The unit each node belongs to, [`NO_UNIT`] above them.
    unit: Vec<u32>,
    /// Root node of each unit, in preorder.
    unit_roots: Vec<u32>,
    /// Sample coordinates in leaf order.
    su: Vec<f32>,
    sv: Vec<f32>,
    sz: Vec<f32>,
    /// Shadow rays in leaf order.
    rays: Vec<ShadowRay>,
    grid: EntryGrid,
}

/// Number of nodes of the tree over `len` samples, memoized (each level has at most two
/// distinct sizes).
fn node_count(len: usize, leaf: usize, memo: &mut HashMap<usize, usize>) -> usize {
    if len <= leaf {
        return 1;
    }
    if let Some(&n) = memo.get(&len) {
        return n;
    }
    let n = 1 + node_count(len / 2, leaf, memo) + node_count(len - len / 2, leaf, memo);
    memo.insert(len, n);
    n
}

impl Bsp {
    fn build(plane: Plane, leaf: usize, buf: &mut Buffers) -> Bsp {
        let Plane {
            proj,
            mut pts,
            rays,
            scale,
        } = plane;
        let mut memo = HashMap::new();
        let total = if pts.is_empty() {
            0
        } else {
            node_count(pts.len(), leaf, &mut memo)
        };
        let mut nodes = vec![Node::default(); total];
        let mut parent = vec![0u32; total];
        if total > 0 {
            build_node(&mut pts, &mut nodes, &mut parent, 0, 0, 0, leaf, &memo);
        }
        let mut unit = vec![NO_UNIT; total];
        let mut unit_roots = Vec::new();
        if total > 0 {
            find_units(&nodes, &mut unit, &mut unit_roots, &memo, leaf);
        }
        let grid = EntryGrid::new(&nodes);
        let mut depth = vec![0u8; total];
        for i in 1..total {
            // Preorder: a parent comes before its children.
            depth[i] = depth[parent[i] as usize] + 1;
        }
        // Coordinates and shadow rays in leaf order, so a leaf reads them contiguously.
        let (mut su, mut sv, mut sz) = (buf.coords.take(), buf.coords.take(), buf.coords.take());
        su.par_extend(pts.par_iter().with_min_len(4096).map(|p| p.u));
        sv.par_extend(pts.par_iter().with_min_len(4096).map(|p| p.v));
        sz.par_extend(pts.par_iter().with_min_len(4096).map(|p| p.z));
        let mut leaf_rays = buf.rays.take();
        leaf_rays.par_extend(
            pts.par_iter()
                .with_min_len(4096)
                .map(|p| rays[p.id as usize]),
        );
        buf.rays.give(rays);
        buf.pts.give(pts);
        let rays = leaf_rays;
        Bsp {
            proj,
            scale,
            nodes,
            parent,
            depth,
            unit,
            unit_roots,
            su,
            sv,
            sz,
            rays,
            grid,
        }
    }

    /// Hands the per-sample vectors back for the next frame.
    fn recycle(self, buf: &mut Buffers) {
        buf.coords.give(self.su);
        buf.coords.give(self.sv);
        buf.coords.give(self.sz);
        buf.rays.give(self.rays);
    }

    /// The largest |(u, v, 1)| over the plane's samples.
    fn max_direction_length(&self) -> f32 {
        let r = self.nodes[0];
        let u = r.lo[0].abs().max(r.hi[0].abs());
        let v = r.lo[1].abs().max(r.hi[1].abs());
        (1.0 + u * u + v * v).sqrt()
    }

    /// The nearest common ancestor of nodes `a` and `b`.
    #[inline]
    fn common_ancestor(&self, mut a: u32, mut b: u32) -> u32 {
        while a != b {
            let (da, db) = (self.depth[a as usize], self.depth[b as usize]);
            if da >= db {
                a = self.parent[a as usize];
            }
            if db >= da {
                b = self.parent[b as usize];
            }
        }
        a
    }

    /// The deepest node whose subtree holds every sample the rectangle `lo..hi` can
    /// contain: a sample outside it lies beyond the gap of some split the rectangle
    /// does not cross.
    fn entry(&self, lo: [f32; 2], hi: [f32; 2]) -> u32 {
        if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite()) {
            return 0;
        }
        let g = &self.grid;
        let [c0, c1, r0, r1] = g.cells(lo, hi);
        if c1 <= c0 + 1 && r1 <= r0 + 1 {
            // Within two cells a side: the nearest common ancestor of the corner cells'
            // nodes (a sample under another node lies beyond a gap none of them crosses).
            let mut a = g.node[r0 * g.n + c0];
            for (r, c) in [(r0, c1), (r1, c0), (r1, c1)] {
                a = self.common_ancestor(a, g.node[r * g.n + c]);
            }
            return a;
        }
        let mut ni = 0u32;
        let mut depth = 0;
        loop {
            let n = &self.nodes[ni as usize];
            if n.is_leaf() {
                return ni;
            }
            let a = depth % 2;
            if hi[a] < self.nodes[n.right as usize].lo[a] {
                ni += 1;
            } else if lo[a] > self.nodes[ni as usize + 1].hi[a] {
                ni = n.right;
            } else {
                return ni;
            }
            depth += 1;
        }
    }
}

/// Builds the subtree over `pts` into `nodes` (its preorder slice, starting at node index
/// `base`); `start` is the index of `pts[0]` in the whole plane.
#[allow(clippy::too_many_arguments)]
fn build_node(
    pts: &mut [Pt],
    nodes: &mut [Node],
    parent: &mut [u32],
    base: u32,
    start: u32,
    depth: u32,
    leaf: usize,
    memo: &HashMap<usize, usize>,
) {
    let len = pts.len();
    if len <= leaf {
        let mut n = Node {
            lo: [f32::INFINITY; 2],
            hi: [f32::NEG_INFINITY; 2],
            zmax: f32::NEG_INFINITY,
            start,
            len: len as u32,
            right: 0,
        };
        for p in pts.iter() {
            n.lo = [n.lo[0].min(p.u), n.lo[1].min(p.v)];
            n.hi = [n.hi[0].max(p.u), n.hi[1].max(p.v)];
            n.zmax = n.zmax.max(p.z);
        }
        nodes[0] = n;
        return;
    }
    // Split in half at the median along x on even levels and y on odd ones.
    let mid = len / 2;
    if depth & 1 == 0 {
        pts.select_nth_unstable_by(mid, |a, b| a.u.total_cmp(&b.u));
    } else {
        pts.select_nth_unstable_by(mid, |a, b| a.v.total_cmp(&b.v));
    }
    let left_nodes = if mid <= leaf { 1 } else { memo[&mid] };
    let (lp, rp) = pts.split_at_mut(mid);
    let (head, rest) = nodes.split_at_mut(1);
    let (ln, rn) = rest.split_at_mut(left_nodes);
    let (_, prest) = parent.split_at_mut(1);
    let (lpar, rpar) = prest.split_at_mut(left_nodes);
    lpar[0] = base;
    rpar[0] = base;
    let right = base + 1 + left_nodes as u32;
    if len >= PARALLEL_BUILD_MIN {
        rayon::join(
            || build_node(lp, ln, lpar, base + 1, start, depth + 1, leaf, memo),
            || {
                build_node(
                    rp,
                    rn,
                    rpar,
                    right,
                    start + mid as u32,
                    depth + 1,
                    leaf,
                    memo,
                )
            },
        );
    } else {
        build_node(lp, ln, lpar, base + 1, start, depth + 1, leaf, memo);
        build_node(
            rp,
            rn,
            rpar,
            right,
            start + mid as u32,
            depth + 1,
            leaf,
            memo,
        );
    }
    let (l, r) = (ln[0], rn[0]);
    head[0] = Node {
        lo: [l.lo[0].min(r.lo[0]), l.lo[1].min(r.lo[1])],
        hi: [l.hi[0].max(r.hi[0]), l.hi[1].max(r.hi[1])],
        zmax: l.zmax.max(r.zmax),
        start,
        len: len as u32,
        right,
    };
}

/// The units of parallel work: preorder subtrees at depth [`UNIT_DEPTH`], or leaves above
/// it. Each node below a unit root is marked with its unit.
fn find_units(
    nodes: &[Node],
    unit: &mut [u32],
    roots: &mut Vec<u32>,
    memo: &HashMap<usize, usize>,
    leaf: usize,
) {
    let mut stack = vec![(0u32, 0u32)];
    while let Some((ni, depth)) = stack.pop() {
        let n = nodes[ni as usize];
        if depth == UNIT_DEPTH || n.is_leaf() {
            let size = if n.len as usize <= leaf {
                1
            } else {
                memo[&(n.len as usize)]
            };
            let u = roots.len() as u32;
            roots.push(ni);
            unit[ni as usize..ni as usize + size].fill(u);
        } else {
            // Right pushed first so units are numbered in preorder.
            stack.push((n.right, depth + 1));
            stack.push((ni + 1, depth + 1));
        }
    }
}

/// A uniform grid over the root's rectangle that maps each cell to the deepest node whose
/// subtree holds every sample the cell can contain: a small triangle starts its traversal
/// there instead of at the root.
struct EntryGrid {
    /// Cells per side.
    n: usize,
    lo: [f32; 2],
    cell: [f32; 2],
    inv_cell: [f32; 2],
    node: Vec<u32>,
}

/// Cells are widened by this fraction on each side when nodes are assigned, so a rectangle
/// the look-up places in a cell lies inside the widened cell despite rounding.
const GRID_CELL_MARGIN: f32 = 1.0 / 64.0;

impl EntryGrid {
    fn new(nodes: &[Node]) -> EntryGrid {
        let leaves = nodes.len().div_ceil(2);
        // About four cells per leaf: a triangle smaller than a leaf usually fits one cell.
        let n = if nodes.is_empty() {
            1
        } else {
            ((leaves as f64).sqrt() as usize * 2).clamp(1, 1024)
        };
        let (lo, hi) = match nodes.first() {
            Some(r) => (r.lo, r.hi),
            None => ([0.0; 2], [1.0; 2]),
        };
        let mut cell = [0, 1].map(|a| ((hi[a] - lo[a]) / n as f32).max(f32::MIN_POSITIVE));
        // Cells too small for the coordinates' precision would misplace rectangles: one
        // cell (the root) then.
        let coarse = (0..2).any(|a| cell[a] < 256.0 * f32::EPSILON * (lo[a].abs() + hi[a].abs()));
        let n = if coarse { 1 } else { n };
        if coarse {
            cell = [0, 1].map(|a| (hi[a] - lo[a]).max(f32::MIN_POSITIVE));
        }
        let mut g = EntryGrid {
            n,
            lo,
            cell,
            inv_cell: cell.map(|c| 1.0 / c),
            node: vec![0; n * n],
        };
        if !nodes.is_empty() {
            g.assign(nodes, 0, 0, [0, n], [0, n]);
        }
        g
    }

    /// The widened extent of cells `k` along axis `a`.
    fn cell_lo(&self, a: usize, k: usize) -> f32 {
        self.lo[a] + (k as f32 - GRID_CELL_MARGIN) * self.cell[a]
    }
    fn cell_hi(&self, a: usize, k: usize) -> f32 {
        self.lo[a] + (k as f32 + 1.0 + GRID_CELL_MARGIN) * self.cell[a]
    }

    /// Assigns the cells `cols × rows` to node `ni` or its descendants.
    fn assign(
        &mut self,
        nodes: &[Node],
        ni: u32,
        depth: usize,
        cols: [usize; 2],
        rows: [usize; 2],
    ) {
        if cols[0] >= cols[1] || rows[0] >= rows[1] {
            return;
        }
        for r in rows[0]..rows[1] {
            self.node[r * self.n + cols[0]..r * self.n + cols[1]].fill(ni);
        }
        let n = nodes[ni as usize];
        if n.is_leaf() {
            return;
        }
        let a = depth % 2;
        let range = if a == 0 { cols } else { rows };
        let (left, right) = (nodes[ni as usize + 1], nodes[n.right as usize]);
        // Cells wholly before the right child's first sample go left, cells wholly after
        // the left child's last sample go right; cells across the gap stay here.
        let mut k1 = range[0];
        while k1 < range[1] && self.cell_hi(a, k1) < right.lo[a] {
            k1 += 1;
        }
        let mut k2 = range[1];
        while k2 > k1 && self.cell_lo(a, k2 - 1) > left.hi[a] {
            k2 -= 1;
        }
        let (lr, rr) = ([range[0], k1], [k2, range[1]]);
        if a == 0 {
            self.assign(nodes, ni + 1, depth + 1, lr, rows);
            self.assign(nodes, n.right, depth + 1, rr, rows);
        } else {
            self.assign(nodes, ni + 1, depth + 1, cols, lr);
            self.assign(nodes, n.right, depth + 1, cols, rr);
        }
    }

    /// The cells holding the rectangle's corners: columns `c0..=c1`, rows `r0..=r1`.
    #[inline]
    fn cells(&self, lo: [f32; 2], hi: [f32; 2]) -> [usize; 4] {
        let last = (self.n - 1) as f32;
        // Clamped first, so truncation is the floor.
        let cell =
            |a: usize, x: f32| ((x - self.lo[a]) * self.inv_cell[a]).clamp(0.0, last) as usize;
        [
            cell(0, lo[0]),
            cell(0, hi[0]),
            cell(1, lo[1]),
            cell(1, hi[1]),
        ]
    }
}

// ---------------------------------------------------------------------------------------
// Triangle set-up: the light-space footprint, widened for culling.

/// A caster triangle in one light image plane. Every test is conservative: a sample
/// outside it cannot be hit by the triangle's exact ray test.
#[derive(Clone, Copy, Debug)]
struct TriSetup {
    /// Edge functions `a·u + b·v + c`, oriented and widened so a covered sample has all
    /// three ≥ 0.
    e: [[f32; 3]; 3],
    /// Bounding rectangle of the footprint.
    lo: [f32; 2],
    hi: [f32; 2],
    /// Minimum light depth of the triangle (a sample nearer the light cannot be shadowed).
    zmin: f32,
    /// Triangle index.
    id: u32,
    /// The node its traversal starts at.
    entry: u32,
}

/// An edge function that every point passes (for triangles whose orientation is not
/// reliable in floating point).
const PASS_ALL: [f32; 3] = [0.0, 0.0, 1.0];

impl TriSetup {
    /// True when the triangle may cover a sample of `n` that lies behind it.
    #[inline]
    fn overlaps(&self, n: &Node) -> bool {
        if self.lo[0] > n.hi[0]
            || self.hi[0] < n.lo[0]
            || self.lo[1] > n.hi[1]
            || self.hi[1] < n.lo[1]
        {
            return false;
        }
        if self.zmin > n.zmax {
            return false;
        }
        for e in &self.e {
            let m =
                e[2] + (e[0] * n.lo[0]).max(e[0] * n.hi[0]) + (e[1] * n.lo[1]).max(e[1] * n.hi[1]);
            if m < 0.0 {
                return false;
            }
        }
        true
    }

    /// True when the triangle may cover the sample at `(u, v)` with depth `z` from in
    /// front of it; evaluated without branches so the leaf loop stays tight.
    #[inline]
    fn may_cover(&self, u: f32, v: f32, z: f32) -> bool {
        let e = &self.e;
        (z >= self.zmin)
            & (u >= self.lo[0])
            & (u <= self.hi[0])
            & (v >= self.lo[1])
            & (v <= self.hi[1])
            & (e[0][0] * u + e[0][1] * v + e[0][2] >= 0.0)
            & (e[1][0] * u + e[1][1] * v + e[1][2] >= 0.0)
            & (e[2][0] * u + e[2][1] * v + e[2][2] >= 0.0)
    }
}

/// Sets triangle `id` (vertices `v`) up for `bsp`; `None` when it cannot shadow any sample.
fn setup(bsp: &Bsp, v: [Vec3; 3], id: u32) -> Option<TriSetup> {
    let eps = CULL_TOLERANCE;
    let root = &bsp.nodes[0];
    let mut t = match bsp.proj {
        Projection::Ortho { c, s, t, w } => {
            let p = v.map(|p| {
                let q = p - c;
                [q.dot(s), q.dot(t), q.dot(w)]
            });
            // Positions may be off by this much between the plane and the ray test.
            let tol = eps * bsp.scale;
            let zmin = p[0][2].min(p[1][2]).min(p[2][2]) - tol;
            if zmin > root.zmax {
                return None;
            }
            let lo = [
                p[0][0].min(p[1][0]).min(p[2][0]) - tol,
                p[0][1].min(p[1][1]).min(p[2][1]) - tol,
            ];
            let hi = [
                p[0][0].max(p[1][0]).max(p[2][0]) + tol,
                p[0][1].max(p[1][1]).max(p[2][1]) + tol,
            ];
            let area2 = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
            let mut e = [PASS_ALL; 3];
            let mut edges = [[0.0f32; 3]; 3];
            let mut perimeter = 0.0;
            for i in 0..3 {
                let (a, b) = (p[i], p[(i + 1) % 3]);
                // E(p) = (b − a) × (p − a), formed relative to `a` so its rounding error
                // scales with the edge length, not with the coordinates squared.
                let ea = a[1] - b[1];
                let eb = b[0] - a[0];
                let len = (ea * ea + eb * eb).sqrt();
                edges[i] = [ea, eb, len];
                perimeter += len;
            }
            // Moving each vertex by `tol` changes twice the area by at most this: beyond
            // it the orientation is certain and the edge functions may cull.
            let area_error = 4.0 * tol * perimeter;
            let sigma = area2.signum();
            let ecs = [0, 1, 2].map(|i| -(edges[i][0] * p[i][0] + edges[i][1] * p[i][1]));
            if area2.abs() > area_error {
                for i in 0..3 {
                    let [ea, eb, len] = edges[i];
                    e[i] = [sigma * ea, sigma * eb, sigma * ecs[i] + 2.0 * tol * len];
                }
            } else {
                // Nearly edge-on: the triangle lies in the slab along its longest edge whose
                // half-width is its height (twice the area over the edge, with its error).
                let i = (0..3)
                    .max_by(|&a, &b| edges[a][2].total_cmp(&edges[b][2]))
                    .unwrap_or(0);
                let [ea, eb, len] = edges[i];
                let w = area2.abs() + area_error + 2.0 * tol * len;
                e[0] = [ea, eb, ecs[i] + w];
                e[1] = [-ea, -eb, -ecs[i] + w];
            }
            TriSetup {
                e,
                lo,
                hi,
                zmin,
                id,
                entry: 0,
            }
        }
        Projection::Persp { l, s, t, f } => {
            let q = v.map(|p| {
                let d = p - l;
                Vec3::new(d.dot(s), d.dot(t), d.dot(f))
            });
            let ql = q.map(|q| q.length());
            // The shadow-ray test decides as if each vertex were moved by up to a few ulps
            // of the distances involved; `delta` bounds that move with room to spare.
            let delta = 2.0 * eps * (bsp.scale + ql[0].max(ql[1]).max(ql[2]));
            let zmin = q[0].z.min(q[1].z).min(q[2].z) - delta;
            if zmin > root.zmax {
                return None;
            }
            if q.iter().all(|q| q.z < -2.0 * delta) {
                // Entirely behind the plane: no sample's segment to the light reaches it.
                return None;
            }
            let mut t = TriSetup {
                e: [PASS_ALL; 3],
                lo: [f32::NEG_INFINITY; 2],
                hi: [f32::INFINITY; 2],
                zmin,
                id,
                entry: 0,
            };
            let d_max = bsp.max_direction_length();
            let front = 4.0 * delta;
            if q.iter().all(|q| q.z > front) {
                // The rectangle of a triangle wholly in front of the light's plane.
                (t.lo, t.hi) = projected_rect(&q, delta);
            } else {
                // Across the plane: the part nearer the plane than `front` projects beyond
                // every sample unless it passes close to the light, so the rectangle of the
                // part in front bounds the footprint (a lower bound of the distance to the
                // light decides).
                let normal = (q[1] - q[0]).cross(q[2] - q[0]);
                let centroid = (q[0] + q[1] + q[2]) / 3.0;
                let radius = q
                    .iter()
                    .map(|p| (*p - centroid).length())
                    .fold(0.0f32, f32::max);
                let plane_dist = q[0].dot(normal).abs() / normal.length();
                let r_min = plane_dist.max(centroid.length() - radius);
                if r_min > 16.0 * delta * d_max {
                    let mut clipped = Vec::with_capacity(4);
                    for i in 0..3 {
                        let (a, b) = (q[i], q[(i + 1) % 3]);
                        if a.z >= front {
                            clipped.push(a);
                        }
                        if (a.z >= front) != (b.z >= front) {
                            clipped.push(a + (b - a) * ((front - a.z) / (b.z - a.z)));
                        }
                    }
                    if clipped.is_empty() {
                        return None;
                    }
                    (t.lo, t.hi) = projected_rect(&clipped, delta);
                }
            }
            // The planes through the light and each edge: n·(u, v, 1) is the edge function
            // of the projected edge, valid whatever side of the light's plane the vertices
            // lie on (homogeneous rasterization).
            let n = [q[0].cross(q[1]), q[1].cross(q[2]), q[2].cross(q[0])];
            let nl = n.map(|n| n.length());
            let margin = [0, 1, 2].map(|i| 2.0 * delta * (ql[i] + ql[(i + 1) % 3]) * d_max);
            // Moving the vertices by delta changes the triple product q0·(q1×q2) by at most
            // delta·Σ|qj×qk| (and delta²-terms); f32 rounding adds a few ε·|q0||q1||q2|.
            // Beyond that the orientation is certain and the edge functions may cull.
            let det = q[0].dot(n[1]);
            let det_error = 2.0 * delta * (nl[0] + nl[1] + nl[2])
                + 6.0 * delta * delta * (ql[0] + ql[1] + ql[2])
                + 8.0 * f32::EPSILON * ql[0] * ql[1] * ql[2];
            if det.abs() > det_error {
                let sigma = det.signum();
                for i in 0..3 {
                    t.e[i] = [sigma * n[i].x, sigma * n[i].y, sigma * n[i].z + margin[i]];
                }
            } else if q.iter().all(|q| q.z > front) {
                // Nearly edge-on from the light, and wholly in front of it: on the plane
                // z = 1 the triangle lies in the slab along the edge that looks longest,
                // n·(u, v, 1) between 0 and det/z at the opposite vertex (widened twice over
                // for its error).
                let i = (0..3).max_by(|&a, &b| nl[a].total_cmp(&nl[b])).unwrap_or(0);
                let w = 2.0 * (det.abs() + det_error) / q[(i + 2) % 3].z + margin[i];
                t.e[0] = [n[i].x, n[i].y, n[i].z + w];
                t.e[1] = [-n[i].x, -n[i].y, -n[i].z + w];
            }
            t
        }
    };
    t.entry = bsp.entry(t.lo, t.hi);
    Some(t)
}

/// The rectangle on the plane z = 1 of the points `q` (all in front of the light's plane),
/// each widened for a move of up to `delta`: u = x/z then moves by at most
/// delta·(1 + |u|)/z.
fn projected_rect(q: &[Vec3], delta: f32) -> ([f32; 2], [f32; 2]) {
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for p in q {
        let (u, v) = (p.x / p.z, p.y / p.z);
        let du = 2.0 * delta * (1.0 + u.abs() + v.abs()) / p.z;
        lo = [lo[0].min(u - du), lo[1].min(v - du)];
        hi = [hi[0].max(u + du), hi[1].max(v + du)];
    }
    (lo, hi)
}

// ---------------------------------------------------------------------------------------
// Hierarchical rasterization.

/// Work counters (the paper's Table 1).
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    nodes_visited: u64,
    occlusion_culled: u64,
    samples_tested: u64,
    ray_tests: u64,
    triangles_binned: u64,
    setup_bytes: usize,
}

impl Counters {
    fn add(&mut self, o: &Counters) {
        self.nodes_visited += o.nodes_visited;
        self.occlusion_culled += o.occlusion_culled;
        self.samples_tested += o.samples_tested;
        self.ray_tests += o.ray_tests;
        self.triangles_binned += o.triangles_binned;
        self.setup_bytes += o.setup_bytes;
    }
}

/// What a triangle does to the light passing through it.
#[derive(Clone, Copy)]
struct Caster {
    v: [[f32; 3]; 3],
    opaque: bool,
    transmittance: Vec3,
}

fn caster(scene: &Scene, id: u32) -> Caster {
    let m = scene.material_of(id as usize);
    Caster {
        v: scene.triangle(id as usize).map(|p| p.to_array()),
        opaque: m.is_opaque(),
        transmittance: m.transmittance,
    }
}

/// Deepest possible traversal stack: one entry per level plus one (a tree over at most 2³²
/// samples has at most 33 levels).
const STACK: usize = 64;

/// One subtree of the BSP and the state of its samples, owned by one thread at a time.
struct Unit<'a> {
    bsp: &'a Bsp,
    root: u32,
    /// Index of the unit's first sample in the plane.
    first: usize,
    /// Transmittance of each sample (leaf order).
    vis: &'a mut [Vec3],
    /// False once a sample is black.
    alive: &'a mut [bool],
    /// Nodes whose samples are all black, indexed from `root`.
    done: Vec<bool>,
    /// Samples not yet black in each leaf, indexed from `root`.
    alive_count: Vec<u32>,
    counters: Counters,
}

impl Unit<'_> {
    /// Rasterizes triangle `t` into the unit, from its entry node down.
    fn rasterize(&mut self, t: &TriSetup, scene: &Scene) {
        let nodes = &self.bsp.nodes;
        let mut caster = None;
        let mut stack = [0u32; STACK];
        stack[0] = t.entry;
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let ni = stack[sp];
            self.counters.nodes_visited += 1;
            if self.done[(ni - self.root) as usize] {
                self.counters.occlusion_culled += 1;
                continue;
            }
            let n = &nodes[ni as usize];
            if !t.overlaps(n) {
                continue;
            }
            if n.is_leaf() {
                if self.leaf(ni, n, t, &mut caster, scene) {
                    self.mark_done(ni);
                }
            } else {
                stack[sp] = n.right;
                stack[sp + 1] = ni + 1;
                sp += 2;
            }
        }
    }

    /// Marks leaf `ni` dark, and every ancestor within the unit whose children are both
    /// dark (the paper's occlusion culling).
    fn mark_done(&mut self, mut ni: u32) {
        loop {
            self.done[(ni - self.root) as usize] = true;
            if ni == self.root {
                return;
            }
            let p = self.bsp.parent[ni as usize];
            let right = self.bsp.nodes[p as usize].right;
            if !(self.done[(p + 1 - self.root) as usize] && self.done[(right - self.root) as usize])
            {
                return;
            }
            ni = p;
        }
    }

    /// Tests the leaf's samples against `t`; true when they are all dark afterwards.
    fn leaf(
        &mut self,
        ni: u32,
        n: &Node,
        t: &TriSetup,
        caster: &mut Option<Caster>,
        scene: &Scene,
    ) -> bool {
        let local = (ni - self.root) as usize;
        self.counters.samples_tested += self.alive_count[local] as u64;
        let start = n.start as usize;
        let len = n.len as usize;
        let bsp = self.bsp;
        let (us, vs, zs) = (
            &bsp.su[start..start + len],
            &bsp.sv[start..start + len],
            &bsp.sz[start..start + len],
        );
        let base = start - self.first;
        let mut flags = [false; 64];
        for block in (0..len).step_by(64) {
            let m = (len - block).min(64);
            let r = block..block + m;
            // The light-space footprint test of every sample of the block, branch-free so
            // the loop vectorizes.
            let alive = &self.alive[base + block..base + block + m];
            for ((((f, &u), &v), &z), &a) in flags
                .iter_mut()
                .zip(&us[r.clone()])
                .zip(&vs[r.clone()])
                .zip(&zs[r])
                .zip(alive)
            {
                *f = a & t.may_cover(u, v, z);
            }
            for (j, _) in flags[..m].iter().enumerate().filter(|(_, &f)| f) {
                let i = block + j;
                let ray = &bsp.rays[start + i];
                if ray.own == t.id {
                    continue;
                }
                self.counters.ray_tests += 1;
                let c = caster.get_or_insert_with(|| self::caster(scene, t.id));
                if ray.hits(&c.v) {
                    let j = base + i;
                    if c.opaque {
                        self.vis[j] = Vec3::ZERO;
                    } else {
                        self.vis[j] *= c.transmittance;
                    }
                    if self.vis[j] == Vec3::ZERO {
                        self.alive[j] = false;
                        self.alive_count[local] -= 1;
                    }
                }
            }
        }
        self.alive_count[local] == 0
    }
}

/// Bins `t` into the units it may overlap: straight into the unit of its entry node, or
/// through the nodes above the units.
fn bin(bsp: &Bsp, t: &TriSetup, out: &mut [Vec<TriSetup>], visited: &mut u64) {
    let u = bsp.unit[t.entry as usize];
    if u != NO_UNIT {
        out[u as usize].push(*t);
        return;
    }
    let mut stack = [0u32; STACK];
    stack[0] = t.entry;
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let ni = stack[sp];
        let u = bsp.unit[ni as usize];
        if u != NO_UNIT {
            out[u as usize].push(TriSetup { entry: ni, ..*t });
            continue;
        }
        *visited += 1;
        let n = &bsp.nodes[ni as usize];
        if t.overlaps(n) {
            stack[sp] = n.right;
            stack[sp + 1] = ni + 1;
            sp += 2;
        }
    }
}

/// Rasterizes every triangle into every plane's BSP and writes the shadow terms to pixels
/// (and to the layer samples, when the frame has layers).
fn rasterize(
    frame: &Frame,
    trees: &[Bsp],
    buf: &mut Buffers,
) -> (Visibility, Option<Vec<Vec3>>, Counters) {
    let view = frame.view;
    let scene = frame.scene;
    let mut out = Visibility::lit(view.width, view.height);
    let pixels = out.value.len();
    let mut layer_out = frame.layers.map(|l| {
        (0..l.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                if frame.layer_lit(l, i) {
                    Vec3::ONE
                } else {
                    Vec3::ZERO
                }
            })
            .collect::<Vec<_>>()
    });
    // Pixels whose viewed side the light cannot reach are dark in every technique.
    out.value
        .par_iter_mut()
        .with_min_len(4096)
        .enumerate()
        .for_each(|(k, v)| {
            if view.covered(k) && !frame.receiver_lit(k) {
                *v = Vec3::ZERO;
            }
        });
    let mut total = Counters::default();
    for bsp in trees {
        if bsp.nodes.is_empty() {
            continue;
        }
        let units = bsp.unit_roots.len();
        // Set-up and binning, in fixed chunks of triangles; each chunk keeps index order.
        let chunks: Vec<(Vec<Vec<TriSetup>>, u64)> = (0..scene.len().div_ceil(BIN_CHUNK))
            .into_par_iter()
            .map(|ci| {
                let mut buckets = vec![Vec::new(); units];
                let mut visited = 0u64;
                for i in ci * BIN_CHUNK..((ci + 1) * BIN_CHUNK).min(scene.len()) {
                    if let Some(t) = setup(bsp, scene.triangle(i), i as u32) {
                        bin(bsp, &t, &mut buckets, &mut visited);
                    }
                }
                (buckets, visited)
            })
            .collect();
        for (buckets, visited) in &chunks {
            total.nodes_visited += visited;
            for b in buckets {
                total.triangles_binned += b.len() as u64;
                total.setup_bytes += b.len() * std::mem::size_of::<TriSetup>();
            }
        }
        // Each unit owns a contiguous run of samples and of nodes.
        let n = bsp.su.len();
        let mut vis = buf.vis.take();
        vis.resize(n, Vec3::ONE);
        let mut alive = buf.flags.take();
        alive.resize(n, true);
        let mut work = Vec::with_capacity(units);
        {
            let (mut vr, mut ar) = (&mut vis[..], &mut alive[..]);
            for (u, &r) in bsp.unit_roots.iter().enumerate() {
                let node = bsp.nodes[r as usize];
                let (v, vrest) = vr.split_at_mut(node.len as usize);
                let (a, arest) = ar.split_at_mut(node.len as usize);
                (vr, ar) = (vrest, arest);
                let end = bsp
                    .unit_roots
                    .get(u + 1)
                    .map_or(bsp.nodes.len(), |&x| x as usize);
                // Nodes of the subtree: from the root to the next unit's root, less the
                // nodes above the units that preorder puts between them.
                let size = (r as usize..end)
                    .take_while(|&i| bsp.unit[i] == u as u32)
                    .count();
                let alive_count = (r as usize..r as usize + size)
                    .map(|i| bsp.nodes[i].len)
                    .collect();
                work.push(Unit {
                    bsp,
                    root: r,
                    first: node.start as usize,
                    vis: v,
                    alive: a,
                    done: vec![false; size],
                    alive_count,
                    counters: Counters::default(),
                });
            }
        }
        work.par_iter_mut().enumerate().for_each(|(u, unit)| {
            for (buckets, _) in &chunks {
                for t in &buckets[u] {
                    unit.rasterize(t, scene);
                }
            }
        });
        for unit in &work {
            total.add(&unit.counters);
        }
        drop(work);
        for (r, v) in bsp.rays.iter().zip(&vis) {
            let k = r.pixel as usize;
            match &mut layer_out {
                Some(l) if k >= pixels => l[k - pixels] = *v,
                _ => out.value[k] = *v,
            }
        }
        buf.vis.give(vis);
        buf.flags.give(alive);
    }
    (out, layer_out, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::intersect_triangle;

    use crate::math::TestRng as Lcg;

    #[test]
    fn presheared_ray_test_is_the_watertight_test() {
        let mut rng = Lcg(11);
        let mut hits = 0;
        for i in 0..200_000 {
            let o = rng.v() * 3.0;
            // Directions along the axes and with negative components exercise every shear
            // permutation and the f64 fallback on exact edge hits.
            let mut dir = rng.v().normalize();
            if i % 7 == 0 {
                dir = [Vec3::X, -Vec3::Y, Vec3::Z][i % 3];
            }
            let t_max = if i % 2 == 0 {
                f32::INFINITY
            } else {
                rng.next() * 4.0
            };
            let c = o + dir * (rng.next() * 3.0);
            let v = if i % 5 == 0 {
                // A triangle with an edge through the ray's point of passage.
                let a = c + rng.v();
                [a, c + (c - a), c + rng.v()]
            } else {
                [c + rng.v(), c + rng.v(), c + rng.v()]
            };
            let exact = intersect_triangle(o, dir, 0.0, t_max, v).is_some();
            let ray = ShadowRay::new(o, dir, t_max, 0, 0);
            assert_eq!(ray.hits(&v.map(|p| p.to_array())), exact, "case {i}");
            hits += exact as u32;
        }
        assert!(hits > 10_000);
    }

    #[test]
    fn bsp_splits_at_the_median_and_bounds_its_samples() {
        let mut rng = Lcg(5);
        for (n, leaf) in [
            (1usize, 64usize),
            (63, 64),
            (1000, 7),
            (5000, 64),
            (40_000, 64),
            (3, 1),
        ] {
            let pts: Vec<Pt> = (0..n)
                .map(|i| Pt {
                    u: rng.next() * rng.next(),
                    v: rng.next(),
                    z: rng.next(),
                    id: i as u32,
                })
                .collect();
            let rays: Vec<ShadowRay> = (0..n)
                .map(|i| ShadowRay::new(Vec3::ZERO, Vec3::Y, 1.0, 0, i as u32))
                .collect();
            let original = pts.clone();
            let proj = Projection::Ortho {
                c: Vec3::ZERO,
                s: Vec3::X,
                t: Vec3::Z,
                w: -Vec3::Y,
            };
            let bsp = Bsp::build(
                Plane {
                    proj,
                    pts,
                    rays,
                    scale: 1.0,
                },
                leaf,
                &mut Buffers::default(),
            );
            let mut ids: Vec<u32> = bsp.rays.iter().map(|r| r.pixel).collect();
            for (i, &id) in ids.iter().enumerate() {
                let p = original[id as usize];
                assert_eq!(
                    (bsp.su[i], bsp.sv[i], bsp.sz[i]),
                    (p.u, p.v, p.z),
                    "rays follow their samples"
                );
            }
            ids.sort_unstable();
            assert!(
                ids.iter().enumerate().all(|(i, &id)| id == i as u32),
                "a permutation"
            );
            fn check(bsp: &Bsp, ni: u32, depth: u32, leaf: usize) {
                let n = bsp.nodes[ni as usize];
                let range = n.start as usize..(n.start + n.len) as usize;
                let pts: Vec<Pt> = range
                    .map(|i| Pt {
                        u: bsp.su[i],
                        v: bsp.sv[i],
                        z: bsp.sz[i],
                        id: 0,
                    })
                    .collect();
                for p in &pts {
                    assert!(
                        p.u >= n.lo[0]
                            && p.u <= n.hi[0]
                            && p.v >= n.lo[1]
                            && p.v <= n.hi[1]
                            && p.z <= n.zmax
                    );
                }
                if n.is_leaf() {
                    assert!(n.len as usize <= leaf);
                    return;
                }
                assert!(n.len as usize > leaf);
                let (l, r) = (bsp.nodes[ni as usize + 1], bsp.nodes[n.right as usize]);
                assert_eq!(l.len, n.len / 2, "split in half");
                assert_eq!(l.len + r.len, n.len);
                assert_eq!(r.start, n.start + l.len);
                let key = |p: &Pt| if depth & 1 == 0 { p.u } else { p.v };
                let lmax = pts[..l.len as usize]
                    .iter()
                    .map(key)
                    .fold(f32::MIN, f32::max);
                let rmin = pts[l.len as usize..]
                    .iter()
                    .map(key)
                    .fold(f32::MAX, f32::min);
                assert!(lmax <= rmin, "median split along the level's axis");
                check(bsp, ni + 1, depth + 1, leaf);
                check(bsp, n.right, depth + 1, leaf);
            }
            check(&bsp, 0, 0, leaf);
            // Every sample inside a rectangle lies in the subtree of the rectangle's entry.
            for _ in 0..2000 {
                let (cu, cv, r) = (rng.next(), rng.next(), rng.next() * rng.next() * 0.05);
                let (lo, hi) = ([cu - r, cv - r * 0.5], [cu + r * 0.7, cv + r]);
                let e = bsp.nodes[bsp.entry(lo, hi) as usize];
                for i in 0..n {
                    if bsp.su[i] >= lo[0]
                        && bsp.su[i] <= hi[0]
                        && bsp.sv[i] >= lo[1]
                        && bsp.sv[i] <= hi[1]
                    {
                        assert!(
                            i >= e.start as usize && i < (e.start + e.len) as usize,
                            "sample {i} outside the entry"
                        );
                    }
                }
            }
            let mut memo = HashMap::new();
            assert_eq!(bsp.nodes.len(), node_count(n, leaf, &mut memo));
        }
    }
}
