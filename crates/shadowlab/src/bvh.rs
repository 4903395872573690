//! The ground truth's BVH: `obvhs`'s compressed wide BVH (CWBVH), built with PLOC and a
//! little reinsertion, with a median-split fallback for degenerate geometry.
//!
//! PLOC pairs each node with its nearest neighbour in Morton order. When many primitives
//! have the same bounding box (a triangle instanced thousands of times, a file listing one
//! face over and over) every candidate is equally near, the pairing degenerates into a
//! chain, and the tree gets as deep as the primitive count. That breaks two things:
//! `obvhs`'s conversion to the wide BVH recurses once per level (a stack overflow), and
//! its ray traversal keeps a fixed stack of [`TRAVERSAL_STACK`] node groups that silently
//! overwrites its last entry when full, so a ray could miss a caster. So the PLOC tree's
//! depth is measured before conversion and the wide tree's after; when either is too deep,
//! the binary tree is rebuilt by splitting the primitive list at its median along the
//! longest axis of the centroids' bounds, which is at most ⌈log₂ n⌉ deep whatever the
//! geometry. PLOC's pairing is also slow on equal boxes (a few merges a pass), so a scene
//! with more than `MAX_REPEATS` primitives in one box goes to the median split directly. Either tree holds every primitive, so the traced answer is the same; only
//! its speed differs.

use crate::math::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// The node groups `obvhs`'s CWBVH traversal can hold on its stack.
pub const TRAVERSAL_STACK: usize = 32;

/// The deepest PLOC tree converted as it is. A wide tree is never deeper than its binary
/// tree, and the conversion's recursion stays well inside a 2 MiB thread stack.
const MAX_BINARY_DEPTH: usize = 512;

/// The deepest wide tree traced: one level below the traversal stack's size, so the stack
/// never fills.
const MAX_WIDE_DEPTH: usize = TRAVERSAL_STACK - 1;

/// The most primitives with one bounding box PLOC is given. Its pairing of equal boxes
/// merges only a few per pass, so its time grows with the square of their number.
const MAX_REPEATS: usize = 64;

/// Builds the wide BVH over `tris`, each triangle's box grown by `pad` on every side.
///
/// The padding keeps the tree from culling a triangle that the watertight triangle test
/// would report hit: that test may place a grazing hit a few ulps outside the triangle's
/// exact box (a shadow ray leaving a surface just above a nearly coplanar neighbour), and a
/// tight box would then answer differently from testing every triangle.
pub fn build(tris: &[Triangle], pad: f32) -> CwBvh {
    let boxes: Vec<Aabb> = tris.iter().map(|t| padded(t.aabb(), pad)).collect();
    let params = BvhBuildParams::fast_build();
    let max_leaf = params.max_prims_per_leaf.clamp(1, 3);
    if most_repeated_box(&boxes) > MAX_REPEATS {
        return bvh2_to_cwbvh(&median_split(&boxes), max_leaf, true, false);
    }
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        &boxes,
        (0..boxes.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    if binary_depth(&bvh2) <= MAX_BINARY_DEPTH {
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        if binary_depth(&bvh2) <= MAX_BINARY_DEPTH {
            let wide = bvh2_to_cwbvh(&bvh2, max_leaf, true, false);
            if wide_depth(&wide) <= MAX_WIDE_DEPTH {
                return wide;
            }
        }
    }
    bvh2_to_cwbvh(&median_split(&boxes), max_leaf, true, false)
}

/// Box `b` grown by `pad` on every side.
fn padded(b: Aabb, pad: f32) -> Aabb {
    let p = Vec3A::splat(pad);
    Aabb::new(b.min - p, b.max + p)
}

/// The largest number of primitives sharing one bounding box (counted by a 64-bit hash of
/// the box's bits, so a collision can only overstate it).
fn most_repeated_box(boxes: &[Aabb]) -> usize {
    let mut keys: Vec<u64> = boxes
        .iter()
        .map(|b| {
            let bits = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z];
            bits.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
                (h ^ u64::from(v.to_bits())).wrapping_mul(0x0000_0100_0000_01b3)
            })
        })
        .collect();
    keys.sort_unstable();
    keys.chunk_by(|a, b| a == b)
        .map(<[u64]>::len)
        .max()
        .unwrap_or(0)
}

