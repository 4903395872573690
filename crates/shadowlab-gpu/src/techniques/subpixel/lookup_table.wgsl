// gpu:subpixel, the library's `lookup_table.rs` (`Lut::half_plane`): a half-plane on the
// screen, a·x + b·y + c ≥ 0 in pixel-local coordinates, as the bitmask of the samples it
// covers, from the table built once on the CPU exactly as the CPU technique builds it
// (entry 2i its mask, 2i + 1 its uncertain samples, tested exactly here). Masks are
// 128 bits (vec4<u32>); the samples past `fr.samples` are never set. Composed after
// subpixel/bindings.wgsl.

const LUT_ANGLES: u32 = 256u;
const LUT_DISTANCES: u32 = 128u;
const LUT_REACH: f32 = 0.7072;

// The samples of word w (samples 32w to 32w + 31) that the pattern has.
fn word_mask(w: u32) -> u32 {
    let lo = w * 32u;
    if fr.samples >= lo + 32u {
        return 0xffffffffu;
    }
    if fr.samples > lo {
        return (1u << (fr.samples - lo)) - 1u;
    }
    return 0u;
}

// Masks are built word by word, without indexing a vector by a variable.
fn all_mask() -> vec4<u32> {
    return vec4<u32>(word_mask(0u), word_mask(1u), word_mask(2u), word_mask(3u));
}

fn bit(i: u32) -> vec4<u32> {
    let b = 1u << (i % 32u);
    let w = i / 32u;
    return vec4<u32>(select(0u, b, w == 0u), select(0u, b, w == 1u), select(0u, b, w == 2u), select(0u, b, w == 3u));
}

fn is_zero(m: vec4<u32>) -> bool {
    return all(m == vec4<u32>(0u));
}

fn ones(m: vec4<u32>) -> u32 {
    return countOneBits(m.x) + countOneBits(m.y) + countOneBits(m.z) + countOneBits(m.w);
}

// The library's `diamond_angle`: (quadrant, fraction).
fn diamond_angle(a: f32, b: f32) -> vec2<f32> {
    if b >= 0.0 {
        if a >= 0.0 {
            return vec2<f32>(0.0, b / (a + b));
        }
        return vec2<f32>(1.0, (-a) / (b - a));
    }
    if a <= 0.0 {
        return vec2<f32>(2.0, (-b) / (-a - b));
    }
    return vec2<f32>(3.0, a / (a - b));
}

// Rust's `x as i32` for the small range used here: NaN is 0, the rest saturates.
fn to_signed(x: f32) -> i32 {
    if x >= -1.0e6 {
        return i32(min(x, 1.0e6));
    }
    if x < -1.0e6 {
        return -1000000;
    }
    return 0;
}

// Rust's `x as u32` for the small range used here: NaN and negatives are 0.
fn to_index(x: f32) -> u32 {
    return u32(max(to_signed(x), 0));
}

// The samples among `bits` (of the word starting at sample `base`) on the positive side
// of a·x + b·y + c, tested exactly.
fn exact_word(bits: u32, base: u32, a: f32, b: f32, c: f32) -> u32 {
    var out = 0u;
    var rest = bits;
    while rest != 0u {
        let i = firstTrailingBit(rest);
        rest &= rest - 1u;
        let s = lut_samples[base + i];
        if a * s.x + b * s.y + c >= 0.0 {
            out |= 1u << i;
        }
    }
    return out;
}

fn half_plane(a: f32, b: f32, c: f32) -> vec4<u32> {
    let v0 = c + 0.5 * (a + b);
    let nn = a * a + b * b;
    if v0 * v0 >= LUT_REACH * LUT_REACH * nn {
        if v0 >= 0.0 {
            return all_mask();
        }
        return vec4<u32>(0u);
    }
    let dist = v0 / sqrt(nn);
    let qf = diamond_angle(a, b);
    let quarter = LUT_ANGLES / 4u;
    // Float-to-integer conversions as Rust's `as` makes them (NaN to 0, saturating): a
    // shader's conversion of NaN or of a value out of range is undefined, and would read
    // an arbitrary entry.
    let ai = (u32(qf.x) * quarter + to_index(floor(qf.y * f32(quarter) + 0.5))) % LUT_ANGLES;
    let u = to_signed(floor(dist * (f32(LUT_DISTANCES) / (2.0 * LUT_REACH)))) + i32(LUT_DISTANCES / 2u);
    let di = u32(clamp(u, 0, i32(LUT_DISTANCES) - 1));
    let e = ai * LUT_DISTANCES + di;
    let near = lut[2u * e + 1u];
    let exact = vec4<u32>(exact_word(near.x, 0u, a, b, c), exact_word(near.y, 32u, a, b, c), exact_word(near.z, 64u, a, b, c), exact_word(near.w, 96u, a, b, c));
    let m = (lut[2u * e] & ~near) | exact;
    return m;
}
