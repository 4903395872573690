//! Stage three of exact soft alias-free shadows, the soft counterpart of the hard
//! technique's *rasterization of blockers* (Aila & Laine 2004, Section 5.1): every caster
//! triangle's penumbra footprint ([`super::footprint`]) is traversed through the BSP of
//! each light image plane, and in the leaves each view sample under it has its light
//! samples classified by bitmask ([`super::classify`]); the samples in the uncertain band
//! take the reference's own ray, so every light sample's verdict is the reference's.
//!
//! Opaque casters set bits of the sample's *dark* mask; a view sample whose lit samples
//! are all dark drops out of later triangles, and a node whose samples all have, out of
//! the traversal (the paper's occlusion culling). Alpha-masked casters take the ray test
//! on every sample the planes do not rule out (the texture decides at the ray's
//! barycentrics). Semi-transparent casters are recorded with the light samples they may
//! hide, and each light sample's transmittance is their product in triangle-index order
//! (the reference's order) unless an opaque caster hides it.
//!
//! The work is split over the BSP's units (subtrees owning their samples), each taking
//! the triangles in index order: results and counters are the same for any thread count.
//! The shadow term of a view sample is the sum of its light samples' transmittances in
//! sample order divided by `N`, the reference's arithmetic.

use super::super::bsp::{Bsp, Node};
use super::classify::{classify, live_box, masks, Caster, Receiver, Verdict};
use super::footprint::{footprint, DepthBound, Footprint};
use super::samples::{bounding_corners, frame_at, LightSamples, GROUP, GROUP_BITS};
use super::transform::LitMasks;
use crate::area_light::AreaLight;
use crate::frame::{Frame, Visibility};
use crate::math::{intersect_triangle, SurfacePoint, Vec3};
use crate::scene::Scene;
use crate::soft_reference::shadow_ray;
use rayon::prelude::*;

/// Work counters.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Counters {
    /// Nodes the traversals entered.
    pub(super) nodes_visited: u64,
    /// Nodes skipped because every light sample of every sample in them was dark.
    pub(super) occlusion_culled: u64,
    /// (view sample, triangle) pairs classified.
    pub(super) pairs: u64,
    /// Pairs decided whole by the light's bounding square: no light sample hidden…
    pub(super) pairs_missed: u64,
    /// …or every one.
    pub(super) pairs_hidden: u64,
    /// Pairs classified sample by sample with bitmasks.
    pub(super) pairs_masked: u64,
    /// Pairs whose view sample lies in the triangle's plane: every light sample's ray.
    pub(super) pairs_grazing: u64,
    /// Exact ray tests (light samples in an uncertain band, masked or grazing casters).
    pub(super) ray_tests: u64,
}

impl Counters {
    fn add(&mut self, o: &Counters) {
        self.nodes_visited += o.nodes_visited;
        self.occlusion_culled += o.occlusion_culled;
        self.pairs += o.pairs;
        self.pairs_missed += o.pairs_missed;
        self.pairs_hidden += o.pairs_hidden;
        self.pairs_masked += o.pairs_masked;
        self.pairs_grazing += o.pairs_grazing;
        self.ray_tests += o.ray_tests;
    }
}

/// What the leaves need of the frame.
pub(super) struct Ctx<'a> {
    pub(super) frame: &'a Frame<'a>,
    pub(super) area: &'a AreaLight,
    pub(super) ls: &'a LightSamples,
    pub(super) lit: &'a LitMasks,
}

/// Deepest traversal stack (see the hard technique's).
const STACK: usize = 64;

/// One caster as the leaves use it: its geometry and what it does to light.
struct Cast {
    c: Caster,
    id: u32,
    opaque: bool,
    masked: bool,
    transmittance: Vec3,
}

