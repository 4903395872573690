//! Fitting the map's frustum of `psm` (Stamminger & Drettakis 2002, Sections 3–4: "the
//! window of the shadow map is chosen so that all points in H are included", seen from the
//! post-perspective light), in f64.
//!
//! The frustum is fitted to the vertices of the transformed body `H'` (it is convex, so
//! its vertices bound it): for a post-space point light (plain or inverted), the window of
//! their tangents seen from `q`, off-centre so no texel is spent outside `H'`; for a
//! post-space directional light, their window across the light direction, an orthographic
//! map. A point light that would see `H'` over more than [`MAX_POINT_TANGENT`] (or from
//! inside it) gets the faces of a cube around `q` instead.

use super::post_space::{PostBody, PostLight, PostLightSource, MIN_POST_EXTENT};
use crate::light::CUBE_FACES;
use crate::math::pick_up_f64;
use glam::{DMat4, DVec3, DVec4};

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
/// A map's window side and an orthographic map's depth range are at least this fraction of
/// the window's larger span, so a flat body (all in one plane) still gets a solid frustum.
const SLIVER: f64 = 1e-3;
/// A perspective map sees a body vertex only when it lies in front of `q` by at least this
/// fraction of its distance (the cosine of its angle to the axis): its tangent stays finite.
const MIN_FRONT_COSINE: f64 = 1e-9;
/// A perspective map's depth range is padded by at least this fraction of its far distance,
/// so a body at one distance from `q` still gets a range to divide by.
const MIN_DEPTH_SPAN: f64 = 1e-6;
/// A cube face whose body reaches behind `q` (`q` inside the body) gets its near plane at
/// this fraction of its far distance: near enough for casters around `q`, far enough to
/// keep the face's depth digits.
const INSIDE_NEAR_FRACTION: f64 = 1e-4;

/// A map frustum in post-perspective space, in f64, before it is joined to the world.
pub(super) struct MapFit {
    /// Post-perspective space to the map's clip space.
    pub(super) clip_from_post: DMat4,
    /// Post-space linear depth beyond the near plane: `depth_row · (p', 1)`.
    pub(super) depth_row: DVec4,
    /// Texel size in post units: absolute (orthographic) or per unit distance from `q`.
    pub(super) texel: f64,
    /// Distance of the near plane from `q` (0 for orthographic maps).
    pub(super) near: f64,
    /// Far minus near plane.
    pub(super) span: f64,
    /// True for a map along a post-space directional light.
    pub(super) orthographic: bool,
}

/// The maps of a frame: one map, or the faces of a cube around `q` with the map index of
/// each of the six faces (`usize::MAX` for faces that see nothing of the body).
/// `world_directional` tells a directional world light (its post-space cones may be wide:
/// they are the uniform case).
pub(super) fn fit_maps(
    light: &PostLightSource,
    world_directional: bool,
    body: &PostBody,
    res: u32,
) -> (Vec<MapFit>, Option<[usize; 6]>) {
    let pts = &body.pts;
    if light.kind == PostLight::Directional {
        return (
            vec![fit_orthographic(light.dir, body.centre, pts, res)],
            None,
        );
    }
    let q = light.q;
    let limit = if world_directional || light.kind == PostLight::Inverted {
        f64::INFINITY
    } else {
        MAX_POINT_TANGENT
    };
    if let Some(m) = fit_perspective(q, pts, res, limit) {
        return (vec![m], None);
    }
    let mut maps = Vec::new();
    let mut faces = [usize::MAX; 6];
    for (i, (axis, up)) in CUBE_FACES.iter().enumerate() {
        if let Some(m) = fit_cube_face(q, axis.as_dvec3(), up.as_dvec3(), pts, res) {
            faces[i] = maps.len();
            maps.push(m);
        }
    }
    (maps, Some(faces))
}

/// A matrix from its four rows.
fn from_rows(r: [DVec4; 4]) -> DMat4 {
    DMat4::from_cols(r[0], r[1], r[2], r[3]).transpose()
}

