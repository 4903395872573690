// gpu:afsm, the exclusive prefix sum the counting sorts use (cells' sample counts, cells'
// chunk counts, triangles' work counts): each block of 1024 words is summed in workgroup
// memory and its total kept; the totals are summed the same way (recursively, by the
// driver); each block then adds its total's prefix. Integer sums: the same words in any
// order of threads. A sum past 32 bits raises `overflow` (the driver then runs the frame
// again with smaller batches).

struct ScanParams {
    // Words to sum (a multiple of nothing; the rest of the last block reads as zero).
    n: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

@group(0) @binding(0) var<uniform> sp: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;
@group(0) @binding(3) var<storage, read_write> overflow: array<atomic<u32>>;

const THREADS: u32 = 256u;
const PER_THREAD: u32 = 4u;
const BLOCK: u32 = 1024u;

var<workgroup> part: array<u32, 256>;

fn block_id(wid: vec3<u32>) -> u32 {
    return wid.y * 32768u + wid.x;
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let blk = block_id(wid);
    let first = blk * BLOCK + li * PER_THREAD;
    var v: array<u32, 4>;
    var total = 0u;
    for (var k = 0u; k < PER_THREAD; k++) {
        let i = first + k;
        var x = 0u;
        if i < sp.n {
            x = data[i];
        }
        v[k] = total;
        if total + x < total {
            atomicStore(&overflow[0], 1u);
        }
        total += x;
    }
    part[li] = total;
    workgroupBarrier();
    // Hillis–Steele inclusive scan of the threads' totals.
    for (var off = 1u; off < THREADS; off *= 2u) {
        var add = 0u;
        if li >= off {
            add = part[li - off];
        }
        workgroupBarrier();
        if part[li] + add < add {
            atomicStore(&overflow[0], 1u);
        }
        part[li] += add;
        workgroupBarrier();
    }
    let before = part[li] - total;
    for (var k = 0u; k < PER_THREAD; k++) {
        let i = first + k;
        if i < sp.n {
            data[i] = before + v[k];
        }
    }
    if li == THREADS - 1u {
        sums[blk] = part[li];
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(workgroup_id) wid: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let blk = block_id(wid);
    let add = sums[blk];
    let first = blk * BLOCK + li * PER_THREAD;
    for (var k = 0u; k < PER_THREAD; k++) {
        let i = first + k;
        if i < sp.n {
            if data[i] + add < add {
                atomicStore(&overflow[0], 1u);
            }
            data[i] += add;
        }
    }
}
