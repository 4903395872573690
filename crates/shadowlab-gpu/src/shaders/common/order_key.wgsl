// A float as an unsigned key whose order is the floats' order (negative floats bit-flipped,
// the others with the sign bit set), for reductions by integer atomicMin/atomicMax: they
// are exact and do not depend on the order threads run. `shader::float_of_key` reads a key
// back on the CPU.

fn order_key(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    if (b & 0x80000000u) != 0u {
        return ~b;
    }
    return b | 0x80000000u;
}
