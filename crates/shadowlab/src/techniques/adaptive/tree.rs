//! The hierarchical grid of adaptive shadow maps (Fernando et al. 2001, Section 3): "each
//! node in an ASM tree has a shadow map of a fixed resolution and a partitioning of that
//! shadow map into a fixed number of cells. Each of these cells may contain another tree
//! node." Here a light has one tree per light view (a point light's six cube faces), its
//! nodes held in a slot arena; this module holds the nodes, the views, and the walk from a
//! root to the deepest node covering a point.

use super::params::Params;
use crate::frame::Frame;
use crate::light::{cube_face, Light, LightView};
use crate::math::{Aabb, Vec3};
use glam::{DMat4, DVec4};

/// Refinement stops at this effective resolution (texels across a root view): beyond it
/// the f32 clip coordinates of a tile's triangles and the look-ups' light-space
/// coordinates err by more than a few hundredths of a texel.
pub const MAX_EFFECTIVE_RESOLUTION: u64 = 1 << 20;
/// Marks an empty cell in a node's child table.
pub(super) const NO_NODE: u32 = u32::MAX;
/// The largest `u` or `v` kept inside a view: below 1 so that `u · scale` floors to the
/// view's last texel rather than one past it, and close enough to 1 (a millionth of a
/// texel at [`MAX_EFFECTIVE_RESOLUTION`]) not to move any look-up to another texel.
const LAST_UV: f64 = 1.0 - 1e-12;

/// `x.floor() as i64` without a library call in the per-pixel loops (values far outside
/// the i64 range saturate, as the cast does).
#[inline]
pub(super) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    t - ((t as f64) > x) as i64
}

/// Root-view image coordinates of the clip-space point `c`, in f64. Multiplies by `1/w`
/// where `math::ndc_to_uv` divides (in f32): the look-ups and the analysis need f64 at
/// effective resolutions up to [`MAX_EFFECTIVE_RESOLUTION`], and the product rounds
/// differently from the quotient.
#[inline]
pub(super) fn uv_of(c: DVec4) -> (f64, f64) {
    let inv_w = 1.0 / c.w;
    (c.x * inv_w * 0.5 + 0.5, 0.5 - c.y * inv_w * 0.5)
}

/// What the tree was built for; a different scene or light starts a new tree.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Fingerprint {
    pub(super) name: String,
    pub(super) triangles: usize,
    pub(super) revision: u64,
    pub(super) bounds: Aabb,
    pub(super) light: Light,
}

impl Fingerprint {
    pub(super) fn of(frame: &Frame) -> Self {
        Fingerprint {
            name: frame.scene.name.clone(),
            triangles: frame.scene.len(),
            revision: frame.scene.revision,
            bounds: frame.scene.bounds,
            light: *frame.light,
        }
    }
}

/// One node of a tree: a depth and id tile over a square of its light view.
#[derive(Debug)]
pub(super) struct Node {
    pub(super) face: u8,
    pub(super) level: u8,
    /// Origin in texels of this level's effective resolution.
    pub(super) x0: u32,
    pub(super) y0: u32,
    /// Tile side in texels.
    pub(super) res: u32,
    /// Cells per side.
    pub(super) cells: u32,
    pub(super) parent: u32,
    pub(super) parent_cell: u32,
    /// Unique over the tree's life, so a stale reference to a reused slot is detected.
    pub(super) serial: u64,
    pub(super) children: Vec<u32>,
    pub(super) live_children: u32,
    pub(super) depth: Vec<f32>,
    pub(super) id: Vec<u32>,
    /// Last frame whose analysis or look-ups used this node or a descendant.
    pub(super) stamp: u64,
    /// Frame the node was made in.
    pub(super) created: u64,
    /// Analysed pixels per frame whose mismatch it resolves, averaged over the frames of
    /// one analysis period (each frame sees a different share of the pixels).
    pub(super) benefit: f32,
}

impl Node {
    pub(super) fn bytes(res: u32, cells: u32) -> u64 {
        let texels = res as u64 * res as u64;
        texels * 8 + cells as u64 * cells as u64 * 4 + std::mem::size_of::<Node>() as u64
    }

    /// Position of `(u, v)` in this node's texels, given its level's effective resolution.
    #[inline]
    pub(super) fn local(&self, u: f64, v: f64, scale: f64) -> (f64, f64) {
        (u * scale - self.x0 as f64, v * scale - self.y0 as f64)
    }

    #[inline]
    pub(super) fn contains(&self, lx: f64, ly: f64) -> bool {
        let r = self.res as f64;
        lx >= 0.0 && ly >= 0.0 && lx < r && ly < r
    }

    #[inline]
    pub(super) fn texel(&self, lx: f64, ly: f64) -> (u32, u32) {
        let m = self.res as i64 - 1;
        (
            floor_i64(lx).clamp(0, m) as u32,
            floor_i64(ly).clamp(0, m) as u32,
        )
    }

    #[inline]
    pub(super) fn cell(&self, lx: f64, ly: f64) -> u32 {
        let size = (self.res / self.cells) as f64;
        let m = self.cells as i64 - 1;
        let cx = floor_i64(lx / size).clamp(0, m) as u32;
        let cy = floor_i64(ly / size).clamp(0, m) as u32;
        cy * self.cells + cx
    }
}

