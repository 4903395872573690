//! Stage three of alias-free shadow maps (Aila & Laine 2004, Section 5.1; "Rasterization
//! of blockers" in Table 1): every caster triangle is rasterized hierarchically into the
//! BSP of each light image plane. The traversal descends only into nodes the triangle's
//! footprint ([`TriSetup`]) overlaps, and in the leaves each sample is tested for coverage
//! and depth, its shadow term going straight to the sample's screen pixel (or layer
//! sample).
//!
//! The paper's occlusion culling: a node whose samples are all in shadow is skipped by
//! every later triangle, and a triangle beyond a node's maximum depth skips the node.
//! Semi-transparent casters (Section 4) modulate the sample's RGB transmittance, an opaque
//! one sets it to black. An alpha-masked caster counts only where its texture keeps it, at
//! the barycentrics of the exact ray test (the reference's own bits).
//!
//! The work is split over the subtrees of the BSP (units, each owning its samples), and each
//! unit takes its triangles in index order, binned in fixed chunks: results and counters
//! are identical for any thread count.

use super::bsp::{Bsp, Node, NO_UNIT};
use super::setup::{setup, TriSetup};
use super::{Buffers, Frame, Visibility};
use crate::math::Vec3;
use crate::scene::Scene;
use rayon::prelude::*;

/// Triangles per chunk of the binning pass (a fixed size keeps counters independent of the
/// thread count).
const BIN_CHUNK: usize = 8 * 1024;

/// Work counters (the paper's Table 1).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Counters {
    /// Nodes the traversals (and the binning above the units) entered.
    pub(super) nodes_visited: u64,
    /// Nodes skipped because all their samples were already dark.
    pub(super) occlusion_culled: u64,
    /// Samples not yet dark in the leaves visited.
    pub(super) samples_tested: u64,
    /// Samples inside a triangle's footprint that took the exact test.
    pub(super) ray_tests: u64,
    /// Triangle set-ups handed to units.
    pub(super) triangles_binned: u64,
    /// Bytes of those set-ups.
    pub(super) setup_bytes: usize,
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
    v: [Vec3; 3],
    opaque: bool,
    transmittance: Vec3,
    masked: bool,
}

/// The caster of triangle `id`.
fn caster(scene: &Scene, id: u32) -> Caster {
    let m = scene.material_of(id as usize);
    Caster {
        v: scene.triangle(id as usize),
        opaque: m.is_opaque(),
        transmittance: m.transmittance,
        masked: m.alpha_mask.is_some(),
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
        let bsp = self.bsp;
        let mut caster = None;
        walk(&bsp.nodes, t.entry, |ni| {
            self.counters.nodes_visited += 1;
            if self.done[(ni - self.root) as usize] {
                self.counters.occlusion_culled += 1;
                return false;
            }
            let n = &bsp.nodes[ni as usize];
            if !t.overlaps(n) {
                return false;
            }
            if !n.is_leaf() {
                return true;
            }
            if self.leaf(ni, n, t, &mut caster, scene) {
                self.mark_done(ni);
            }
            false
        });
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
                let hit = match ray.hit(c.v) {
                    Some(b) => !c.masked || !scene.cut_out(t.id as usize, b),
                    None => false,
                };
                if hit {
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
    walk(&bsp.nodes, t.entry, |ni| {
        let u = bsp.unit[ni as usize];
        if u != NO_UNIT {
            out[u as usize].push(TriSetup { entry: ni, ..*t });
            return false;
        }
        *visited += 1;
        t.overlaps(&bsp.nodes[ni as usize])
    });
}

/// Visits the subtree of `entry` depth-first in preorder (left child first): `descend(ni)`
/// says whether to go on into the children of internal node `ni`.
#[inline]
fn walk(nodes: &[Node], entry: u32, mut descend: impl FnMut(u32) -> bool) {
    let mut stack = [0u32; STACK];
    stack[0] = entry;
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let ni = stack[sp];
        if descend(ni) {
            stack[sp] = nodes[ni as usize].right;
            stack[sp + 1] = ni + 1;
            sp += 2;
        }
    }
}

/// The shadow terms of every triangle rasterized into every plane's BSP: per pixel, and per
/// layer sample when the frame has layers.
pub(super) fn rasterize(
    frame: &Frame,
    trees: &[Bsp],
    buf: &mut Buffers,
) -> (Visibility, Option<Vec<Vec3>>, Counters) {
    let scene = frame.scene;
    let (mut out, mut layer_out) = unshadowed(frame);
    let pixels = out.value.len();
    let mut total = Counters::default();
    for bsp in trees {
        if bsp.nodes.is_empty() {
            continue;
        }
        let chunks = bin_chunks(bsp, scene, &mut total);
        let n = bsp.su.len();
        let mut vis = buf.vis.take();
        vis.resize(n, Vec3::ONE);
        let mut alive = buf.flags.take();
        alive.resize(n, true);
        let mut work = units(bsp, &mut vis, &mut alive);
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

/// The shadow terms before any caster: lit, except where the viewed side of the surface
/// faces away from the light (dark in every technique).
fn unshadowed(frame: &Frame) -> (Visibility, Option<Vec<Vec3>>) {
    let view = frame.view;
    let mut out = Visibility::lit(view.width, view.height);
    let layer_out = frame.layers.map(|l| {
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
    out.value
        .par_iter_mut()
        .with_min_len(4096)
        .enumerate()
        .for_each(|(k, v)| {
            if view.covered(k) && !frame.receiver_lit(k) {
                *v = Vec3::ZERO;
            }
        });
    (out, layer_out)
}

/// Per chunk of [`BIN_CHUNK`] triangles: the set-ups binned into each unit (in index
/// order) and the nodes the binning visited. Adds the binning's counts to `total`.
fn bin_chunks(bsp: &Bsp, scene: &Scene, total: &mut Counters) -> Vec<(Vec<Vec<TriSetup>>, u64)> {
    let units = bsp.unit_roots.len();
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
    chunks
}

/// The units of `bsp`, each with its own contiguous run of the samples' transmittances
/// `vis` and flags `alive` (leaf order) and of the nodes.
fn units<'a>(bsp: &'a Bsp, vis: &'a mut [Vec3], alive: &'a mut [bool]) -> Vec<Unit<'a>> {
    let mut work = Vec::with_capacity(bsp.unit_roots.len());
    let (mut vr, mut ar) = (vis, alive);
    for (u, &r) in bsp.unit_roots.iter().enumerate() {
        let node = bsp.nodes[r as usize];
        let (v, vrest) = vr.split_at_mut(node.len as usize);
        let (a, arest) = ar.split_at_mut(node.len as usize);
        (vr, ar) = (vrest, arest);
        let end = bsp
            .unit_roots
            .get(u + 1)
            .map_or(bsp.nodes.len(), |&x| x as usize);
        // Nodes of the subtree: from the root to the next unit's root, less the nodes above
        // the units that preorder puts between them.
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
    work
}
