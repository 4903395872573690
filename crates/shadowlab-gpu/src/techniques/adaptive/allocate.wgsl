// gpu:asm, stage `allocate`: the page table's side of the LRU allocation. The driver has
// given each requested page a slot of the physical pool (free slots first, then the least
// recently used, never one used this frame; requests taken by benefit, ties in table
// order), so the result does not depend on the order in which threads ran. `apply` writes
// the new entries into the page table and empties the entries of the pages they evict;
// `clear` fills the new pages' texels with an empty map (no triangle) before `render`
// draws into them.

struct AllocU {
    // Updates (or pages to clear).
    count: u32,
    row: u32,
    page: u32,
    atlas_cols: u32,
}

// One update: the entry made resident, its slot, and the entry it evicts (or NO_ENTRY).
struct Update {
    entry: u32,
    slot: u32,
    evicted: u32,
    _pad0: u32,
}

const NO_ENTRY: u32 = 0xffffffffu;
const NO_ID: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> au: AllocU;
@group(0) @binding(1) var<storage, read> updates: array<Update>;
@group(0) @binding(2) var<storage, read_write> table: array<u32>;

@compute @workgroup_size(64)
fn apply(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * au.row + gid.x;
    if i >= au.count {
        return;
    }
    let u = updates[i];
    if u.evicted != NO_ENTRY {
        table[u.evicted] = 0u;
    }
    table[u.entry] = u.slot + 1u;
}

// `clear`'s bindings follow `apply`'s, so the two entry points share one module.
@group(0) @binding(3) var<uniform> cu: AllocU;
@group(0) @binding(4) var<storage, read> slots: array<u32>;
@group(0) @binding(5) var id_out: texture_storage_2d<r32uint, write>;

// One thread a texel of the new pages.
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = gid.y * cu.row + gid.x;
    let per = cu.page * cu.page;
    if t >= cu.count * per {
        return;
    }
    let s = slots[t / per];
    let r = t % per;
    let x = (s % cu.atlas_cols) * cu.page + r % cu.page;
    let y = (s / cu.atlas_cols) * cu.page + r / cu.page;
    textureStore(id_out, vec2<i32>(i32(x), i32(y)), vec4<u32>(NO_ID, 0u, 0u, 0u));
}
