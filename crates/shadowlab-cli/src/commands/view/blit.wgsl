// The viewer's view pass: the shaded view copied to the window pixel for pixel (its
// texel at the pixel, no filtering, so the window shows `render`'s very bytes), with the
// error overlay laid over it where the overlay's alpha says so; outside the view the
// window's background.

struct Blit {
    // The view's size in pixels.
    width: u32,
    height: u32,
    // 1 when the error overlay is shown.
    error_on: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> blit: Blit;
@group(0) @binding(1) var view_image: texture_2d<f32>;
@group(0) @binding(2) var error_image: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the window.
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<u32>(at.xy);
    if p.x >= blit.width || p.y >= blit.height {
        return vec4<f32>(0.08, 0.08, 0.08, 1.0);
    }
    var c = textureLoad(view_image, vec2<i32>(p), 0).rgb;
    if blit.error_on == 1u {
        let e = textureLoad(error_image, vec2<i32>(p), 0);
        c = mix(c, e.rgb, e.a);
    }
    return vec4<f32>(c, 1.0);
}