/// One light view and its tree's root.
#[derive(Debug)]
pub(super) struct Face {
    pub(super) view: LightView,
    /// `clip_from_world` in f64 for look-ups.
    pub(super) clip_from_world: DMat4,
    /// Root tile side in texels.
    pub(super) resolution: u32,
    pub(super) root: u32,
    /// Root cells per side (the culling grid).
    pub(super) grid: u32,
    /// Triangles whose projection overlaps each root cell, ascending.
    pub(super) bins: Vec<Vec<u32>>,
}

impl Face {
    /// Root-view image coordinates (`u, v` in `[0, 1)`) and linear depth of `p`.
    #[inline]
    pub(super) fn project(&self, p: Vec3) -> (f64, f64, f32) {
        let c = self.clip_from_world * DVec4::new(p.x as f64, p.y as f64, p.z as f64, 1.0);
        let (u, v) = uv_of(c);
        (
            u.clamp(0.0, LAST_UV),
            v.clamp(0.0, LAST_UV),
            self.view.depth(p),
        )
    }
}

/// The forest of one light: a tree per light view, nodes in a slot arena.
#[derive(Debug)]
pub(super) struct Tree {
    pub(super) fingerprint: Fingerprint,
    pub(super) views: Vec<LightView>,
    pub(super) faces: Vec<Option<Face>>,
    pub(super) nodes: Vec<Option<Node>>,
    pub(super) free: Vec<u32>,
    /// Bytes held by nodes and culling lists.
    pub(super) bytes: u64,
    pub(super) next_serial: u64,
    /// Texel refinement per level (`cells`).
    pub(super) refine: u32,
    /// Tile side of non-root nodes.
    pub(super) tile: u32,
}

impl Tree {
    pub(super) fn new(fingerprint: Fingerprint, views: Vec<LightView>, p: &Params) -> Self {
        Tree {
            fingerprint,
            faces: views.iter().map(|_| None).collect(),
            views,
            nodes: Vec::new(),
            free: Vec::new(),
            bytes: 0,
            next_serial: 0,
            refine: p.cells,
            tile: p.tile_resolution,
        }
    }

    #[inline]
    pub(super) fn node(&self, s: u32) -> &Node {
        self.nodes[s as usize]
            .as_ref()
            .expect("slot holds a live node")
    }

    #[inline]
    pub(super) fn node_mut(&mut self, s: u32) -> &mut Node {
        self.nodes[s as usize]
            .as_mut()
            .expect("slot holds a live node")
    }

    /// The light view of a live node.
    #[inline]
    pub(super) fn face(&self, n: &Node) -> &Face {
        self.faces[n.face as usize]
            .as_ref()
            .expect("node of a live face")
    }

    /// Effective resolution of `level` in `face`: texels across the whole root view.
    #[inline]
    pub(super) fn scale(&self, face: &Face, level: u8) -> f64 {
        face.resolution as f64 * (self.refine as f64).powi(level as i32)
    }

    /// The deepest level whose effective resolution stays within the limit.
    pub(super) fn max_level(&self, face: &Face) -> u8 {
        let mut l = 0u8;
        let mut e = face.resolution as u64;
        while e * self.refine as u64 <= MAX_EFFECTIVE_RESOLUTION {
            e *= self.refine as u64;
            l += 1;
        }
        l
    }

    /// The light view that `p` falls in.
    pub(super) fn face_of(&self, light: &Light, p: Vec3) -> usize {
        match *light {
            Light::Point { position } if self.views.len() == 6 => cube_face(p - position),
            _ => 0,
        }
    }

    pub(super) fn insert(&mut self, n: Node) -> u32 {
        self.bytes += Node::bytes(n.res, n.cells);
        match self.free.pop() {
            Some(s) => {
                self.nodes[s as usize] = Some(n);
                s
            }
            None => {
                self.nodes.push(Some(n));
                (self.nodes.len() - 1) as u32
            }
        }
    }

    /// Makes the root node of light view `face`, a `res²` tile of `grid²` cells holding
    /// `depth` and `id`.
    pub(super) fn add_root(&mut self, face: u8, grid: u32, now: u64, tile: RootTile) -> u32 {
        let root = Node {
            face,
            level: 0,
            x0: 0,
            y0: 0,
            res: tile.res,
            cells: grid,
            parent: NO_NODE,
            parent_cell: 0,
            serial: self.next_serial,
            children: vec![NO_NODE; (grid * grid) as usize],
            live_children: 0,
            depth: tile.depth,
            id: tile.id,
            stamp: now,
            created: now,
            benefit: 0.0,
        };
        self.next_serial += 1;
        self.insert(root)
    }

