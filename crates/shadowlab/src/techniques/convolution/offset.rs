//! Offsetting and scaling the reconstructed step (Annen et al. 2007, Section 3.2.2): the
//! offset subtracted from the receiver depth so that a surface that is its own occluder is
//! lit, found automatically for the expansion in effect, and the scale of the step.

use super::expansion::Expansion;

/// steeper and lights `z = d` without an offset, at the price of sharper (re-aliased) shadows.
pub const DEFAULT_SCALE: f32 = 1.0;
/// Where the attenuated step never overshoots 1 (large α), the automatic offset is where it
/// first comes this close to its maximum: smaller values light self-occluding surfaces more
/// fully but push the offset out (more contact-shadow leaking).
pub const OFFSET_PLATEAU_TOLERANCE: f32 = 0.01;
/// The automatic offset aims the step at `1 + LIT_MARGIN` for a self-occluding surface, so
/// that after clamping it is fully lit despite the 8-bit quantization of the basis (whose
/// reconstruction error stays below about 0.006 at M = 4); a larger margin costs offset.
pub const LIT_MARGIN: f32 = 0.01;
/// The largest offset accepted, in normalized depth: beyond it the margin that keeps
/// `z − d + offset` inside one period of the series vanishes.
pub const MAX_OFFSET: f32 = 0.25;
/// Resolution of the search for the automatic offset, in normalized depth.
const OFFSET_SEARCH_STEP: f32 = 1.0 / 8192.0;

impl Expansion {
    /// The automatic offset: the smallest `t > 0` at which [`Self::step`] reaches
    /// `1 + LIT_MARGIN` — so a self-occluding surface clamps to fully lit even with the
    /// 8-bit quantization noise — or, where the step's maximum over `(0, ½]` stays below
    /// that, comes within [`OFFSET_PLATEAU_TOLERANCE`] of its maximum.
    pub fn auto_offset(&self) -> f32 {
        let n = (0.5 / OFFSET_SEARCH_STEP) as u32;
        let values: Vec<f32> = (1..=n)
            .map(|i| self.step(i as f32 * OFFSET_SEARCH_STEP))
            .collect();
        let peak = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let target = if peak >= 1.0 + LIT_MARGIN {
            1.0 + LIT_MARGIN
        } else {
            peak - OFFSET_PLATEAU_TOLERANCE
        };
        let i = values
            .iter()
            .position(|&v| v >= target)
            .unwrap_or(values.len() - 1);
        ((i + 1) as f32 * OFFSET_SEARCH_STEP).min(MAX_OFFSET)
    }
}

#[cfg(test)]
mod tests {
    use super::super::expansion::DEFAULT_ALPHA;
    use super::*;

    #[test]
    fn auto_offset_lights_self_occluders() {
        for m in [4, 8, 16] {
            let e = Expansion {
                m,
                alpha: DEFAULT_ALPHA,
            };
            let o = e.auto_offset();
            assert!(o > 0.0 && o <= MAX_OFFSET);
            assert!(e.step(o) >= 0.97, "m {m}: step(offset {o}) = {}", e.step(o));
        }
        assert!(
            Expansion { m: 16, alpha: 0.5 }.auto_offset()
                < Expansion { m: 4, alpha: 0.5 }.auto_offset()
        );
    }
}