/// One unit of the BSP and its samples' state (unit-local indices, leaf order).
struct Unit<'a> {
    ctx: &'a Ctx<'a>,
    bsp: &'a Bsp,
    root: u32,
    first: usize,
    rec: Vec<Receiver>,
    /// Surface point and normal of each sample, for its rays.
    surf: Vec<(SurfacePoint, Vec3)>,
    lit: Vec<u64>,
    dark: Vec<u64>,
    /// Per sample, the box of its live light samples' frame coordinates.
    boxes: Vec<[f32; 4]>,
    /// Light samples left lit, per leaf (local node index).
    alive: Vec<u32>,
    done: Vec<bool>,
    /// Semi-transparent pairs: (sample, triangle) in triangle order, and their masks.
    semi: Vec<(u32, u32)>,
    semi_masks: Vec<u64>,
    counters: Counters,
}

/// Visits the nodes below `entry` that `descend` accepts (preorder).
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

impl<'a> Unit<'a> {
    fn new(ctx: &'a Ctx<'a>, bsp: &'a Bsp, root: u32) -> Unit<'a> {
        let view = ctx.frame.view;
        let rn = &bsp.nodes[root as usize];
        let (first, len) = (rn.start as usize, rn.len as usize);
        let words = ctx.ls.words;
        let mut rec = Vec::with_capacity(len);
        let mut surf = Vec::with_capacity(len);
        let mut lit = Vec::with_capacity(len * words);
        for ray in &bsp.rays[first..first + len] {
            let k = ray.pixel as usize;
            let sp = view.surface_point(k);
            let o = Vec3::from_array(ray.o);
            rec.push(Receiver::new(o, frame_at(ctx.area, sp.p), ctx.ls));
            surf.push((sp, view.normal[k]));
            lit.extend_from_slice(ctx.lit.of(k));
        }
        // The subtree's nodes run from the root to its rightmost leaf (preorder).
        let mut end = root;
        while !bsp.nodes[end as usize].is_leaf() {
            end = bsp.nodes[end as usize].right;
        }
        let count = (end - root + 1) as usize;
        let mut alive = vec![0u32; count];
        walk(&bsp.nodes, root, |ni| {
            let n = &bsp.nodes[ni as usize];
            if n.is_leaf() {
                let s = n.start as usize - first;
                alive[(ni - root) as usize] = (s..s + n.len as usize)
                    .filter(|&i| lit[i * words..(i + 1) * words].iter().any(|&w| w != 0))
                    .count() as u32;
            }
            !n.is_leaf()
        });
        let boxes = lit.chunks(words).map(|m| live_box(m, ctx.ls)).collect();
        Unit {
            ctx,
            bsp,
            root,
            first,
            boxes,
            rec,
            surf,
            dark: vec![0; lit.len()],
            lit,
            alive,
            done: vec![false; count],
            semi: Vec::new(),
            semi_masks: Vec::new(),
            counters: Counters::default(),
        }
    }

    /// The light samples of sample `j` that no opaque caster hides yet.
    fn live(&self, j: usize) -> [u64; MAX_WORDS] {
        let words = self.ctx.ls.words;
        let span = j * words..(j + 1) * words;
        let mut out = [0u64; MAX_WORDS];
        for ((o, &l), &d) in out
            .iter_mut()
            .zip(&self.lit[span.clone()])
            .zip(&self.dark[span])
        {
            *o = l & !d;
        }
        out
    }

    /// Traverses footprint `f` through the unit, each node's rectangle narrowed to the
    /// penumbra no deeper than the node's samples where `bound` gives one.
    fn rasterize(&mut self, f: &Footprint, scene: &Scene, bound: Option<&DepthBound>) {
        let bsp = self.bsp;
        let mut cast = None;
        let mut depth = None;
        walk(&bsp.nodes, self.root, |ni| {
            self.counters.nodes_visited += 1;
            let local = (ni - self.root) as usize;
            if self.done[local] {
                self.counters.occlusion_culled += 1;
                return false;
            }
            let n = &bsp.nodes[ni as usize];
            if !f.overlaps(n) {
                return false;
            }
            let narrowed = bound.and_then(|b| {
                let c = depth.get_or_insert_with(|| b.caster(bsp, scene.triangle(f.id as usize)));
                c.as_ref().and_then(|c| b.rect(c, n.zmax))
            });
            let g = match narrowed {
                Some((lo, hi)) => Footprint {
                    lo: [f.lo[0].max(lo[0]), f.lo[1].max(lo[1])],
                    hi: [f.hi[0].min(hi[0]), f.hi[1].min(hi[1])],
                    ..*f
                },
                None => *f,
            };
            if !g.overlaps(n) {
                return false;
            }
            if !n.is_leaf() {
                return true;
            }
            let c = cast.get_or_insert_with(|| caster(scene, f.id));
            self.leaf(n, local, &g, c);
            if self.alive[local] == 0 {
                self.mark_done(ni);
            }
            false
        });
    }

    /// Marks node `ni` done, and every ancestor in the unit whose children both are.
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

    /// Classifies the leaf's samples under `f` against caster `c`.
    fn leaf(&mut self, n: &Node, local: usize, f: &Footprint, c: &Cast) {
        let bsp = self.bsp;
        let words = self.ctx.ls.words;
        let start = n.start as usize;
        for i in start..start + n.len as usize {
            let j = i - self.first;
            if !f.holds(bsp.su[i], bsp.sv[i], bsp.sz[i]) || bsp.rays[i].own == c.id {
                continue;
            }
            let live = self.live(j);
            if live.iter().all(|&w| w == 0) {
                continue;
            }
            self.counters.pairs += 1;
            let hidden = self.pair(j, c, &live[..words]);
            if hidden {
                let now = self.live(j);
                // The box only bounds the live samples: it is re-fitted when a group of
                // them has gone dark, the shrink that decides pairs whole.
                if live.iter().zip(&now).any(|(&a, &b)| group_died(a, b)) {
                    self.boxes[j] = live_box(&now[..words], self.ctx.ls);
                }
                if now.iter().all(|&w| w == 0) {
                    self.alive[local] -= 1;
                }
            }
        }
    }

    /// One (view sample `j`, caster `c`) pair over the light samples `live`; true when
    /// it darkened some.
    fn pair(&mut self, j: usize, c: &Cast, live: &[u64]) -> bool {
        let ls = self.ctx.ls;
        let words = ls.words;
        let verdict = classify(&self.rec[j], &c.c, ls, self.boxes[j]);
        let mut inside = [0u64; MAX_WORDS];
        let mut outside = [0u64; MAX_WORDS];
        match verdict {
            Verdict::Miss => {
                self.counters.pairs_missed += 1;
                return false;
            }
            Verdict::Hit => {
                self.counters.pairs_hidden += 1;
                inside[..words].copy_from_slice(live);
            }
            Verdict::Planes(p, count) => {
                self.counters.pairs_masked += 1;
                masks(
                    &p[..count],
                    ls,
                    live,
                    &mut inside[..words],
                    &mut outside[..words],
                );
            }
            Verdict::Grazing => self.counters.pairs_grazing += 1,
        }
        if !c.opaque {
            // Every sample the planes do not rule out, for the product in index order.
            let mask: Vec<u64> = (0..words).map(|w| live[w] & !outside[w]).collect();
            if mask.iter().any(|&w| w != 0) {
                self.semi.push((j as u32, c.id));
                self.semi_masks.extend_from_slice(&mask);
            }
            return false;
        }
        let mut changed = false;
        for w in 0..words {
            let certain = if c.masked { 0 } else { live[w] & inside[w] };
            let mut bits = live[w] & !outside[w] & !certain;
            let mut hit = certain;
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if self.ray_hits(j, w * 64 + b, c) {
                    hit |= 1 << b;
                }
            }
            if hit != 0 {
                self.dark[j * words + w] |= hit;
                changed = true;
            }
        }
        changed
    }

