//! Silhouette edges, the input of the silhouette mask map of Pan et al. 2009 ("Fast,
//! Sub-pixel Antialiased Shadow Maps", Section 3.2): the scene's edge adjacency (built once
//! per scene and cached) and the test that picks the edges seen from the light as
//! silhouettes.

use crate::light::Light;
use crate::math::Vec3;
use crate::scene::Scene;
use rayon::prelude::*;

/// Edges of the scene with the opposite vertex of every face that shares them.
pub(super) struct Adjacency {
    /// [`fingerprint`] of the scene it was built from.
    pub(super) fingerprint: u64,
    /// Triangles of that scene.
    pub(super) triangles: usize,
    /// First endpoint of each edge.
    pub(super) a: Vec<Vec3>,
    /// Second endpoint of each edge.
    pub(super) b: Vec<Vec3>,
    /// Faces of edge `e` are `opp[opp_start[e]..opp_start[e + 1]]`.
    opp_start: Vec<u32>,
    opp: Vec<Vec3>,
}

impl std::fmt::Debug for Adjacency {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Adjacency {{ edges: {}, triangles: {} }}",
            self.a.len(),
            self.triangles
        )
    }
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// A hash of every vertex position (and which triangles are alpha-masked), to tell whether a cached adjacency still fits.
pub(super) fn fingerprint(scene: &Scene) -> u64 {
    const CHUNK: usize = 4096;
    let n = scene.len();
    let parts: Vec<u64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut h = FNV_OFFSET;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                for p in scene.triangle(i) {
                    for x in p.to_array() {
                        h = (h ^ x.to_bits() as u64).wrapping_mul(FNV_PRIME);
                    }
                }
                // Alpha-masked triangles are welded differently (see `Adjacency::build`).
                if scene.material_of(i).alpha_mask.is_some() {
                    h = (h ^ 1).wrapping_mul(FNV_PRIME);
                }
            }
            h
        })
        .collect();
    parts.iter().fold(FNV_OFFSET ^ n as u64, |h, &p| {
        (h ^ p).wrapping_mul(FNV_PRIME)
    })
}

impl Adjacency {
    /// The adjacency of `scene`, whose [`fingerprint`] is `fingerprint`.
    pub(super) fn build(scene: &Scene, fingerprint: u64) -> Self {
        let n = scene.len();
        let corner = |c: usize| scene.triangle(c / 3)[c % 3];
        // Weld corners with bit-identical positions (after folding −0 into +0). An
        // alpha-masked triangle's corners weld with none: its outline may run anywhere
        // inside it, so each of its edges is a boundary, a silhouette from every light.
        let key = |c: usize| {
            let p = corner(c) + Vec3::ZERO;
            let t = c / 3;
            let own = if scene.material_of(t).alpha_mask.is_some() {
                t as u32 + 1
            } else {
                0
            };
            [p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), own]
        };
        let mut corners: Vec<([u32; 4], u32)> = (0..3 * n)
            .into_par_iter()
            .map(|c| (key(c), c as u32))
            .collect();
        corners.par_sort_unstable();
        let mut vid = vec![0u32; 3 * n];
        let mut next = 0u32;
        for i in 0..corners.len() {
            if i > 0 && corners[i].0 != corners[i - 1].0 {
                next += 1;
            }
            vid[corners[i].1 as usize] = next;
        }
        // Edges as (low vertex, high vertex, opposite corner), grouped by sorting.
        let mut edges: Vec<(u32, u32, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|t| {
                let vid = &vid;
                (0..3).filter_map(move |e| {
                    let a = vid[3 * t + e];
                    let b = vid[3 * t + (e + 1) % 3];
                    (a != b).then(|| (a.min(b), a.max(b), (3 * t + (e + 2) % 3) as u32))
                })
            })
            .collect();
        edges.par_sort_unstable();
        // The position of a welded vertex: any corner that carries it.
        let mut pos_of = vec![Vec3::ZERO; next as usize + 1];
        for c in 0..3 * n {
            pos_of[vid[c] as usize] = corner(c);
        }
        let mut adj = Adjacency {
            fingerprint,
            triangles: n,
            a: Vec::new(),
            b: Vec::new(),
            opp_start: vec![0],
            opp: Vec::with_capacity(edges.len()),
        };
        let mut i = 0;
        while i < edges.len() {
            let (lo, hi, _) = edges[i];
            adj.a.push(pos_of[lo as usize]);
            adj.b.push(pos_of[hi as usize]);
            while i < edges.len() && edges[i].0 == lo && edges[i].1 == hi {
                adj.opp.push(corner(edges[i].2 as usize));
                i += 1;
            }
            adj.opp_start.push(adj.opp.len() as u32);
        }
        adj
    }

    /// The opposite vertex of every face that shares edge `e`.
    pub(super) fn faces(&self, e: usize) -> &[Vec3] {
        &self.opp[self.opp_start[e] as usize..self.opp_start[e + 1] as usize]
    }

    /// Number of edges.
    pub(super) fn len(&self) -> usize {
        self.a.len()
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> u64 {
        (self.a.len() * 24 + self.opp_start.len() * 4 + self.opp.len() * 12) as u64
    }

    /// Whether edge `e` is a silhouette seen from the light: its faces all lie on one side
    /// of the plane through the edge and the light (a fold), or it has one face (a mesh
    /// boundary) or more than two (non-manifold). Degenerate cases count as silhouettes.
    fn is_silhouette(&self, e: usize, toward: &Toward) -> bool {
        let faces = &self.opp[self.opp_start[e] as usize..self.opp_start[e + 1] as usize];
        if faces.len() != 2 {
            return true;
        }
        let a = self.a[e];
        let m = (self.b[e] - a).cross(toward.at(a));
        let s0 = m.dot(faces[0] - a);
        let s1 = m.dot(faces[1] - a);
        s0 == 0.0 || s1 == 0.0 || (s0 > 0.0) == (s1 > 0.0)
    }
}