    /// Gives `parent`'s empty `cell` a child node (its tile still to be rendered).
    pub(super) fn add_child(&mut self, parent: u32, cell: u32, now: u64, benefit: f32) -> u32 {
        let (tile, refine) = (self.tile, self.refine);
        let pn = self.node(parent);
        debug_assert_eq!(pn.children[cell as usize], NO_NODE, "the cell is empty");
        let ct = pn.res / pn.cells;
        let (cx, cy) = (cell % pn.cells, cell / pn.cells);
        let node = Node {
            face: pn.face,
            level: pn.level + 1,
            x0: (pn.x0 + cx * ct) * refine,
            y0: (pn.y0 + cy * ct) * refine,
            res: tile,
            cells: refine,
            parent,
            parent_cell: cell,
            serial: self.next_serial,
            children: vec![NO_NODE; (refine * refine) as usize],
            live_children: 0,
            depth: Vec::new(),
            id: Vec::new(),
            stamp: now,
            created: now,
            benefit,
        };
        self.next_serial += 1;
        let s = self.insert(node);
        let pn = self.node_mut(parent);
        pn.children[cell as usize] = s;
        pn.live_children += 1;
        s
    }

    /// The deepest node of `face` covering `(u, v)`.
    pub(super) fn locate(&self, face: &Face, u: f64, v: f64) -> u32 {
        let mut s = face.root;
        let mut scale = face.resolution as f64;
        loop {
            let n = self.node(s);
            let (lx, ly) = n.local(u, v, scale);
            let c = n.children[n.cell(lx, ly) as usize];
            if c == NO_NODE {
                return s;
            }
            s = c;
            scale *= self.refine as f64;
        }
    }

    /// Marks `s` and its ancestors as used in frame `now`.
    pub(super) fn touch(&mut self, mut s: u32, now: u64) {
        loop {
            let n = self.node_mut(s);
            if n.stamp == now {
                return;
            }
            n.stamp = now;
            if n.level == 0 {
                return;
            }
            s = n.parent;
        }
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> u64 {
        self.bytes + self.culling_bytes()
    }

    pub(super) fn live_nodes(&self) -> impl Iterator<Item = &Node> {
        self.nodes.iter().flatten()
    }

    /// The root-view square that node `n` covers.
    pub(super) fn square(&self, n: &Node) -> Square {
        let e = self.scale(self.face(n), n.level);
        Square {
            u0: n.x0 as f64 / e,
            v0: n.y0 as f64 / e,
            size: n.res as f64 / e,
        }
    }
}

/// A square `[u0, u0 + size] × [v0, v0 + size]` of a root view's image coordinates: the
/// area a node's tile covers.
#[derive(Clone, Copy, Debug)]
pub(super) struct Square {
    pub(super) u0: f64,
    pub(super) v0: f64,
    pub(super) size: f64,
}

/// A root's rendered tile: its side and its depths and triangle ids.
pub(super) struct RootTile {
    pub(super) res: u32,
    pub(super) depth: Vec<f32>,
    pub(super) id: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::super::test_scenes::{face, small_scene};
    use super::*;
    use crate::light::light_views;
    use crate::techniques::shadow_map::DIRECTIONAL_PAD;

    #[test]
    fn locate_finds_the_deepest_node_covering_a_point() {
        let scene = small_scene();
        let light = Light::Directional { to_light: Vec3::Y };
        let p = Params {
            root_resolution: 64,
            tile_resolution: 32,
            cells: 4,
            ..Params::default()
        };
        let fp = Fingerprint {
            name: String::new(),
            triangles: scene.len(),
            revision: scene.revision,
            bounds: scene.bounds,
            light,
        };
        let views = light_views(&light, &scene.bounds, &scene.bounds, DIRECTIONAL_PAD);
        let mut tree = Tree::new(fp, views, &p);
        let mut f = face(&scene, &light, 64, 32, 4);
        let empty = RootTile {
            res: 64,
            depth: Vec::new(),
            id: Vec::new(),
        };
        f.root = tree.add_root(0, f.grid, 0, empty);
        // A pseudo-random refinement, three levels deep.
        let mut state = 12345u64;
        let mut next = |n: u32| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) % n as u64) as u32
        };
        let mut frontier = vec![f.root];
        for _ in 0..3 {
            let mut children = Vec::new();
            for &s in &frontier {
                let cells = tree.node(s).cells;
                for _ in 0..3 {
                    let c = next(cells * cells);
                    if tree.node(s).children[c as usize] == NO_NODE {
                        children.push(tree.add_child(s, c, 0, 0.0));
                    }
                }
            }
            frontier = children;
        }
        tree.faces[0] = Some(f);
        let f = tree.faces[0].as_ref().unwrap();
        for _ in 0..20000 {
            let (u, v) = (
                next(1 << 20) as f64 / (1 << 20) as f64,
                next(1 << 20) as f64 / (1 << 20) as f64,
            );
            let mut best: Option<(u8, u32)> = None;
            for (s, n) in tree.nodes.iter().enumerate() {
                let Some(n) = n else { continue };
                let e = tree.scale(f, n.level);
                let (lx, ly) = n.local(u, v, e);
                if n.contains(lx, ly) && best.is_none_or(|b| n.level > b.0) {
                    best = Some((n.level, s as u32));
                }
            }
            assert_eq!(tree.locate(f, u, v), best.unwrap().1, "at ({u}, {v})");
        }
    }
}
