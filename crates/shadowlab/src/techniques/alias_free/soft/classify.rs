//! The bitmask classification of exact soft alias-free shadows: which of a view sample's
//! `N` light samples a caster triangle certainly hides, which it certainly leaves, and
//! which lie so close to one of its edges that only the reference's own ray can tell.
//!
//! The ray from the view sample's shadow-ray origin `o` to light sample `P` hits the
//! triangle exactly when `P` is on the inner side of the three planes through `o` and each
//! edge and beyond the triangle's plane (for a distant light, when the direction is). Each
//! of these four is an affine function `α·x + β·y + γ` of the sample's frame coordinates
//! (see [`super::samples`]), so the light's bounding square first decides whole pairs (no
//! sample can be inside, or every sample is) and otherwise one pass over the sample
//! arrays gives two bitmasks: the samples inside every plane by its margin, and those
//! outside one by its margin. This is the sub-pixel paper's look-up-table idea (Pan et
//! al. 2009) applied to the light's samples, with the table replaced by evaluating the
//! planes directly (two fused multiply-adds a sample and plane, vectorized), which is
//! exact to the margin instead of to a table's bin.
//!
//! The margins are [`SOFT_TOLERANCE`] of the magnitudes each function is computed from
//! (coordinates, and the products of the distances that the watertight test's own
//! rounding moves a vertex or a direction by), so a sample classified either way gets the
//! same answer from the exact ray test; the band between is left to that test.
//!
//! A view sample lying in the triangle's plane within the margins (a neighbour of its own
//! triangle on the same flat surface) has no certain side: it is left entirely to the ray
//! test unless it lies outside the triangle by more than any ray from it to the light
//! could travel within the margins before leaving the plane.

use super::samples::{grow, union, Frame3, FrameBox, LightSamples, EMPTY_BOX, GROUP, GROUP_BITS};
use super::SOFT_TOLERANCE;
use crate::math::Vec3;

/// One view sample as the classification sees it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Receiver {
    /// Shadow-ray origin.
    pub(super) o: Vec3,
    /// The light's frame from this sample.
    pub(super) f: Frame3,
    /// `A − w·o`: the frame's origin relative to `o` (its direction for a distant light).
    pub(super) aw: Vec3,
    /// Magnitude of the coordinates the functions are formed from.
    pub(super) size: f32,
    /// Longest reach from `o` to a light sample (a direction's length for a distant light).
    pub(super) reach: f32,
}

impl Receiver {
    /// The receiver at shadow-ray origin `o` under the frame `f`.
    pub(super) fn new(o: Vec3, f: Frame3, ls: &LightSamples) -> Receiver {
        let span = ls.ext * (f.u.length() + f.v.length());
        let aw = f.a - o * ls.w;
        Receiver {
            o,
            f,
            aw,
            size: f.a.length() + span + o.length() * ls.w,
            reach: aw.length() + span,
        }
    }
}

/// A caster triangle and its plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct Caster {
    pub(super) v: [Vec3; 3],
    /// `(v₁ − v₀) × (v₂ − v₀)` and its length.
    nt: Vec3,
    nt_len: f32,
    /// `nt · v₀`.
    dt: f32,
    /// Largest vertex coordinate magnitude.
    vlen: f32,
    /// Longest edge.
    e_max: f32,
}

impl Caster {
    /// The caster with vertices `v`.
    pub(super) fn new(v: [Vec3; 3]) -> Caster {
        let nt = (v[1] - v[0]).cross(v[2] - v[0]);
        Caster {
            v,
            nt,
            nt_len: nt.length(),
            dt: nt.dot(v[0]),
            vlen: v.iter().map(|p| p.length()).fold(0.0, f32::max),
            e_max: (0..3)
                .map(|k| (v[(k + 1) % 3] - v[k]).length())
                .fold(0.0, f32::max),
        }
    }
}

/// An affine function `α·x + β·y + γ` of the light-sample coordinates and its margin.
pub(super) type Plane = [f32; 4];

/// What a triangle does to a view sample's light samples.
#[derive(Clone, Copy, Debug)]
pub(super) enum Verdict {
    /// No light sample's ray hits it.
    Miss,
    /// Every light sample's ray hits it.
    Hit,
    /// A sample's ray hits it when every plane is positive (certainly, beyond its margin),
    /// and misses it when one is negative beyond its margin.
    Planes([Plane; 4], usize),
    /// Every light sample's ray decides.
    Grazing,
}

