//! The virtual map's layout (mip levels, pages, the page table's entry order) and the
//! physical pool's slots with their LRU stamps: the CPU's side of stage `allocate`.
//!
//! The analysis stamps each slot it reads with the frame's clock and records each page it
//! requests once, with the number of receivers requesting it; the requests come back as a
//! set, and [`Pool::assign`] hands them slots by that benefit, ties in the table's entry
//! order (coarsest level first), so the allocation is a function of the set, the counts
//! and the stamps alone, not of the order in which GPU threads ran.

/// A requested page: its table entry and its benefit (the receivers requesting it).
pub(super) type Request = (u32, u32);

/// A table entry that names no page.
pub(super) const NO_ENTRY: u32 = u32::MAX;

/// The virtual map's shape: `faces` light views, each `side` texels a side at its finest
/// level, `levels` mip levels, pages of `page` texels a side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Layout {
    pub(super) page: u32,
    pub(super) levels: u32,
    pub(super) side: u32,
    pub(super) faces: u32,
}

/// One page of the virtual map: its view, level and page column and row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Page {
    pub(super) face: u32,
    pub(super) level: u32,
    pub(super) x: u32,
    pub(super) y: u32,
}

impl Layout {
    /// Pages across a view at level `l`.
    pub(super) fn pages_across(&self, l: u32) -> u32 {
        (self.side / self.page) >> l
    }

    /// Texels across a view at level `l`.
    pub(super) fn texels_across(&self, l: u32) -> u32 {
        self.side >> l
    }

    /// Entries of level `l` (every view).
    fn level_entries(&self, l: u32) -> u32 {
        let n = self.pages_across(l);
        self.faces * n * n
    }

    /// The first entry of level `l`: the coarser levels come first (`pages.wgsl`'s
    /// `level_base`).
    pub(super) fn level_base(&self, l: u32) -> u32 {
        ((l + 1)..self.levels).map(|k| self.level_entries(k)).sum()
    }

    /// Entries of the whole table.
    pub(super) fn entries(&self) -> u32 {
        self.level_base(0) + self.level_entries(0)
    }

    /// The entries of the coarsest level, which is always resident.
    pub(super) fn coarsest(&self) -> std::ops::Range<u32> {
        0..self.level_entries(self.levels - 1)
    }

    /// The page of entry `e`.
    pub(super) fn page(&self, e: u32) -> Page {
        let mut l = self.levels - 1;
        let mut base = 0;
        loop {
            let count = self.level_entries(l);
            if e < base + count || l == 0 {
                let n = self.pages_across(l);
                let r = e - base;
                return Page {
                    face: r / (n * n),
                    level: l,
                    x: r % n,
                    y: r % (n * n) / n,
                };
            }
            base += count;
            l -= 1;
        }
    }
}

/// A new page's slot, and the page it evicts ([`NO_ENTRY`] for none): `allocate.wgsl`'s
/// `Update`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Update {
    pub(super) entry: u32,
    pub(super) slot: u32,
    pub(super) evicted: u32,
    pub(super) pad: u32,
}

/// The pool's slots: the entry each holds and the last frame that read it.
#[derive(Clone, Debug)]
pub(super) struct Pool {
    entry: Vec<u32>,
    stamp: Vec<u32>,
    /// Slots `0..pinned` hold the coarsest level and are never evicted.
    pinned: u32,
}

impl Pool {
    /// `slots` empty slots, the first `pinned` to be reserved for the coarsest level.
    pub(super) fn new(slots: u32, pinned: u32) -> Self {
        Pool {
            entry: vec![NO_ENTRY; slots as usize],
            stamp: vec![0; slots as usize],
            pinned,
        }
    }

    /// Slots holding a page.
    pub(super) fn resident(&self) -> usize {
        self.entry.iter().filter(|&&e| e != NO_ENTRY).count()
    }