    /// The reference's own decision: does the ray from sample `j` to light sample `i`
    /// hit caster `c` (where its texture keeps it)?
    fn ray_hits(&mut self, j: usize, i: usize, c: &Cast) -> bool {
        self.counters.ray_tests += 1;
        let (sp, n) = &self.surf[j];
        let Some((o, dir, len)) = shadow_ray(self.ctx.area, sp, *n, self.ctx.ls.uvs[i]) else {
            return false;
        };
        intersect_triangle(o, dir, 0.0, len, c.c.v)
            .is_some_and(|h| !self.ctx.frame.scene.cut_out(c.id as usize, h.b))
    }

    /// The shadow terms of the unit's samples, in its sample order.
    fn finish(mut self, scene: &Scene) -> (Vec<Vec3>, Counters) {
        let ls = self.ctx.ls;
        let words = ls.words;
        let n = ls.len();
        let mut order: Vec<usize> = (0..self.semi.len()).collect();
        // Stable: each sample's casters stay in triangle order.
        order.sort_by_key(|&p| self.semi[p].0);
        let mut values = Vec::with_capacity(self.rec.len());
        let mut next = 0;
        for j in 0..self.rec.len() {
            let from = next;
            while next < order.len() && self.semi[order[next]].0 as usize == j {
                next += 1;
            }
            let live = self.live(j);
            if from == next {
                let seen: u32 = live.iter().map(|w| w.count_ones()).sum();
                values.push(Vec3::splat(seen as f32) / n.max(1) as f32);
                continue;
            }
            let mut rgb = Vec3::ZERO;
            for &i in &ls.stored {
                let i = i as usize;
                let (w, b) = (i / 64, i % 64);
                if live[w] >> b & 1 == 0 {
                    continue; // adds zero
                }
                let mut t = Vec3::ONE;
                for &p in &order[from..next] {
                    let (_, id) = self.semi[p];
                    if self.semi_masks[p * words + w] >> b & 1 == 1 {
                        let c = caster(scene, id);
                        if self.ray_hits(j, i, &c) {
                            t *= c.transmittance;
                        }
                    }
                }
                rgb += t;
            }
            values.push(rgb / n.max(1) as f32);
        }
        (values, self.counters)
    }
}