/// The verdict of caster `c` on receiver `r`.
///
/// `bx` bounds the frame coordinates of the light samples that still matter
/// (`[x_lo, x_hi, y_lo, y_hi]`): whole-pair decisions are taken over it.
pub(super) fn classify(r: &Receiver, c: &Caster, ls: &LightSamples, bx: [f32; 4]) -> Verdict {
    let tol = SOFT_TOLERANCE;
    let w = ls.w;
    let rel = c.v.map(|v| v - r.o);
    let rl = rel.map(|d| d.length());
    let s_max = rl[0].max(rl[1]).max(rl[2]);
    let fo = c.nt.dot(r.o) - c.dt;
    // Moving a vertex by tol·s_max (the watertight test's rounding, relative to o)
    // moves nt by up to 2·e_max times that, so fo and the plane's value at a light sample
    // by that times their distances, plus |nt| times the move.
    let mv = s_max * (2.0 * c.e_max);
    let m_o = tol * (c.nt_len * (r.o.length() + c.vlen + s_max) + mv * s_max);
    let m_f = tol * (c.nt_len * (r.size + c.vlen + s_max) + mv * (r.reach + s_max));
    // The triangle's plane over the light: n·P − w·(n·v₀).
    let f_plane = [
        c.nt.dot(r.f.u),
        c.nt.dot(r.f.v),
        c.nt.dot(r.f.a) - w * c.dt,
        m_f,
    ];
    if fo.abs() <= m_o {
        return grazing(r, c, bx, f_plane, fo.abs() + m_o, s_max);
    }
    // Oriented so the inner side is positive: the edge planes' orientation is the sign of
    // (v₀ − o)·((v₁ − o) × (v₂ − o)) = −fo, and "beyond" is the side opposite to o.
    let sigma = -fo.signum();
    let mut planes = [[0.0f32; 4]; 4];
    let mut count = 0;
    let mut add = |p: Plane| -> bool {
        let p = [sigma * p[0], sigma * p[1], sigma * p[2], p[3]];
        let (lo, hi) = range(&p, bx);
        if hi < -p[3] {
            // Every sample is outside.
            return false;
        }
        // Kept unless every sample is inside (a NaN is kept: it certifies nothing).
        if lo.is_nan() || lo <= p[3] {
            planes[count] = p;
            count += 1;
        }
        true
    };
    if !add(f_plane) {
        return Verdict::Miss;
    }
    for k in 0..3 {
        let k1 = (k + 1) % 3;
        let n = rel[k].cross(rel[k1]);
        // Rounding of the frame and of this evaluation (|n| times the magnitudes), of n
        // (moving either end by tol of its distance), and of the ray's direction.
        let m = tol * (n.length() * (r.size + r.reach) + 2.0 * rl[k] * rl[k1] * r.reach);
        if !add([n.dot(r.f.u), n.dot(r.f.v), n.dot(r.aw), m]) {
            return Verdict::Miss;
        }
    }
    if count == 0 {
        Verdict::Hit
    } else {
        Verdict::Planes(planes, count)
    }
}

/// The verdict for a receiver in the triangle's plane (within the margins): a miss when
/// it lies outside the triangle by more than a ray to the light can move in the plane
/// while it is that close to it, else the rays decide. `d_o` bounds |fo|.
fn grazing(r: &Receiver, c: &Caster, bx: [f32; 4], f: Plane, d_o: f32, s_max: f32) -> Verdict {
    let (lo, hi) = range(&f, bx);
    // The light's least distance from the plane, times |nt|.
    let fm = if lo > 0.0 {
        lo
    } else if hi < 0.0 {
        -hi
    } else {
        0.0
    };
    if fm.is_nan() || fm <= f[3] {
        return Verdict::Grazing;
    }
    // A ray crosses the plane within this distance of o (similar triangles).
    let r_hit = r.reach * d_o / (fm - f[3]);
    let slack = SOFT_TOLERANCE * (s_max + r.o.length() + c.vlen);
    for k in 0..3 {
        let g = c.nt.cross(c.v[(k + 1) % 3] - c.v[k]);
        let dist = g.dot(r.o - c.v[k]) / g.length();
        if dist < -(r_hit + slack) {
            return Verdict::Miss;
        }
    }
    Verdict::Grazing
}

/// The least and greatest value of plane `p` over the box `bx` of frame coordinates.
fn range(p: &Plane, bx: [f32; 4]) -> (f32, f32) {
    let (x0, x1) = (p[0] * bx[0], p[0] * bx[1]);
    let (y0, y1) = (p[1] * bx[2], p[1] * bx[3]);
    (
        p[2] + x0.min(x1) + y0.min(y1),
        p[2] + x0.max(x1) + y0.max(y1),
    )
}

/// The box `[x_lo, x_hi, y_lo, y_hi]` of the light samples set in `live` (a whole live
/// group contributes its stored box, the same minimum and maximum over the same samples).
pub(super) fn live_box(live: &[u64], ls: &LightSamples) -> FrameBox {
    let mut b = EMPTY_BOX;
    for (w, &bits) in live.iter().enumerate() {
        for g in 0..64 / GROUP {
            let mut bits = (bits >> (g * GROUP)) & GROUP_BITS;
            if bits == GROUP_BITS {
                b = union(b, ls.group_box(w * (64 / GROUP) + g));
                continue;
            }
            while bits != 0 {
                let i = w * 64 + g * GROUP + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                b = grow(b, ls.xs[i], ls.ys[i]);
            }
        }
    }
    b
}

/// Groups in a word.
const WORD_GROUPS: usize = 64 / GROUP;