/// The number of nodes on the longest root-to-leaf path of a binary BVH.
fn binary_depth(bvh: &Bvh2) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        let node = &bvh.nodes[i];
        if !node.is_leaf() {
            let first = node.first_index as usize;
            stack.push((first, d + 1));
            stack.push((first + 1, d + 1));
        }
    }
    deepest
}

/// The number of nodes on the longest root-to-leaf path of a wide BVH.
fn wide_depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        let node = &bvh.nodes[i];
        for ch in 0..8 {
            if !node.is_child_empty(ch) && !node.is_leaf(ch) {
                stack.push((node.child_node_index(ch) as usize, d + 1));
            }
        }
    }
    deepest
}

/// A binary BVH with one primitive per leaf whose every inner node splits its primitives
/// in half (at the median centroid along the longest axis of their centroids' bounds).
fn median_split(boxes: &[Aabb]) -> Bvh2 {
    let centroids: Vec<Vec3A> = boxes.iter().map(|b| b.center()).collect();
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![Bvh2Node::default(); (2 * boxes.len()).saturating_sub(1).max(1)];
    let mut next = 1usize;
    // (node index, primitive range): the range is split in place in `order`.
    let mut stack = vec![(0usize, 0usize, boxes.len())];
    while let Some((node, lo, hi)) = stack.pop() {
        let prims = &mut order[lo..hi];
        let mut bounds = Aabb::empty();
        for &p in prims.iter() {
            bounds = bounds.union(&boxes[p as usize]);
        }
        if hi - lo <= 1 {
            nodes[node] = Bvh2Node::new(bounds, 1, lo as u32);
            continue;
        }
        let mut spread = Aabb::empty();
        for &p in prims.iter() {
            spread.extend(centroids[p as usize]);
        }
        let axis = spread.diagonal().max_position();
        let mid = (hi - lo) / 2;
        // Ties in the centroid go to the lower primitive index, so the split is the same
        // on every run.
        prims.select_nth_unstable_by(mid, |&a, &b| {
            centroids[a as usize][axis]
                .total_cmp(&centroids[b as usize][axis])
                .then(a.cmp(&b))
        });
        let first = next;
        next += 2;
        nodes[node] = Bvh2Node::new(bounds, 0, first as u32);
        stack.push((first, lo, lo + mid));
        stack.push((first + 1, lo + mid, hi));
    }
    nodes.truncate(next);
    Bvh2 {
        nodes,
        primitive_indices: order,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(x: f32) -> Triangle {
        Triangle {
            v0: Vec3A::new(x, 0.0, 0.0),
            v1: Vec3A::new(x + 1.0, 0.0, 0.0),
            v2: Vec3A::new(x, 1.0, 0.0),
        }
    }

    /// Every primitive is reached exactly once from the root of a wide BVH.
    fn primitives_reached(bvh: &CwBvh) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes[i];
            for ch in 0..8 {
                if node.is_child_empty(ch) {
                    continue;
                }
                if node.is_leaf(ch) {
                    let (first, count) = node.child_primitives(ch);
                    out.extend((first..first + count).map(|k| bvh.primitive_indices[k as usize]));
                } else {
                    stack.push(node.child_node_index(ch) as usize);
                }
            }
        }
        out.sort_unstable();
        out
    }

    #[test]
    fn a_triangle_repeated_many_times_gives_a_shallow_tree_holding_every_copy() {
        let n = 20_000u32;
        let tris = vec![tri(0.0); n as usize];
        let bvh = build(&tris, 0.0);
        assert!(wide_depth(&bvh) <= MAX_WIDE_DEPTH, "{}", wide_depth(&bvh));
        assert_eq!(primitives_reached(&bvh), (0..n).collect::<Vec<_>>());
    }

    #[test]
    fn the_median_split_holds_every_primitive_at_logarithmic_depth() {
        let n = 1000u32;
        let tris: Vec<Triangle> = (0..n).map(|i| tri((i % 7) as f32)).collect();
        let boxes: Vec<Aabb> = tris.iter().map(|t| t.aabb()).collect();
        let bvh2 = median_split(&boxes);
        assert!(binary_depth(&bvh2) <= 11, "{}", binary_depth(&bvh2));
        let wide = bvh2_to_cwbvh(&bvh2, 3, true, false);
        assert_eq!(primitives_reached(&wide), (0..n).collect::<Vec<_>>());
    }
}