/// The ranges of a body's vertices along a map's image axes `x`, `y` and its depth axis `z`.
#[derive(Clone, Copy)]
struct Extent {
    x: (f64, f64),
    y: (f64, f64),
    z: (f64, f64),
}

impl Extent {
    const EMPTY: Extent = Extent {
        x: (f64::INFINITY, f64::NEG_INFINITY),
        y: (f64::INFINITY, f64::NEG_INFINITY),
        z: (f64::INFINITY, f64::NEG_INFINITY),
    };

    fn grow(&mut self, x: f64, y: f64, z: f64) {
        let grow = |(lo, hi): (f64, f64), v: f64| (lo.min(v), hi.max(v));
        (self.x, self.y, self.z) = (grow(self.x, x), grow(self.y, y), grow(self.z, z));
    }

    /// The larger image span (at least [`MIN_POST_EXTENT`]) and the window of square
    /// texels around the image ranges: centre and padded half-sides `(cx, cy, hx, hy)`.
    fn window(&self) -> (f64, (f64, f64, f64, f64)) {
        let (x0, x1, y0, y1) = (self.x.0, self.x.1, self.y.0, self.y.1);
        let span = (x1 - x0).max(y1 - y0).max(MIN_POST_EXTENT);
        let (hx, hy) = (window_half(x1 - x0, span), window_half(y1 - y0, span));
        (span, ((x0 + x1) * 0.5, (y0 + y1) * 0.5, hx, hy))
    }
}

/// Orthographic map along the post-space light direction `dir` (towards the light).
fn fit_orthographic(dir: DVec3, centre: DVec3, pts: &[DVec3], res: u32) -> MapFit {
    // The frame of `dir` mirrored (right = up × dir): the same numbers as computing it so.
    let (right, up) = frame_of(dir, pick_up_f64(dir));
    let right = -right;
    // Light view: x = right, y = up, z = towards the light; depth = −z grows away from it.
    let mut e = Extent::EMPTY;
    for p in pts {
        let r = *p - centre;
        e.grow(r.dot(right), r.dot(up), -r.dot(dir));
    }
    let (span, (cx, cy, hx, hy)) = e.window();
    let (d0, d1) = e.z;
    let pad = (d1 - d0).max(span * SLIVER) * DEPTH_PAD;
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
        span: far - near,
        orthographic: true,
    }
}

/// Half the window for a span of `s`, padded, and at least a sliver of the larger span so a
/// flat body still gets a non-degenerate window.
fn window_half(s: f64, span: f64) -> f64 {
    (s.max(span * SLIVER) * 0.5) * (1.0 + 2.0 * WINDOW_PAD)
}

/// An orthonormal light frame looking along `axis`: (right, up).
pub(super) fn frame_of(axis: DVec3, up_hint: DVec3) -> (DVec3, DVec3) {
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
        let (right, up) = frame_of(axis, pick_up_f64(axis));
        let mut e = Extent::EMPTY;
        for p in pts {
            let r = *p - q;
            let t = r.dot(axis);
            if t.is_nan() || t <= MIN_FRONT_COSINE * r.length() {
                return None;
            }
            e.grow(r.dot(right) / t, r.dot(up) / t, t);
        }
        window = Some((axis, right, up, e));
        let (cx, cy) = ((e.x.0 + e.x.1) * 0.5, (e.y.0 + e.y.1) * 0.5);
        axis = (axis + right * cx + up * cy).normalize();
    }
    let (axis, right, up, e) = window?;
    if [e.x.0, e.x.1, e.y.0, e.y.1]
        .iter()
        .any(|x| x.abs() > max_tangent)
    {
        return None;
    }
    let (_, (cx, cy, hx, hy)) = e.window();
    let (t0, t1) = e.z;
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
    let span = (t1 - t0).max(t1 * MIN_DEPTH_SPAN);
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
        (t1 * INSIDE_NEAR_FRACTION, t1 * (1.0 + DEPTH_PAD))
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
        span: far - near,
        orthographic: false,
    }
}
