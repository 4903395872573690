//! The Hamburger four-moment bound of moment shadow mapping (Peters & Klein, "Moment Shadow
//! Mapping", I3D 2015, Algorithm 3, "Hamburger 4MSM").
//!
//! Given the (biased) moments `b = (E[z], E[z²], E[z³], E[z⁴])` of the depth distribution
//! under a filter and a receiver at depth `z_f`, the sharp lower bound on the share of the
//! distribution in front of `z_f`, over every distribution with those moments, is attained
//! by a distribution on three points: `z_f` and the two roots `z₂ ≤ z₃` of the quadratic
//! whose coefficients `c` solve the Hankel system `B c = (1, z_f, z_f²)`,
//! `B = [[1, b₁, b₂], [b₁, b₂, b₃], [b₂, b₃, b₄]]`. Its mass in front of `z_f` is the shadow
//! intensity: 0 when `z_f ≤ z₂`, the weight of `z₂` when `z₂ < z_f ≤ z₃`, and one minus the
//! weight of `z_f` beyond `z₃`.
//!
//! Invariants: the system is solved by the paper's Cholesky (LDLᵀ) factorization of `B`;
//! the result lies in `[0, 1]`. Departure: the arithmetic is f64 where the paper's shader
//! uses f32; the moments themselves are what the map stored (16-bit or f32), so only the
//! rounding of the solve changes, and a degenerate `B` (pivots not positive, as a zero
//! moment bias on a flat filter region gives) yields 0 instead of a NaN.

/// The three-point distribution that attains the bound: support `(z_f, z₂, z₃)`, the
/// shadow intensity, and whether the Hankel matrix was positive definite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// The smaller root `z₂`.
    pub z2: f64,
    /// The larger root `z₃`.
    pub z3: f64,
    /// The lower bound on the share of the distribution in front of `z_f` (the shadow
    /// intensity; the lit fraction is one minus it).
    pub intensity: f64,
}

