//! Stage three's set-up for exact soft alias-free shadows: each caster triangle's
//! *penumbra footprint* on a light image plane (the soft counterpart of the hard
//! technique's triangle set-up), a conservative rectangle and minimum depth that every
//! view sample some light sample's ray through the triangle can start from lies in.
//!
//! Why it bounds: if the segment from a point `p` to a light point `l` passes through the
//! triangle at `t`, then `p − c = (t − c) + s·(t − l)` with `s ≥ 0` (`c` the light's
//! centre, the projection's origin). Seen from `c`, `p` lies in the cone spanned by the
//! vectors `vₖ − c` and `vₖ − cⱼ` (vertices `vₖ`, corners `cⱼ` of the light's bounding
//! shape, which holds every `l`): when all of them point into the face, the cone's image is
//! the hull of their projections (its rectangle is kept), and the depth of `p` is at least
//! that of the nearest vertex. A cone that leaves the face is not bounded (the whole face).
//! For a distant light (orthographic plane) `p = t + s·d` with `d` in the light's cone:
//! the triangle's rectangle widened by the depth range times the tangent of its angular
//! radius.
//!
//! Every bound is widened by [`SOFT_TOLERANCE`] of the distances involved: a larger
//! widening only sends more pairs to the exact classification.
//!
//! The cone reaches every depth behind the triangle, but a BSP node's samples lie no deeper
//! than its `zmax`, and a shallow receiver sees only a narrow penumbra. With `c` the origin,
//! `p = (1 + s)·t − s·l` has the image of `t − σ·l`, `σ = s / (1 + s)`; when every vertex
//! lies deeper than every light corner, `p_z ≤ Z` bounds `s` by
//! `S = (Z − t_z,min) / (t_z,min − l_z,max)`, so the image lies in the hull of the vertices'
//! images and those of `vₖ − σ_max·cⱼ`, `σ_max = S / (1 + S) < 1` ([`DepthBound`]).

use super::super::bsp::{Bsp, Node};
use super::super::transform::{Ortho, Persp, Projection};
use super::SOFT_TOLERANCE;
use crate::math::Vec3;

/// A caster's penumbra footprint on one plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct Footprint {
    pub(super) lo: [f32; 2],
    pub(super) hi: [f32; 2],
    /// No sample nearer the light than this can be shadowed.
    pub(super) zmin: f32,
    /// Triangle index.
    pub(super) id: u32,
}

impl Footprint {
    /// True when the footprint may hold a sample of `n`.
    #[inline]
    pub(super) fn overlaps(&self, n: &Node) -> bool {
        self.lo[0] <= n.hi[0]
            && self.hi[0] >= n.lo[0]
            && self.lo[1] <= n.hi[1]
            && self.hi[1] >= n.lo[1]
            && self.zmin <= n.zmax
    }

    /// True when the footprint may hold the sample at `(u, v)` of depth `z`.
    #[inline]
    pub(super) fn holds(&self, u: f32, v: f32, z: f32) -> bool {
        (u >= self.lo[0])
            & (u <= self.hi[0])
            & (v >= self.lo[1])
            & (v <= self.hi[1])
            & (z >= self.zmin)
    }
}

/// A perspective plane's light corners, for footprints bounded by a node's depth.
pub(super) struct DepthBound {
    /// The corners in the face's coordinates (relative to the light's centre).
    corners: Vec<Vec3>,
    /// Their greatest depth.
    lz_max: f32,
    /// The plane's distance scale.
    scale: f32,
}

/// One caster as [`DepthBound::rect`] bounds it: its vertices in the face's coordinates,
/// their least depth (less the slack) and its distance beyond the deepest light corner.
pub(super) struct CasterDepth {
    v: [Vec3; 3],
    tz_min: f32,
    gap: f32,
}

impl DepthBound {
    /// The bound of a perspective plane; `None` for an orthographic one.
    pub(super) fn of(bsp: &Bsp, corners: &[Vec3]) -> Option<DepthBound> {
        let Projection::Persp(pp) = &bsp.proj else {
            return None;
        };
        let corners: Vec<Vec3> = corners.iter().map(|&c| pp.coords(c)).collect();
        let lz_max = corners
            .iter()
            .map(|c| c.z)
            .fold(f32::NEG_INFINITY, f32::max);
        Some(DepthBound {
            corners,
            lz_max,
            scale: bsp.scale,
        })
    }

    /// Triangle `v` on `bsp`'s plane (this bound's); `None` when it is not deeper than
    /// every light corner, where no tighter bound than the cone's holds.
    pub(super) fn caster(&self, bsp: &Bsp, v: [Vec3; 3]) -> Option<CasterDepth> {
        let Projection::Persp(pp) = &bsp.proj else {
            return None;
        };
        let v = v.map(|p| pp.coords(p));
        let slack = SOFT_TOLERANCE * self.scale;
        let tz_min = v[0].z.min(v[1].z).min(v[2].z) - slack;
        let gap = tz_min - (self.lz_max + slack);
        // Every vertex deeper than every corner (false for a NaN).
        let deeper = gap > 0.0;
        deeper.then_some(CasterDepth { v, tz_min, gap })
    }

