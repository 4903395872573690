//! Triangle set-up for the rasterization of alias-free shadow maps (Aila & Laine 2004,
//! Section 5.1: the traversal "proceeds to subnodes that are at least partially covered by
//! the input primitive"): each caster triangle's footprint on one light image plane — its
//! bounding rectangle, three edge functions and minimum light depth — widened so that no
//! test that uses it can drop a sample the exact shadow-ray test would count.
//!
//! The widening: every light-space position may be off by [`CULL_TOLERANCE`] of the
//! distances involved between this set-up and the ray test. On a perspective plane the
//! edge functions are the planes through the light and each edge (homogeneous
//! rasterization: no clipping at the light's plane); a triangle nearly edge-on from the
//! light, whose orientation rounding could flip, is bounded by the slab along its longest
//! edge instead.

use super::bsp::{Bsp, Node};
use super::transform::{Ortho, Persp, Projection};
use super::CULL_TOLERANCE;
use crate::math::Vec3;

// Orthographic planes: `tol` = CULL_TOLERANCE × the scene's diagonal bounds how far a
// vertex or a sample may be off between the plane and the ray test.

/// Widening of an edge function, in `tol` × the edge's length: the edge and the sample may
/// each be off by `tol`, which moves the sample's signed distance to the edge by up to
/// 2·tol, and the edge function is that distance times the edge's length.
const ORTHO_EDGE_WIDENING: f32 = 2.0;
/// Uncertainty of twice the triangle's area, in `tol` × its perimeter: moving one vertex by
/// `tol` changes twice the area by at most `tol` times the opposite edge (to first order),
/// `tol`·perimeter for all three; four leaves room for the second-order terms and the
/// area's own rounding. Beyond it the orientation is certain and the edge functions cull.
const ORTHO_AREA_ERROR: f32 = 4.0;

// Perspective planes: everything in units of δ, the bound on how far a vertex or a sample
// may be off in light space (see `DELTA`); `d_max` is the largest |(u, v, 1)| over the
// plane's samples.

/// δ in [`CULL_TOLERANCE`]s of the distances involved (the plane's scale plus the
/// vertex's distance to the light). Two, for room: a δ too small could drop a shadowed
/// sample, one too large only sends more samples to the exact test.
const DELTA: f32 = 2.0;
/// A triangle whose vertices all lie more than this many δ behind the light's plane is
/// culled: moved by δ it stays more than δ behind, out of reach of every segment from a
/// sample in front of the plane (z > 0) to the light, even with the sample moved by δ.
const BEHIND: f32 = 2.0;
/// Vertices more than this many δ in front of the light's plane are "in front": moved by δ
/// they keep at least ¾ of their depth, so dividing by it is safe and their projection
/// moves by at most 4/3 of the first-order bound (see [`PROJECTED_WIDENING`]).
const FRONT: f32 = 4.0;
/// A triangle crossing the plane whose distance to the light exceeds this many δ·d_max
/// may leave its part nearer the plane than [`FRONT`]·δ out of its rectangle: a point there
/// projects at |(u, v, 1)| = r/z > 16/4·d_max, and moved by δ still beyond 3·d_max, outside
/// every sample.
const NEAR_LIGHT: f32 = 16.0;
/// Widening of a projected vertex, in units of δ(1 + |u| + |v|)/z, the first-order bound
/// of how far u = x/z and v = y/z move when x, y, z move by δ: in front of the plane
/// ([`FRONT`]) the exact bound is at most 4/3 of it; two leaves room.
const PROJECTED_WIDENING: f32 = 2.0;
/// Widening of an edge plane's function n·(u, v, 1), in units of δ(|qᵢ| + |qⱼ|)·d_max:
/// moving the edge's ends by δ changes n = qᵢ × qⱼ by at most δ(|qᵢ| + |qⱼ|) (first
/// order), and |(u, v, 1)| ≤ d_max at every sample; two leaves room for the second-order
/// term.
const EDGE_PLANE_WIDENING: f32 = 2.0;
/// The slab of a nearly edge-on triangle is as wide as its height on the plane z = 1,
/// (|det| + its error)/z at the opposite vertex, times this: that z may be off by δ < z/4
/// (a factor of 4/3); two leaves room.
const SLAB_WIDENING: f32 = 2.0;