/// True when a group of light samples live in word `before` has none live in `after`.
fn group_died(before: u64, after: u64) -> bool {
    (0..64 / GROUP).any(|g| {
        let m = GROUP_BITS << (g * GROUP);
        before & m != 0 && after & m == 0
    })
}

/// Most bitmask words a view sample holds (see [`super::MAX_EXACT_LIGHT_SAMPLES`]).
pub(super) const MAX_WORDS: usize = (super::MAX_EXACT_LIGHT_SAMPLES as usize).div_ceil(64);

/// The caster of triangle `id`.
fn caster(scene: &Scene, id: u32) -> Cast {
    let m = scene.material_of(id as usize);
    Cast {
        c: Caster::new(scene.triangle(id as usize)),
        id,
        opaque: m.is_opaque(),
        masked: m.alpha_mask.is_some(),
        transmittance: m.transmittance,
    }
}

/// Every plane's shadow terms into `out` (by pixel).
pub(super) fn rasterize(ctx: &Ctx, trees: &[Bsp], out: &mut Visibility) -> Counters {
    let scene = ctx.frame.scene;
    let corners = bounding_corners(ctx.area);
    let tan_radius = match ctx.area {
        AreaLight::Distant { .. } => ctx.area.radius(),
        _ => 0.0,
    };
    let mut total = Counters::default();
    for bsp in trees {
        let prints: Vec<Footprint> = (0..scene.len() as u32)
            .into_par_iter()
            .with_min_len(1024)
            .filter_map(|id| footprint(bsp, &corners, tan_radius, scene.triangle(id as usize), id))
            .collect();
        let bound = DepthBound::of(bsp, &corners);
        let units: Vec<(usize, Vec<Vec3>, Counters)> = bsp
            .unit_roots
            .par_iter()
            .map(|&root| {
                let mut unit = Unit::new(ctx, bsp, root);
                let rn = &bsp.nodes[root as usize];
                for f in prints.iter().filter(|f| f.overlaps(rn)) {
                    unit.rasterize(f, scene, bound.as_ref());
                }
                let first = unit.first;
                let (values, counters) = unit.finish(scene);
                (first, values, counters)
            })
            .collect();
        for (first, values, counters) in units {
            for (i, v) in values.into_iter().enumerate() {
                out.value[bsp.rays[first + i].pixel as usize] = v;
            }
            total.add(&counters);
        }
    }
    total
}
