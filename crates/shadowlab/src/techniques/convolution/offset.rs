//! Offsetting and scaling the reconstructed step (Annen et al. 2007, Section 3.2.2): the
//! scale of the step about a pivot ([`DEFAULT_SCALE`], [`DEFAULT_PIVOT`]) and the offset
//! subtracted from the receiver depth so that a surface that is its own occluder is lit
//! after scaling, found automatically for the expansion and scale in effect.

use super::expansion::Expansion;

/// Default scale of the reconstructed step: 2, the paper's value (Section 3.2.2, Figure 4),
/// which makes the transition steeper. The paper scales about 0 (`2f`), which lights
/// `z = d` without an offset but doubles the ringing left in shadow (lobes up to 0.10 at
/// M = 16 past the step); here it is taken about [`DEFAULT_PIVOT`], which clamps them to
/// below 0.003. With the offset that lights a self-occluding surface after scaling
/// ([`Expansion::auto_offset_scaled`], 0.0018 of the normalized depth at M = 16, against
/// 0.020 unscaled), a receiver is half shadowed once its occluder is 0.008 of the depth
/// range in front of it and fully (≤ 0.01) at 0.018, against 0.020 and 0.038 unscaled:
/// contact shadows reach two to three times closer to their casters. The price: a filtered
/// penumbra of coverage `c` shows `clamp(2c − 0.1, 0, 1)`, twice as steep (edges sharper,
/// less anti-aliased) and shifted a twentieth of the way into the lit side. Measured at
/// 480×360 against the 16-sample reference on the 20 meshes of `scripts/verdict-table.sh`,
/// this default lowered `csm`'s mean error on every one (by 7–52%) against scale 1 with its
/// offset; scale 1.5 about 0 gained 0–38%, and scale 2 about 0 (the paper's) lost to scale
/// 1 on 11 of the 20 (ringing in shadow, 8-bit noise on lit surfaces clamped just below 1).
pub const DEFAULT_SCALE: f32 = 2.0;
/// Default pivot of the scale: the shadow value it is taken about, `pivot + scale · (f −
/// pivot)`. 0 is the paper's `scale · f`; 0.1 with scale 2 maps `f ≤ 0.05` to 0, which
/// clamps the Gibbs ringing of the shadowed side away as the paper's clamp already does on
/// the lit side, and needs a small offset in return. Measured as [`DEFAULT_SCALE`] is:
/// pivots 0.1 and 0.15 are within 2% of each other on every mesh, 0.3 had up to 9% more
/// error, 0 up to twice as much.
pub const DEFAULT_PIVOT: f32 = 0.1;
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
        self.auto_offset_scaled(1.0, 0.0)
    }

    /// [`Self::auto_offset`] of the step scaled by `scale` about `pivot`,
    /// `pivot + scale · (step − pivot)`, before clamping.
    pub fn auto_offset_scaled(&self, scale: f32, pivot: f32) -> f32 {
        let n = (0.5 / OFFSET_SEARCH_STEP) as u32;
        let values: Vec<f32> = (1..=n)
            .map(|i| pivot + scale * (self.step(i as f32 * OFFSET_SEARCH_STEP) - pivot))
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

    #[test]
    fn scaled_offset_lights_self_occluders_closer_to_the_step() {
        for m in [4, 8, 16] {
            let e = Expansion { m, alpha: 0.0 };
            let (s, p) = (DEFAULT_SCALE, DEFAULT_PIVOT);
            let o = e.auto_offset_scaled(s, p);
            let lit = p + s * (e.step(o) - p);
            assert!(lit >= 1.0 + LIT_MARGIN - 1e-4, "m {m}: {lit} at {o}");
            // Just below the offset the scaled step is not yet lit: the offset is the least.
            let before = p + s * (e.step(o - 2.0 / 8192.0) - p);
            assert!(before < 1.0 + LIT_MARGIN, "m {m}: {before}");
            assert!(
                o < 0.25 * e.auto_offset(),
                "m {m}: {o} vs {}",
                e.auto_offset()
            );
        }
        // Scale 1 about any pivot is the unscaled step.
        let e = Expansion { m: 16, alpha: 0.0 };
        assert_eq!(e.auto_offset_scaled(1.0, 0.5), e.auto_offset());
    }
}
