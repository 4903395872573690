//! Where the cascades of `cascaded` split the view depth range: the practical split scheme
//! (Zhang et al., "Parallel-Split Shadow Maps", 2006; Engel, "Cascaded Shadow Maps",
//! ShaderX⁵; Dimitrov, "Cascaded Shadow Maps", NVIDIA 2007).

/// The practical split scheme: split `i` of `n` over `[near, far]` is
/// `C_i = λ·near·(far/near)^(i/n) + (1 − λ)·(near + (far − near)·i/n)`, the blend of the
/// logarithmic scheme (λ = 1, the same texel density ratio for every cascade) and the
/// uniform one (λ = 0). Returns the `n + 1` planes `C_0 = near … C_n = far`, increasing.
pub fn practical_splits(near: f32, far: f32, n: usize, lambda: f32) -> Vec<f32> {
    let (near, far) = (near as f64, far as f64);
    let l = lambda as f64;
    let mut c: Vec<f32> = (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64;
            let log = near * (far / near).powf(s);
            let uni = near + (far - near) * s;
            (l * log + (1.0 - l) * uni) as f32
        })
        .collect();
    // The ends exactly, whatever the rounding of powf.
    c[0] = near as f32;
    c[n] = far as f32;
    c
}

/// The cascade that view depth `z` falls in: the last `i` with `splits[i] ≤ z` (clamped to
/// the first and the last cascade).
#[inline]
pub fn cascade_of(splits: &[f32], z: f32) -> usize {
    let n = splits.len() - 1;
    let mut i = 0;
    while i + 1 < n && z >= splits[i + 1] {
        i += 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambda_zero_is_uniform_and_one_is_logarithmic() {
        let (n, f) = (0.5f32, 200.0f32);
        let uni = practical_splits(n, f, 4, 0.0);
        for (i, c) in uni.iter().enumerate() {
            let want = n + (f - n) * i as f32 / 4.0;
            assert!((c - want).abs() <= 1e-4 * want, "{i}: {c} vs {want}");
        }
        let log = practical_splits(n, f, 4, 1.0);
        for (i, c) in log.iter().enumerate() {
            let want = n * (f / n).powf(i as f32 / 4.0);
            assert!((c - want).abs() <= 1e-4 * want, "{i}: {c} vs {want}");
        }
        // Logarithmic splits have a constant ratio between consecutive planes.
        let r = log[1] / log[0];
        for w in log.windows(2) {
            assert!((w[1] / w[0] - r).abs() < 1e-3 * r);
        }
        // In between, every plane lies between the two schemes'.
        let mid = practical_splits(n, f, 4, 0.5);
        for i in 0..=4 {
            assert!(mid[i] >= log[i] - 1e-3 && mid[i] <= uni[i] + 1e-3);
        }
    }

    #[test]
    fn depths_select_their_cascade() {
        let s = practical_splits(1.0, 100.0, 4, 0.5);
        assert_eq!(cascade_of(&s, 0.5), 0);
        assert_eq!(cascade_of(&s, s[1]), 1);
        assert_eq!(cascade_of(&s, (s[2] + s[3]) * 0.5), 2);
        assert_eq!(cascade_of(&s, 1e6), 3);
    }
}
