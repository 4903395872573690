//! Stage two of alias-free shadow maps (Aila & Laine 2004, Section 5.1 "Light-Space
//! Hierarchy"; "BSP construction" in Table 1): the sampling points of one light image plane
//! are organised into an axis-aligned 2D BSP tree, split in half at the median (quickselect,
//! expected linear time) alternately along x and y until a leaf holds at most `leaf-size`
//! samples. Every node keeps the tight rectangle of its samples and their maximum light
//! depth, for the rasterization's culling.
//!
//! Also built here: the subtrees that are the units of parallel work, and the
//! [`EntryGrid`] that lets a small triangle start its traversal below the root (a departure
//! from the paper, which starts every traversal at the root).

use super::shadow_ray::ShadowRay;
use super::transform::{Plane, Projection, Pt};
use super::Buffers;
use rayon::prelude::*;
use std::collections::HashMap;

/// BSP depth of the subtrees that are the units of parallel work (up to 2⁶ = 64 units):
/// enough for load balance on a few cores while the binning above them stays cheap.
const UNIT_DEPTH: u32 = 6;
/// Below this many samples a BSP subtree is built on one thread.
const PARALLEL_BUILD_MIN: usize = 32 * 1024;

/// A BSP node: the tight rectangle and maximum depth of its samples. Internal nodes have
/// their left child right after them (preorder) and `right` further on; leaves have
/// `right == 0` and own the samples `start .. start + len`.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Node {
    pub(super) lo: [f32; 2],
    pub(super) hi: [f32; 2],
    pub(super) zmax: f32,
    pub(super) start: u32,
    pub(super) len: u32,
    pub(super) right: u32,
}

impl Node {
    /// True for a leaf (no children).
    #[inline]
    pub(super) fn is_leaf(&self) -> bool {
        self.right == 0
    }
}

/// Marks nodes above the units of parallel work.
pub(super) const NO_UNIT: u32 = u32::MAX;

/// The BSP of one light image plane, with its samples in leaf order.
pub(super) struct Bsp {
    pub(super) proj: Projection,
    /// Scale of the culling tolerance (see [`Plane::scale`]).
    pub(super) scale: f32,
    /// The nodes in preorder, the root first.
    pub(super) nodes: Vec<Node>,
    /// Parent of each node (the root's is itself).
    pub(super) parent: Vec<u32>,
    /// Depth of each node (the root's is 0).
    depth: Vec<u8>,
    /// The unit each node belongs to, [`NO_UNIT`] above them.
    pub(super) unit: Vec<u32>,
    /// Root node of each unit, in preorder.
    pub(super) unit_roots: Vec<u32>,
    /// Sample coordinates in leaf order.
    pub(super) su: Vec<f32>,
    pub(super) sv: Vec<f32>,
    pub(super) sz: Vec<f32>,
    /// Shadow rays in leaf order.
    pub(super) rays: Vec<ShadowRay>,
    grid: EntryGrid,
}

/// Number of nodes of the tree over `len` samples, memoized (each level has at most two
/// distinct sizes).
pub(super) fn node_count(len: usize, leaf: usize, memo: &mut HashMap<usize, usize>) -> usize {
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
    /// The tree over the samples of `plane`, leaves holding at most `leaf` samples.
    pub(super) fn build(plane: Plane, leaf: usize, buf: &mut Buffers) -> Bsp {
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
            let root = Place {
                base: 0,
                start: 0,
                depth: 0,
            };
            Build { leaf, memo: &memo }.node(&mut pts, &mut nodes, &mut parent, root);
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
    pub(super) fn recycle(self, buf: &mut Buffers) {
        buf.coords.give(self.su);
        buf.coords.give(self.sv);
        buf.coords.give(self.sz);
        buf.rays.give(self.rays);
    }

    /// The largest |(u, v, 1)| over the plane's samples.
    pub(super) fn max_direction_length(&self) -> f32 {
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
    pub(super) fn entry(&self, lo: [f32; 2], hi: [f32; 2]) -> u32 {
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

/// What every level of one tree's build shares.
struct Build<'a> {
    /// A leaf holds at most this many samples.
    leaf: usize,
    /// [`node_count`]'s memo for this tree.
    memo: &'a HashMap<usize, usize>,
}

/// Where one subtree goes.
#[derive(Clone, Copy)]
struct Place {
    /// Index of the subtree's root among all nodes.
    base: u32,
    /// Index of the subtree's first sample in the whole plane.
    start: u32,
    /// Level of the subtree's root (even: split along x, odd: along y).
    depth: u32,
}

impl Build<'_> {
    /// Builds the subtree over `pts` into `nodes` and `parent` (its preorder slices,
    /// starting at node index `at.base`).
    fn node(&self, pts: &mut [Pt], nodes: &mut [Node], parent: &mut [u32], at: Place) {
        let (leaf, memo) = (self.leaf, self.memo);
        let Place { base, start, depth } = at;
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
        let left_at = Place {
            base: base + 1,
            start,
            depth: depth + 1,
        };
        let right_at = Place {
            base: right,
            start: start + mid as u32,
            depth: depth + 1,
        };
        let mut build_left = || self.node(lp, &mut *ln, lpar, left_at);
        let mut build_right = || self.node(rp, &mut *rn, rpar, right_at);
        if len >= PARALLEL_BUILD_MIN {
            rayon::join(build_left, build_right);
        } else {
            build_left();
            build_right();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{TestRng as Lcg, Vec3};
    use crate::techniques::alias_free::transform::Ortho;

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
            let proj = Projection::Ortho(Ortho {
                c: Vec3::ZERO,
                s: Vec3::X,
                t: Vec3::Z,
                w: -Vec3::Y,
            });
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
