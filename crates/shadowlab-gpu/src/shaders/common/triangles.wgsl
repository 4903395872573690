// The scene's triangles as the stages that test them bind them: a stage composed after
// this file declares `tris` (nine f32 a triangle), `tri_material`, `materials`, `uvs` (six
// f32 a triangle), and `texels`; `masks` is 0 when no material of the scene is masked.
// WGSL resolves module-scope names in any order, so the declarations follow in the stage.

// Vertex `k` of triangle `tri`.
fn vertex(tri: u32, k: u32) -> vec3<f32> {
    let i = tri * 9u + k * 3u;
    return vec3<f32>(tris[i], tris[i + 1u], tris[i + 2u]);
}

// The library's `Scene::cut_out`: true where the triangle's mask removes it at `b`.
fn cut_out(masks: u32, tri: u32, b: vec3<f32>) -> bool {
    let m = materials[tri_material[tri]];
    if masks == 0u || m.masked == 0u {
        return false;
    }
    let i = tri * 6u;
    let uv0 = vec2<f32>(uvs[i], uvs[i + 1u]);
    let uv1 = vec2<f32>(uvs[i + 2u], uvs[i + 3u]);
    let uv2 = vec2<f32>(uvs[i + 4u], uvs[i + 5u]);
    let uv = uv0 * b.x + uv1 * b.y + uv2 * b.z;
    let x = wrap_texel(m.wrap_u, uv.x * f32(m.width), m.width);
    let y = wrap_texel(m.wrap_v, uv.y * f32(m.height), m.height);
    let byte = m.texel_offset + y * m.width + x;
    let a = (texels[byte / 4u] >> ((byte % 4u) * 8u)) & 0xffu;
    return !(f32(a) / 255.0 * m.factor >= m.cutoff);
}
