// gpu:vsm / evsm / msm / csm, stage `mipmap` (Annen et al. 2007, Section 4.1: "we then
// build a mip-map of this texture ... to prevent minification aliasing"): entry `reduce`
// makes one level from the previous as the library's `MipChain::build` does (a 2×2 average
// where both sides are even, else area-weighted box taps), rounded to the storage format;
// entry `pack` writes a level in the texture format's bytes (rows padded for the copy into
// the mip level of the sampled texture). Composed after filtering/filtered.wgsl.

struct MipU {
    // Source level's sides and first texel; destination's.
    sw: u32,
    sh: u32,
    src: u32,
    dw: u32,
    dh: u32,
    dst: u32,
    format: u32,
    // Words a packed texel takes (1, 2 or 4) and a packed row.
    texel_words: u32,
    row_words: u32,
    // The packed level's first word.
    packed_at: u32,
    // 4 for four-channel textures, 2 for two.
    channels: u32,
    // 1 when 16-bit codes go into a float texture (no 16-bit normalized formats here).
    as_float: u32,
}

@group(0) @binding(0) var<uniform> mip: MipU;
@group(0) @binding(1) var<storage, read_write> levels: array<vec4<f32>>;
var<private> tech: TechU;

// The area-weighted taps of destination texel `i` along a side of `s` source texels
// reduced to `d`: the source interval [i·s/d, (i+1)·s/d).
fn box_weight(i: u32, j: u32, s: u32, d: u32) -> f32 {
    let step = f32(s) / f32(d);
    let a = f32(i) * step;
    let b = f32(i + 1u) * step;
    let overlap = max(min(b, f32(j) + 1.0) - max(a, f32(j)), 0.0);
    return overlap / step;
}

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= mip.dw || gid.y >= mip.dh {
        return;
    }
    let x = gid.x;
    let y = gid.y;
    var acc = vec4<f32>(0.0);
    if (mip.sw & 1u) == 0u && (mip.sh & 1u) == 0u {
        let r0 = mip.src + 2u * y * mip.sw + 2u * x;
        let r1 = r0 + mip.sw;
        acc = (levels[r0] + levels[r0 + 1u] + levels[r1] + levels[r1 + 1u]) * 0.25;
    } else {
        let sx = f32(mip.sw) / f32(mip.dw);
        let sy = f32(mip.sh) / f32(mip.dh);
        let y0 = u32(floor(f32(y) * sy));
        let y1 = min(u32(ceil(f32(y + 1u) * sy)), mip.sh);
        let x0 = u32(floor(f32(x) * sx));
        let x1 = min(u32(ceil(f32(x + 1u) * sx)), mip.sw);
        for (var j = y0; j < y1; j++) {
            let wy = box_weight(y, j, mip.sh, mip.dh);
            for (var i = x0; i < x1; i++) {
                let w = wy * box_weight(x, i, mip.sw, mip.dw);
                if w > 0.0 {
                    acc += w * levels[mip.src + j * mip.sw + i];
                }
            }
        }
    }
    levels[mip.dst + y * mip.dw + x] = store(acc, mip.format);
}

@group(0) @binding(2) var<storage, read_write> packed: array<u32>;

@compute @workgroup_size(8, 8)
fn pack(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= mip.sw || gid.y >= mip.sh {
        return;
    }
    let v = levels[mip.src + gid.y * mip.sw + gid.x];
    let at = mip.packed_at + gid.y * mip.row_words + gid.x * mip.texel_words;
    if mip.format == STORE_U8 {
        let c = vec4<u32>(v);
        packed[at] = c.x | (c.y << 8u) | (c.z << 16u) | (c.w << 24u);
    } else if mip.format == STORE_UNORM16 && mip.as_float == 0u {
        let c = vec4<u32>(v);
        packed[at] = c.x | (c.y << 16u);
        if mip.channels == 4u {
            packed[at + 1u] = c.z | (c.w << 16u);
        }
    } else if mip.format == STORE_F16 {
        packed[at] = pack2x16float(v.xy);
        if mip.channels == 4u {
            packed[at + 1u] = pack2x16float(v.zw);
        }
    } else {
        // 32-bit floats; 16-bit codes on an adapter without 16-bit normalized textures,
        // stored as floats of the same value.
        var f = v;
        if mip.format == STORE_UNORM16 {
            f = v / 65535.0;
        }
        packed[at] = bitcast<u32>(f.x);
        packed[at + 1u] = bitcast<u32>(f.y);
        if mip.channels == 4u {
            packed[at + 2u] = bitcast<u32>(f.z);
            packed[at + 3u] = bitcast<u32>(f.w);
        }
    }
}
