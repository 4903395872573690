//! Removing nodes (Fernando et al. 2001, Section 3.2): the tree lives in a fixed memory
//! budget, so a new node may need another's memory. "We use a LRU scheme on all nodes that
//! were not used in the last frame, removing the least recently used nodes. If there are no
//! such nodes [...] we remove an existing node only if a new node that needs to be created
//! has a greater benefit than the existing node." Only leaves are removed here, so a
//! node's descendants go before it.

use super::tree::{Node, Tree, NO_NODE};

impl Tree {
    /// Removes a leaf node.
    fn evict(&mut self, s: u32) {
        let n = self.nodes[s as usize].take().expect("evicting a live node");
        debug_assert_eq!(n.live_children, 0, "only leaves are evicted");
        self.bytes -= Node::bytes(n.res, n.cells);
        let parent = self.node_mut(n.parent);
        parent.children[n.parent_cell as usize] = NO_NODE;
        parent.live_children -= 1;
        self.free.push(s);
    }

    /// The leaf to evict so that a new node fits: a leaf unused in the last frame, least
    /// recently used first; else an in-use leaf of smaller benefit than `benefit`. Never a
    /// root, a node made in frame `now`, or `protect`.
    fn pick_victim(&self, now: u64, protect: Option<u32>, benefit: f32) -> Option<u32> {
        let mut unused: Option<(u64, u8, u32)> = None;
        let mut used: Option<(u32, u64, u8, u32)> = None;
        for (s, n) in self.nodes.iter().enumerate() {
            let Some(n) = n else { continue };
            let s = s as u32;
            if n.level == 0 || n.live_children > 0 || n.created == now || Some(s) == protect {
                continue;
            }
            // Deeper nodes first among equals: they hold the least-shared detail.
            let depth_key = u8::MAX - n.level;
            if n.stamp + 1 < now {
                let k = (n.stamp, depth_key, s);
                if unused.is_none_or(|u| k < u) {
                    unused = Some(k);
                }
            } else if n.benefit < benefit {
                // Non-negative floats order as their bits.
                let k = (n.benefit.to_bits(), n.stamp, depth_key, s);
                if used.is_none_or(|u| k < u) {
                    used = Some(k);
                }
            }
        }
        unused.map(|k| k.2).or(used.map(|k| k.3))
    }

    /// Evicts leaves (see `pick_victim`) until `need` more bytes fit within `budget`.
    /// Returns how many it evicted and whether the bytes fit; they do not when no leaf
    /// is left to evict.
    pub(super) fn make_room(
        &mut self,
        need: u64,
        budget: u64,
        now: u64,
        protect: Option<u32>,
        benefit: f32,
    ) -> (u64, bool) {
        let mut evicted = 0;
        while self.bytes + need > budget {
            match self.pick_victim(now, protect, benefit) {
                Some(s) => {
                    self.evict(s);
                    evicted += 1;
                }
                None => return (evicted, false),
            }
        }
        (evicted, true)
    }
}