    /// The rectangle `[lo, hi]` holding the image of every view sample no deeper than `z`
    /// that a light sample's ray through caster `c` can start from; `None` when a
    /// generator lies too close to the light's plane.
    pub(super) fn rect(&self, c: &CasterDepth, z: f32) -> Option<([f32; 2], [f32; 2])> {
        let tol = SOFT_TOLERANCE;
        if !z.is_finite() {
            return None;
        }
        let reach = (z + tol * self.scale - c.tz_min).max(0.0);
        let s_max = reach / c.gap * (1.0 + tol);
        let sigma = (s_max / (1.0 + s_max) * (1.0 + tol)).min(1.0);
        if !sigma.is_finite() {
            return None;
        }
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        let mut add = |g: Vec3| -> bool {
            // In front of the light's plane by the margin (false for a NaN).
            let in_front = g.z > tol * (g.length() + self.scale);
            if in_front {
                widen(&mut lo, &mut hi, g, self.scale);
            }
            in_front
        };
        for p in &c.v {
            if !add(*p) {
                return None;
            }
            for &l in &self.corners {
                if !add(*p - l * sigma) {
                    return None;
                }
            }
        }
        Some((lo, hi))
    }
}

/// `[lo, hi]` grown to hold the image of generator `g` (in front of the plane), widened by
/// the rounding of its projection and of the samples' own.
fn widen(lo: &mut [f32; 2], hi: &mut [f32; 2], g: Vec3, scale: f32) {
    let (u, w) = (g.x / g.z, g.y / g.z);
    let d = 4.0 * SOFT_TOLERANCE * (1.0 + u.abs() + w.abs()) * (1.0 + (g.length() + scale) / g.z);
    *lo = [lo[0].min(u - d), lo[1].min(w - d)];
    *hi = [hi[0].max(u + d), hi[1].max(w + d)];
}

/// The footprint of triangle `id` (vertices `v`) on `bsp`'s plane; `corners` bound the
/// light, `tan_radius` is a distant light's angular extent. `None` when it can shadow no
/// sample of the plane.
pub(super) fn footprint(
    bsp: &Bsp,
    corners: &[Vec3],
    tan_radius: f32,
    v: [Vec3; 3],
    id: u32,
) -> Option<Footprint> {
    let root = bsp.nodes.first()?;
    let f = match &bsp.proj {
        Projection::Ortho(o) => ortho(o, bsp.scale, root, tan_radius, v, id),
        Projection::Persp(p) => perspective(p, bsp.scale, corners, v, id),
    }?;
    f.overlaps(root).then_some(f)
}

/// On a distant light's orthographic plane.
fn ortho(
    o: &Ortho,
    scale: f32,
    root: &Node,
    tan_radius: f32,
    v: [Vec3; 3],
    id: u32,
) -> Option<Footprint> {
    let p = v.map(|p| o.coords(p));
    let tol = SOFT_TOLERANCE * scale;
    let zmin = p[0][2].min(p[1][2]).min(p[2][2]) - tol;
    let reach = (root.zmax - zmin).max(0.0) * tan_radius * (1.0 + SOFT_TOLERANCE) + tol;
    let lo = [0, 1].map(|a| p[0][a].min(p[1][a]).min(p[2][a]) - reach);
    let hi = [0, 1].map(|a| p[0][a].max(p[1][a]).max(p[2][a]) + reach);
    Some(Footprint { lo, hi, zmin, id })
}

/// On a perspective face about the light's centre.
fn perspective(
    pp: &Persp,
    scale: f32,
    corners: &[Vec3],
    v: [Vec3; 3],
    id: u32,
) -> Option<Footprint> {
    let rot = |d: Vec3| Vec3::new(d.dot(pp.s), d.dot(pp.t), d.dot(pp.f));
    let mut gens = [Vec3::ZERO; 3 + 3 * 8];
    let mut count = 0;
    for p in v {
        gens[count] = pp.coords(p);
        count += 1;
        for &c in corners {
            gens[count] = rot(p - c);
            count += 1;
        }
    }
    let gens = &gens[..count];
    let tol = SOFT_TOLERANCE;
    if gens.iter().all(|g| g.z < -tol * g.length()) {
        // The cone lies behind the face: no sample of it is in reach.
        return None;
    }
    if gens.iter().any(|g| g.z <= tol * (g.length() + scale)) {
        return Some(Footprint {
            lo: [f32::NEG_INFINITY; 2],
            hi: [f32::INFINITY; 2],
            zmin: f32::NEG_INFINITY,
            id,
        });
    }
    let zmin = v
        .iter()
        .map(|p| pp.coords(*p).z)
        .fold(f32::INFINITY, f32::min)
        - tol * scale;
    let mut lo = [f32::INFINITY; 2];
    let mut hi = [f32::NEG_INFINITY; 2];
    for &g in gens {
        widen(&mut lo, &mut hi, g, scale);
    }
    Some(Footprint { lo, hi, zmin, id })
}