/// For every light sample, whether it is certainly inside all `planes` (`inside`) and
/// certainly outside one (`outside`), one bit a sample. In each live word, one pass over
/// its groups' boxes first decides each group whose box lies inside every plane, or
/// outside one, by its margin plus the rounding of the box's bound (each of its samples
/// would be decided so one by one); the other live groups are evaluated sample by sample.
/// Both passes run over fixed-size arrays (so the loops vectorize). Words where `live` is
/// empty are left alone; planes with a non-finite coefficient certify nothing.
pub(super) fn masks(
    planes: &[Plane],
    ls: &LightSamples,
    live: &[u64],
    inside: &mut [u64],
    outside: &mut [u64],
) {
    if !planes.iter().flatten().all(|c| c.is_finite()) {
        return;
    }
    let [x_lo, x_hi, y_lo, y_hi] = &ls.group_bounds;
    // Each plane with the bounds that give its least and greatest value over a box, and
    // its margin widened by a few ulps of the magnitudes a bound is summed from (over the
    // whole shape), which covers the bound's own rounding.
    let mut prepared = [(Plane::default(), [&x_lo[..], x_hi, y_lo, y_hi]); 4];
    for (q, p) in prepared.iter_mut().zip(planes) {
        let m = p[3] + 8.0 * f32::EPSILON * (p[2].abs() + (p[0].abs() + p[1].abs()) * ls.ext);
        let (xa, xb) = if p[0] >= 0.0 {
            (x_lo, x_hi)
        } else {
            (x_hi, x_lo)
        };
        let (ya, yb) = if p[1] >= 0.0 {
            (y_lo, y_hi)
        } else {
            (y_hi, y_lo)
        };
        *q = ([p[0], p[1], p[2], m], [xa, xb, ya, yb]);
    }
    let prepared = &prepared[..planes.len()];
    for (wi, &lw) in live.iter().enumerate() {
        if lw == 0 {
            continue;
        }
        // Over the word's groups, the least of (lower bound − margin) and of (upper
        // bound + margin) over the planes.
        let mut lo = [f32::INFINITY; WORD_GROUPS];
        let mut hi = [f32::INFINITY; WORD_GROUPS];
        let at = wi * WORD_GROUPS..(wi + 1) * WORD_GROUPS;
        for (p, [xa, xb, ya, yb]) in prepared {
            let (Ok(xa), Ok(xb), Ok(ya), Ok(yb)) = (
                <&[f32; WORD_GROUPS]>::try_from(&xa[at.clone()]),
                <&[f32; WORD_GROUPS]>::try_from(&xb[at.clone()]),
                <&[f32; WORD_GROUPS]>::try_from(&ya[at.clone()]),
                <&[f32; WORD_GROUPS]>::try_from(&yb[at.clone()]),
            ) else {
                return;
            };
            for g in 0..WORD_GROUPS {
                let a = p[0] * xa[g] + p[1] * ya[g] + p[2] - p[3];
                let b = p[0] * xb[g] + p[1] * yb[g] + p[2] + p[3];
                lo[g] = if a < lo[g] { a } else { lo[g] };
                hi[g] = if b < hi[g] { b } else { hi[g] };
            }
        }
        let (mut i, mut o) = (0u64, 0u64);
        for k in 0..WORD_GROUPS {
            if (lw >> (k * GROUP)) & GROUP_BITS == 0 {
                continue;
            }
            let (gi, go) = if lo[k] > 0.0 {
                (GROUP_BITS, 0)
            } else if hi[k] < 0.0 {
                (0, GROUP_BITS)
            } else {
                group_masks(planes, ls, (wi * WORD_GROUPS + k) * GROUP)
            };
            i |= gi << (k * GROUP);
            o |= go << (k * GROUP);
        }
        inside[wi] = i;
        outside[wi] = o;
    }
}

/// The inside and outside bits of the group starting at sample `first`, sample by sample.
fn group_masks(planes: &[Plane], ls: &LightSamples, first: usize) -> (u64, u64) {
    let (Ok(xc), Ok(yc)): (Result<&[f32; GROUP], _>, Result<&[f32; GROUP], _>) = (
        ls.xs[first..first + GROUP].try_into(),
        ls.ys[first..first + GROUP].try_into(),
    ) else {
        return (0, 0);
    };
    // Least value of (E − margin) and of (E + margin) over the planes.
    let mut lo = [f32::INFINITY; GROUP];
    let mut hi = [f32::INFINITY; GROUP];
    for p in planes {
        for j in 0..GROUP {
            let e = p[0] * xc[j] + p[1] * yc[j] + p[2];
            let (a, b) = (e - p[3], e + p[3]);
            lo[j] = if a < lo[j] { a } else { lo[j] };
            hi[j] = if b < hi[j] { b } else { hi[j] };
        }
    }
    let (mut i, mut o) = (0u64, 0u64);
    for j in 0..GROUP {
        i |= u64::from(lo[j] > 0.0) << j;
        o |= u64::from(hi[j] < 0.0) << j;
    }
    (i, o)
}
