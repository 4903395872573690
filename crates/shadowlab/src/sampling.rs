//! Sub-pixel sample patterns shared by the supersampled reference and the
//! anti-aliased techniques, so both are measured on the same positions.

use crate::error::{Error, Result};
use crate::math::{vec2, Vec2};

/// The kind of sub-pixel pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatternKind {
    /// An a×b grid (a·b = n, as square as n allows) of spacing 1/a by 1/b, placed so that
    /// one sample lies on the pixel centre: along an axis with an odd count the samples are
    /// the cell centres, with an even count they sit on the cell corners `i / a` (the first
    /// on the pixel's left or top edge, which the pixel owns).
    Grid,
    /// The grid rotated by atan(1/2) about the pixel centre and wrapped into the pixel:
    /// distinct x and y coordinates, better for near-horizontal and near-vertical edges.
    /// The centre sample stays on the centre.
    RotatedGrid,
}

impl std::str::FromStr for PatternKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "grid" => Ok(PatternKind::Grid),
            "rotated-grid" | "rgss" => Ok(PatternKind::RotatedGrid),
            _ => Err(Error::param(format!(
                "unknown sample pattern {s:?}: expected grid or rotated-grid"
            ))),
        }
    }
}

/// The most samples per pixel any pattern holds.
pub const MAX_SAMPLES: u32 = 1024;

/// `n` sample positions in `[0, 1)²` relative to the pixel's corner. Every pattern holds
/// the pixel centre `(0.5, 0.5)` (at index [`centre_index`]): techniques that evaluate
/// sub-samples on the centre sample's surface rely on that one sample being exact, and the
/// supersampled reference shares these positions.
pub fn pattern(kind: PatternKind, n: u32) -> Result<Vec<Vec2>> {
    if n == 0 || n > MAX_SAMPLES {
        return Err(Error::param(format!(
            "samples per pixel {n} is outside 1..={MAX_SAMPLES}"
        )));
    }
    if n == 1 {
        return Ok(vec![vec2(0.5, 0.5)]);
    }
    // The most square factorization a × b = n with a ≥ b.
    let mut b = (n as f64).sqrt() as u32;
    while !n.is_multiple_of(b) {
        b -= 1;
    }
    let a = n / b;
    // Cell centres for an odd count, cell corners for an even one: either way the middle
    // sample of the axis lands on 0.5.
    let axis = |i: u32, m: u32| {
        if m % 2 == 1 {
            (i as f32 + 0.5) / m as f32
        } else {
            i as f32 / m as f32
        }
    };
    let mut out = Vec::with_capacity(n as usize);
    for j in 0..b {
        for i in 0..a {
            out.push(vec2(axis(i, a), axis(j, b)));
        }
    }
    if kind == PatternKind::RotatedGrid {
        let (s, c) = (0.5f32).atan().sin_cos();
        for p in &mut out {
            let d = *p - vec2(0.5, 0.5);
            let r = vec2(d.x * c - d.y * s, d.x * s + d.y * c) + vec2(0.5, 0.5);
            *p = vec2(wrap_unit(r.x), wrap_unit(r.y));
        }
    }
    Ok(out)
}

/// `x` wrapped into `[0, 1)` (`rem_euclid` can round a tiny negative value up to 1.0).
fn wrap_unit(x: f32) -> f32 {
    let r = x.rem_euclid(1.0);
    if r >= 1.0 {
        0.0
    } else {
        r
    }
}

/// The index of the pixel-centre sample `(0.5, 0.5)` in `samples`, if there is one.
pub fn centre_index(samples: &[Vec2]) -> Option<usize> {
    samples.iter().position(|s| *s == vec2(0.5, 0.5))
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
                assert!(p
                    .iter()
                    .all(|q| (0.0..1.0).contains(&q.x) && (0.0..1.0).contains(&q.y)));
                let mean = p.iter().fold(Vec2::ZERO, |a, q| a + *q) / n as f32;
                // A centred grid of an even count is off by half a spacing (at most 1/4).
                assert!(
                    (mean - vec2(0.5, 0.5)).abs().max_element() <= 0.25 + 1e-6,
                    "{kind:?} {n} mean {mean}"
                );
                assert!(
                    centre_index(&p).is_some(),
                    "{kind:?} {n} has no centre sample"
                );
                for (i, a) in p.iter().enumerate() {
                    for b in &p[i + 1..] {
                        assert!((*a - *b).length() > 1e-4, "{kind:?} {n}: {a} repeated");
                    }
                }
            }
        }
    }
}