/// The Hamburger 4MSM bound for moments `b` and receiver depth `zf` (see the module doc).
/// `None` when `B` is not positive definite.
pub fn bound(b: [f64; 4], zf: f64) -> Option<Bound> {
    let [b1, b2, b3, b4] = b;
    // LDLᵀ of the Hankel matrix.
    let d22 = b2 - b1 * b1;
    if d22 <= 0.0 || d22.is_nan() {
        return None;
    }
    let l32 = (b3 - b1 * b2) / d22;
    let d33 = (b4 - b2 * b2) - l32 * l32 * d22;
    if d33 <= 0.0 || d33.is_nan() {
        return None;
    }
    // Forward substitution of L y = (1, zf, zf²) (L₂₁ = b₁, L₃₁ = b₂), then D, then Lᵀ.
    let y2 = zf - b1;
    let y3 = zf * zf - b2 - l32 * y2;
    let c3 = y3 / d33;
    let c2 = y2 / d22 - l32 * c3;
    let c1 = 1.0 - b1 * c2 - b2 * c3;
    // Roots of c₃ z² + c₂ z + c₁.
    if c3 == 0.0 || !c3.is_finite() {
        return None;
    }
    let p = c2 / c3;
    let q = c1 / c3;
    let r = (0.25 * p * p - q).max(0.0).sqrt();
    let (z2, z3) = (-0.5 * p - r, -0.5 * p + r);
    let intensity = if zf <= z2 {
        0.0
    } else if zf <= z3 {
        // Weight of z₂ in the distribution on {z_f, z₂, z₃}.
        (zf * z3 - b1 * (zf + z3) + b2) / ((z3 - z2) * (zf - z2))
    } else {
        // One minus the weight of z_f.
        1.0 - (z2 * z3 - b1 * (z2 + z3) + b2) / ((zf - z2) * (zf - z3))
    };
    Some(Bound {
        z2,
        z3,
        intensity: if intensity.is_finite() {
            intensity.clamp(0.0, 1.0)
        } else {
            0.0
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The power moments 0..=4 of a distribution.
    fn moments(points: &[(f64, f64)]) -> [f64; 5] {
        let mut m = [0.0; 5];
        for &(z, w) in points {
            let mut zk = 1.0;
            for mk in &mut m {
                *mk += w * zk;
                zk *= z;
            }
        }
        m
    }

    /// Solves the 5×5 system `V w = m` (`V[k][j] = x_j^k`) by Gaussian elimination with
    /// partial pivoting; `None` when singular.
    fn solve5(x: [f64; 5], m: [f64; 5]) -> Option<[f64; 5]> {
        let mut a = [[0.0f64; 6]; 5];
        for (k, row) in a.iter_mut().enumerate() {
            for j in 0..5 {
                row[j] = x[j].powi(k as i32);
            }
            row[5] = m[k];
        }
        for col in 0..5 {
            let piv = (col..5).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
            if a[piv][col].abs() < 1e-14 {
                return None;
            }
            a.swap(col, piv);
            let pivot = a[col];
            for (i, row) in a.iter_mut().enumerate() {
                if i != col {
                    let f = row[col] / pivot[col];
                    for (r, p) in row.iter_mut().zip(pivot.iter()).skip(col) {
                        *r -= f * p;
                    }
                }
            }
        }
        Some(std::array::from_fn(|i| a[i][5] / a[i][i]))
    }

    /// Brute force: the least mass in front of `zf` over every distribution on `grid` with
    /// moments `m`, as the minimum of the linear program's objective over its vertices (every
    /// 5-point subset whose moment system has a non-negative solution).
    fn brute_force_lower_bound(grid: &[f64], m: [f64; 5], zf: f64) -> f64 {
        let n = grid.len();
        let mut best = f64::INFINITY;
        let mut idx = [0usize, 1, 2, 3, 4];
        loop {
            let x = idx.map(|i| grid[i]);
            if let Some(w) = solve5(x, m) {
                let residual: f64 = (0..5usize)
                    .map(|k| {
                        let mk: f64 = w.iter().zip(&x).map(|(w, x)| w * x.powi(k as i32)).sum();
                        (mk - m[k]).abs()
                    })
                    .sum();
                if w.iter().all(|&w| w >= -1e-10) && residual < 1e-9 {
                    let front: f64 = w
                        .iter()
                        .zip(&x)
                        .filter(|(_, &x)| x < zf)
                        .map(|(w, _)| w)
                        .sum();
                    best = best.min(front);
                }
            }
            // Next combination in lexicographic order.
            let mut i = 4;
            loop {
                if idx[i] < n - 5 + i {
                    idx[i] += 1;
                    for j in i + 1..5 {
                        idx[j] = idx[j - 1] + 1;
                    }
                    break;
                }
                if i == 0 {
                    return best;
                }
                i -= 1;
            }
        }
    }

    #[test]
    fn hamburger_bound_equals_the_brute_force_lower_bound() {
        let mut seed = 0x2545_f491_u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for case in 0..40 {
            let k = 3 + case % 4;
            let pts: Vec<(f64, f64)> = (0..k).map(|_| (rnd(), 0.05 + rnd())).collect();
            let total: f64 = pts.iter().map(|p| p.1).sum();
            let pts: Vec<(f64, f64)> = pts.iter().map(|&(z, w)| (z, w / total)).collect();
            let m = moments(&pts);
            let zf = rnd();
            let b = bound([m[1], m[2], m[3], m[4]], zf).expect("three or more points: B > 0");
            // A lower bound for the distribution the moments came from.
            let truth: f64 = pts.iter().filter(|p| p.0 < zf).map(|p| p.1).sum();
            assert!(
                b.intensity <= truth + 1e-9,
                "case {case}: {} > {truth}",
                b.intensity
            );
            // Over every distribution on a grid that holds the generating points and the
            // bound's own support: never below the bound, and attained.
            let mut grid: Vec<f64> = (0..14).map(|i| (i as f64 + 0.5) / 14.0).collect();
            grid.extend(pts.iter().map(|p| p.0));
            grid.extend([zf, b.z2, b.z3]);
            let brute = brute_force_lower_bound(&grid, m, zf);
            assert!(
                (brute - b.intensity).abs() < 1e-6,
                "case {case}: brute force {brute} vs Hamburger {}",
                b.intensity
            );
            checked += 1;
        }
        assert_eq!(checked, 40);
    }

    #[test]
    fn a_single_occluder_in_front_shadows_fully() {
        // Moments biased towards a spread distribution (as the lookup does) around one
        // occluder at 0.3: a receiver well behind it is shadowed, one in front lit.
        let alpha = 3e-5;
        let z = 0.3f64;
        let b = [z, z * z, z * z * z, z * z * z * z].map(|m| (1.0 - alpha) * m + alpha * 0.5);
        assert!(bound(b, 0.8).unwrap().intensity > 0.99);
        assert!(bound(b, 0.1).unwrap().intensity < 0.01);
    }
}