    /// The table entries of the resident pages, in slot order.
    pub(super) fn entries(&self) -> impl Iterator<Item = u32> + '_ {
        self.entry.iter().copied().filter(|&e| e != NO_ENTRY)
    }

    /// Slots in the pool.
    pub(super) fn slots(&self) -> u32 {
        self.entry.len() as u32
    }

    /// The coarsest level's `entries` placed in the pinned slots, in order.
    pub(super) fn pin(&mut self, entries: std::ops::Range<u32>, now: u32) -> Vec<Update> {
        entries
            .zip(0..self.pinned)
            .map(|(e, s)| {
                self.entry[s as usize] = e;
                self.stamp[s as usize] = now;
                Update {
                    entry: e,
                    slot: s,
                    evicted: NO_ENTRY,
                    pad: 0,
                }
            })
            .collect()
    }

    /// Takes the GPU's stamps (the last frame that read each slot).
    pub(super) fn stamp(&mut self, used: &[u32]) {
        for (s, &u) in self.stamp.iter_mut().zip(used) {
            *s = (*s).max(u);
        }
    }

    /// Gives slots to the `requests` (distinct entries with their benefits), at most `max`:
    /// taken by decreasing benefit, ties in entry order, into the free slots first (lowest first), then the slots not read in frame
    /// `now`, least recently read first (ties by slot). A page read this frame is never
    /// evicted; requests beyond the slots available wait for a later pass.
    pub(super) fn assign(&mut self, requests: &[(u32, u32)], now: u32, max: usize) -> Vec<Update> {
        let mut requests = requests.to_vec();
        requests.sort_unstable_by_key(|&(e, b)| (std::cmp::Reverse(b), e));
        requests.dedup();
        let mut free: Vec<u32> = Vec::new();
        let mut old: Vec<(u32, u32)> = Vec::new();
        for s in self.pinned..self.slots() {
            let i = s as usize;
            if self.entry[i] == NO_ENTRY {
                free.push(s);
            } else if self.stamp[i] < now {
                old.push((self.stamp[i], s));
            }
        }
        old.sort_unstable();
        let candidates = free.into_iter().chain(old.into_iter().map(|(_, s)| s));
        requests
            .into_iter()
            .map(|(e, _)| e)
            .take(max)
            .zip(candidates)
            .map(|(e, s)| {
                let i = s as usize;
                let evicted = self.entry[i];
                self.entry[i] = e;
                self.stamp[i] = now;
                Update {
                    entry: e,
                    slot: s,
                    evicted,
                    pad: 0,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_decode_to_their_pages_coarsest_first() {
        let l = Layout {
            page: 4,
            levels: 3,
            side: 32,
            faces: 2,
        };
        // Levels 2, 1, 0 have 2, 4 and 8 pages across: 2·4 + 2·16 + 2·64 entries.
        assert_eq!(l.entries(), 8 + 32 + 128);
        assert_eq!(l.coarsest(), 0..8);
        assert_eq!(l.level_base(1), 8);
        assert_eq!(l.level_base(0), 40);
        let mut seen = 0;
        for lv in (0..3).rev() {
            let n = l.pages_across(lv);
            for f in 0..2 {
                for y in 0..n {
                    for x in 0..n {
                        let e = l.level_base(lv) + f * n * n + y * n + x;
                        assert_eq!(e, seen, "entries are dense and ordered");
                        let p = l.page(e);
                        assert_eq!((p.face, p.level, p.x, p.y), (f, lv, x, y));
                        seen += 1;
                    }
                }
            }
        }
    }

    #[test]
    fn assignment_is_free_first_then_least_recently_used_never_this_frame() {
        let mut p = Pool::new(6, 2);
        assert_eq!(p.pin(0..2, 1).len(), 2);
        // Frame 1: four free slots, five requests in any order: the four of most benefit,
        // ties by entry.
        let u = p.assign(&[(40, 1), (12, 2), (30, 2), (20, 2), (10, 5)], 1, 100);
        let got: Vec<(u32, u32, u32)> = u.iter().map(|u| (u.entry, u.slot, u.evicted)).collect();
        assert_eq!(
            got,
            vec![
                (10, 2, NO_ENTRY),
                (12, 3, NO_ENTRY),
                (20, 4, NO_ENTRY),
                (30, 5, NO_ENTRY)
            ]
        );
        // Frame 3: slots 3 and 5 were read in frame 3, slot 2 in frame 2, slot 4 in 1.
        p.stamp(&[3, 3, 2, 3, 1, 3]);
        let u = p.assign(&[(50, 1), (40, 1), (60, 1)], 3, 100);
        let got: Vec<(u32, u32, u32)> = u.iter().map(|u| (u.entry, u.slot, u.evicted)).collect();
        assert_eq!(got, vec![(40, 4, 20), (50, 2, 10)]);
        assert_eq!(p.resident(), 6);
        // The cap on new pages.
        p.stamp(&[4; 6]);
        assert_eq!(p.assign(&[(70, 1), (80, 1)], 5, 1).len(), 1);
    }
}
