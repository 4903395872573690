// gpu:msm, the test of stage `lookup` (Peters & Klein 2015, Algorithm 3, "Hamburger
// 4MSM"): the filtered values decoded to moments (Θ⁻¹ for the quantized storage), biased
// towards (½, ½, ½, ½) by α, and the sharp lower bound on the occluded share from the
// Cholesky (LDLᵀ) solve of the Hankel system, in f32 as the paper's shader does (the
// library solves it in f64). Composed after moments/msm_quantize.wgsl.

fn hamburger_lit(moments: vec4<f32>, d: f32) -> f32 {
    let finite = abs(moments) < vec4<f32>(3.0e38);
    if !all(finite) || !(abs(d) < 3.0e38) {
        return 1.0;
    }
    let a = tp(1u);
    let b = (1.0 - a) * moments + a * 0.5;
    let zf = d - tp(2u);
    let d22 = b.y - b.x * b.x;
    var singular = !(d22 > 0.0);
    var intensity = 0.0;
    if !singular {
        let l32 = (b.z - b.x * b.y) / d22;
        let d33 = (b.w - b.y * b.y) - l32 * l32 * d22;
        singular = !(d33 > 0.0);
        if !singular {
            let y2 = zf - b.x;
            let y3 = zf * zf - b.y - l32 * y2;
            let c3 = y3 / d33;
            let c2 = y2 / d22 - l32 * c3;
            let c1 = 1.0 - b.x * c2 - b.y * c3;
            singular = c3 == 0.0 || !(abs(c3) < 3.0e38);
            if !singular {
                let p = c2 / c3;
                let q = c1 / c3;
                let r = sqrt(max(0.25 * p * p - q, 0.0));
                let z2 = -0.5 * p - r;
                let z3 = -0.5 * p + r;
                if zf <= z2 {
                    intensity = 0.0;
                } else if zf <= z3 {
                    intensity = (zf * z3 - b.x * (zf + z3) + b.y) / ((z3 - z2) * (zf - z2));
                } else {
                    intensity = 1.0 - (z2 * z3 - b.x * (z2 + z3) + b.y) / ((zf - z2) * (zf - z3));
                }
                if abs(intensity) < 3.0e38 {
                    intensity = clamp(intensity, 0.0, 1.0);
                } else {
                    intensity = 0.0;
                }
            }
        }
    }
    if singular {
        // Every moment is that of one depth: lit unless it is in front.
        return select(0.0, 1.0, zf <= b.x);
    }
    return 1.0 - intensity;
}

fn shade(d: f32, view_index: u32) -> f32 {
    let raw = fetch(0u);
    if tp(0u) < 0.5 {
        return hamburger_lit(raw, d);
    }
    let inverse = mat4x4<f32>(
        vec4<f32>(tp(20u), tp(21u), tp(22u), tp(23u)),
        vec4<f32>(tp(24u), tp(25u), tp(26u), tp(27u)),
        vec4<f32>(tp(28u), tp(29u), tp(30u), tp(31u)),
        vec4<f32>(tp(32u), tp(33u), tp(34u), tp(35u)),
    );
    return hamburger_lit(inverse * (raw - vec4<f32>(tp(3u), 0.0, 0.0, 0.0)), d);
}
