//! Sub-pixel sample patterns shared by the supersampled reference and the
//! anti-aliased techniques, so both are measured on the same positions.

use crate::error::{Error, Result};
use crate::math::{vec2, Vec2};

/// The kind of sub-pixel pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternKind {
    /// An a×b grid of cell centres (a·b = n, as square as n allows).
    Grid,
    /// The grid rotated by atan(1/2) about the pixel centre and wrapped into the pixel:
    /// distinct x and y coordinates, better for near-horizontal and near-vertical edges.
    RotatedGrid,
}

impl std::str::FromStr for PatternKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "grid" => Ok(PatternKind::Grid),
            "rotated-grid" | "rgss" => Ok(PatternKind::RotatedGrid),
            _ => Err(Error::param(format!("unknown sample pattern {s:?}: expected grid or rotated-grid"))),
        }
    }
}

/// The most samples per pixel any pattern holds.
pub const MAX_SAMPLES: u32 = 1024;

/// `n` sample positions in `[0, 1)²` relative to the pixel's corner.
pub fn pattern(kind: PatternKind, n: u32) -> Result<Vec<Vec2>> {
    if n == 0 || n > MAX_SAMPLES {
        return Err(Error::param(format!("samples per pixel {n} is outside 1..={MAX_SAMPLES}")));
    }
    if n == 1 {
        return Ok(vec![vec2(0.5, 0.5)]);
    }
    // The most square factorization a × b = n with a ≥ b.
    let mut b = (n as f64).sqrt() as u32;
    while n % b != 0 {
        b -= 1;
    }
    let a = n / b;
    let mut out = Vec::with_capacity(n as usize);
    for j in 0..b {
        for i in 0..a {
            out.push(vec2((i as f32 + 0.5) / a as f32, (j as f32 + 0.5) / b as f32));
        }
    }
    if kind == PatternKind::RotatedGrid {
        let (s, c) = (0.5f32).atan().sin_cos();
        for p in &mut out {
            let d = *p - vec2(0.5, 0.5);
            let r = vec2(d.x * c - d.y * s, d.x * s + d.y * c) + vec2(0.5, 0.5);
            *p = vec2(r.x.rem_euclid(1.0), r.y.rem_euclid(1.0));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_have_n_distinct_samples_inside_the_pixel() {
        for kind in [PatternKind::Grid, PatternKind::RotatedGrid] {
            for n in [1, 4, 8, 16, 32, 64, 128] {
                let p = pattern(kind, n).unwrap();
                assert_eq!(p.len(), n as usize);
                assert!(p.iter().all(|q| (0.0..1.0).contains(&q.x) && (0.0..1.0).contains(&q.y)));
                let mean = p.iter().fold(Vec2::ZERO, |a, q| a + *q) / n as f32;
                assert!((mean - vec2(0.5, 0.5)).length() < 0.1, "{kind:?} {n} mean {mean}");
            }
        }
    }
}