/// A caster triangle in one light image plane. Every test is conservative: a sample
/// outside it cannot be hit by the triangle's exact ray test.
#[derive(Clone, Copy, Debug)]
pub(super) struct TriSetup {
    /// Edge functions `a·u + b·v + c`, oriented and widened so a covered sample has all
    /// three ≥ 0.
    pub(super) e: [[f32; 3]; 3],
    /// Bounding rectangle of the footprint.
    pub(super) lo: [f32; 2],
    pub(super) hi: [f32; 2],
    /// Minimum light depth of the triangle (a sample nearer the light cannot be shadowed).
    pub(super) zmin: f32,
    /// Triangle index.
    pub(super) id: u32,
    /// The node its traversal starts at.
    pub(super) entry: u32,
}

/// An edge function that every point passes (for triangles whose orientation is not
/// reliable in floating point).
const PASS_ALL: [f32; 3] = [0.0, 0.0, 1.0];

impl TriSetup {
    /// True when the triangle may cover a sample of `n` that lies behind it.
    #[inline]
    pub(super) fn overlaps(&self, n: &Node) -> bool {
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
    pub(super) fn may_cover(&self, u: f32, v: f32, z: f32) -> bool {
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
pub(super) fn setup(bsp: &Bsp, v: [Vec3; 3], id: u32) -> Option<TriSetup> {
    let mut t = match &bsp.proj {
        Projection::Ortho(o) => ortho(o, bsp, v, id)?,
        Projection::Persp(p) => perspective(p, bsp, v, id)?,
    };
    t.entry = bsp.entry(t.lo, t.hi);
    Some(t)
}

/// The set-up on an orthographic plane.
fn ortho(o: &Ortho, bsp: &Bsp, v: [Vec3; 3], id: u32) -> Option<TriSetup> {
    let root = &bsp.nodes[0];
    let p = v.map(|p| o.coords(p));
    // Positions may be off by this much between the plane and the ray test.
    let tol = CULL_TOLERANCE * bsp.scale;
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
    let area2 =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    let mut e = [PASS_ALL; 3];
    let mut edges = [[0.0f32; 3]; 3];
    let mut perimeter = 0.0;
    for i in 0..3 {
        let (a, b) = (p[i], p[(i + 1) % 3]);
        // E(p) = (b − a) × (p − a), formed relative to `a` so its rounding error scales
        // with the edge length, not with the coordinates squared.
        let ea = a[1] - b[1];
        let eb = b[0] - a[0];
        let len = (ea * ea + eb * eb).sqrt();
        edges[i] = [ea, eb, len];
        perimeter += len;
    }
    let area_error = ORTHO_AREA_ERROR * tol * perimeter;
    let sigma = area2.signum();
    let ecs = [0, 1, 2].map(|i| -(edges[i][0] * p[i][0] + edges[i][1] * p[i][1]));
    if area2.abs() > area_error {
        for i in 0..3 {
            let [ea, eb, len] = edges[i];
            e[i] = [
                sigma * ea,
                sigma * eb,
                sigma * ecs[i] + ORTHO_EDGE_WIDENING * tol * len,
            ];
        }
    } else {
        // Nearly edge-on: the triangle lies in the slab along its longest edge whose
        // half-width is its height (twice the area over the edge, with its error).
        let i = (0..3)
            .max_by(|&a, &b| edges[a][2].total_cmp(&edges[b][2]))
            .unwrap_or(0);
        let [ea, eb, len] = edges[i];
        let w = area2.abs() + area_error + ORTHO_EDGE_WIDENING * tol * len;
        e[0] = [ea, eb, ecs[i] + w];
        e[1] = [-ea, -eb, -ecs[i] + w];
    }
    Some(TriSetup {
        e,
        lo,
        hi,
        zmin,
        id,
        entry: 0,
    })
}

/// The set-up on a perspective plane.
fn perspective(pp: &Persp, bsp: &Bsp, v: [Vec3; 3], id: u32) -> Option<TriSetup> {
    let root = &bsp.nodes[0];
    let q = v.map(|p| pp.coords(p));
    let ql = q.map(|q| q.length());
    // The shadow-ray test decides as if each vertex were moved by up to a few ulps of the
    // distances involved; `delta` bounds that move with room to spare.
    let delta = DELTA * CULL_TOLERANCE * (bsp.scale + ql[0].max(ql[1]).max(ql[2]));
    let zmin = q[0].z.min(q[1].z).min(q[2].z) - delta;
    if zmin > root.zmax {
        return None;
    }
    if q.iter().all(|q| q.z < -BEHIND * delta) {
        // Entirely behind the plane: no sample's segment to the light reaches it.
        return None;
    }
    let d_max = bsp.max_direction_length();
    let (lo, hi) = perspective_rect(&q, delta, d_max)?;
    Some(TriSetup {
        e: edge_planes(&q, ql, delta, d_max),
        lo,
        hi,
        zmin,
        id,
        entry: 0,
    })
}

/// The bounding rectangle of the footprint of the triangle `q` (light space) on the plane
/// z = 1: unbounded where it may pass too close to the light, `None` when no part of it is
/// in front of the plane.
fn perspective_rect(q: &[Vec3; 3], delta: f32, d_max: f32) -> Option<([f32; 2], [f32; 2])> {
    let front = FRONT * delta;
    if q.iter().all(|q| q.z > front) {
        // The rectangle of a triangle wholly in front of the light's plane.
        return Some(projected_rect(q, delta));
    }
    // Across the plane: the part nearer the plane than `front` projects beyond every
    // sample unless it passes close to the light, so the rectangle of the part in front
    // bounds the footprint (a lower bound of the distance to the light decides).
    let normal = (q[1] - q[0]).cross(q[2] - q[0]);
    let centroid = (q[0] + q[1] + q[2]) / 3.0;
    let radius = q
        .iter()
        .map(|p| (*p - centroid).length())
        .fold(0.0f32, f32::max);
    let plane_dist = q[0].dot(normal).abs() / normal.length();
    let r_min = plane_dist.max(centroid.length() - radius);
    if r_min > NEAR_LIGHT * delta * d_max {
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
        return Some(projected_rect(&clipped, delta));
    }
    Some(([f32::NEG_INFINITY; 2], [f32::INFINITY; 2]))
}

/// The edge functions of the triangle `q` (light space, vertex distances `ql`): the planes
/// through the light and each edge, or the slab of a triangle nearly edge-on from the light,
/// or [`PASS_ALL`] where neither is certain.
fn edge_planes(q: &[Vec3; 3], ql: [f32; 3], delta: f32, d_max: f32) -> [[f32; 3]; 3] {
    let mut e = [PASS_ALL; 3];
    // The planes through the light and each edge: n·(u, v, 1) is the edge function of the
    // projected edge, valid whatever side of the light's plane the vertices lie on
    // (homogeneous rasterization).
    let n = [q[0].cross(q[1]), q[1].cross(q[2]), q[2].cross(q[0])];
    let nl = n.map(|n| n.length());
    let margin = [0, 1, 2].map(|i| EDGE_PLANE_WIDENING * delta * (ql[i] + ql[(i + 1) % 3]) * d_max);
    // Moving the vertices by delta changes the triple product q0·(q1×q2) by at most
    // delta·Σ|qj×qk| (doubled here for room) and delta²-terms; f32 rounding adds a few
    // ε·|q0||q1||q2|. Beyond that the orientation is certain and the edge functions may cull.
    let det = q[0].dot(n[1]);
    let det_error = 2.0 * delta * (nl[0] + nl[1] + nl[2])
        + 6.0 * delta * delta * (ql[0] + ql[1] + ql[2])
        + 8.0 * f32::EPSILON * ql[0] * ql[1] * ql[2];
    if det.abs() > det_error {
        let sigma = det.signum();
        for i in 0..3 {
            e[i] = [sigma * n[i].x, sigma * n[i].y, sigma * n[i].z + margin[i]];
        }
    } else if q.iter().all(|q| q.z > FRONT * delta) {
        // Nearly edge-on from the light, and wholly in front of it: on the plane z = 1 the
        // triangle lies in the slab along the edge that looks longest, n·(u, v, 1) between
        // 0 and det/z at the opposite vertex (widened for its error).
        let i = (0..3).max_by(|&a, &b| nl[a].total_cmp(&nl[b])).unwrap_or(0);
        let w = SLAB_WIDENING * (det.abs() + det_error) / q[(i + 2) % 3].z + margin[i];
        e[0] = [n[i].x, n[i].y, n[i].z + w];
        e[1] = [-n[i].x, -n[i].y, -n[i].z + w];
    }
    e
}

/// The rectangle on the plane z = 1 of the points `q` (all in front of the light's plane),
/// each widened for a move of up to `delta` (see [`PROJECTED_WIDENING`]).
fn projected_rect(q: &[Vec3], delta: f32) -> ([f32; 2], [f32; 2]) {
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for p in q {
        let (u, v) = (p.x / p.z, p.y / p.z);
        let du = PROJECTED_WIDENING * delta * (1.0 + u.abs() + v.abs()) / p.z;
        lo = [lo[0].min(u - du), lo[1].min(v - du)];
        hi = [hi[0].max(u + du), hi[1].max(v + du)];
    }
    (lo, hi)
}