/// The direction towards the light from a point.
#[derive(Clone, Copy)]
pub(super) enum Toward {
    /// A directional light: this unit direction everywhere.
    Direction(Vec3),
    /// A spot or point light at this position.
    Position(Vec3),
}

impl Toward {
    /// The direction rule of `light`.
    pub(super) fn new(light: &Light) -> Self {
        match *light {
            Light::Directional { to_light } => Toward::Direction(to_light.normalize()),
            Light::Spot { position, .. } | Light::Point { position } => Toward::Position(position),
        }
    }

    /// The (unnormalized, for positional lights) direction from `p` towards the light.
    #[inline]
    pub(super) fn at(&self, p: Vec3) -> Vec3 {
        match *self {
            Toward::Direction(d) => d,
            Toward::Position(l) => l - p,
        }
    }
}

/// The silhouette edges seen from the light, in edge order.
pub(super) fn silhouette_edges(adj: &Adjacency, toward: &Toward) -> Vec<u32> {
    (0..adj.len() as u32)
        .into_par_iter()
        .with_min_len(1024)
        .filter(|&e| adj.is_silhouette(e as usize, toward))
        .collect()
}

/// The scene's edges as the silhouette test reads them, built once per scene as
/// [`Subpixel`](super::Subpixel) builds them (vertices welded by bit-identical position).
#[derive(Clone, Debug)]
pub struct EdgeAdjacency {
    /// First endpoint of each edge.
    pub a: Vec<Vec3>,
    /// Second endpoint of each edge.
    pub b: Vec<Vec3>,
    /// Per edge, the opposite vertices of its two faces, or `None` when it has not exactly
    /// two (a boundary or non-manifold edge, always a silhouette).
    pub faces: Vec<Option<[Vec3; 2]>>,
}

/// The edge adjacency of `scene` (see [`EdgeAdjacency`]).
pub fn edge_adjacency(scene: &Scene) -> EdgeAdjacency {
    let adj = Adjacency::build(scene, fingerprint(scene));
    let faces = (0..adj.len())
        .map(|e| match adj.faces(e) {
            [f0, f1] => Some([*f0, *f1]),
            _ => None,
        })
        .collect();
    EdgeAdjacency {
        a: adj.a.clone(),
        b: adj.b.clone(),
        faces,
    }
}
